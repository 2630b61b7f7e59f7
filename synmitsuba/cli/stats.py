"""``synmitsuba stats DIR``: what a generated dataset holds, as a PNG of histograms and a JSON."""
from __future__ import annotations

import json
import os


def run(args) -> int:
    from synmitsuba.cli.args import output_file
    from synmitsuba.data.stats import dataset_stats, stats_figure, summarise
    from synmitsuba.io.files import atomic_path
    png = output_file(args.out) if args.out else os.path.join(args.dataset, "stats.png")  # checked before the work
    stats = dataset_stats(args.dataset)
    print(stats_figure(stats, png))
    path = os.path.splitext(png)[0] + ".json"
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        json.dump(summarise(stats), fh, indent=1)
    print(path)
    print(f"{stats['sequences']} sequences, {stats['subjects']} subjects, {stats['frames']} frames, "
          f"{stats['samples']} images, {stats['views']} views")
    o = stats["occlusion"]
    if o["share"] is not None:
        target = f" (target {o['target_share']:.2f})" if o["target_share"] else ""
        print(f"visible fraction in {o['visible']}: {o['share']:.3f} of subject records{target}; "
              f"fully visible {o['fully_visible_share']:.3f}; valid {o['valid_share']:.3f}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("stats", help="counts and histograms of a generated dataset (PNG + JSON)",
                       description="Counts of sequences, subjects, frames and views, and histograms of visible "
                       "fraction (and the share partly hidden against compose.occlusion's target), keypoint visibility, "
                       "subject height, camera distance, pitch, height and field of view, camera kinds and "
                       "orientations, skin tone (ITA), garment kinds and motions: DIR/stats.png and DIR/stats.json.")
    p.add_argument("dataset", help="a folder synmitsuba generate wrote")
    p.add_argument("--out", help="PNG to write (default: DATASET/stats.png; the JSON goes beside it)")
    p.set_defaults(func=run)
