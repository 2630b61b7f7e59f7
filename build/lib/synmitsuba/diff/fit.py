"""Inverse texture fitting: Adam on a ``DiffScene``'s variables against multi-view targets.

A torch loss can sit on the render through ``dr.wrap``::

    @dr.wrap(source="drjit", target="torch")
    def l1(img, ref):                      # torch tensors in, a torch scalar out
        return (img - ref).abs().mean()

    sm.fit_texture(ds, cameras, targets, ["subject1_tshirt.base_rgb"], loss=l1)
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.diff.scene import DiffScene
from synmitsuba.errors import ConfigError
from synmitsuba.schema import POSITIVE, Number


@dataclass
class FitResult:
    """What a fit did: the loss after every step (mean over views), the fitted and the starting
    values as plain numbers, and seconds per step."""

    losses: list = field(default_factory=list)
    values: dict = field(default_factory=dict)
    initial: dict = field(default_factory=dict)
    seconds_per_step: float = 0.0


def mse(img, target):
    import drjit as dr
    return dr.mean(dr.square(img - target), axis=None)


def _targets(cameras, targets) -> list:
    import mitsuba as mi
    if len(cameras) == 0 or len(cameras) != len(targets):
        raise ConfigError("targets", f"{len(targets)} images for {len(cameras)} cameras",
                          "give one target image per camera (and at least one)")
    out = []
    for i, (cam, t) in enumerate(zip(cameras, targets)):
        arr = np.asarray(t, dtype=np.float32)[..., :3]
        if arr.shape != (cam.height, cam.width, 3):
            raise ConfigError(f"targets[{i}]", f"array{arr.shape}",
                              f"give an H x W x 3 linear RGB image of the camera's size ({cam.height} x {cam.width})")
        out.append(mi.TensorXf(arr))
    return out


def _learning_rates(ds: DiffScene, names: list, lr) -> dict:
    if lr is None:
        return {k: ds.specs[k].lr for k in names}
    if isinstance(lr, dict):
        unknown = sorted(set(lr) - set(names))
        if unknown:
            raise ConfigError("lr", unknown[0], f"give learning rates only for fitted variables: {', '.join(names)}")
        return {k: float(lr.get(k, ds.specs[k].lr)) for k in names}
    return {k: float(Number(1e-9, 100)("lr", lr)) for k in names}


def fit_texture(scene: DiffScene, cameras: list, targets: list, params, steps: int = 50, lr=None, spp: int = 16,
                seed: int = 0, loss=None, callback=None) -> FitResult:
    """Fit ``params`` (variable names, or {name: starting value}) of ``scene`` so that its
    renders from ``cameras`` match ``targets`` (linear RGB arrays), with ``mi.ad.Adam``.
    ``lr``: None (each variable's own rate), a number, or {name: rate}; ``loss(img, target)``
    a drjit scalar (default: mean squared error). Values are kept in their ranges after every
    step. ``callback(step, loss, scene)`` is called after each step."""
    import drjit as dr
    import mitsuba as mi
    if not isinstance(scene, DiffScene):
        raise ConfigError("scene", type(scene).__name__, "give a synmitsuba.diff.DiffScene")
    steps, spp = POSITIVE("steps", steps), POSITIVE("spp", spp)
    refs = _targets(cameras, targets)
    names = list(params)
    for k in names:
        scene._spec(k)
        if isinstance(params, dict):
            scene.set(k, params[k])
    rates = _learning_rates(scene, names, lr)
    loss = loss or mse
    opt = mi.ad.Adam(lr=min(rates.values()))
    for k in names:
        opt[k] = scene.variables[k]
    opt.set_learning_rate(rates)
    result = FitResult(initial={k: scene.get(k) for k in names})
    t0 = time.perf_counter()
    for step in range(steps):
        for k in names:
            scene.variables[k] = opt[k]
        total = 0.0
        for i, (cam, ref) in enumerate(zip(cameras, refs)):
            s = seed + step * len(cameras) + i
            value = loss(scene.render(cam, spp=spp, seed=2 * s), ref) / len(cameras)
            dr.backward(value)
            total += float(value.array[0] if hasattr(value, "array") else value)
        opt.step()
        for k in names:
            spec = scene.specs[k]
            opt[k] = dr.clip(opt[k], spec.low, spec.high)
        result.losses.append(total)
        if callback is not None:
            callback(step, total, scene)
    for k in names:
        scene.variables[k] = dr.detach(opt[k])
    result.seconds_per_step = (time.perf_counter() - t0) / steps
    result.values = {k: scene.get(k) for k in names}
    return result
