"""SMPL-X and SMPL labels for layered subjects: the SynBody paper's two-step fit, run on the
model files the user supplies (``synmitsuba.body.smplx_model``; nothing licensed ships here).

1. Shape, once per subject: betas (and, with ``gender="auto"``, the gender file that fits
   best) fitted to the anny body in its rest pose, the model's pose free, from rotations that
   turn its bones onto anny's; losses: surface distance both ways (point to plane at the
   nearest vertex, robust, normals agreeing) and the joints ``body_model_to_anny`` pairs.
2. Pose, per frame: global orientation, body pose and translation start from the clip (each
   model joint turns as its anny bone does, from the fitted rest pose) and are refined by the
   same losses plus a pull toward that start (the pose prior) and between neighbouring frames,
   in chunks of frames batched in torch, each chunk warm-started from the last frame before it.

   The fingers and SMPL-X's jaw start from anny's finger bones and head (a clip that does not
   move the fingers keeps anny's hand) and are refined with the body; the expression (10
   coefficients, from a file with an expression basis) starts neutral and is fitted against
   the body with the clip's face track (``Motion.face``) on it. The eyes keep anny's gaze.
Each frame records the mean and max distance from the model's vertices to the posed anny body
(exact point-to-triangle, mm), the same mean over the model's hand and face vertices
(``smplx_solve.part_vertices``) and the joint error (paired joints, the rest-pose offset between
the two rigs turning with the bone, mm); a frame whose mean surface distance exceeds
``threshold_mm`` is flagged (``ok`` false).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from synmitsuba.annotate.bodyparams import root_in_camera
from synmitsuba.annotate.smplx_solve import FitSettings, fit_frames, fit_shape
from synmitsuba.body.smplx_model import GENDERS, available_genders, find_model, load_model
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import axis_angle_to_matrix, matrix_to_axis_angle
from synmitsuba.schema import POSITIVE, Choice, Flag, Number, Params, Text, optional, spec


@dataclass
class SMPLXOptions(Params):
    """Generation configs' ``smplx:`` section: fit SMPL-X (and SMPL) to every subject."""

    enabled: bool = spec(False, Flag(), doc="fit SMPL-X to every subject; needs the model files")
    model_path: str | None = spec(None, optional(Text()), doc="folder of SMPLX_*.npz (default: $SMPLX_MODEL_PATH)")
    smpl: bool = spec(False, Flag(), doc="fit SMPL too (SMPL_*.npz or .pkl in the same folder or $SMPL_MODEL_PATH)")
    gender: str = spec("auto", Choice(("auto",) + GENDERS), doc="auto: each file present, the best fit kept")
    n_betas: int = spec(10, POSITIVE)
    threshold_mm: float = spec(10.0, Number(0.0), doc="frames whose mean surface distance exceeds it are flagged")
    hand_pca: int = spec(0, Number(0, 45, integer=True), doc="also write each fitted hand as this many of the model "
                         "file's hand PCA components (left_hand_pca, right_hand_pca; 0: none)")

    def __post_init__(self):
        if self.enabled:  # no work starts before the files are known to be there
            for kind in self.kinds:
                try:
                    find_model(self.model_path, "neutral" if self.gender == "auto" else self.gender, kind)
                except ConfigError as exc:
                    if self.gender != "auto" or not available_genders(self.model_path, kind):
                        raise ConfigError("model_path", self.model_path, f"{exc.field}: {exc.fix}") from None
            if self.hand_pca:
                genders = available_genders(self.model_path) if self.gender == "auto" else [self.gender]
                for g in genders:
                    check_hand_components(find_model(self.model_path, g), self.hand_pca)

    @property
    def kinds(self) -> tuple:
        return ("smplx", "smpl") if self.smpl else ("smplx",)


def fit_subject(human, clip, frames, options: SMPLXOptions, settings: FitSettings | None = None) -> dict:
    """{kind: SMPLXFit} for the kinds ``options`` asks for (empty when disabled)."""
    if not options.enabled:
        return {}
    return {kind: fit_smplx(human, clip, options.model_path, kind, options.gender, frames, options.n_betas,
                            options.threshold_mm, settings, options.hand_pca if kind == "smplx" else 0)
            for kind in options.kinds}


def check_hand_components(path: str, n: int) -> None:
    """A one-line error, before any fitting, when the SMPL-X file at ``path`` has no hand PCA."""
    import zipfile
    keys: set = set()
    if path.endswith(".npz"):
        with zipfile.ZipFile(path) as z:
            keys = {k.removesuffix(".npy") for k in z.namelist()}
    if not {"hands_componentsl", "hands_componentsr", "hands_meanl", "hands_meanr"} <= keys and path.endswith(".npz"):
        raise ConfigError("hand_pca", n, f"{path} has no hands_components/hands_mean arrays (the published SMPL-X "
                          "files do); use hand_pca: 0 to write the full axis-angle only")


def pca_hands(hands: np.ndarray, components: np.ndarray, mean: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Fitted hands (N, 2, 15, 3) (left, right; axis-angle) as ``n`` coefficients each of the
    model file's hand components (2, 45, 45), mean removed, least squares: the smplx package's
    ``use_pca=True, num_pca_comps=n, flat_hand_mean=False`` poses them back. Returns (N, 2, n)
    and (N,) the mean angle (deg) over the 30 finger joints between the fitted rotations and
    those the coefficients give back."""
    flat = hands.reshape(len(hands), 2, 45)
    coef = np.stack([np.linalg.lstsq(components[k, :n].T, (flat[:, k] - mean[k]).T, rcond=None)[0].T
                     for k in range(2)], 1)
    back = np.einsum("nkc,kcd->nkd", coef, components[:, :n]) + mean
    diff = np.swapaxes(axis_angle_to_matrix(back.reshape(-1, 3)), -1, -2) @ axis_angle_to_matrix(flat.reshape(-1, 3))
    angle = np.degrees(np.linalg.norm(matrix_to_axis_angle(diff), axis=-1)).reshape(len(hands), 30)
    return coef, angle.mean(1)


@dataclass
class SMPLXFit:
    """A subject's fitted parameters for ``frames`` of its clip (model joint order, axis-angle,
    local; ``pose[:, 0]`` is the global orientation), world frame (metres, y up)."""

    kind: str
    gender: str
    betas: np.ndarray           # (B,)
    frames: np.ndarray          # (N,) clip frames
    pose: np.ndarray            # (N, J, 3)
    transl: np.ndarray          # (N, 3)
    pelvis: np.ndarray          # (3,) the shaped model's rest pelvis joint: the pivot of global_orient
    surface_mean_mm: np.ndarray  # (N,)
    surface_max_mm: np.ndarray   # (N,)
    joint_mm: np.ndarray         # (N,)
    threshold_mm: float = 10.0
    expression: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (N, E) fitted coefficients
    hand_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (N,) hand vertices' mean distance
    face_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (N,) face vertices' mean distance
    joint_names: tuple = ()
    n_expression: int = 10
    meta: dict = field(default_factory=dict)
    hand_pca: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 0)))  # (N, 2, K) with hand_pca=K
    hand_pca_deg: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (N,) what the K components miss

    @property
    def ok(self) -> np.ndarray:
        return self.surface_mean_mm <= self.threshold_mm

    def index(self, frame: int) -> int:
        hit = np.flatnonzero(self.frames == int(frame))
        if not len(hit):
            raise ConfigError("frame", frame, f"not fitted; fitted clip frames: {self.frames[:8].tolist()}...")
        return int(hit[0])

    def _expression(self, i: int) -> np.ndarray:
        """Row ``i``'s expression, ``n_expression`` long (zeros past what the file's basis has)."""
        out = np.zeros(self.n_expression)
        if self.expression.size:
            e = self.expression[i][:self.n_expression]
            out[:len(e)] = e
        return out

    def params(self, frame: int, camera=None) -> dict:
        """The frame's parameters in the smplx package's names (world frame, or ``camera``'s:
        global orientation composed with R, translation such that the posed model is R v + t)."""
        i = self.index(frame)
        pose = self.pose[i].copy()
        transl = self.transl[i].copy()
        if camera is not None:
            R0, transl = root_in_camera(axis_angle_to_matrix(pose[0]), transl, self.pelvis, camera)
            pose[0] = matrix_to_axis_angle(R0)
        out = {"model": self.kind, "gender": self.gender, "betas": self.betas.copy(), "global_orient": pose[0],
               "transl": transl}
        if self.kind == "smplx":
            out.update(body_pose=pose[1:22], jaw_pose=pose[22], leye_pose=pose[23], reye_pose=pose[24],
                       left_hand_pose=pose[25:40], right_hand_pose=pose[40:55], expression=self._expression(i))
        else:
            out["body_pose"] = pose[1:]
        out["fit"] = {"surface_mean_mm": float(self.surface_mean_mm[i]), "surface_max_mm": float(self.surface_max_mm[i]),
                      "joint_mm": float(self.joint_mm[i]), "ok": bool(self.ok[i])}
        if len(self.hand_mm):
            out["fit"].update(hand_mm=float(self.hand_mm[i]), face_mm=float(self.face_mm[i]))
        if self.hand_pca.size:
            out.update(left_hand_pca=self.hand_pca[i, 0].copy(), right_hand_pca=self.hand_pca[i, 1].copy())
            out["fit"]["hand_pca_deg"] = float(self.hand_pca_deg[i])
        return out


def fit_smplx(human, clip, model_path: str | None = None, kind: str = "smplx", gender: str = "auto",
              frames=None, n_betas: int = 10, threshold_mm: float = 10.0,
              settings: FitSettings | None = None, hand_pca: int = 0) -> SMPLXFit:
    """Fit SMPL-X (``kind="smplx"``) or SMPL to a layered human (its anny body) over ``frames``
    (default all) of ``clip`` (a ``Motion`` on the human's skeleton, as placed in the scene).
    ``gender="auto"`` fits every gender file present and keeps the best. ``hand_pca`` > 0
    (SMPL-X) also expresses the fitted hands in that many of the file's hand components."""
    s = settings or FitSettings()
    body = getattr(human, "body", human)
    if clip.skeleton.names != body.skeleton.names:
        raise ConfigError("clip", clip.source or "motion", "the clip must be on the human's skeleton: "
                          "retarget it first (sm.retarget(motion, human.skeleton))")
    frames = np.arange(clip.n_frames) if frames is None else np.asarray(frames, np.int64)
    if len(frames) == 0 or frames.min() < 0 or frames.max() >= clip.n_frames:
        raise ConfigError("frames", frames.tolist()[:8], f"give clip frames in [0, {clip.n_frames - 1}]")
    genders = available_genders(model_path, kind) if gender == "auto" else [gender]
    models = [load_model(model_path, g, kind) for g in (genders or ["neutral"])]
    if hand_pca and kind == "smplx":  # the loaded arrays: .pkl files too, without reading any file again
        for m in models:
            if m.hands_components is None or m.hands_mean is None:
                raise ConfigError("hand_pca", hand_pca, f"{m.path} has no hands_components/hands_mean arrays (the "
                                  "published SMPL-X files do); use hand_pca: 0 to write the full axis-angle only")
    shapes = [fit_shape(m, body, n_betas, s) for m in models]
    shape = min(shapes, key=lambda sh: sh.error_mm)  # the gender file that fits best
    r = fit_frames(shape, body, clip, frames, s)
    m = shape.model
    fit = SMPLXFit(m.kind, m.gender, shape.betas, frames, r.pose, r.transl, r.pelvis, r.surface_mean_mm,
                   r.surface_max_mm, r.joint_mm, threshold_mm, r.expression, r.hand_mm, r.face_mm, m.joint_names,
                   meta={"model_file": m.path, "shape_error_mm": shape.error_mm, "n_betas": len(shape.betas)})
    if hand_pca and kind == "smplx":
        assert m.hands_components is not None and m.hands_mean is not None  # checked above
        fit.hand_pca, fit.hand_pca_deg = pca_hands(r.pose[:, 25:55].reshape(-1, 2, 15, 3), m.hands_components,
                                                   m.hands_mean, hand_pca)
    return fit
