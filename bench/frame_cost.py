"""End-to-end frame cost of a sequence against Mitsuba's own render of the same loaded scene.

Two walking/waving subjects with hair, two views, N frames: per frame the posing (skinning and
in-place updates), sm.render (RGB + exact passes + coverage), denoising and writing; in the same
run a raw ``mi.render`` of the same loaded scene with a plain ``perspective`` sensor at the same
size, spp and sampler. Also the resident memory after each frame. Prints JSON.

    python bench/frame_cost.py [--frames 30] [--res 256] [--spp 16] [--denoise none|oidn] [--coverage 9]
                               [--count 2] [--views 2] [--subjects FILE]
"""
import argparse
import json
import os
import resource
import statistics
import sys
import tempfile
import time

import numpy as np
from subject_cache import cached


def rss_mb() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


PLACES = (("walk", -0.6), ("wave", 0.7), ("squat", -1.8), ("run", 1.9))


def build_subjects(frames: int, count: int = 2) -> list:
    """Subjects with shoulder-length hair side by side: walking, waving (then squatting, running)."""
    import synmitsuba as sm
    subjects = []
    for k, (kind, x) in enumerate(PLACES[:count]):
        rng = np.random.default_rng(10 + k)
        human = sm.build_subject(sm.sample_subject(rng, {"hair_style": "shoulder"}))
        clip = sm.retarget(sm.procedural_motion(kind, rng, seconds=max(1.0, frames / 30)), human.skeleton)
        subjects.append((human, clip.moved(0, (x, 0, 0)), 1 + k))
    return subjects


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--denoise", default="none")
    ap.add_argument("--coverage", type=int, default=9, help="coverage_samples (sub-pixel rays for alpha)")
    ap.add_argument("--out", help="folder for the written samples (default: a temporary folder)")
    ap.add_argument("--subjects", help="file of built subjects: read if present, else written (see subject_cache.py)")
    ap.add_argument("--count", type=int, default=2, choices=(1, 2, 3, 4), help="how many subjects")
    ap.add_argument("--views", type=int, default=2, choices=(1, 2, 3, 4), help="how many cameras")
    ap.add_argument("--no-raw", action="store_true", help="skip the raw mi.render (a memory run)")
    args = ap.parse_args(argv)
    import mitsuba as mi

    import synmitsuba as sm
    from synmitsuba.compose.stage import preview_stage
    from synmitsuba.engine.build import STATS, build, settle_frame_memory
    from synmitsuba.engine.settings import choose_sampler
    sm.set_variant()
    scene = preview_stage()
    subjects = cached(args.subjects, lambda: build_subjects(args.frames, args.count))[:args.count]
    eyes = ((0.5, 1.3, 5.0), (4.0, 1.6, 2.5), (-4.0, 1.8, 3.0), (0.3, 2.2, -5.0))
    views = [sm.Camera.look_at(eye=e, target=(0, 0.9, 0), fov_y_deg=40, width=args.res, height=args.res)
             for e in eyes[:args.views]]
    sampler = choose_sampler("auto", args.spp)
    path = mi.load_dict({"type": "path", "max_depth": 6})  # what sm.render uses (max_depth 6)
    rows, rss = [], []
    out = args.out or tempfile.mkdtemp(prefix="synmitsuba-frame-cost-")
    os.makedirs(out, exist_ok=True)
    for f in range(args.frames):
        t0 = time.perf_counter()
        for human, clip, inst in subjects:
            human.add_to(scene, *clip.frame(f % clip.n_frames), instance=inst)
        t1 = time.perf_counter()
        built = build(scene)  # the in-place update, timed on its own
        t2 = time.perf_counter()
        row = {"pose_s": t1 - t0, "update_s": t2 - t1, "render_s": 0.0, "rgb_s": 0.0, "denoise_s": 0.0, "exact_s": 0.0,
               "write_s": 0.0, "raw_s": 0.0}
        for v, cam in enumerate(views):
            t3 = time.perf_counter()
            s = sm.render(scene, cam, spp=args.spp, seed=f, denoise=args.denoise, coverage_samples=args.coverage)
            t4 = time.perf_counter()
            sm.write_sample(s, os.path.join(out, f"f{f:04d}_v{v}"))
            t5 = time.perf_counter()
            sensor = mi.load_dict({"type": "perspective", "fov": 40, "fov_axis": "y",
                                   "to_world": mi.ScalarTransform4f().look_at(origin=cam.center.tolist(),
                                                                               target=[0, 0.9, 0], up=[0, 1, 0]),
                                   "film": {"type": "hdrfilm", "width": args.res, "height": args.res,
                                            "rfilter": {"type": "box"}, "component_format": "float32"},
                                   "sampler": {"type": sampler, "sample_count": args.spp}})
            t6 = time.perf_counter()
            if not args.no_raw:
                np.array(mi.render(built.mi_scene, sensor=sensor, integrator=path, spp=args.spp, seed=f))
            row["raw_s"] += time.perf_counter() - t6
            row["render_s"] += t4 - t3
            row["write_s"] += t5 - t4
            for key in ("rgb", "denoise", "exact"):
                row[f"{key}_s"] += s.timings[key]
        settle_frame_memory()  # as pipeline.render_sequence does after each frame
        rows.append(row)
        rss.append(rss_mb())
    later = rows[2:] if len(rows) > 3 else rows[1:]

    def med(key):
        return round(statistics.median(r[key] for r in later), 4)
    ours = med("pose_s") + med("update_s") + med("render_s")
    from synmitsuba.engine.variant import current_variant
    result = {"bench": "frame_cost", "variant": current_variant(), "frames": args.frames, "views": len(views), "res": args.res, "spp": args.spp,
              "sampler": sampler, "denoise": args.denoise, "coverage_samples": args.coverage, "first_frame_s": round(sum(rows[0].values()), 3),
              "per_frame_median_s": {k: med(k) for k in rows[0]},
              "frame_over_raw": None if args.no_raw else round(ours / max(med("raw_s"), 1e-9), 3), "goal_frame_over_raw": 1.10,
              "scene_loads": STATS["loads"], "in_place_updates": STATS["updates"],
              "rss_mb_after_frame": [round(rss[0], 1), round(rss[min(1, len(rss) - 1)], 1), round(rss[-1], 1)],
              "rss_growth_after_second_frame": round(rss[-1] / rss[min(1, len(rss) - 1)] - 1, 4),
              "rss_growth_after_first_frame": round(rss[-1] / rss[0] - 1, 4), "goal_rss_growth": 0.05,
              "rss_mb_every_10_frames": [round(r) for r in rss[::10]],
              "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
              "subjects": len(subjects)}
    print(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
