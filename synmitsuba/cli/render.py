"""``synmitsuba render SCENE.yaml --out DIR``: render every camera of a scene file."""
from __future__ import annotations

import os

from synmitsuba.errors import ConfigError


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
        assert w > 0 and h > 0
        return w, h
    except (ValueError, AssertionError):
        raise ConfigError("--res", text, "give WIDTHxHEIGHT in pixels, e.g. 640x480") from None


def run(args) -> int:
    from tqdm import tqdm

    import synmitsuba as sm
    from synmitsuba.io.scenefile import load_scene_file
    sm.set_variant(args.variant)
    sf = load_scene_file(args.scene)
    spp = args.spp if args.spp is not None else sf.settings.spp
    seed = args.seed if args.seed is not None else sf.settings.seed
    os.makedirs(args.out, exist_ok=True)
    if sf.subjects:
        from synmitsuba.pipeline import add_subjects
        add_subjects(sf.scene, sf.subjects, seed=seed, base=os.path.dirname(os.path.abspath(args.scene)))
    written = []
    for name, cam in tqdm(sf.cameras, desc="views", unit="view", disable=args.quiet):
        if args.res:
            cam = cam.resized(*_resolution(args.res))
        sample = sm.render(sf.scene, cam, spp=spp, seed=seed, max_depth=sf.settings.max_depth)
        written.append(sm.write_sample(sample, os.path.join(args.out, name)))
    for paths in written:
        print(paths.get("png", paths["exr"]))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("render", help="render a scene file (YAML) into EXR + JSON + PNG per camera")
    p.add_argument("scene", help="scene file, e.g. scenes/demo.yaml")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--spp", type=int, help="samples per pixel (default: the file's render.spp)")
    p.add_argument("--res", help="resolution WIDTHxHEIGHT for every camera (K is scaled)")
    p.add_argument("--variant", help="Mitsuba variant (default llvm_ad_rgb)")
    p.add_argument("--seed", type=int, help="render seed (default: the file's render.seed)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
