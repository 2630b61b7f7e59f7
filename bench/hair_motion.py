"""Hair under motion (issue 12): strands rigid with the head against strands that follow the body
below the neck (``hair.follow_weights``) and against those also kept from stretching and off the
body (``pose(resolve=True)``: ``hair.limit_stretch``), on random subjects with long, shoulder-length and bob
hair x walk, run, squat, jump, wave and three head poses (turned 70 deg, bent 35 deg forward,
tilted 35 deg sideways), every ``--stride``-th frame. A strand point (roots aside) is inside when
it lies behind the closest posed body point and its winding number in the posed body is over
1/2 (every 4th strand is measured). Also: strand stretch (99.5th percentile of a segment's
length over its rest length) and the cost of posing the strands (``settle``: what shortening
and clearing adds). Prints JSON.

    python bench/hair_motion.py [--subjects 6] [--stride 4]
"""
from __future__ import annotations

import argparse
import os
import sys
import json
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))

MOTIONS = ("walk", "run", "squat", "jump", "wave")
STYLES = ("long", "shoulder", "bob")


def head_poses(sk):
    """Local rotations (3, J, 3, 3): the head turned, bent forward, tilted sideways (split over
    the three neck joints and the head)."""
    from synmitsuba.geometry import axis_rotation
    out = []
    for axis, deg in (("y", 70.0), ("x", 35.0), ("z", 35.0)):
        R = np.broadcast_to(np.eye(3), (len(sk), 3, 3)).copy()
        for name in ("neck01", "neck02", "neck03", "head"):
            R[sk.index(name)] = axis_rotation(axis, np.radians(deg / 4))
        out.append(R)
    return out


def inside_share(h, layers, points) -> tuple[int, float]:
    from synmitsuba.body.binding import signed_distance
    from reference import winding_numbers  # tests/reference.py: the independent check
    body = np.empty_like(h.body.vertices)
    body[h.split.source] = layers[0].vertices
    d = signed_distance(body, h.body.faces, points, k=8)
    behind = np.flatnonzero(d < 0)
    inside = behind[winding_numbers(body, h.body.faces, points[behind]) > 0.5]
    return len(inside), float(-d[inside].min()) if len(inside) else 0.0


def main(argv=None) -> int:
    import synmitsuba as sm
    from scipy import sparse
    from synmitsuba.motion.sources import load_motion
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=6)
    ap.add_argument("--stride", type=int, default=4)
    args = ap.parse_args(argv)
    from synmitsuba.body.collide import Surface
    rows, cost = {}, {"rigid": [], "follow": [], "settle": []}
    for s in range(args.subjects):
        style = STYLES[s % len(STYLES)]
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(s), {"texture_size": 64, "hair_style": style,
                                                                          "accessories": []}))
        follow = h.hair_weights
        n = follow.shape[0]
        rigid = sparse.csr_matrix((np.ones(n), (np.arange(n), np.full(n, h.head_bone))), shape=follow.shape)
        rest_len = np.linalg.norm(np.diff(h.hair.points, axis=1), axis=2)
        frames = [(f"pose_{k}", [(R, None)]) for k, R in enumerate(head_poses(h.skeleton))]
        for motion in MOTIONS:
            m = sm.retarget(load_motion(motion, np.random.default_rng(s), seconds=1.0), h.skeleton)
            frames.append((motion, [m.frame(f) for f in range(0, m.n_frames, args.stride)]))
        for name, poses in frames:
            for mode, w in (("rigid", rigid), ("follow", follow), ("settled", follow)):
                h.hair_weights = w
                r = rows.setdefault(f"{style}/{name}", {}).setdefault(mode, [0, 0, 0.0, 0.0])
                for rot, root in poses:
                    h._posed.clear()
                    t = time.perf_counter()
                    layers = h.pose(rot, root, resolve=mode == "settled")
                    if mode != "settled":
                        cost[mode].append(time.perf_counter() - t)
                    else:
                        T, body = h._transforms(rot, root), np.empty_like(h.body.vertices)
                        body[h.split.source] = layers[0].vertices
                        surface = Surface.of(body, h.body.faces, h._incidence, h._around)
                        t = time.perf_counter()
                        h._pose_strands(T, surface)
                        t1 = time.perf_counter()
                        h._pose_strands(T, None)
                        cost["settle"].append(2 * t1 - t - time.perf_counter())
                    pts = next(x for x in layers if x.name == "hair").points[::4]
                    k, deepest = inside_share(h, layers, pts[:, 1:].reshape(-1, 3))
                    stretch = np.linalg.norm(np.diff(pts, axis=1), axis=2) / np.maximum(rest_len[h.hair.region < 5][::4], 1e-9)
                    r[0], r[1] = r[0] + k, r[1] + pts[:, 1:].size // 3
                    r[2], r[3] = max(r[2], deepest), max(r[3], float(np.percentile(stretch, 99.5)))
        h.hair_weights = follow
    out = {k: {mode: {"inside_percent": round(100 * v[0] / max(v[1], 1), 3), "deepest_mm": round(1e3 * v[2], 1),
                      "stretch_p995": round(v[3], 3)} for mode, v in r.items()} for k, r in sorted(rows.items())}
    pooled = {mode: round(100 * sum(r[mode][0] for r in rows.values()) / sum(r[mode][1] for r in rows.values()), 3)
              for mode in ("rigid", "follow", "settled")}
    print(json.dumps({"bench": "hair_motion", "subjects": args.subjects, "stride": args.stride,
                      "inside_percent_pooled": pooled,
                      "pose_ms_median": {k: round(1e3 * float(np.median(v)), 1) for k, v in cost.items()},
                      "rows": out}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
