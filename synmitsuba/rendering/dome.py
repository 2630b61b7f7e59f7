"""The background of a ground-projected panorama: pixels that see past every shape show the
panorama where their ray meets the ``Dome`` (as seen from the dome's centre, where the photo was
shot), instead of at infinity. The path tracer lights the scene from the panorama at infinity;
only what the camera sees directly moves onto the dome."""
from __future__ import annotations

import numpy as np

from synmitsuba.scene.panorama import dome_directions, lookup

TAPS = 4   # sub-frame cameras at most that the dome is averaged over under motion blur


def _cameras(cameras: list) -> list:
    """The cameras to average the dome over: one when the view did not move over the exposure,
    else ``TAPS`` spread over its sub-frames (a blur of a few pixels needs no more). Pixel
    centres only: a panorama seen at 1280 x 720 is magnified (7.5 pixels a texel at 60 degrees),
    so nothing aliases."""
    c0 = cameras[0]
    if all(np.array_equal(c.R, c0.R) and np.array_equal(c.t, c0.t) and np.array_equal(c.K, c0.K) for c in cameras):
        return [c0]
    pick = np.unique(np.linspace(0, len(cameras) - 1, min(TAPS, len(cameras))).round().astype(int))
    return [cameras[k] for k in pick]


def _dome_radiance(environment, cameras: list, whole: np.ndarray, edge: np.ndarray) -> tuple:
    """Averaged over ``cameras``: the panorama where the pixel-centre rays of the ``whole``
    pixels meet the dome, and for the ``edge`` pixels that minus the panorama along the ray."""
    pixels, rot, dome = environment.pixels(), environment.rotation_deg, environment.dome
    seen, swap = np.zeros((int(whole.sum()), 3)), np.zeros((int(edge.sum()), 3))
    for cam in cameras:
        rays = cam.pixel_rays()
        w, e = rays[whole], rays[edge]
        seen = seen + lookup(pixels, dome_directions(cam.center, w, dome), rot)
        swap = swap + lookup(pixels, dome_directions(cam.center, e, dome), rot) - lookup(pixels, e, rot)
    return seen / len(cameras), swap / len(cameras)


def on_dome(rgb: np.ndarray, environment, camera, alpha: np.ndarray, cameras: list | None = None) -> np.ndarray:
    """``rgb`` with each pixel's background share (1 - alpha) seen on the environment's dome.
    Pixels that see only background are the dome's panorama outright (averaged over ``cameras``,
    the exposure's sub-frame cameras under motion blur, so it blurs as the traced image does);
    at a shape's edge the panorama along the ray is swapped for the dome's by difference.
    Replacing outright matters: the traced background and an exact lookup differ at the
    panorama's edges, and a difference left there drew each edge twice. Unchanged without a
    dome."""
    dome = getattr(environment, "dome", None)
    if dome is None:
        return rgb
    background = np.clip(1.0 - np.asarray(alpha, np.float64), 0.0, 1.0)
    if not background.any():
        return rgb
    cameras = _cameras([camera] if not cameras else list(cameras))
    out = np.array(rgb, dtype=np.float32, copy=True)
    whole, edge = background >= 1.0, (background > 0) & (background < 1.0)
    seen, swap = _dome_radiance(environment, cameras, whole, edge)
    out[whole] = environment.scale * seen
    out[edge] += (environment.scale * background[edge][:, None] * swap).astype(np.float32)
    return np.clip(out, 0.0, None)
