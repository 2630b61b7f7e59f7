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
    rot[roots] = camera.R @ rot[roots]
    rest = skeleton.rest_positions[0]
    transl = camera.R @ (rest + np.asarray(root_translation, np.float64)) + camera.t - rest
    return rot, transl
