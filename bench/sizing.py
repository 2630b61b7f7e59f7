"""Size grading over sampled subjects: the wearers' chart sizes (chest, hips), each garment's
girth to spare by grade, what measuring a body costs, and on one body a t-shirt's shell girth
round the chest cut a size small, true and large.

    python bench/sizing.py [--subjects 60]
"""
from __future__ import annotations

import argparse
import collections
import json
import time

import numpy as np


def main() -> int:
    import synmitsuba as sm
    from synmitsuba.body.anny_model import anny_body
    from synmitsuba.body.garments import GARMENTS, GarmentParams, body_regions, build_garment
    from synmitsuba.body.sizing import CHARTS, garment_fit, measure_girths, perimeter
    from synmitsuba.scene.layers import Layer
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=60)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    sizes: dict = {"chest": collections.Counter(), "hip": collections.Counter()}
    ease, cost = collections.defaultdict(list), []
    for _ in range(args.subjects):
        recipe = sm.sample_subject(rng, {"accessories": [], "texture_size": 64})
        body = anny_body(recipe.phenotypes)
        r = body_regions(body)
        t = time.perf_counter()
        measure_girths(body.vertices, r.group, r.crotch_y, r.waist_y, r.shoulder[1] - 0.05)
        cost.append(time.perf_counter() - t)
        for layer in (Layer.TOP, Layer.BOTTOM):
            chart = CHARTS[layer]
            sizes[chart.measure][chart.name(chart.size_of(getattr(r.girths, chart.measure)))] += 1
        for g in recipe.garments:
            if g.grade is not None:
                ease[g.grade].append(garment_fit(GARMENTS[g.kind].layer, g.grade, r.girths).ease)
    human = sm.build_subject(sm.sample_subject(np.random.default_rng(7), {"outfit": ["tshirt"], "jacket": False,
                                                                          "shoes": False, "accessories": []}))
    r, y = human.regions, 0.5 * (human.regions.waist_y + human.regions.shoulder[1])
    from scipy.spatial import cKDTree
    near = cKDTree(human.body.vertices)
    shell = {}
    for grade in (-1, 0, 1):
        v = build_garment(human.body, r, human.split, GarmentParams(kind="tshirt", ease=0.005, thickness=0.003,
                                                                    grade=grade)).vertices
        keep = (r.group[near.query(v)[1]] == "torso") & (np.abs(v[:, 1] - y) < 0.01)
        shell[grade] = round(perimeter(v[keep][:, [0, 2]]), 4)
    print(json.dumps({"subjects": args.subjects, "wearer_sizes": {k: dict(sorted(c.items())) for k, c in sizes.items()},
                      "ease_cm_p5_p50_p95_n": {k: [round(100 * float(np.percentile(v, q)), 1) for q in (5, 50, 95)]
                                               + [len(v)] for k, v in sorted(ease.items())},
                      "measure_s_median": round(float(np.median(cost)), 4),
                      "tshirt_shell_chest_girth_m": {"body": round(perimeter(human.body.vertices[
                          (r.group == "torso") & (np.abs(human.body.vertices[:, 1] - y) < 0.01)][:, [0, 2]]), 4),
                          **{str(k): v for k, v in shell.items()}}}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
