"""``synmitsuba render SCENE.yaml --out DIR``: render and label a scene file's cameras, frame by
frame, exactly as ``synmitsuba generate`` renders sequence 0 of a config naming that scene."""
from __future__ import annotations

from synmitsuba.cli.args import add_variant_option, natural_int, output_dir, positive_int, resolution
from synmitsuba.engine.settings import DENOISERS


def scene_config(args, doc):
    """The generation config that ``render`` runs: the scene file's render settings unless the
    options say otherwise."""
    from synmitsuba.generate.config import GenerateConfig, RenderOptions
    r = doc.render
    render = RenderOptions(spp=args.spp or r.spp, max_depth=r.max_depth, sampler=r.sampler,
                           denoise=args.denoise or r.denoise, shutter_deg=[r.shutter_deg, r.shutter_deg],
                           subframes=r.subframes, photo=r.photo)
    return GenerateConfig(sequences=1, seed=r.seed if args.seed is None else args.seed, frames=args.frames,
                          stride=args.stride, annotate=not args.no_labels,
                          flow="adjacent" if args.frames == 1 else "rendered", render=render, scene=args.scene)


def run(args) -> int:
    from tqdm import tqdm

    from synmitsuba.compose.scenefile import check_scene_file
    from synmitsuba.engine.variant import set_variant
    from synmitsuba.generate.run import sequence_frames, sequence_spec, write_sequence
    doc = check_scene_file(args.scene)  # every key and file checked before anything is built
    output_dir(args.out)
    set_variant(args.variant)
    cfg = scene_config(args, doc)
    spec = sequence_spec(cfg, 0)
    if args.res:
        for view in spec.views:
            view.cameras = [c.resized(*args.res) for c in view.cameras]
    total = len(sequence_frames(cfg, spec.n_frames)) * len(spec.views)
    with tqdm(total=total, desc="samples", unit="sample", disable=args.quiet) as bar:
        stems = write_sequence(spec, cfg, 0, args.out, bar)
    for stem in stems:
        print(f"{args.out}/{stem}.png")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("render", help="render and label a scene file (YAML): EXR + JSON + PNG per camera and frame",
                       description="Render every camera of a scene file at its subjects' frames into EXR (every pass) "
                       "+ JSON (labels) + PNG, named fFFFF_<camera>, beside the scene.json it compiles to: the same "
                       "files `synmitsuba generate` writes for sequence 0 of a config whose scene is this file.")
    p.add_argument("scene", help="scene file, e.g. scenes/demo.yaml")
    p.add_argument("--out", required=True, help="output folder (created)")
    p.add_argument("--frames", type=positive_int, default=1, help="frames rendered; one shows each subject's "
                   "`frame`, with flow to the next clip frame (default: 1)")
    p.add_argument("--stride", type=positive_int, default=1, help="clip frames between rendered frames (default: 1)")
    p.add_argument("--spp", type=positive_int, help="samples per pixel (default: the file's render.spp)")
    p.add_argument("--res", type=resolution, help="resolution WIDTHxHEIGHT for every camera, K scaled (default: "
                   "each camera's)")
    add_variant_option(p)
    p.add_argument("--seed", type=natural_int, help="global seed of subjects, motions and rendering (default: the "
                   "file's render.seed)")
    p.add_argument("--denoise", choices=DENOISERS, help="denoise the RGB with Intel Open Image Denoise, "
                   "keeping the raw one as rgb_noisy (default: the file's render.denoise)")
    p.add_argument("--no-labels", action="store_true", help="render only: no subject labels, flow or body "
                   "passes (default: labels written)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
