"""Garment penetration under motion (issue 12): random subjects x walk, run, squat, jump, wave
at every ``--stride``-th frame, skinned alone and resolved (``body.collide``). A garment vertex
is inside when it lies behind the closest posed body point (sign from that feature's angle-
weighted pseudonormal, searched among the faces around its 8 nearest vertices) and its winding
number in the posed body is over 1/2 (a few posed triangles flip, whose back side is not
inside); reported per garment kind and motion: share of vertices inside and the deepest, and
the same for the vertices away from where the posed body runs into itself (``_in_overlap``).
Goal: <= 0.5 % and <= 5 mm. Prints JSON.

    python bench/garment_collisions.py [--subjects 20] [--stride 3]
"""
from __future__ import annotations

import argparse
import collections
import json

import numpy as np

MOTIONS = ("walk", "run", "squat", "jump", "wave")


def _in_overlap(body, faces, points, depth, reach: float = 0.03) -> np.ndarray:
    """(N,) True where a body triangle within ``depth + reach`` of the point (``depth``: how far
    inside it is) is buried in another part
    of the posed body (winding number 1 mm outside its centre over 1/2): a thigh pressed into
    the belly in a squat, an arm into the chest. There no place is outside both, so no
    resolver can clear the cloth: reported apart. Centres, not vertices: anny's triangles are
    up to 4 cm long, and one can cross an arm with all three corners outside it."""
    from scipy.spatial import cKDTree
    from synmitsuba.geometry import face_normals, winding_numbers
    out = np.zeros(len(points), bool)
    if not len(points):
        return out
    centres = body[faces].mean(1)
    near = cKDTree(centres).query_ball_point(points, np.asarray(depth) + reach)
    ids = np.unique(np.concatenate([np.asarray(n, int) for n in near]))
    if not len(ids):
        return out
    buried = np.zeros(len(faces), bool)
    buried[ids] = winding_numbers(body, faces, centres[ids] + 0.001 * face_normals(body[faces[ids]])) > 0.5
    return np.array([buried[n].any() for n in near])


def main(argv=None) -> int:
    import synmitsuba as sm
    from synmitsuba.body.binding import signed_distance
    from synmitsuba.geometry import winding_numbers
    from synmitsuba.motion.sources import load_motion
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=20)
    ap.add_argument("--stride", type=int, default=3)
    args = ap.parse_args(argv)
    stats = collections.defaultdict(lambda: [0, 0, 0.0, 0, 0.0])  # (kind, motion, resolved) -> inside, total,
    # deepest, inside where the body does not overlap itself, deepest there
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
                        free = inside[~_in_overlap(body, h.body.faces, lay.vertices[inside], -d[inside])]
                        r = stats[(lay.name, motion, resolve)]
                        r[0], r[1], r[3] = r[0] + len(inside), r[1] + len(d), r[3] + len(free)
                        r[2] = max(r[2], float(-d[inside].min()) if len(inside) else 0.0)
                        r[4] = max(r[4], float(-d[free].min()) if len(free) else 0.0)
    rows = {}
    for (kind, motion, resolve), (inside, total, deepest, free, deepest_free) in sorted(stats.items()):
        rows.setdefault(f"{kind}/{motion}", {})["resolved" if resolve else "skinned"] = {
            "inside_percent": round(100 * inside / total, 3), "deepest_mm": round(1e3 * deepest, 1),
            "free_inside_percent": round(100 * free / total, 3), "free_deepest_mm": round(1e3 * deepest_free, 1)}
    pooled = {k: {"inside_percent": round(100 * sum(v[0] for (_, _, r), v in stats.items() if r == k)
                                          / max(1, sum(v[1] for (_, _, r), v in stats.items() if r == k)), 3),
                  "free_inside_percent": round(100 * sum(v[3] for (_, _, r), v in stats.items() if r == k)
                                               / max(1, sum(v[1] for (_, _, r), v in stats.items() if r == k)), 3),
                  "worst_row_free_inside_percent": max(x["resolved" if k else "skinned"]["free_inside_percent"]
                                                       for x in rows.values()),
                  "free_deepest_mm": max(x["resolved" if k else "skinned"]["free_deepest_mm"] for x in rows.values())}
              for k in (False, True)}
    print(json.dumps({"bench": "garment_collisions", "subjects": args.subjects, "stride": args.stride,
                      "skinned": pooled[False], "resolved": pooled[True],
                      "goal": {"inside_percent": 0.5, "deepest_mm": 5.0}, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
