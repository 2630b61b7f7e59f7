"""The small humanoid skeleton procedural motions are written on (T-pose rest, facing +z,
y up, feet on the ground, the character's left at +x, an average adult of 1.78 m).
Motions on it reach any body model through ``retarget``."""
from __future__ import annotations

import numpy as np

from synmitsuba.body.skeleton import Skeleton

_LEFT = [  # name, parent, rest position (left side; the right side mirrors x)
    ("l_hip", "pelvis", (0.09, 0.92, 0.0)), ("l_knee", "l_hip", (0.09, 0.50, 0.0)),
    ("l_ankle", "l_knee", (0.09, 0.085, 0.0)), ("l_toe", "l_ankle", (0.09, 0.02, 0.13)),
    ("l_toe_end", "l_toe", (0.09, 0.0, 0.19)),
    ("l_collar", "chest", (0.03, 1.45, 0.0)), ("l_shoulder", "l_collar", (0.18, 1.45, 0.0)),
    ("l_elbow", "l_shoulder", (0.46, 1.45, 0.0)), ("l_wrist", "l_elbow", (0.71, 1.45, 0.0)),
    ("l_hand_end", "l_wrist", (0.80, 1.45, 0.0)),
]
_SPINE = [("pelvis", None, (0.0, 0.95, 0.0)), ("spine1", "pelvis", (0.0, 1.05, 0.0)),
          ("spine2", "spine1", (0.0, 1.18, 0.0)), ("chest", "spine2", (0.0, 1.32, 0.0)),
          ("neck", "chest", (0.0, 1.50, 0.0)), ("head", "neck", (0.0, 1.60, 0.0)),
          ("head_end", "head", (0.0, 1.78, 0.0))]


def _mirror(rows):
    return [("r_" + n[2:], ("r_" + p[2:]) if p.startswith("l_") else p, (-x, y, z)) for n, p, (x, y, z) in rows]


def humanoid_skeleton() -> Skeleton:
    rows = _SPINE + _LEFT + _mirror(_LEFT)
    names = [r[0] for r in rows]
    parents = [-1 if p is None else names.index(p) for _, p, _ in rows]
    return Skeleton(tuple(names), np.array(parents), np.array([r[2] for r in rows], dtype=np.float64))


FEET = {"left": ("l_ankle", "l_toe", "l_toe_end"), "right": ("r_ankle", "r_toe", "r_toe_end")}
HEEL_BACK = 0.055  # metres: the heel's contact point behind the ankle, on the ground


def sole_clearance(rotations: np.ndarray, root_translation: np.ndarray) -> np.ndarray:
    """The humanoid's lowest sole point per frame (F,): of each heel's contact point, the sole
    under each ball (both rigid with the foot) and each toe's tip. 0 when a foot stands."""
    from synmitsuba.body.skeleton import forward_kinematics
    sk = humanoid_skeleton()
    G, P = forward_kinematics(sk, rotations, root_translation)
    low = []
    for a, toe, tip in FEET.values():
        i, j, k = sk.index(a), sk.index(toe), sk.index(tip)
        rest = sk.rest_positions
        heel = P[:, i] + G[:, i] @ np.array([0.0, -rest[i, 1], -HEEL_BACK])
        ball = P[:, j] + G[:, i] @ np.array([0.0, -rest[j, 1], 0.0])
        low.append(np.minimum(np.minimum(heel[:, 1], ball[:, 1]), P[:, k, 1]))
    return np.minimum(*low)
