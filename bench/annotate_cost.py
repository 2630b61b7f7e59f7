"""Annotation cost per frame (issue 8): subject labels (keypoints with visibility, amodal masks,
boxes, body parameters) and exact forward + backward flow against the render of the same view in the same run, as a share
(goal <= 15 %). A composed scene of 4 subjects; prints JSON.

    python bench/annotate_cost.py [--res 512] [--spp 16] [--views 4] [--frames 2]
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=512)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--frames", type=int, default=2)
    args = ap.parse_args(argv)
    import synmitsuba as sm
    from synmitsuba.annotate import Annotator
    from synmitsuba.annotate.flow import SequenceFlow, flow_targets
    cfg = {"environments": ["plaza"], "subjects": {"count": 4, "motions": ["walk", "idle", "wave", "jog"]},
           "cameras": {"count": args.views, "width": args.res, "height": args.res, "points": 64}}
    spec = sm.compose_scene(cfg, np.random.default_rng(3), seed=3)
    scene, placed = spec.build()
    annotator = Annotator(placed)
    flows = SequenceFlow(scene, placed)
    render_s, label_s = [], []
    targets = flow_targets(list(range(args.frames)), spec.n_frames, 1)
    for f in range(args.frames):
        for p in placed:
            p.pose_in(scene, f)
        for v in spec.views:
            t = time.perf_counter()
            sample = sm.render(scene, v.cameras[f], spp=args.spp, seed=f)
            render_s.append(time.perf_counter() - t)
            t = time.perf_counter()
            annotator.annotate(sample, scene, f, valid=v.valid)
            flows.add(sample, v.cameras, f, targets[f])
            label_s.append(time.perf_counter() - t)
    steady = slice(len(spec.views), None)  # the first frame's views compile kernels
    print(json.dumps({"subjects": len(placed), "views": len(spec.views), "resolution": args.res, "spp": args.spp,
                      "render_s_median": round(float(np.median(render_s[steady])), 3),
                      "annotate_s_median": round(float(np.median(label_s[steady])), 3),
                      "annotate_share_of_render": round(float(np.median(label_s[steady]) / np.median(render_s[steady])), 3),
                      "first_frame_annotate_s": round(float(np.mean(label_s[:len(spec.views)])), 3)}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
