"""``synmitsuba subject --seed N --out DIR``: a turntable of one sampled subject (PNG views, EXR
samples with every pass, the recipe JSON, a contact image); ``--sheet K`` instead renders K
random subjects into one contact sheet."""
from __future__ import annotations

import json
import os

import numpy as np


def _stage(sm, human, instance: int = 1):
    scene = sm.Scene()
    ground = np.array([[-50, 0, -50], [50, 0, -50], [50, 0, 50], [-50, 0, 50]], float)
    scene.add_mesh("ground", ground, np.array([[0, 2, 1], [0, 3, 2]]), material=sm.Material(base_color=0.45),
                   layer=sm.Layer.GROUND)
    scene.set_environment(sm.SunSky(sun_direction=(0.5, 0.9, 0.7), sky_scale=1.5))
    human.add_to(scene, instance=instance)
    return scene


def _camera(sm, human, angle_deg: float, w: int, h: int):
    top = human.body.vertices[:, 1].max()
    a = np.radians(angle_deg)
    dist = 1.15 * top / np.tan(np.radians(35) / 2) / 2 + 0.3
    eye = (dist * np.sin(a), 0.55 * top + 0.25, dist * np.cos(a))
    return sm.Camera.look_at(eye=eye, target=(0, 0.5 * top, 0), fov_y_deg=35, width=w, height=h)


def turntable(args) -> int:
    import synmitsuba as sm
    sm.set_variant(args.variant)
    recipe = sm.sample_subject(np.random.default_rng(args.seed))
    human = sm.build_subject(recipe)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "recipe.json"), "w") as fh:
        json.dump(recipe.to_dict(), fh, indent=1, sort_keys=True)
    scene = _stage(sm, human)
    w, h = (int(x) for x in args.res.split("x"))
    images = []
    for k in range(args.views):
        cam = _camera(sm, human, 360.0 * k / args.views, w, h)
        sample = sm.render(scene, cam, spp=args.spp, seed=args.seed)
        paths = sm.write_sample(sample, os.path.join(args.out, f"view_{k:02d}"))
        images.append(sm.to_srgb8(sample.rgb))
        layers = (np.array([[[0, 0, 0], [230, 190, 160], [200, 40, 40], [40, 80, 200], [180, 60, 180], [40, 40, 40],
                             [120, 80, 30], [90, 60, 20], [40, 200, 200], [200, 200, 40], [110, 110, 110]]], np.uint8)[0])
        images.append(layers[np.clip(sample.layer, 0, 10)])
    sheet = sm.write_png(os.path.join(args.out, "turntable.png"), sm.contact_sheet(images, columns=2 * min(args.views, 4)))
    print(sheet)
    return 0


def sheet(args) -> int:
    import synmitsuba as sm
    sm.set_variant(args.variant)
    w, h = (int(x) for x in args.res.split("x"))
    images = []
    for k in range(args.sheet):
        human = sm.build_subject(sm.sample_subject(np.random.default_rng(args.seed + k)))
        cam = _camera(sm, human, 25.0, w, h)
        images.append(sm.to_srgb8(sm.render(_stage(sm, human), cam, spp=args.spp, seed=k).rgb))
    os.makedirs(os.path.dirname(os.path.abspath(args.out)) or ".", exist_ok=True)
    path = args.out if args.out.endswith(".png") else os.path.join(args.out, "subjects.png")
    print(sm.write_png(path, sm.contact_sheet(images, columns=min(8, args.sheet))))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("subject", help="render a turntable of a sampled layered human (or a contact sheet)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True, help="output folder (or .png path with --sheet)")
    p.add_argument("--views", type=int, default=6)
    p.add_argument("--res", default="240x320")
    p.add_argument("--spp", type=int, default=32)
    p.add_argument("--sheet", type=int, default=0, help="render this many subjects (seeds seed..seed+K-1) into one image")
    p.add_argument("--variant")
    p.set_defaults(func=lambda a: sheet(a) if a.sheet else turntable(a))
