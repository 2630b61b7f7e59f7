"""Where sampled garments' decals land on the body, and how square they lie: for every garment
of N sampled subjects that carries a decal, its centre looked up through the built mesh's uv
(front of the chest, elsewhere on the garment, or on no face of it) and its circle's width over
its height on the body. Run it against older code with ``PYTHONPATH=<checkout>`` for a before.

    python bench/prints.py [--subjects 40]
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from reference import uv_to_rest  # noqa: E402


def main() -> int:
    import synmitsuba as sm
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=40)
    args = ap.parse_args()
    where: dict = collections.defaultdict(collections.Counter)
    shape, slanted, patterned = [], 0, 0
    for seed in range(args.subjects):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        r = h.regions
        for m in h.garments:
            t = m.params.texture
            if getattr(t, "pattern", "none") != "none":
                patterned += 1
                slanted += t.uv_rotation_deg % 90 != 0
            if getattr(t, "decal", "none") == "none":
                continue
            p = uv_to_rest(m.vertices, m.faces, m.uv, np.asarray(t.decal_center))
            if p is None:
                where[m.params.kind]["on no face"] += 1
                continue
            chest = p[2] > r.neck_xz[1] and abs(p[0] - r.neck_xz[0]) < 0.12 and 0.0 < r.neck_y - p[1] < 0.3
            where[m.params.kind]["chest" if chest else "elsewhere"] += 1
            aspect = getattr(t, "uv_aspect", 1.0)
            ang = np.radians([0, 90, 180, 270])
            rim = [uv_to_rest(m.vertices, m.faces, m.uv, np.asarray(t.decal_center) + t.decal_size * d)
                   for d in np.stack([np.cos(ang) / aspect, np.sin(ang)], 1)]
            if chest and all(x is not None for x in rim):
                shape.append(float(np.linalg.norm(rim[0] - rim[2]) / np.linalg.norm(rim[1] - rim[3])))
    total = collections.Counter()
    for c in where.values():
        total.update(c)
    print(json.dumps({"subjects": args.subjects, "decals": dict(total), "by_kind": {k: dict(c) for k, c in where.items()},
                      "chest_decal_width_over_height_median": round(float(np.median(shape)), 3) if shape else None,
                      "patterned_garments": patterned, "patterns_off_the_grain": int(slanted)}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
