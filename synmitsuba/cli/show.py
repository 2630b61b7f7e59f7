"""``synmitsuba show SAMPLE [--out PNG]``: a panel of a written sample's labels."""
from __future__ import annotations


import os

from synmitsuba.cli.args import output_file, positive_int


def run(args) -> int:
    from synmitsuba.io.exr import read_sample
    from synmitsuba.io.overlay import sample_panel
    from synmitsuba.io.preview import write_png
    if os.path.isdir(args.sample):
        return _sheet(args)
    sample = read_sample(args.sample)
    stem = args.sample[:-4] if args.sample.endswith(".exr") else args.sample
    out = args.out or f"{stem}_panel.png"
    output_file(out)
    print(write_png(out, sample_panel(sample)))
    for rec in sample.subjects:
        counts = {n: int((rec["visibility"] == k).sum()) for k, n in
                  ((1, "visible"), (2, "self"), (3, "subject"), (4, "object"), (0, "outside"))}
        print(f"subject {rec['instance']}: visible fraction {rec['visible_fraction']:.2f}, keypoints {counts}, "
              f"valid {rec['valid']}")
    return 0


def _sheet(args) -> int:
    from synmitsuba.errors import ConfigError
    from synmitsuba.io.listing import list_samples
    from synmitsuba.io.overlay import dataset_sheet
    from synmitsuba.io.preview import write_png
    stems = list_samples(args.sample)
    if not stems:
        raise ConfigError("sample", args.sample, "this folder holds no complete samples")
    out = args.out or os.path.join(args.sample, "contact_sheet.png")
    output_file(out)
    print(write_png(out, dataset_sheet(stems, args.count)))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("show", help="a PNG panel of a sample's labels (keypoints, boxes, depth, ids, masks)",
                       description="Draw a written sample's labels into one PNG: RGB with keypoints coloured by "
                       "visibility (green visible, yellow self-occluded, red behind a subject, blue behind an "
                       "object) and boxes (white amodal, orange visible), depth, normals, instance ids, layer ids "
                       "and each subject's amodal mask (dimmed where hidden).")
    p.add_argument("sample", help="a sample stem (dir/name, as write_sample wrote it) or its .exr; or a dataset "
                   "folder for a contact sheet of several samples (RGB with keypoints, depth, instance, layers)")
    p.add_argument("--out", help="PNG to write (default: <stem>_panel.png, or DIR/contact_sheet.png)")
    p.add_argument("--count", type=positive_int, default=6, help="samples on a folder's contact sheet")
    p.set_defaults(func=run)
