"""Body parameters in the camera frame (the paper's theta_c): the root's rotation and
translation composed with the camera's world->camera R, t, so that posing the body with them
and the same bone rotations gives the camera-frame vertices ``R v + t``."""
from __future__ import annotations

import numpy as np

from synmitsuba.scene.camera import Camera


def body_params_in_camera(skeleton, rotations, root_translation, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(rotations (J, 3, 3) with every root's composed with R, root_translation (3,)) such that
    ``skin(rest, weights, bone_transforms(skeleton, rot_c, root_c))`` equals ``R v + t``.
    The root joint sits at ``rest + root_translation``; in the camera it must sit at
    ``R (rest + root_translation) + t``."""
    rot = np.array(rotations, dtype=np.float64)
    roots = np.flatnonzero(skeleton.parents < 0)
    rot[roots], transl = root_in_camera(rot[roots], root_translation, skeleton.rest_positions[0], camera)
    return rot, transl


def root_in_camera(root_rotation, translation, pivot, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """A body's root rotation and translation seen from ``camera``, for a model that turns
    about the rest joint ``pivot`` and then moves by ``translation`` (x -> R_root (x - pivot) +
    pivot + translation, as SMPL, SMPL-X and our skeletons do): (R R_root, R (pivot +
    translation) + t - pivot)."""
    pivot = np.asarray(pivot, np.float64)
    return camera.R @ root_rotation, camera.R @ (pivot + np.asarray(translation, np.float64)) + camera.t - pivot
