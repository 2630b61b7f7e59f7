"""Generation throughput and memory (issue 9), printed as JSON: sequences per hour for a reduced
hps.yaml (2 subjects, 8 frames, 2 views, 256x256) with 1 and 2 workers on this machine, Ray's
overhead against the local pool on the same work (when Ray is installed; goal <= 10 %), and
each worker's resident memory after every sequence (growth from its second to its last sequence;
goal <= 5 % over 50 sequences: a leak across scene loads is what users of Blender pipelines
meet most).

    python bench/generate_cost.py [--sequences 6] [--workers 1 2]
    python bench/generate_cost.py --sequences 50 --workers 1 --no-ray   # the RSS run
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REDUCED = ["compose.subjects.count=2", "compose.subjects.seconds=0.5", "frames=8", "compose.cameras.count=2",
           "compose.cameras.width=256", "compose.cameras.height=256", "render.spp=16", "render.denoise=none"]


def run(workers: int, sequences: int, out: str, executor: str = "local") -> dict:
    args = [sys.executable, "-m", "synmitsuba", "generate", os.path.join(ROOT, "configs", "hps.yaml"), "--out", out,
            "--quiet", "--workers", str(workers), "--sequences", str(sequences), "--executor", executor]
    for s in REDUCED:
        args += ["--set", s]
    t = time.perf_counter()
    subprocess.run(args, check=True, capture_output=True)
    seconds = time.perf_counter() - t
    log = [json.loads(x) for x in open(os.path.join(out, "run.log"))]
    by_pid = collections.defaultdict(list)
    for e in log:
        by_pid[e["pid"]].append(e["rss_mb"])
    # growth after the first sequence (which loads the libraries, compiles kernels, fills caches)
    growth = [100 * (v[-1] / v[1] - 1) for v in by_pid.values() if len(v) > 2]
    # each sequence has another environment and other subjects, so one sequence's RSS swings by
    # a few % with its scene: the trend compares the medians of the first and last ten (after the first)
    trend = [100 * (_median(v[-10:]) / _median(v[1:11]) - 1) for v in by_pid.values() if len(v) >= 21]
    return {"executor": executor, "workers": workers, "sequences": sequences, "seconds": round(seconds, 1),
            "sequences_per_hour": round(3600 * sequences / seconds, 1),
            "peak_rss_mb_per_worker": {str(e["pid"]): e["peak_rss_mb"] for e in log},
            "rss_mb_per_worker_after_sequence": {str(k): v for k, v in by_pid.items()},
            "rss_growth_percent_second_to_last": [round(g, 1) for g in growth],
            "rss_trend_percent_median_last10_vs_2_to_11": [round(g, 1) for g in trend]}


def _median(values: list) -> float:
    v = sorted(values)
    return (v[len(v) // 2] + v[(len(v) - 1) // 2]) / 2


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sequences", type=int, default=6)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--no-ray", action="store_true", help="skip the Ray run (e.g. for a long RSS run)")
    args = ap.parse_args(argv)
    results = []
    for w in args.workers:
        out = tempfile.mkdtemp(prefix=f"gen{w}_")
        try:
            results.append(run(w, args.sequences, out))
        finally:
            shutil.rmtree(out, ignore_errors=True)
    report = {"config": "hps.yaml reduced: " + ", ".join(REDUCED), "runs": results}
    if len(results) > 1:
        report["speedup_2_over_1"] = round(results[0]["seconds"] / results[1]["seconds"], 2)
    import importlib.util
    if args.no_ray:
        pass
    elif importlib.util.find_spec("ray") is None:
        report["ray"] = "not installed: pip install 'synmitsuba[ray]'"
    else:
        out = tempfile.mkdtemp(prefix="genray_")
        try:
            r = run(args.workers[-1], args.sequences, out, "ray")
        finally:
            shutil.rmtree(out, ignore_errors=True)
        results.append(r)
        report["ray_overhead_percent"] = round(100 * (r["seconds"] / results[len(args.workers) - 1]["seconds"] - 1), 1)
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
