"""``synmitsuba view DIR [--sequence N]``: a generated sequence in the Rerun viewer."""
from __future__ import annotations

import argparse
import os

from synmitsuba.cli.args import natural_int, output_file


def run(args) -> int:
    import subprocess

    from synmitsuba.io.viewer import sequence_folder, viewer_available, write_recording
    folder = sequence_folder(args.dataset, args.sequence)
    out = args.out or os.path.join(folder, "recording.rrd")
    if not out.endswith(".rrd"):
        from synmitsuba.errors import ConfigError
        raise ConfigError("--out", out, "give a file name ending in .rrd")
    output_file(out)
    counts = write_recording(folder, out, meshes=not args.no_meshes)
    print(out)
    print(f"{counts['samples']} samples: {counts['frames']} frames x {counts['views']} views, "
          f"{counts['meshes']} body meshes")
    if args.open and viewer_available():
        subprocess.Popen(["rerun", out], start_new_session=True)
    else:
        print(f"open it with: rerun {out}   (or drag it into https://app.rerun.io)")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("view", help="a generated sequence as a Rerun recording (cameras, images, depth, keypoints, "
                       "boxes, body meshes) on its frame timeline",
                       description="Write one sequence of a generated dataset as a Rerun recording (.rrd) and open "
                       "it in the Rerun viewer when a display is available.")
    p.add_argument("dataset", help="a folder synmitsuba generate wrote (or one sequence folder)")
    p.add_argument("--sequence", type=natural_int, help="sequence index (default: the first complete one)")
    p.add_argument("--out", help="recording to write (default: the sequence folder's recording.rrd)")
    p.add_argument("--no-meshes", action="store_true", help="skip the body meshes (default: rebuilt from scene.json, "
                   "a few seconds a subject)")
    p.add_argument("--open", action=argparse.BooleanOptionalAction, default=True,
                   help="open the viewer when a display is available (default: True)")
    p.set_defaults(func=run)
