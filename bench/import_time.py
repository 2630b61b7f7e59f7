"""Import time of `import synmitsuba` (goal < 0.3 s: Mitsuba, torch and anny load on first use),
against a bare interpreter and `import numpy` in the same run. Prints JSON."""
import json
import statistics
import subprocess
import sys
import time


def seconds(code: str, runs: int = 7) -> float:
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


if __name__ == "__main__":
    bare, numpy, ours = seconds("pass"), seconds("import numpy"), seconds("import synmitsuba")
    full = seconds("import synmitsuba as sm; sm.set_variant(); sm.Camera; sm.build_subject", runs=3)
    loaded = subprocess.run([sys.executable, "-c", "import sys, synmitsuba; print(sorted(m for m in ('mitsuba', "
                             "'drjit', 'torch', 'anny', 'scipy', 'trimesh') if m in sys.modules))"],
                            capture_output=True, text=True, check=True).stdout.strip()
    print(json.dumps({"bench": "import_time", "python_s": round(bare, 3), "import_numpy_s": round(numpy, 3),
                      "import_synmitsuba_s": round(ours, 3), "over_numpy_s": round(ours - numpy, 3),
                      "goal_s": 0.3, "import_and_set_variant_s": round(full, 3), "heavy_modules_loaded": loaded}))
