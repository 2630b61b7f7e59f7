"""AMASS import (SMPL-X npz: root_orient, pose_body, pose_hand, pose_jaw, trans, betas,
mocap_frame_rate).

Without the licensed SMPL-X model the rest skeleton is an approximation of the neutral SMPL-X
joints (average adult, metres, y up, T-pose), documented in ``SMPLX_REST``; rotations and root
translation are exact. AMASS is z-up; it is turned to our y-up frame.
"""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.body.skeleton import Skeleton
from synmitsuba.body.smplx_model import FINGERS as _FINGERS
from synmitsuba.body.smplx_model import SMPLX_JOINT_NAMES as SMPLX_JOINTS
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import axis_angle_to_matrix
from synmitsuba.motion.motion import Motion

_BODY_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 15, 15, 15]


def _parents() -> np.ndarray:
    parents = list(_BODY_PARENTS)
    for wrist in (20, 21):
        for finger in range(5):
            base = len(parents)
            parents += [wrist, base, base + 1]
    return np.array(parents)


# Approximate neutral SMPL-X rest joints (left side; +x is the body's left), T-pose, feet on y=0.
_HALF = {"pelvis": (0, 0.93, 0.0), "left_hip": (0.06, 0.84, 0.0), "spine1": (0, 1.04, -0.01),
         "left_knee": (0.10, 0.47, 0.0), "spine2": (0, 1.17, 0.01), "left_ankle": (0.09, 0.07, -0.04),
         "spine3": (0, 1.23, 0.01), "left_foot": (0.12, 0.02, 0.08), "neck": (0, 1.44, -0.02),
         "left_collar": (0.08, 1.37, 0.0), "head": (0, 1.51, 0.01), "left_shoulder": (0.17, 1.40, -0.01),
         "left_elbow": (0.43, 1.40, -0.03), "left_wrist": (0.68, 1.40, -0.02), "jaw": (0, 1.53, 0.04),
         "left_eye_smplhf": (0.03, 1.6, 0.08)}


def smplx_rest() -> np.ndarray:
    rest = np.zeros((len(SMPLX_JOINTS), 3))
    for i, name in enumerate(SMPLX_JOINTS):
        key = name.replace("right_", "left_")
        if key in _HALF:
            rest[i] = _HALF[key]
        elif "_" in name and name.split("_", 1)[1] in [f for f in _FINGERS]:  # fingers along the hand
            finger = name.split("_", 1)[1]
            k = int(finger[-1])
            spread = {"index": 0.025, "middle": 0.0, "ring": -0.02, "pinky": -0.04, "thumb": 0.04}[finger[:-1]]
            rest[i] = (0.76 + 0.025 * k, 1.40, spread)
        if name.startswith("right_"):
            rest[i, 0] *= -1
    return rest


SMPLX_REST = smplx_rest()
# Where SMPL-X's own model puts the pelvis joint (neutral shape, model coordinates): AMASS
# ``trans`` is relative to it, since SMPL adds the unrotated J0 (world = R (x - J0) + J0 + trans).
SMPLX_PELVIS_MODEL = np.array([0.0031, -0.3514, 0.0120])
Z_UP_TO_Y_UP = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])  # (x, y, z) -> (x, z, -y)


def smplx_skeleton() -> Skeleton:
    return Skeleton(SMPLX_JOINTS, _parents(), SMPLX_REST)


def load_amass(path: str, labels=()) -> Motion:
    """Read an AMASS SMPL-X npz into a Motion on the SMPL-X skeleton (y up, metres)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ConfigError("amass path", path, "no such file")
    try:
        data = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise ConfigError("amass path", path, f"not a readable npz archive ({exc})") from None
    for key in ("root_orient", "pose_body", "trans"):
        if key not in data:
            raise ConfigError(f"amass.{key}", None, f"{path} lacks '{key}'; an AMASS SMPL-X npz has root_orient, "
                              "pose_body, pose_hand, pose_jaw, trans, betas, mocap_frame_rate")
    F = len(data["trans"])
    aa = np.zeros((F, len(SMPLX_JOINTS), 3))
    parts = {"root_orient": (0, 1), "pose_body": (1, 21), "pose_jaw": (22, 1), "pose_eye": (23, 2),
             "pose_hand": (25, 30)}
    for key, (start, count) in parts.items():
        if key in data:
            arr = np.asarray(data[key], dtype=np.float64).reshape(F, -1)
            if arr.shape[1] != 3 * count:
                raise ConfigError(f"amass.{key}", f"array{data[key].shape}", f"expected ({F}, {3 * count})")
            aa[:, start:start + count] = arr.reshape(F, count, 3)
    R = axis_angle_to_matrix(aa)
    R[:, 0] = Z_UP_TO_Y_UP @ R[:, 0]
    trans = np.asarray(data["trans"], dtype=np.float64) @ Z_UP_TO_Y_UP.T
    # SMPL rotates the root about the pelvis joint: pelvis_world = J0 + trans (z-up), then y-up
    root = trans + SMPLX_PELVIS_MODEL @ Z_UP_TO_Y_UP.T - SMPLX_REST[0]
    fps = float(data["mocap_frame_rate"]) if "mocap_frame_rate" in data else 120.0
    return Motion(smplx_skeleton(), R, root, fps, labels=tuple(labels), source=os.path.abspath(path),
                  meta={"betas": np.asarray(data["betas"]).tolist() if "betas" in data else None,
                        "rest_skeleton": "approximate neutral SMPL-X"})
