"""``synmitsuba compose CONFIG --seed N --out DIR``: compose one scene (environment, subjects
placed over their clips, cameras scored by occlusion) and write its spec, a top-down picture
and one render per camera."""
from __future__ import annotations

import os

from synmitsuba.cli.args import add_variant_option, natural_int, output_dir, positive_int
from synmitsuba.engine.settings import DENOISERS


def run(args) -> int:
    import numpy as np
    from tqdm import tqdm

    from synmitsuba.compose.composition import compose_scene, load_compose_config
    from synmitsuba.compose.topdown import draw_topdown
    from synmitsuba.engine.variant import set_variant
    from synmitsuba.io.exr import write_sample
    from synmitsuba.io.files import atomic_path
    from synmitsuba.io.preview import write_png
    from synmitsuba.pipeline import render_sequence
    cfg = load_compose_config(args.config)  # every key checked before anything is built
    output_dir(args.out)
    set_variant(args.variant)
    spec = compose_scene(cfg, np.random.default_rng(args.seed), seed=args.seed)
    path = os.path.join(args.out, "scene.json")
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write(spec.to_json(indent=1))
    print(path)
    print(write_png(os.path.join(args.out, "topdown.png"), draw_topdown(spec)))
    frame = spec.n_frames // 2 if args.frame is None else min(args.frame, spec.n_frames - 1)
    for f, view, sample in tqdm(render_sequence(spec, frames=[frame], spp=args.spp, seed=args.seed, denoise=args.denoise),
                                total=len(spec.views), desc="views", unit="view", disable=args.quiet):
        paths = write_sample(sample, os.path.join(args.out, f"{view}_f{f:04d}"))
        print(paths.get("png", paths["exr"]))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("compose", help="compose a scene from a config: spec JSON, top-down PNG, a render per camera",
                       description="Compose one scene: an environment, subjects placed over their whole clips, "
                       "cameras scored by ray-cast occlusion. Writes scene.json (the SceneSpec), topdown.png and "
                       "one render (EXR + JSON + PNG) per camera.")
    p.add_argument("config", help="composition config (YAML), e.g. configs/compose.yaml")
    p.add_argument("--seed", type=natural_int, default=0, help="composition and render seed")
    p.add_argument("--out", required=True, help="output folder (created)")
    p.add_argument("--spp", type=positive_int, default=16, help="samples per pixel of the renders")
    p.add_argument("--denoise", choices=DENOISERS, default="none", help="denoise the renders' RGB with Intel "
                   "Open Image Denoise (the raw one is kept as rgb_noisy)")
    p.add_argument("--frame", type=natural_int, help="clip frame rendered (default: the middle one)")
    add_variant_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
