"""``render``: the path-traced RGB pass plus exact geometry passes from pixel-centre rays.

Mitsuba's ``aov`` integrator averages ids over pixel samples and reports ray distance, so the
geometry passes are computed here from one primary ray through each pixel centre
(``scene.ray_intersect``); alpha is the fraction of ``coverage_samples`` stratified sub-pixel
rays that hit geometry (``ray_intersect_preliminary``, about half the cost).
"""
from __future__ import annotations

import math
import time

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.render import sensor as sensor_mod
from synmitsuba.render.build import build
from synmitsuba.render.sample import Sample
from synmitsuba.render.variant import current_variant
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.scene import Scene

_integrators: dict = {}


def _check_int(field: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ConfigError(field, value, f"give an integer >= {low}")
    return int(value)


def _integrator(max_depth: int):
    import mitsuba as mi
    key = (current_variant(), max_depth)
    if key not in _integrators:
        _integrators[key] = mi.load_dict({"type": "path", "max_depth": max_depth})
    return _integrators[key]


def render(scene: Scene, camera: Camera, spp: int = 16, seed: int = 0, max_depth: int = 6,
           coverage_samples: int = 16, rfilter: str = "box") -> Sample:
    """Render one view of ``scene``: RGB (path tracer, ``spp`` samples per pixel, ``max_depth``
    bounces) and exact depth/normal/position/uv/instance/layer passes. Deterministic in ``seed``."""
    import mitsuba as mi
    spp = _check_int("spp", spp, 1)
    seed = _check_int("seed", seed, 0)
    max_depth = _check_int("max_depth", max_depth, 1)
    coverage_samples = _check_int("coverage_samples", coverage_samples, 1)
    if not isinstance(camera, Camera):
        raise ConfigError("camera", type(camera).__name__, "give a synmitsuba.Camera")
    variant = current_variant()
    sensor_mod.register(variant)
    t0 = time.perf_counter()
    built = build(scene)
    t1 = time.perf_counter()
    sensor = mi.load_dict(sensor_mod.sensor_dict(camera, spp, rfilter))
    rgb = np.array(mi.render(built.mi_scene, sensor=sensor, integrator=_integrator(max_depth),
                             spp=spp, seed=seed), dtype=np.float32)[..., :3]
    t2 = time.perf_counter()
    passes = exact_passes(built, camera)
    passes["alpha"], passes["coverage"] = coverage(built, camera, coverage_samples, seed)
    t3 = time.perf_counter()
    meta = {"spp": spp, "seed": seed, "max_depth": max_depth, "coverage_samples": coverage_samples,
            "variant": variant, "rfilter": rfilter,
            "seconds": {"build": t1 - t0, "rgb": t2 - t1, "exact": t3 - t2}}
    return Sample(rgb=rgb, camera=camera, meta=meta, **passes)


def _camera_rays(camera: Camera, per_pixel: int = 1, seed: int | None = None):
    """World rays built inside drjit: ``per_pixel`` rays per pixel, through the pixel centre
    (``seed`` None) or at stratified jittered positions (a side x side grid, seeded PCG32).
    Returns (ray, unit directions)."""
    import drjit as dr
    import mitsuba as mi
    H, W = camera.height, camera.width
    idx = dr.arange(mi.UInt32, H * W * per_pixel)
    pixel, k = idx // per_pixel, idx % per_pixel
    x, y = mi.Float(pixel % W), mi.Float(pixel // W)
    if seed is None:
        ox = oy = mi.Float(0.5)
    else:
        side = math.ceil(math.sqrt(per_pixel))
        rng = mi.PCG32(size=H * W * per_pixel, initstate=mi.UInt64(idx), initseq=mi.UInt64(seed))
        ox = (mi.Float(k % side) + rng.next_float32()) / side
        oy = (mi.Float(k // side) + rng.next_float32()) / side
    M = mi.Matrix3f((camera.R.T @ np.linalg.inv(camera.K)).tolist())
    d = dr.normalize(M @ mi.Vector3f(x + ox, y + oy, 1.0))
    o = mi.Point3f(*[float(c) for c in camera.center])
    return mi.Ray3f(o, d), d


def exact_passes(built, camera: Camera) -> dict:
    """Depth, mask, normal, position, uv, instance and layer from pixel-centre rays."""
    import drjit as dr
    import mitsuba as mi
    H, W = camera.height, camera.width
    ray, d = _camera_rays(camera)
    si = built.mi_scene.ray_intersect(ray)
    hit = si.is_valid()
    axis = mi.Vector3f(*camera.R[2].tolist())
    depth = dr.select(hit, si.t * dr.dot(d, axis), 0.0)
    n = dr.select(dr.dot(si.sh_frame.n, d) > 0, -si.sh_frame.n, si.sh_frame.n)  # face the camera
    Rm = mi.Matrix3f(camera.R.tolist())
    n_cam = dr.select(hit, dr.normalize(Rm @ n), 0.0)
    p = dr.select(hit, si.p, 0.0)
    uv = dr.select(hit, mi.Point2f(si.uv.x, 1.0 - si.uv.y), 0.0)  # back to v up
    reg = dr.reinterpret_array(mi.UInt32, si.shape)
    dr.eval(hit, depth, n_cam, p, uv, reg)
    hit_np = np.array(hit, dtype=bool)
    instance, layer = _lookup_ids(built, np.array(reg, dtype=np.uint32), hit_np)
    return {"depth": np.array(depth, dtype=np.float32).reshape(H, W),
            "mask": hit_np.reshape(H, W),
            "normal": np.array(n_cam, dtype=np.float32).T.reshape(H, W, 3),
            "position": np.array(p, dtype=np.float32).T.reshape(H, W, 3),
            "uv": np.array(uv, dtype=np.float32).T.reshape(H, W, 2),
            "instance": instance.reshape(H, W), "layer": layer.reshape(H, W)}


def _lookup_ids(built, reg: np.ndarray, hit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    instance = np.zeros(len(reg), np.int32)
    layer = np.zeros(len(reg), np.uint8)
    if len(built.registry_ids) and hit.any():
        k = np.clip(np.searchsorted(built.registry_ids, reg[hit]), 0, len(built.registry_ids) - 1)
        known = built.registry_ids[k] == reg[hit]
        instance[hit] = np.where(known, built.instance_of[k], 0)
        layer[hit] = np.where(known, built.layer_of[k], 0)
    return instance, layer


def coverage(built, camera: Camera, samples: int, seed: int) -> tuple[np.ndarray, dict]:
    """Soft coverage from stratified jittered sub-pixel rays: the fraction of each pixel covered
    by any geometry (alpha), and per instance id > 0 ({id: (H, W) fraction})."""
    import drjit as dr
    import mitsuba as mi
    H, W = camera.height, camera.width
    ray, _ = _camera_rays(camera, samples, seed=seed)
    pi = built.mi_scene.ray_intersect_preliminary(ray)
    valid = pi.is_valid()
    count = dr.block_sum(dr.select(valid, mi.Float(1.0), 0.0), samples)  # exact integers
    alpha = (np.array(count, dtype=np.float32) / samples).reshape(H, W)
    per_instance: dict[int, np.ndarray] = {}
    if (built.instance_of > 0).any():
        reg = np.array(dr.select(valid, dr.reinterpret_array(mi.UInt32, pi.shape), 0), dtype=np.uint32)
        inst, _ = _lookup_ids(built, reg, reg != 0)
        pixel = np.arange(H * W * samples, dtype=np.int64) // samples
        for i in np.unique(inst):
            if i > 0:
                hits = np.bincount(pixel[inst == i], minlength=H * W)
                per_instance[int(i)] = (hits.astype(np.float32) / samples).reshape(H, W)
    return alpha, per_instance
