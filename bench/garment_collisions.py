"""Garment penetration under motion (issue 12): random subjects x walk, run, squat, jump, wave
at every ``--stride``-th frame, skinned alone and resolved (``body.collide``). A garment vertex
is inside when it lies behind the closest posed body point (sign from that feature's angle-
weighted pseudonormal, searched among the faces around its 8 nearest vertices) and its winding
number in the posed body is over 1/2 (a few posed triangles flip, whose back side is not
inside); reported per garment kind and motion: share of vertices inside and the deepest. Goal: <= 0.5 % and <= 5 mm. Prints JSON.

    python bench/garment_collisions.py [--subjects 20] [--stride 3]
"""
from __future__ import annotations

import argparse
import collections
import json

import numpy as np

MOTIONS = ("walk", "run", "squat", "jump", "wave")


def main(argv=None) -> int:
    import synmitsuba as sm
    from synmitsuba.body.binding import signed_distance
    from synmitsuba.geometry import winding_numbers
    from synmitsuba.motion.sources import load_motion
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=20)
    ap.add_argument("--stride", type=int, default=3)
    args = ap.parse_args(argv)
    stats = collections.defaultdict(lambda: [0, 0, 0.0])  # (kind, motion, resolved) -> inside, total, deepest
    for s in range(args.subjects):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(s), {"texture_size": 64}))
        kinds = {g.params.kind for g in h.garments}
        for motion in MOTIONS:
            m = sm.retarget(load_motion(motion, np.random.default_rng(s), seconds=1.0), h.skeleton)
            for f in range(0, m.n_frames, args.stride):
                rot, root = m.frame(f)
                for resolve in (False, True):
                    layers = h.pose(rot, root, resolve=resolve)
                    body = np.empty_like(h.body.vertices)
                    body[h.split.source] = layers[0].vertices
                    for lay in layers:
                        if lay.name not in kinds:
                            continue
                        d = signed_distance(body, h.body.faces, lay.vertices, k=8)
                        behind = np.flatnonzero(d < 0)
                        inside = behind[winding_numbers(body, h.body.faces, lay.vertices[behind]) > 0.5]
                        depth = -d[inside]
                        r = stats[(lay.name, motion, resolve)]
                        r[0], r[1] = r[0] + len(inside), r[1] + len(d)
                        r[2] = max(r[2], float(depth.max()) if len(depth) else 0.0)
    rows = {}
    for (kind, motion, resolve), (inside, total, deepest) in sorted(stats.items()):
        rows.setdefault(f"{kind}/{motion}", {})["resolved" if resolve else "skinned"] = {
            "inside_percent": round(100 * inside / total, 3), "deepest_mm": round(1e3 * deepest, 1)}
    pooled = {k: round(100 * sum(v[0] for (_, _, r), v in stats.items() if r == k)
                       / max(1, sum(v[1] for (_, _, r), v in stats.items() if r == k)), 3) for k in (False, True)}
    print(json.dumps({"bench": "garment_collisions", "subjects": args.subjects, "stride": args.stride,
                      "inside_percent_all": {"skinned": pooled[False], "resolved": pooled[True]},
                      "goal": {"inside_percent": 0.5, "deepest_mm": 5.0}, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
