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
    passes["alpha"] = coverage(built, camera, coverage_samples, seed)
    t3 = time.perf_counter()
    meta = {"spp": spp, "seed": seed, "max_depth": max_depth, "coverage_samples": coverage_samples,
            "variant": variant, "rfilter": rfilter,
            "seconds": {"build": t1 - t0, "rgb": t2 - t1, "exact": t3 - t2}}
    return Sample(rgb=rgb, camera=camera, meta=meta, **passes)


def _rays(camera: Camera, directions: np.ndarray):
    import mitsuba as mi
    d = directions.reshape(-1, 3).astype(np.float32)
    o = np.broadcast_to(camera.center.astype(np.float32), d.shape)
    return mi.Ray3f(mi.Point3f(np.ascontiguousarray(o.T)), mi.Vector3f(np.ascontiguousarray(d.T)))


def exact_passes(built, camera: Camera) -> dict:
    """Depth, mask, normal, position, uv, instance and layer from pixel-centre rays."""
    import drjit as dr
    import mitsuba as mi
    H, W = camera.height, camera.width
    dirs = camera.pixel_rays()
    si = built.mi_scene.ray_intersect(_rays(camera, dirs))
    hit = np.array(si.is_valid(), dtype=bool)
    t = np.array(si.t, dtype=np.float64)
    p = np.array(si.p, dtype=np.float64).T
    n = np.array(si.sh_frame.n, dtype=np.float64).T
    uv = np.array(si.uv, dtype=np.float64).T
    reg = np.array(dr.reinterpret_array(mi.UInt32, si.shape), dtype=np.uint32)
    d = dirs.reshape(-1, 3)
    depth = np.where(hit, t * (d @ camera.R[2]), 0.0)
    n = np.where((np.einsum("ij,ij->i", n, d) > 0)[:, None], -n, n)  # face the camera
    n_cam = n @ camera.R.T
    n_cam /= np.maximum(np.linalg.norm(n_cam, axis=1, keepdims=True), 1e-12)
    instance, layer = _lookup_ids(built, reg, hit)
    uv = np.stack([uv[:, 0], 1.0 - uv[:, 1]], 1)  # back to v up
    zero = ~hit[:, None]
    return {"depth": depth.reshape(H, W).astype(np.float32),
            "mask": hit.reshape(H, W),
            "normal": np.where(zero, 0.0, n_cam).reshape(H, W, 3).astype(np.float32),
            "position": np.where(zero, 0.0, p).reshape(H, W, 3).astype(np.float32),
            "uv": np.where(zero, 0.0, uv).reshape(H, W, 2).astype(np.float32),
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


def coverage(built, camera: Camera, samples: int, seed: int) -> np.ndarray:
    """Fraction of each pixel covered by geometry, from stratified jittered sub-pixel rays."""
    H, W = camera.height, camera.width
    rng = np.random.default_rng([seed, 0x5A1F])
    side = int(math.ceil(math.sqrt(samples)))
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:samples]
    hits = np.zeros(H * W, np.float32)
    for cell in cells:
        offsets = (cell + rng.random((H, W, 2))) / side
        pi = built.mi_scene.ray_intersect_preliminary(_rays(camera, camera.pixel_rays(offsets)))
        hits += np.array(pi.is_valid(), dtype=np.float32)
    return (hits / len(cells)).reshape(H, W)
