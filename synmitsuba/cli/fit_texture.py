"""``synmitsuba fit-texture TARGETS --subject RECIPE.json --out DIR``: fit a subject's garment
textures to target images with cameras (samples as ``write_sample`` writes them)."""
from __future__ import annotations

import json
import os

import numpy as np

from synmitsuba.cli.args import output_dir, positive_float, positive_int
from synmitsuba.errors import ConfigError

DEFAULT_PARAMS = "base_rgb,pattern_rgb"


def _recipe(path: str):
    from synmitsuba.body.recipe import SubjectRecipe
    if not os.path.isfile(path):
        raise ConfigError("--subject", path, "give the path of a subject recipe JSON (synmitsuba subject --out ...)")
    with open(path) as fh:
        return SubjectRecipe.from_json(fh.read())


def _make_targets(args, recipe) -> int:
    """Render ``--make-targets`` views of the recipe's subject into TARGETS (for a round trip)."""
    from synmitsuba.diff.recipe import rest_scene
    from synmitsuba.io.exr import write_sample
    from synmitsuba.rendering.passes import render
    output_dir(args.targets, "TARGETS")
    scene = rest_scene(recipe, args.radiance)
    for i, cam in enumerate(_ring(args.make_targets, args.size)):
        sample = render(scene, cam, spp=args.target_spp, seed=100 + i)
        print(write_sample(sample, os.path.join(args.targets, f"view{i:02d}"))["exr"])
    return 0


def _ring(count: int, size: int) -> list:
    from synmitsuba.scene.camera import Camera
    return [Camera.look_at(eye=(2.4 * np.sin(a), 1.3, 2.4 * np.cos(a)), target=(0, 1.2, 0), fov_y_deg=24, width=size,
                           height=size) for a in np.linspace(0, 2 * np.pi, count, endpoint=False)]


def run(args) -> int:
    recipe = _recipe(args.subject)
    if args.make_targets:
        return _make_targets(args, recipe)
    if not args.out:
        raise ConfigError("--out", None, "give an output folder for fit.json, recipe.json and compare.png")
    from synmitsuba.diff.fit import fit_texture
    from synmitsuba.diff.recipe import fitted_recipe, rest_scene
    from synmitsuba.diff.scene import DiffScene
    from synmitsuba.diff.texture import VARIABLES
    from synmitsuba.io.listing import list_samples
    from synmitsuba.io.exr import read_sample
    from synmitsuba.io.preview import to_srgb8, write_png
    stems = list_samples(args.targets) if os.path.isdir(args.targets) else []
    if not stems:
        raise ConfigError("TARGETS", args.targets, "give a folder of samples (EXR + JSON with the camera), e.g. "
                          "written by 'synmitsuba fit-texture TARGETS --subject R.json --make-targets 4'")
    names = [n.strip() for n in args.params.split(",") if n.strip()]
    for n in names:
        if n not in VARIABLES:
            raise ConfigError("--params", n, f"use variables of {', '.join(VARIABLES)}")
    out = output_dir(args.out)
    samples = [read_sample(s) for s in stems]
    ds = DiffScene(rest_scene(recipe, args.radiance))
    garments = [g for g in recipe.garments if args.garment in (None, g.kind)]
    if not garments:
        raise ConfigError("--garment", args.garment, f"use one of the subject's garments: "
                          f"{', '.join(g.kind for g in recipe.garments)}")
    for g in garments:
        ds.bind_procedural(f"subject1_{g.kind}", g.texture)
    fitted = [f"subject1_{g.kind}.{n}" for g in garments for n in names]
    progress = (lambda step, loss, _: print(f"step {step + 1}/{args.steps}: loss {loss:.5f}", flush=True))
    result = fit_texture(ds, [s.camera for s in samples], [s.rgb for s in samples], fitted, steps=args.steps,
                         lr=args.lr, spp=args.spp, callback=None if args.quiet else progress)
    report = {"losses": result.losses, "initial": result.initial, "values": result.values,
              "seconds_per_step": result.seconds_per_step, "targets": [os.path.basename(s) for s in stems]}
    _write(os.path.join(out, "fit.json"), json.dumps(report, indent=1))
    _write(os.path.join(out, "recipe.json"), fitted_recipe(recipe, result.values).to_json())
    from synmitsuba.rendering.passes import render
    fitted_img = render(ds.scene, samples[0].camera, spp=args.target_spp, seed=7).rgb
    write_png(os.path.join(out, "compare.png"), to_srgb8(np.concatenate([samples[0].rgb, fitted_img], 1)))
    print(f"loss {result.losses[0]:.5f} -> {result.losses[-1]:.5f}; wrote fit.json, recipe.json, compare.png in {out}")
    return 0


def _write(path: str, text: str) -> None:
    from synmitsuba.io.files import atomic_path
    with atomic_path(path) as tmp, open(tmp, "w") as fh:  # complete or absent, Ctrl-C included
        fh.write(text)


def add_parser(sub) -> None:
    p = sub.add_parser("fit-texture", help="fit a subject's garment textures to target images (differentiable)",
                       description="Fit the procedural garment textures of a subject (rest pose at the origin, "
                       "constant environment) to target samples with cameras, by gradient descent through "
                       "Mitsuba's prb integrator. Writes fit.json (loss curve, start and fitted values), "
                       "recipe.json (the recipe with the fitted textures) and compare.png (target | fitted).")
    p.add_argument("targets", help="folder of target samples (EXR + JSON with the camera)")
    p.add_argument("--subject", required=True, help="the subject's recipe JSON (the garments' starting textures)")
    p.add_argument("--out", help="output folder (no default: required unless --make-targets)")
    p.add_argument("--make-targets", type=positive_int, metavar="N",
                   help="instead of fitting: render N ring views of --subject into TARGETS, a round trip to try (default: fit)")
    p.add_argument("--garment", help="fit one garment kind only (default: every garment)")
    p.add_argument("--params", default=DEFAULT_PARAMS, help="comma-separated texture variables to fit")
    p.add_argument("--steps", type=positive_int, default=60, help="Adam steps")
    p.add_argument("--spp", type=positive_int, default=8, help="samples per pixel while fitting")
    p.add_argument("--lr", type=positive_float, help="Adam learning rate for all (default: each variable's own)")
    p.add_argument("--size", type=positive_int, default=96, help="image side of --make-targets")
    p.add_argument("--target-spp", type=positive_int, default=64, help="spp of --make-targets and compare.png")
    p.add_argument("--radiance", type=positive_float, default=1.0, help="the constant environment's radiance")
    p.add_argument("--quiet", action="store_true", help="no per-step lines")
    p.set_defaults(func=run)
