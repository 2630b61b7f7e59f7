"""``synmitsuba render SCENE.yaml --out DIR``: render every camera of a scene file."""
from __future__ import annotations

import os

from synmitsuba.cli.args import add_variant_option, natural_int, output_dir, positive_int, resolution


def run(args) -> int:
    from tqdm import tqdm

    from synmitsuba.compose.scenefile import read_scene_doc, scene_from_doc
    from synmitsuba.io.exr import write_sample
    from synmitsuba.rendering.passes import render
    from synmitsuba.engine.variant import set_variant
    doc = read_scene_doc(args.scene)  # every key checked before anything is built
    output_dir(args.out)
    set_variant(args.variant)
    sf = scene_from_doc(doc, args.scene, seed=args.seed)
    spp = args.spp if args.spp is not None else sf.settings.spp
    seed = args.seed if args.seed is not None else sf.settings.seed
    written = []
    for name, cam in tqdm(sf.cameras, desc="views", unit="view", disable=args.quiet):
        if args.res:
            cam = cam.resized(*args.res)
        sample = render(sf.scene, cam, spp=spp, seed=seed, max_depth=sf.settings.max_depth,
                        sampler=sf.settings.sampler, denoise=args.denoise or sf.settings.denoise)
        written.append(write_sample(sample, os.path.join(args.out, name)))
    for paths in written:
        print(paths.get("png", paths["exr"]))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("render", help="render a scene file (YAML) into EXR + JSON + PNG per camera",
                       description="Render every camera of a scene file into EXR (every pass) + JSON + PNG.")
    p.add_argument("scene", help="scene file, e.g. scenes/demo.yaml")
    p.add_argument("--out", required=True, help="output folder (created)")
    p.add_argument("--spp", type=positive_int, help="samples per pixel (default: the file's render.spp)")
    p.add_argument("--res", type=resolution, help="resolution WIDTHxHEIGHT for every camera, K scaled (default: "
                   "each camera's)")
    add_variant_option(p)
    p.add_argument("--seed", type=natural_int, help="render and subject seed (default: the file's render.seed)")
    p.add_argument("--denoise", choices=("none", "oidn"), help="denoise the RGB with Intel Open Image Denoise, "
                   "keeping the raw one as rgb_noisy (default: the file's render.denoise)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
