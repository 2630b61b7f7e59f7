"""Sample and build N random subjects (default 1000): count failures and degenerate meshes.
Prints JSON; ``python bench/subjects_robustness.py 100`` for a shorter run."""
from __future__ import annotations

import json
import sys
import time

import numpy as np


def main(n: int = 1000) -> dict:
    import synmitsuba as sm
    failures, degenerate = [], []
    t = time.perf_counter()
    for seed in range(n):
        try:
            h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
            for layer in h.pose():
                if layer.is_curves:
                    ok = np.isfinite(layer.points).all() and (layer.radius > 0).all()
                else:
                    v, f = layer.vertices, layer.faces
                    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
                    ok = len(f) > 0 and np.isfinite(v).all() and f.max() < len(v) and (area > 0).mean() > 0.99
                if not ok:
                    degenerate.append((seed, layer.name))
        except Exception as exc:  # noqa: BLE001 - counted and reported
            failures.append((seed, repr(exc)[:200]))
    return {"bench": "subjects_robustness", "subjects": n, "failures": len(failures), "degenerate_layers": len(degenerate),
            "examples": (failures + degenerate)[:5], "seconds_per_subject": round((time.perf_counter() - t) / n, 3)}


if __name__ == "__main__":
    print(json.dumps(main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000), indent=1))
