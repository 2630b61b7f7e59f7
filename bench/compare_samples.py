"""Compare two samples of the same frame (say one rendered on cuda_ad_rgb, one on llvm_ad_rgb)
pass by pass, printed as JSON: integer and boolean passes by the count of differing pixels, float
passes by their largest and mean absolute difference, RGB also by its mean.

    python bench/compare_samples.py STEM_A STEM_B
"""
from __future__ import annotations

import json
import sys

import numpy as np


def compare(stem_a: str, stem_b: str) -> dict:
    import synmitsuba as sm
    a, b = sm.read_sample(stem_a), sm.read_sample(stem_b)
    out = {"variants": [a.meta.get("variant"), b.meta.get("variant")], "passes": {}}
    for name in sorted(set(a.passes) & set(b.passes)):
        x, y = a.passes[name], b.passes[name]
        if x.dtype == bool or x.dtype.kind in "iu":
            differ = x != y if x.ndim == 2 else (x != y).any(-1)
            out["passes"][name] = {"pixels_differing": int(differ.sum())}
        else:
            d = np.abs(x.astype(np.float64) - y)
            out["passes"][name] = {"max_abs": float(d.max()), "mean_abs": float(d.mean())}
    out["coverage_max_abs"] = max((float(np.abs(a.coverage[i] - b.coverage[i]).max())
                                   for i in set(a.coverage) & set(b.coverage)), default=None)
    out["rgb_means"] = [float(a.passes["rgb"].mean()), float(b.passes["rgb"].mean())]
    return out


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    print(json.dumps(compare(sys.argv[1], sys.argv[2]), indent=1))
