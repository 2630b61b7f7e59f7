"""``Annotator``: per-subject records of one view at one frame (``sample.subjects``).

A record (docs/FORMAT.md, "Subjects"): ``instance``; ``keypoints3d_world`` / ``keypoints3d_cam``
(23, 3) COCO-17 + 6 foot points, metres; ``keypoints2d`` (23, 2) pixels (pixel (0, 0) spans
[0, 1) x [0, 1)); ``visibility`` (23,) classes (``annotate.keypoints.VISIBILITY``);
``visible_fraction_kp`` (23,); ``joints3d_world`` (J, 3) joint centres; ``amodal_mask`` (H, W)
bool: the subject alone, through pixel-centre rays; ``visible_fraction`` = visible / amodal
pixels; ``bbox_visible``, ``bbox_amodal``, ``bbox_keypoints`` ``[x_min, y_min, x_max, y_max]``
pixel edges (None when empty) with ``center`` and ``scale`` = 1.2 max(w, h) / 200 of the
keypoint box (the crop top-down HMR code takes); ``body_params_world`` / ``body_params_cam``
(``root_translation`` (3,), ``rotations`` (J, 3) axis-angle, local, root first in skeleton
order; ``phenotypes``); ``root_world`` (3,); ``valid``.
"""
from __future__ import annotations

import numpy as np

from synmitsuba.annotate.bodyparams import body_params_in_camera
from synmitsuba.annotate.keypoints import keypoint_visibility
from synmitsuba.engine.raycast import cast
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.scene import Scene


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


def _axis_angle(rotations: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation
    return Rotation.from_matrix(rotations).as_rotvec()


class Annotator:
    """Labels for placed subjects (``compose.subjects.PlacedSubject``); keeps one scene per
    subject (its layers alone) for the amodal masks, moved in place frame by frame."""

    def __init__(self, subjects: list):
        self.subjects = subjects
        self._alone = [Scene() for _ in subjects]

    def annotate(self, sample, scene: Scene, frame: int, valid=None) -> list[dict]:
        """Fill and return ``sample.subjects`` for ``scene`` posed at ``frame``. A record is
        valid when some pixel of the subject is visible and ``valid`` (one bool per subject,
        e.g. a view's validity from composition) allows it."""
        cam = sample.camera
        rays = cam.pixel_rays().reshape(-1, 3)
        instances = {p.instance for p in self.subjects}
        records = []
        for i, p in enumerate(self.subjects):
            rot, root = p.motion.frame(int(frame) % p.motion.n_frames)
            p.human.add_to(self._alone[i], rot, root, instance=p.instance, prefix=p.prefix)
            amodal = (cast(self._alone[i], cam.center, rays)[0] == p.instance).reshape(cam.height, cam.width)
            rec = self._record(p, rot, root, cam, scene, instances, amodal, sample.passes["instance"] == p.instance)
            rec["valid"] = bool(rec["visible_fraction"] > 0 and (valid is None or valid[i]))
            records.append(rec)
        sample.subjects = records
        return records

    def _record(self, p, rot, root, cam: Camera, scene, instances, amodal, visible) -> dict:
        kp = p.human.keypoints(rot, root)
        body = p.human.pose(rot, root)[0].vertices
        vis, frac = keypoint_visibility(scene, cam, kp, body, p.instance, instances)
        kp2d, _ = cam.project(kp)
        box, centre, scale = keypoint_box(kp2d, vis)
        rot_c, root_c = body_params_in_camera(p.human.skeleton, rot, root, cam)
        phen = dict(p.human.recipe.phenotypes)
        n_amodal = int(amodal.sum())
        joints = _joints(p.human.skeleton, rot, root)
        return {"instance": int(p.instance), "keypoints3d_world": kp, "keypoints3d_cam": kp @ cam.R.T + cam.t,
                "keypoints2d": kp2d, "visibility": vis, "visible_fraction_kp": frac,
                "joints3d_world": joints,
                "amodal_mask": amodal, "visible_fraction": float(visible.sum() / n_amodal) if n_amodal else 0.0,
                "bbox_visible": mask_box(visible), "bbox_amodal": mask_box(amodal), "bbox_keypoints": box,
                "center": centre, "scale": scale,
                "body_params_world": {"rotations": _axis_angle(rot), "root_translation": np.asarray(root, np.float64),
                                      "phenotypes": phen},
                "body_params_cam": {"rotations": _axis_angle(rot_c), "root_translation": root_c, "phenotypes": phen},
                "root_world": joints[0]}


def _joints(skeleton, rot, root) -> np.ndarray:
    from synmitsuba.body.skeleton import forward_kinematics
    return forward_kinematics(skeleton, rot, np.asarray(root, np.float64))[1]
