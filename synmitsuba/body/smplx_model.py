"""Optional SMPL-X body from model files the user supplies (MPI licence: never shipped).

Point ``SMPLX_MODEL_PATH`` (or ``path=``) at a folder holding ``SMPLX_NEUTRAL.npz`` (or
``SMPLX_MALE.npz`` / ``SMPLX_FEMALE.npz``), or at one such file. Shape blend shapes and joint
regression are applied with numpy; posing uses our skinning like every other body.
"""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.body.anny_model import BodyMesh
from synmitsuba.body.skeleton import Skeleton
from synmitsuba.errors import ConfigError

_BODY = ("pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
         "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
         "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
         "jaw", "left_eye_smplhf", "right_eye_smplhf")
FINGERS = tuple(f"{f}{k}" for f in ("index", "middle", "pinky", "ring", "thumb") for k in (1, 2, 3))
# SMPL-X joint order (body, then left and right hand); AMASS motions use it too
SMPLX_JOINT_NAMES = _BODY + tuple(f"left_{f}" for f in FINGERS) + tuple(f"right_{f}" for f in FINGERS)
REQUIRED = ("v_template", "f", "shapedirs", "J_regressor", "weights", "kintree_table")


def find_model(path: str | None = None, gender: str = "neutral") -> str:
    path = path or os.environ.get("SMPLX_MODEL_PATH")
    name = f"SMPLX_{gender.upper()}.npz"
    if not path:
        raise ConfigError("SMPLX_MODEL_PATH", None, "SMPL-X files are not shipped (MPI licence): download them from "
                          f"smpl-x.is.tue.mpg.de and set SMPLX_MODEL_PATH to the folder holding {name}")
    candidate = os.path.join(path, name) if os.path.isdir(path) else path
    if not os.path.isfile(candidate):
        raise ConfigError("SMPLX_MODEL_PATH", path, f"no {name} there; put the SMPL-X .npz files in that folder")
    return candidate


def smplx_body(betas=None, path: str | None = None, gender: str = "neutral") -> BodyMesh:
    """The SMPL-X body shaped by ``betas``, y up (SMPL-X's own frame), soles on y = 0."""
    data = np.load(find_model(path, gender), allow_pickle=True)
    missing = [k for k in REQUIRED if k not in data]
    if missing:
        raise ConfigError("smplx model", path, f"the file lacks {', '.join(missing)}")
    v = np.asarray(data["v_template"], dtype=np.float64)
    dirs = np.asarray(data["shapedirs"], dtype=np.float64)
    b = np.zeros(dirs.shape[2]) if betas is None else np.asarray(betas, dtype=np.float64)
    n = min(len(b), dirs.shape[2])
    v = v + dirs[:, :, :n] @ b[:n]
    J = np.asarray(data["J_regressor"], dtype=np.float64) @ v
    parents = np.asarray(data["kintree_table"])[0].astype(np.int64)
    parents[0] = -1
    lift = -v[:, 1].min()
    v[:, 1] += lift
    J[:, 1] += lift
    names = SMPLX_JOINT_NAMES[:len(J)] if len(J) <= len(SMPLX_JOINT_NAMES) else tuple(f"joint{i}" for i in range(len(J)))
    F = np.asarray(data["f"], dtype=np.int64)
    return BodyMesh(v, F, np.asarray(data["weights"], dtype=np.float32), Skeleton(names, parents, J),
                    np.zeros((1, 2)), np.zeros_like(F), np.zeros((0, len(v))), ())
