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

import numpy as np


def uv_to_rest(v: np.ndarray, f: np.ndarray, uv: np.ndarray, q: np.ndarray) -> np.ndarray | None:
    """The rest point of the mesh (v, f, uv) at texture coordinates ``q`` (2,): the first face
    whose uv triangle holds it, barycentrically; None where none does."""
    a, b, c = (uv[f[:, i]] for i in range(3))
    d = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    d = np.where(d == 0, np.nan, d)
    l1 = ((q[0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (q[1] - a[:, 1])) / d
    l2 = ((b[:, 0] - a[:, 0]) * (q[1] - a[:, 1]) - (q[0] - a[:, 0]) * (b[:, 1] - a[:, 1])) / d
    hit = np.flatnonzero((l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1))
    if not len(hit):
        return None
    k = hit[0]
    return (1 - l1[k] - l2[k]) * v[f[k, 0]] + l1[k] * v[f[k, 1]] + l2[k] * v[f[k, 2]]


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
