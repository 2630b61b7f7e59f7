"""``Motion``: local joint rotations over time on a named skeleton, plus root translation."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from synmitsuba.body.skeleton import Skeleton, forward_kinematics
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import axis_rotation, slerp_matrices


@dataclass
class Motion:
    """Frames of a skeleton's pose, metres and seconds, world y up.

    rotations        (F, J, 3, 3) local rotations (skeleton convention: axis-aligned rest frames)
    root_translation (F, 3)       added to the root's rest position
    face             (F, 52) or None: ARKit face unit weights (``body.expressions.FACE_UNITS``)
    """

    skeleton: Skeleton
    rotations: np.ndarray
    root_translation: np.ndarray
    fps: float
    labels: tuple[str, ...] = ()
    source: str = ""
    meta: dict = field(default_factory=dict)
    face: np.ndarray | None = None

    def __post_init__(self):
        self.rotations = np.asarray(self.rotations, dtype=np.float64)
        self.root_translation = np.asarray(self.root_translation, dtype=np.float64)
        F, J = len(self.rotations), len(self.skeleton)
        if self.rotations.shape != (F, J, 3, 3):
            raise ConfigError("motion.rotations", f"array{self.rotations.shape}", f"expected (frames, {J}, 3, 3)")
        if self.root_translation.shape != (F, 3):
            raise ConfigError("motion.root_translation", f"array{self.root_translation.shape}", f"expected ({F}, 3)")
        if not (isinstance(self.fps, (int, float)) and self.fps > 0):
            raise ConfigError("motion.fps", self.fps, "give a positive frame rate")
        if self.face is not None:
            self.face = np.asarray(self.face, dtype=np.float64)
            if self.face.ndim != 2 or len(self.face) != F:
                raise ConfigError("motion.face", f"array{self.face.shape}", f"expected ({F}, units)")
        self.labels = tuple(self.labels)

    @property
    def n_frames(self) -> int:
        return len(self.rotations)

    @property
    def duration(self) -> float:
        """Seconds from the first to one past the last frame."""
        return self.n_frames / self.fps

    def global_rotations(self) -> np.ndarray:
        return forward_kinematics(self.skeleton, self.rotations, self.root_translation)[0]

    def joint_positions(self) -> np.ndarray:
        """(frames, joints, 3) world positions in metres, y up."""
        return forward_kinematics(self.skeleton, self.rotations, self.root_translation)[1]

    def clip(self, start_s: float, seconds: float) -> "Motion":
        """Frames in [start_s, start_s + seconds)."""
        first = int(round(start_s * self.fps))
        count = int(round(seconds * self.fps))
        if start_s < 0 or count <= 0 or first + count > self.n_frames:
            raise ConfigError("clip", (start_s, seconds),
                              f"the window must lie inside the motion (0 .. {self.duration:.3f} s)")
        sl = slice(first, first + count)
        return replace(self, rotations=self.rotations[sl].copy(), root_translation=self.root_translation[sl].copy(),
                       face=None if self.face is None else self.face[sl].copy())

    def resample(self, fps: float) -> "Motion":
        """Resample to ``fps``: slerp for rotations, linear for the root; keeps the time span."""
        if not (isinstance(fps, (int, float)) and fps > 0):
            raise ConfigError("fps", fps, "give a positive frame rate")
        if fps == self.fps:
            return self
        n = max(1, int(np.floor((self.n_frames - 1) * fps / self.fps + 1e-9)) + 1)
        t = np.arange(n) * self.fps / fps  # fractional source frame index

        def lerp(a):
            return np.stack([np.interp(t, np.arange(self.n_frames), c) for c in a.T], 1)
        return replace(self, rotations=slerp_matrices(self.rotations, t), root_translation=lerp(self.root_translation),
                       fps=float(fps), face=None if self.face is None else lerp(self.face))

    def moved(self, yaw_deg: float = 0.0, translation=(0.0, 0.0, 0.0)) -> "Motion":
        """The motion turned by ``yaw_deg`` about the vertical axis through the origin, then
        shifted by ``translation`` (metres): how a clip is placed in a scene."""
        Ry = axis_rotation("y", np.radians(yaw_deg))
        rot = self.rotations.copy()
        roots = np.flatnonzero(self.skeleton.parents < 0)
        rot[:, roots] = Ry @ rot[:, roots]
        rest = self.skeleton.rest_positions[0]
        root = (rest + self.root_translation) @ Ry.T - rest + np.asarray(translation, dtype=np.float64)
        return replace(self, rotations=rot, root_translation=root)

    def rolled(self, start: int) -> "Motion":
        """The clip started at frame ``start`` and wrapped round (frame 0 is old frame ``start``)."""
        k = int(start) % self.n_frames
        return replace(self, rotations=np.roll(self.rotations, -k, 0), root_translation=np.roll(self.root_translation, -k, 0),
                       face=None if self.face is None else np.roll(self.face, -k, 0))

    def frame(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """(rotations (J, 3, 3), root_translation (3,)) of frame i."""
        return self.rotations[i], self.root_translation[i]

    def at(self, time: float) -> tuple[np.ndarray, np.ndarray]:
        """The pose at fractional frame ``time`` (clamped to the clip): slerp between the two
        frames around it, the root linearly; a whole ``time`` is that frame exactly."""
        t = float(np.clip(time, 0, self.n_frames - 1))
        i = min(int(np.floor(t)), self.n_frames - 1)
        if t == i:
            return self.frame(i)
        a = t - i
        from scipy.spatial.transform import Rotation
        r0, r1 = Rotation.from_matrix(self.rotations[i]), Rotation.from_matrix(self.rotations[i + 1])
        rot = (r0 * Rotation.from_rotvec((r0.inv() * r1).as_rotvec() * a)).as_matrix()  # slerp, every joint at once
        return rot, (1 - a) * self.root_translation[i] + a * self.root_translation[i + 1]

    def face_at(self, time: float) -> np.ndarray | None:
        """Face unit weights at fractional frame ``time`` (clamped, linear between frames);
        None when the clip has no face track."""
        if self.face is None:
            return None
        t = float(np.clip(time, 0, self.n_frames - 1))
        i = min(int(np.floor(t)), self.n_frames - 2) if self.n_frames > 1 else 0
        a = t - i
        return self.face[i] if a == 0 else (1 - a) * self.face[i] + a * self.face[i + 1]
