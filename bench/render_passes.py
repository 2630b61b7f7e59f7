"""Cost of the exact geometry passes relative to the RGB pass, and kernel reuse.

Renders scenes/demo.yaml's first camera at 512x512, 64 spp, twice (a second seed, then a
second camera) and prints JSON: seconds for RGB and exact passes, their ratio (goal <= 10 %),
and drjit's compile (codegen + backend) vs execution time per render from its kernel history.
"""
from __future__ import annotations

import json
import os
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]


def kernel_times(history: list) -> dict:
    comp = sum((k.get("codegen_time", 0) + k.get("backend_time", 0)) for k in history) / 1e3
    run = sum(k.get("execution_time", 0) for k in history) / 1e3
    return {"kernels": len(history), "compiled": sum(1 for k in history if not k.get("cache_hit", False)),
            "compile_s": round(comp, 4), "execute_s": round(run, 4)}


def main(res: int = 512, spp: int = 64) -> dict:
    import drjit as dr

    import synmitsuba as sm
    from synmitsuba.compose.scenefile_spec import load_scene_file
    from synmitsuba.engine.variant import thread_count
    sm.set_variant()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    sf = load_scene_file(ROOT / "scenes" / "demo.yaml", subjects=False)  # the objects alone, as recorded
    cams = [c.resized(res, res) for _, c in sf.cameras]
    runs = []
    for label, cam, seed in [("first", cams[0], 0), ("second_seed", cams[0], 1), ("second_camera", cams[1], 0)]:
        dr.kernel_history()  # reading it clears it
        t = time.perf_counter()
        s = sm.render(sf.scene, cam, spp=spp, seed=seed)
        wall = time.perf_counter() - t
        sec = s.timings
        runs.append({"render": label, "wall_s": round(wall, 3), "build_s": round(sec["build"], 3),
                     "rgb_s": round(sec["rgb"], 3), "exact_s": round(sec["exact"], 3),
                     "exact_over_rgb": round(sec["exact"] / sec["rgb"], 4),
                     "jit": kernel_times(dr.kernel_history())})
    return {"bench": "render_passes", "resolution": [res, res], "spp": spp,
            "threads": thread_count(),
            "goal_exact_over_rgb": 0.10, "runs": runs}


if __name__ == "__main__":
    res = int(sys.argv[1]) if len(sys.argv) > 1 else 512
    spp = int(sys.argv[2]) if len(sys.argv) > 2 else 64
    import tempfile
    # a fresh kernel cache, so the first render pays the full compile cost as on a new machine
    os.environ["DRJIT_CACHE_DIR"] = tempfile.mkdtemp(prefix="synmitsuba-bench-drjit-")
    print(json.dumps(main(res, spp), indent=1))
