"""A sheet of generated frames, one per environment (issue 36's "look at 12 frames at 1280 x 720"):
``synmitsuba generate hps`` run as a user would, one sequence and one frame per environment,
with hps.yaml's render settings (64 spp + OIDN, photo development, blur, lens); each frame's
RGB PNG is kept at full size under OUT/frames/ and tiled into OUT/sheet.png. Prints JSON
(seconds per frame, the frames written).

    python bench/places_sheet.py --out out/places_sheet [--envs city_street living_room] [--seed 3]
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np


def generate_one(env: str, out: str, seed: int, spp: int) -> float:
    exe = os.path.join(os.path.dirname(sys.executable), "synmitsuba")
    sets = [f"compose.environments=[{env}]", "frames=1", "compose.cameras.count=1", f"render.spp={spp}"]
    cmd = [exe, "generate", "hps", "--sequences", "1", "--seed", str(seed), "--out", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    t = time.perf_counter()
    subprocess.run(cmd, check=True)
    return time.perf_counter() - t


def frame_rgb(folder: str) -> np.ndarray:
    from synmitsuba.io.exr import read_sample
    from synmitsuba.io.listing import list_samples
    from synmitsuba.io.preview import to_srgb8
    sample = read_sample(list_samples(folder)[0])
    return to_srgb8(sample.passes["rgb"])


def main(argv=None):
    import synmitsuba as sm
    from synmitsuba.io.preview import contact_sheet, write_png
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/places_sheet")
    ap.add_argument("--envs", nargs="*", default=None, help="environments (default: all)")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--columns", type=int, default=3)
    ap.add_argument("--scale", type=int, default=2, help="sheet tiles are the frames shrunk by this")
    args = ap.parse_args(argv)
    envs = args.envs or sm.environment_names()
    seconds, tiles = {}, []
    os.makedirs(os.path.join(args.out, "frames"), exist_ok=True)
    for env in envs:
        folder = os.path.join(args.out, "data", env)
        if not os.path.isfile(os.path.join(folder, "manifest.jsonl")) or os.path.getsize(os.path.join(folder, "manifest.jsonl")) == 0:
            seconds[env] = round(generate_one(env, folder, args.seed, args.spp), 1)
        rgb = frame_rgb(folder)
        write_png(os.path.join(args.out, "frames", f"{env}.png"), rgb)
        s = args.scale
        tiles.append(rgb[: rgb.shape[0] // s * s, : rgb.shape[1] // s * s].reshape(
            rgb.shape[0] // s, s, rgb.shape[1] // s, s, -1).mean((1, 3)).astype(np.uint8))
    shape = min(t.shape for t in tiles)   # portrait views are cropped to the landscape tile
    tiles = [t[: shape[0], : shape[1]] if t.shape[0] >= shape[0] else np.pad(t, ((0, shape[0] - t.shape[0]), (0, 0), (0, 0)))
             for t in tiles]
    write_png(os.path.join(args.out, "sheet.png"), contact_sheet(tiles, args.columns))
    print(json.dumps({"seconds": seconds, "frames": os.path.join(args.out, "frames"),
                      "sheet": os.path.join(args.out, "sheet.png")}, indent=1))


if __name__ == "__main__":
    main()
