"""The background of a ground-projected panorama: pixels that see past every shape show the
panorama where their ray meets the ``Dome`` (as seen from the dome's centre, where the photo was
shot), instead of at infinity. The path tracer lights the scene from the panorama at infinity;
only what the camera sees directly moves onto the dome."""
from __future__ import annotations

import numpy as np

from synmitsuba.scene.panorama import dome_directions, lookup


def on_dome(rgb: np.ndarray, environment, camera, alpha: np.ndarray) -> np.ndarray:
    """``rgb`` with each pixel's background share (1 - alpha) seen on the environment's dome:
    the panorama along its pixel-centre ray is swapped for the panorama where that ray meets
    the dome. Unchanged without a dome."""
    dome = getattr(environment, "dome", None)
    if dome is None:
        return rgb
    background = np.clip(1.0 - np.asarray(alpha, np.float64), 0.0, 1.0)
    if not background.any():
        return rgb
    pixels = environment.pixels()
    rays = camera.pixel_rays()
    seen = background > 0
    far = lookup(pixels, rays[seen], environment.rotation_deg)
    near = lookup(pixels, dome_directions(camera.center, rays[seen], dome), environment.rotation_deg)
    out = np.array(rgb, dtype=np.float32, copy=True)
    out[seen] += (environment.scale * background[seen][:, None] * (near - far)).astype(np.float32)
    return np.clip(out, 0.0, None)
