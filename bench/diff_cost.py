"""Differentiable rendering cost (issue 10), printed as JSON: seconds per fit_texture step
(one view: a prb primal and adjoint pass through the drjit texture) and the process's peak
memory, at 128 x 128 and 16 spp, for a subject whose t-shirt's base and stripe colours, scale
and phase are fitted; beside it a plain (non-differentiable) mi.render of the same loaded
scene and spp with the path tracer, as the ratio.

    python bench/diff_cost.py [--size 128] [--spp 16] [--steps 5] [--subjects FILE]
"""
from __future__ import annotations

import argparse
import json
import resource
import time

import numpy as np
from subject_cache import cached


def build_subject():
    """A subject in a striped t-shirt and trousers, and its recipe."""
    import synmitsuba as sm
    recipe = sm.sample_subject(np.random.default_rng(7), {"outfit": ["tshirt", "trousers"], "jacket": False,
                                                          "texture_size": 256})
    shirt = next(g for g in recipe.garments if g.kind == "tshirt")
    shirt.texture.pattern, shirt.texture.bump = "stripes", "none"
    return recipe, sm.build_subject(recipe)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--subjects", help="file of the built subject: read if present, else written (subject_cache.py)")
    args = ap.parse_args(argv)
    import mitsuba as mi
    import synmitsuba as sm
    from synmitsuba.engine.variant import require_variant
    from synmitsuba.rendering import sensor as sensor_mod
    sm.set_variant()
    recipe, human = cached(args.subjects, build_subject)
    shirt = next(g for g in recipe.garments if g.kind == "tshirt")
    scene = sm.Scene()
    scene.set_environment(sm.Constant(1.0))
    human.add_to(scene, instance=1)
    ds = sm.DiffScene(scene)
    ds.bind_procedural("subject1_tshirt", shirt.texture)
    cam = sm.Camera.look_at(eye=(0, 1.3, 2.6), target=(0, 1.1, 0), fov_y_deg=30, width=args.size, height=args.size)
    target = np.array(ds.render(cam, spp=args.spp, seed=1))
    names = [f"subject1_tshirt.{k}" for k in ("base_rgb", "pattern_rgb", "pattern_scale", "phase")]
    sm.fit_texture(ds, [cam], [target], names, steps=1, spp=args.spp)  # compiles the kernels
    fit = sm.fit_texture(ds, [cam], [target], names, steps=args.steps, spp=args.spp)
    sensor_mod.register(require_variant())
    sensor = mi.load_dict(sensor_mod.sensor_dict(cam, args.spp))
    path = mi.load_dict({"type": "path", "max_depth": 4})
    mi.render(ds.built.mi_scene, sensor=sensor, integrator=path, spp=args.spp, seed=0)
    t = time.perf_counter()
    for i in range(args.steps):
        np.array(mi.render(ds.built.mi_scene, sensor=sensor, integrator=path, spp=args.spp, seed=i + 1))
    raw = (time.perf_counter() - t) / args.steps
    print(json.dumps({"variant": require_variant(), "size": args.size, "spp": args.spp, "steps": args.steps,
                      "fitted": names, "seconds_per_step": round(fit.seconds_per_step, 3),
                      "raw_path_render_seconds": round(raw, 3),
                      "step_over_raw_render": round(fit.seconds_per_step / raw, 2),
                      "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
