"""``Annotator``: per-subject records of one view at one frame (``sample.subjects``, typed as
``annotate.labels.SubjectLabels``) and the
layered body passes (``annotate.body``: body part, surface point, body depth and normal, cloth
thickness).

A record (docs/FORMAT.md, "Subjects"): ``instance``; ``keypoints3d_world`` / ``keypoints3d_cam``
(23, 3) COCO-17 + 6 foot points, metres; ``keypoints2d`` (23, 2) pixels (pixel (0, 0) spans
[0, 1) x [0, 1)); ``visibility`` (23,) classes (``annotate.keypoints.VISIBILITY``);
``visible_fraction_kp`` (23,); ``joints3d_world`` / ``joints3d_cam`` (J, 3) joint centres; ``amodal_mask`` (H, W)
bool: the subject alone, through pixel-centre rays; ``visible_fraction`` = visible / amodal
pixels; ``bbox_visible``, ``bbox_amodal``, ``bbox_keypoints`` ``[x_min, y_min, x_max, y_max]``
pixel edges (None when empty) with ``center`` and ``scale`` = 1.2 max(w, h) / 200 of the
keypoint box (the crop top-down HMR code takes); ``body_params_world`` / ``body_params_cam``
(``root_translation`` (3,), ``rotations`` (J, 3) axis-angle, local, root first in skeleton
order; ``phenotypes``); ``root_world`` (3,); ``gaze_cam`` (2, 3) unit gaze of the left and right
eye in the camera frame; ``valid``.
"""
from __future__ import annotations

import numpy as np

from synmitsuba.annotate.body import BodyLayer
from synmitsuba.body.expressions import FACE_UNITS
from synmitsuba.annotate.bodyparams import body_params_in_camera
from synmitsuba.annotate.keypoints import keypoint_visibility
from synmitsuba.annotate.labels import BodyParams, SubjectLabels
from synmitsuba.engine.raycast import far_side, hits_through
from synmitsuba.engine.rays import pixel_centre_rays
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import bounds, matrix_to_axis_angle
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.scene import Scene


def layer_masks(sample, instance: int) -> dict:
    """The subject's visible pixels split by layer (from the layer pass): ``{layer name: (H, W)
    bool}`` for every layer it shows (body = skin, top, bottom, dress, shoes, hair, beard,
    accessory)."""
    from synmitsuba.scene.layers import Layer
    own = sample.passes["instance"] == instance
    return {Layer(int(k)).name.lower(): own & (sample.passes["layer"] == k)
            for k in np.unique(sample.passes["layer"][own])}


def mask_box(mask: np.ndarray) -> list | None:
    """Tight box [x_min, y_min, x_max, y_max] in pixel edges of a boolean mask; None if empty."""
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        return None
    return [int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1]


def keypoint_box(points2d: np.ndarray, visibility: np.ndarray) -> tuple[list | None, list | None, float | None]:
    """Box, centre and scale of the keypoints inside the image."""
    p = points2d[visibility > 0]
    if len(p) == 0:
        return None, None, None
    lo, hi = p.min(0), p.max(0)
    return [float(v) for v in (*lo, *hi)], [float(v) for v in (lo + hi) / 2], float(1.2 * (hi - lo).max() / 200)


def body_model_params(fits: dict, frame: int, camera: Camera) -> dict:
    """``<kind>_world`` / ``<kind>_cam`` parameters of each body-model fit (``smplx``, ``smpl``)
    that covers ``frame``."""
    out = {}
    for kind, fit in fits.items():
        if int(frame) in fit.frames:
            out[f"{kind}_world"], out[f"{kind}_cam"] = fit.params(frame), fit.params(frame, camera)
    return out


class Annotator:
    """Labels for placed subjects (``compose.subjects.PlacedSubject``), cast in the scene they
    are rendered in: amodal masks see one subject through everything else, body passes see the
    bodies through clothes and hair (``engine.raycast.hits_through``)."""

    def __init__(self, subjects: list):
        self.subjects = subjects
        self._frame: int | None = None
        self.bodies = BodyLayer(subjects)
        self._posed: list = []  # per subject at self._frame: (keypoints, body vertices, joints)
        self._points: list = []  # per subject at self._frame: every layer's vertices and strand points

    def _pose(self, frame: int) -> None:
        """Every subject's labels' geometry, once per frame (not per view)."""
        if frame == self._frame:
            return
        self._posed, self._points = [], []
        for p in self.subjects:
            rot, root = p.motion.frame(frame % p.motion.n_frames)
            face = p.motion.face_at(frame % p.motion.n_frames)
            layers = p.layers(frame)  # the arrays pose_in put in the scene (posing is cached)
            body = next(layer.vertices for layer in layers if layer.name == "body")
            self._posed.append((p.human.keypoints(rot, root, face), body, _joints(p.human.skeleton, rot, root)))
            self._points.append(np.concatenate([layer.points.reshape(-1, 3) if layer.is_curves else layer.vertices
                                                for layer in layers]))
        self.bodies.pose([b for _, b, _ in self._posed])
        self._frame = frame

    def annotate(self, sample, scene: Scene, frame: int, valid=None, visible_min: float = 0.0) -> list[SubjectLabels]:
        """Fill and return ``sample.subjects`` for ``scene`` posed at ``frame``. A record is
        valid when some pixel of the subject is visible, its visible fraction is at least
        ``visible_min`` and ``valid`` (one bool per subject, e.g. a view's validity from
        composition) allows it; invalid records are labelled all the same."""
        cam = sample.camera
        rays = pixel_centre_rays(cam).astype(np.float64)  # the instance pass's own rays: visible within amodal
        instances = {p.instance for p in self.subjects}
        self._pose(int(frame))
        self._check_posed(scene, int(frame))
        records = []
        for i, p in enumerate(self.subjects):
            rot, root = p.motion.frame(int(frame) % p.motion.n_frames)
            face = p.motion.face_at(int(frame) % p.motion.n_frames)
            visible = sample.passes["instance"] == p.instance
            # cast along the instance pass's own rays, so the union only guards visible within amodal
            amodal = self._amodal(i, p.instance, cam, rays, scene) | visible
            rec = self._record(p, rot, root, cam, scene, instances, amodal, visible, *self._posed[i])
            rec.expression = np.zeros(len(FACE_UNITS)) if face is None else np.asarray(face, np.float64)
            self._hands(rec, p, rot, root, cam, scene, instances, self._posed[i][1])
            self._face(rec, p, cam, scene, instances, self._posed[i][1])
            rec.valid = bool(rec.visible_fraction > 0 and rec.visible_fraction >= visible_min
                             and (valid is None or valid[i]))
            rec.layer_pixels = {k: int(m.sum()) for k, m in layer_masks(sample, p.instance).items()}
            rec.add_body_models(body_model_params(p.fits, int(frame) % p.motion.n_frames, cam))
            records.append(rec)
        sample.subjects = records
        sample.passes.update(self.bodies.passes(cam, scene, sample.passes["instance"], sample.passes["depth"],
                                                sample.passes["layer"]))
        return records

    def _check_posed(self, scene: Scene, frame: int) -> None:
        """The masks are cast in ``scene``: every subject must stand there as posed at ``frame``."""
        for p, (_, body, _) in zip(self.subjects, self._posed):
            mesh = scene.meshes.get(f"{p.prefix}_body")
            if mesh is None or not np.array_equal(mesh.vertices, body):
                raise ConfigError("scene", f"{p.prefix}_body " + ("missing" if mesh is None else "at another pose"),
                                  f"pose every subject in the scene at frame {frame} first "
                                  "(PlacedSubject.pose_in(scene, frame)): its labels are cast there")
        for p in self.subjects:  # its pixels, masks and keypoint visibility are counted by id
            other = next((name for name, s in (*scene.meshes.items(), *scene.curves.items())
                          if s.instance == p.instance and not name.startswith(f"{p.prefix}_")), None)
            if other is not None:
                raise ConfigError(f"{p.prefix}.instance", p.instance, f"the shape {other!r} has this id too; give "
                                  "every subject an id no object or other subject has")

    def _amodal(self, i: int, instance: int, cam: Camera, rays: np.ndarray, scene: Scene) -> np.ndarray:
        """The subject alone through pixel-centre rays, cast only inside the image box its
        geometry projects to (the whole image when part of it is behind the camera), through
        whatever stands in front of it."""
        pts = self._points[i]
        uv, z = cam.project(pts)
        mask = np.zeros((cam.height, cam.width), bool)
        x0, y0, x1, y1 = 0, 0, cam.width, cam.height
        if (z > 1e-6).all():
            lo, hi = bounds(uv)
            lo, hi = np.floor(lo).astype(int) - 2, np.ceil(hi).astype(int) + 2
            x0, y0 = max(lo[0], 0), max(lo[1], 0)
            x1, y1 = min(hi[0], cam.width), min(hi[1], cam.height)
            if x0 >= x1 or y0 >= y1:
                return mask
        grid = rays.reshape(cam.height, cam.width, 3)[y0:y1, x0:x1].reshape(-1, 3)
        own = [n for shapes in (scene.meshes, scene.curves) for n, sh in shapes.items() if sh.instance == instance]
        hits = hits_through(scene, cam.center, grid, own, far_side(pts, cam.center))
        mask[y0:y1, x0:x1] = (hits["instance"] == instance).reshape(y1 - y0, x1 - x0)
        return mask

    @staticmethod
    def _hands(rec: SubjectLabels, p, rot, root, cam: Camera, scene, instances, body) -> None:
        """Both hands' 21 points (``LayeredHuman.hand_keypoints``) and their visibility, tested
        as the body's keypoints are with a finger's margins (1 cm of clothing, 8 mm around)."""
        pts = p.human.hand_keypoints(rot, root)
        vis, _ = keypoint_visibility(scene, cam, pts.reshape(-1, 3), body, p.instance, instances, clothing=0.01,
                                     radius=0.008)
        rec.hands3d_world, rec.hands3d_cam = pts, pts @ cam.R.T + cam.t
        rec.hands2d, rec.hands_visibility = cam.project(pts.reshape(-1, 3))[0].reshape(2, 21, 2), vis.reshape(2, 21)

    @staticmethod
    def _face(rec: SubjectLabels, p, cam: Camera, scene, instances, body) -> None:
        """The face's 68 points (``LayeredHuman.face_keypoints``: rows of the frame's posed
        ``body``, which the scene holds) and their visibility, tested with 4 mm around each and
        what lies within 1 cm in front of the skin not counted (brows, lashes and a short beard
        grow over the points; an annotator marks the brow and the eye through them)."""
        pts = body[p.human.face_point_rows]
        vis, _ = keypoint_visibility(scene, cam, pts, body, p.instance, instances, clothing=0.01, radius=0.004)
        rec.face3d_world, rec.face3d_cam = pts, pts @ cam.R.T + cam.t
        rec.face2d, rec.face_visibility = cam.project(pts)[0], vis

    def _record(self, p, rot, root, cam: Camera, scene, instances, amodal, visible, kp, body, joints) -> SubjectLabels:
        vis, frac = keypoint_visibility(scene, cam, kp, body, p.instance, instances)
        kp2d, _ = cam.project(kp)
        box, centre, scale = keypoint_box(kp2d, vis)
        rot_c, root_c = body_params_in_camera(p.human.skeleton, rot, root, cam)
        phen = dict(p.human.recipe.phenotypes)
        n_amodal = int(amodal.sum())
        return SubjectLabels(
            int(p.instance), keypoints3d_world=kp, keypoints3d_cam=kp @ cam.R.T + cam.t, keypoints2d=kp2d,
            visibility=vis, visible_fraction_kp=frac, joints3d_world=joints, joints3d_cam=joints @ cam.R.T + cam.t,
            amodal_mask=amodal, visible_fraction=float(visible.sum() / n_amodal) if n_amodal else 0.0,
            bbox_visible=mask_box(visible), bbox_amodal=mask_box(amodal), bbox_keypoints=box, center=centre, scale=scale,
            body_params_world=BodyParams(matrix_to_axis_angle(rot), np.asarray(root, np.float64), phen),
            body_params_cam=BodyParams(matrix_to_axis_angle(rot_c), root_c, phen), root_world=joints[0],
            gaze_cam=p.human.gaze(rot, root) @ cam.R.T)


def _joints(skeleton, rot, root) -> np.ndarray:
    from synmitsuba.body.skeleton import forward_kinematics
    return forward_kinematics(skeleton, rot, np.asarray(root, np.float64))[1]
