"""How the cloth is put on before a clip: with the arms in the rest A-pose (the hands clear of any
skirt; hands hanging inside a flared shell ended up under the settled cloth, and a jump's arm
swing carried the hem over the head: issue 34's stability clip 20), the arms brought down to the
clip's first pose over ``ClothSettings.lead_s`` (``Collider.lead``), then the cloth left to hang
at that pose for the rest of ``settle_s``. ``Schedule`` says where the body and the held
particles are at each solver frame, settling and clip alike."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from synmitsuba.cloth.simulate import ClothSettings, Collider


def arm_joints(skeleton) -> np.ndarray:
    """Joints from each shoulder down (``shoulder01.L``/``.R`` and their descendants)."""
    inside = np.zeros(len(skeleton), bool)
    for side in "LR":
        inside[skeleton.index(f"shoulder01.{side}")] = True
    for j, p in enumerate(skeleton.parents):
        inside[j] |= p >= 0 and inside[p]
    return np.flatnonzero(inside)


def arms_from_rest(frame: tuple[np.ndarray, np.ndarray], arms: np.ndarray, w: float):
    """``frame``'s pose with its ``arms`` at the fraction ``w`` of the way from the rest pose
    (an A-pose, hands clear of any skirt: w = 0) to their own (w = 1), slerped."""
    from scipy.spatial.transform import Rotation
    rotations, root = frame
    out = np.array(rotations, dtype=np.float64)
    out[arms] = Rotation.from_rotvec(Rotation.from_matrix(out[arms]).as_rotvec() * w).as_matrix()
    return out, root


@dataclass
class Schedule:
    """Where the collider and the held particles are at the end of each solver frame ``f``: the
    settling frames (f < 0), the first ``lead`` of them moving along ``Collider.lead`` to frame
    0, where the rest stand still; then the clip's frames."""

    collider: Collider
    settle: int
    lead: int
    first: tuple[np.ndarray, np.ndarray]  # frame 0

    @classmethod
    def of(cls, collider: Collider, s: ClothSettings) -> Schedule:
        settle = int(round(s.settle_s * collider.fps))
        lead = min(max(int(round(s.lead_s * collider.fps)), 1), settle) if collider.lead is not None else 0
        return cls(collider, settle, lead, collider.at(0))

    def start(self) -> tuple[np.ndarray, np.ndarray]:
        """Where the cloth is put on."""
        return self.collider.lead(0.0) if self.lead and self.collider.lead is not None else self.first

    def moving(self, f: int) -> bool:
        """Whether the body and held particles move during solver frame ``f`` (else they stand)."""
        return f > 0 or f < self.lead - self.settle

    def at(self, f: int) -> tuple[np.ndarray, np.ndarray]:
        if f > 0:
            return self.collider.at(f)
        if self.moving(f) and self.collider.lead is not None:
            return self.collider.lead(smoothstep((f + self.settle + 1) / self.lead))
        return self.first


def smoothstep(x: float) -> float:
    x = min(max(x, 0.0), 1.0)
    return x * x * (3 - 2 * x)
