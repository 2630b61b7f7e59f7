"""``render``: the path-traced RGB pass plus exact geometry passes from pixel-centre rays.

Mitsuba's ``aov`` integrator averages ids over pixel samples and reports ray distance, so the
geometry passes are computed here from one primary ray through each pixel centre
(``scene.ray_intersect``); alpha is the fraction of ``coverage_samples`` stratified sub-pixel
rays that hit geometry (``ray_intersect_preliminary``, about half the cost).
"""
from __future__ import annotations

import functools
import time
import warnings
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from synmitsuba.errors import ConfigError, SynMitsubaWarning
from synmitsuba.rendering import sensor as sensor_mod
from synmitsuba.engine.build import build
from synmitsuba.engine.rays import camera_rays
from synmitsuba.engine.settings import DENOISERS, OIDN_QUALITY
from synmitsuba.engine.settings import choose_sampler
from synmitsuba.rendering.denoise import guide_samples, guides, oidn
from synmitsuba.rendering.dome import on_dome
from synmitsuba.engine.variant import require_variant
from synmitsuba.sample import PASSES, Sample
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.layers import Layer
from synmitsuba.scene.materials import EnvMap
from synmitsuba.scene.scene import Scene
from synmitsuba.schema import POSITIVE, Choice, Number

_integrators: dict = {}


def _integrator(max_depth: int):
    import mitsuba as mi
    key = (require_variant(), max_depth)
    if key not in _integrators:
        _integrators[key] = mi.load_dict({"type": "path", "max_depth": max_depth})
    return _integrators[key]


def _lighting(scene: Scene) -> str:
    """The kind of lighting that picks ``auto``'s sampler (``engine.settings.AUTO_SAMPLERS``)."""
    return "envmap" if isinstance(scene.environment, EnvMap) else "sky"


def render_rgb(scene: Scene, camera: Camera, spp: int = 16, seed: int = 0, max_depth: int = 6, rfilter: str = "box",
               sampler: str = "auto", guide_spp: int = 0) -> tuple[np.ndarray, tuple | None]:
    """The path-traced RGB alone (H, W, 3 float32 linear), what ``render`` traces, for callers
    that combine several (motion blur's sub-frames); with ``guide_spp``, also the denoising
    guides (albedo, normal) at that many samples per pixel, else None."""
    sensor_mod.register(require_variant())
    built = build(scene)
    sensor_dict = sensor_mod.sensor_dict(camera, spp, rfilter, choose_sampler(sampler, spp, _lighting(scene)))
    rgb = _trace(built, sensor_dict, spp, seed, max_depth)
    return rgb, (guides(built.mi_scene, sensor_dict, seed, guide_spp) if guide_spp else None)


def _trace(built, sensor_dict: dict, spp: int, seed: int, max_depth: int) -> np.ndarray:
    """The path tracer's linear RGB (H, W, 3 float32) through the sensor ``sensor_dict``."""
    import mitsuba as mi
    return np.array(mi.render(built.mi_scene, sensor=mi.load_dict(sensor_dict), integrator=_integrator(max_depth),
                              spp=spp, seed=seed), dtype=np.float32)[..., :3]


def render(scene: Scene, camera: Camera, spp: int = 16, seed: int = 0, max_depth: int = 6,
           coverage_samples: int = 9, rfilter: str = "box", sampler: str = "auto", denoise: str = "none",
           rgb: np.ndarray | None = None, denoise_guides: tuple | None = None,
           dome_cameras: list | None = None) -> Sample:
    """Render one view of ``scene``: RGB (path tracer, ``spp`` samples per pixel, ``max_depth``
    bounces) and exact depth/normal/position/uv/instance/layer passes. Deterministic in ``seed``.
    ``sampler``: ``auto`` (the best that keeps spp exactly, see ``render.denoise``) or a Mitsuba
    sampler; ``denoise="oidn"`` (or ``oidn-balanced``, ``oidn-fast``: OIDN's cheaper qualities)
    denoises ``rgb`` and keeps the raw one as ``rgb_noisy``.
    ``coverage_samples`` (alpha, per-instance coverage): 9 by measurement on the demo's edge
    pixels against 256 rays, RMS error 0.43 / 0.14 / 0.069 / 0.059 for 1 / 4 / 9 / 16 rays.
    ``rgb``: an RGB traced already (``render_rgb``; motion blur's sub-frame average) to use
    instead of tracing one; the exact passes are this scene's and camera's. ``denoise_guides``:
    the (albedo, normal) that image was traced with (motion blur's: averaged over its sub-frames,
    so the denoiser does not sharpen what moved), instead of this scene's. ``dome_cameras``: the
    cameras that image was traced with (motion blur's sub-frames), over which an HDRI dome seen
    behind everything is averaged (``rendering.dome``)."""
    spp, max_depth, coverage_samples = (POSITIVE(n, v) for n, v in
                                        (("spp", spp), ("max_depth", max_depth), ("coverage_samples", coverage_samples)))
    seed = Number(0, 2 ** 32 - 1, integer=True)("seed", seed)
    Choice(DENOISERS)("denoise", denoise)
    if not isinstance(camera, Camera):
        raise ConfigError("camera", type(camera).__name__, "give a synmitsuba.Camera")
    if scene.environment is None and not scene.lights:
        warnings.warn(SynMitsubaWarning("the scene has no environment and no light: the RGB is black; add one "
                                        "with scene.set_environment(sm.SunSky()) or scene.add_light(...)"),
                      stacklevel=2)
    variant = require_variant()
    sensor_mod.register(variant)
    t0 = time.perf_counter()
    built = build(scene)
    t1 = time.perf_counter()
    chosen = choose_sampler(sampler, spp, _lighting(scene))
    sensor_dict = sensor_mod.sensor_dict(camera, spp, rfilter, chosen)
    if rgb is None:
        rgb = _trace(built, sensor_dict, spp, seed, max_depth)
    elif np.shape(rgb) != (camera.height, camera.width, 3):
        raise ConfigError("rgb", f"array{np.shape(rgb)}", f"give ({camera.height}, {camera.width}, 3): the camera's image")
    extra = {}
    t_rgb = time.perf_counter()
    passes = exact_passes(built, camera)
    passes["alpha"], passes["coverage"] = coverage(built, camera, coverage_samples, seed, exact=passes)
    rgb = on_dome(rgb, scene.environment, camera, passes["alpha"], dome_cameras)
    t2 = time.perf_counter()
    if denoise != "none":
        albedo, normal = (guides(built.mi_scene, sensor_dict, seed, guide_samples(spp)) if denoise_guides is None
                          else denoise_guides)
        extra["rgb_noisy"], rgb = rgb, oidn(rgb, albedo, normal, quality=OIDN_QUALITY[denoise])
    t3 = time.perf_counter()
    meta = {"spp": spp, "seed": seed, "max_depth": max_depth, "coverage_samples": coverage_samples,
            "variant": variant, "rfilter": rfilter, "sampler": chosen, "denoise": denoise}
    timings = {"build": t1 - t0, "rgb": t_rgb - t1, "exact": t2 - t_rgb, "denoise": t3 - t2}
    cov = passes.pop("coverage")
    if not passes["mask"].any():
        warnings.warn(SynMitsubaWarning("the camera sees no geometry: every pixel is background; check the "
                                        "camera's position, target and field of view"), stacklevel=2)
    return Sample(camera=camera, passes={"rgb": rgb, **extra, **passes}, coverage=cov, meta=meta, timings=timings)


@dataclass
class Hit:
    """What the pixel-centre rays found: the surface interaction, the hit flag, the unit ray
    directions and each hit's shape registry id; the inputs of every exact pass."""

    si: Any  # Mitsuba / drjit arrays
    hit: Any
    d: Any
    reg: Any
    camera: Camera
    built: Any

    @functools.cached_property
    def has_uv(self):
        """Whether each hit shape has texture coordinates (shared by the uv and uv_valid passes)."""
        return self.built.lookup("has_uv", self.reg, self.hit) > 0


# pass name -> function(Hit) -> drjit array (one value or vector per pixel)
EXACT_PASSES: dict[str, Callable] = {}


def exact_pass(name: str):
    """Register the computation of an exact pass (declared in ``synmitsuba.sample.PASSES``)."""
    def deco(fn):
        if name not in PASSES:
            raise ValueError(f"declare pass {name!r} with synmitsuba.sample.register_pass first")
        EXACT_PASSES[name] = fn
        return fn
    return deco


@exact_pass("depth")
def _depth(h: Hit):
    import drjit as dr
    import mitsuba as mi
    axis = mi.Vector3f(*h.camera.R[2].tolist())
    dr.make_opaque(axis)
    return dr.select(h.hit, h.si.t * dr.dot(h.d, axis), 0.0)


@exact_pass("mask")
def _mask(h: Hit):
    return h.hit


@exact_pass("normal")
def _normal(h: Hit):
    import drjit as dr
    import mitsuba as mi
    n = dr.select(dr.dot(h.si.sh_frame.n, h.d) > 0, -h.si.sh_frame.n, h.si.sh_frame.n)  # face the camera
    R = mi.Matrix3f(h.camera.R.tolist())
    dr.make_opaque(R)
    return dr.select(h.hit, dr.normalize(R @ n), 0.0)


@exact_pass("position")
def _position(h: Hit):
    """The eye + t * the ray, as depth is: Mitsuba's ``si.p`` interpolates the triangle's corners
    with float32 barycentrics, millimetres off on a triangle kilometres across."""
    import drjit as dr
    import mitsuba as mi
    eye = mi.Point3f(*h.camera.center.tolist())
    dr.make_opaque(eye)
    return dr.select(h.hit, eye + h.si.t * h.d, 0.0)


@exact_pass("uv_valid")
def _uv_valid(h: Hit):
    return h.has_uv


@exact_pass("uv")
def _uv(h: Hit):
    import drjit as dr
    import mitsuba as mi
    # Mitsuba reports barycentric-like coordinates on shapes without uv: those become 0
    return dr.select(h.has_uv, mi.Point2f(h.si.uv.x, 1.0 - h.si.uv.y), 0.0)  # back to v up


@exact_pass("instance")
def _instance(h: Hit):
    return h.built.lookup("instance", h.reg, h.hit)


@exact_pass("layer")
def _layer(h: Hit):
    return h.built.lookup("layer", h.reg, h.hit)


def _to_numpy(value, spec, H: int, W: int) -> np.ndarray:
    arr = np.array(value)
    arr = arr.T if spec.components > 1 else arr
    return arr.reshape((H, W, spec.components) if spec.components > 1 else (H, W)).astype(spec.dtype)


def exact_passes(built, camera: Camera) -> dict:
    """Every registered exact pass from one ray through each pixel centre."""
    import drjit as dr
    import mitsuba as mi
    ray, d = camera_rays(camera)
    si = built.mi_scene.ray_intersect(ray)
    hit = si.is_valid()
    h = Hit(si, hit, d, dr.select(hit, dr.reinterpret_array(mi.UInt32, si.shape), 0), camera, built)
    values = {name: fn(h) for name, fn in EXACT_PASSES.items()}
    dr.eval(*values.values())
    return {name: _to_numpy(v, PASSES[name], camera.height, camera.width) for name, v in values.items()}


def edge_pixels(instance: np.ndarray, mask: np.ndarray, thin: np.ndarray) -> np.ndarray:
    """Flat indices of the pixels whose coverage can be fractional: their 3 x 3 neighbourhood of
    pixel centres sees more than one (instance, hit) pair, or thin geometry (``thin``: hair).
    A straight edge that crosses a pixel always puts one of its four neighbours' centres on the
    other side, so elsewhere the centre ray's answer (0 or 1) is the coverage; only slivers
    thinner than a pixel that no centre hits are missed."""
    key = instance.astype(np.int64) * 2 + mask
    H, W = key.shape
    padded, thin = np.pad(key, 1, mode="edge"), np.pad(thin, 1)
    edge = np.zeros((H, W), bool)
    for dy in range(3):
        for dx in range(3):
            edge |= (padded[dy:dy + H, dx:dx + W] != key) | thin[dy:dy + H, dx:dx + W]
    return np.flatnonzero(edge).astype(np.uint32)


def coverage(built, camera: Camera, samples: int, seed: int, exact: dict | None = None) -> tuple[np.ndarray, dict]:
    """Soft coverage from stratified jittered sub-pixel rays: the fraction of each pixel covered
    by any geometry (alpha), and per instance id > 0 ({id: (H, W) fraction}); reduced in drjit.
    With ``exact`` (this view's exact passes) rays are cast only at ``edge_pixels``: the same
    values there, the centre ray's 0 or 1 elsewhere (a tenth of the rays on a full-body view)."""
    import drjit as dr
    import mitsuba as mi
    H, W = camera.height, camera.width
    ids = built.instance_ids
    if exact is None:
        pixels, alpha, full = None, np.zeros(H * W, np.float32), {i: np.zeros(H * W, np.float32) for i in ids}
    else:
        pixels = edge_pixels(exact["instance"], exact["mask"], exact["layer"] == int(Layer.HAIR))
        alpha = exact["mask"].astype(np.float32).ravel()
        full = {i: (exact["instance"] == i).astype(np.float32).ravel() for i in ids}
    at = slice(None) if pixels is None else pixels
    if pixels is None or len(pixels):
        ray, _ = camera_rays(camera, samples, seed=seed, pixels=pixels)
        pi = built.mi_scene.ray_intersect_preliminary(ray)
        valid = pi.is_valid()
        one = mi.Float(1.0)
        count = dr.block_sum(dr.select(valid, one, 0.0), samples)  # exact integers
        sums = []
        if ids:
            inst = built.lookup("instance", dr.select(valid, dr.reinterpret_array(mi.UInt32, pi.shape), 0), valid)
            sums = [dr.block_sum(dr.select(inst == i, one, 0.0), samples) for i in ids]
        dr.eval(count, *sums)
        alpha[at] = np.array(count, dtype=np.float32) / samples
        for i, s in zip(ids, sums):
            full[i][at] = np.array(s, dtype=np.float32) / samples
    per_instance = {i: frac.reshape(H, W) for i, frac in full.items() if frac.any()}
    return alpha.reshape(H, W), per_instance
