"""Camera rays built inside drjit, shared by every cast that must agree pixel for pixel: the
exact passes, coverage and the labels' casts (a ray rebuilt in float64 elsewhere can land on
the other side of a grazing edge)."""
from __future__ import annotations

import math

import numpy as np

from synmitsuba.scene.camera import Camera


def strata(n: int) -> tuple[int, int]:
    """(rows, columns) of sub-pixel strata for ``n`` rays: rows x columns == n exactly, as
    square as n allows (a prime n gives 1 x n strips), so the strata tile the whole pixel and
    a jittered ray in each gives an unbiased coverage estimate for any n."""
    rows = max(d for d in range(1, int(math.isqrt(n)) + 1) if n % d == 0)
    return rows, n // rows


def camera_rays(camera: Camera, per_pixel: int = 1, seed: int | None = None, pixels: np.ndarray | None = None):
    """World rays built inside drjit: ``per_pixel`` rays per pixel, through the pixel centre
    (``seed`` None) or one jittered ray in each of ``strata(per_pixel)`` strata (seeded PCG32),
    for every pixel or for the flat indices ``pixels``. A pixel's rays do not depend on which
    other pixels are cast. Returns (ray, unit directions)."""
    import drjit as dr
    import mitsuba as mi
    H, W = camera.height, camera.width
    n = H * W if pixels is None else len(pixels)
    idx = dr.arange(mi.UInt32, n * per_pixel)
    pixel, k = idx // per_pixel, idx % per_pixel
    if pixels is not None:
        pixel = dr.gather(mi.UInt32, mi.UInt32(np.asarray(pixels, np.uint32)), pixel)
    x, y = mi.Float(pixel % W), mi.Float(pixel // W)
    if seed is None:
        ox = oy = mi.Float(0.5)
    else:
        rows, cols = strata(per_pixel)
        # the seed is opaque: a new seed (every frame of a sequence) reuses the compiled kernel.
        # PCG32 adds each lane's index to both inputs; taking it off again makes a ray's stream
        # depend on its pixel and stratum alone, whichever pixels are cast
        ray_id, lane = mi.UInt64(pixel * per_pixel + k), dr.arange(mi.UInt64, n * per_pixel)
        rng = mi.PCG32(size=n * per_pixel, initstate=2 * ray_id - lane,  # type: ignore[operator]
                       initseq=dr.opaque(mi.UInt64, seed) + ray_id - lane)
        ox = (mi.Float(k % cols) + rng.next_float32()) / cols
        oy = (mi.Float(k // cols) + rng.next_float32()) / rows
    o = mi.Point3f(*[float(c) for c in camera.center])
    dr.make_opaque(o)
    d = pixel_directions(camera, x + ox, y + oy)
    return mi.Ray3f(o, d), d


def pixel_directions(camera: Camera, u, v):
    """Unit world directions (drjit) of the rays through pixel coordinates ``u``, ``v``: the
    pinhole's ``R^T K^-1 [u, v, 1]``, or through the camera's lens distortion. The camera's
    numbers are opaque values, not literals: another camera reuses the compiled kernels."""
    import drjit as dr
    import mitsuba as mi
    if not camera.distorted:
        M = mi.Matrix3f(camera.ray_matrix.tolist())
        dr.make_opaque(M)
        return dr.normalize(M @ mi.Vector3f(u, v, 1.0))
    from synmitsuba.scene.lens import LENS_MODELS, drjit_ops
    Kinv, Rt = mi.Matrix3f(np.linalg.inv(camera.K).tolist()), mi.Matrix3f(camera.R.T.tolist())
    k = [mi.Float(float(c)) for c in np.asarray(camera.dist)]
    dr.make_opaque(Kinv, Rt, *k)
    n = Kinv @ mi.Vector3f(u, v, 1.0)
    dx, dy, dz = LENS_MODELS[camera.lens].direction(n.x, n.y, k, drjit_ops())
    return dr.normalize(Rt @ mi.Vector3f(dx, dy, dz))


def pixel_centre_rays(camera: Camera) -> np.ndarray:
    """(H * W, 3) float32: the unit directions of ``camera_rays(camera)``, bit for bit, for casts
    run from numpy (``engine.raycast``) that must meet what the exact passes met."""
    from synmitsuba.engine.variant import require_variant
    require_variant()
    _, d = camera_rays(camera)
    return np.stack([np.asarray(c.numpy(), np.float32) for c in (d.x, d.y, d.z)], 1)
