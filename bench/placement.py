"""Placement that keeps its promise (issue 35): how many of a config's subjects are placed, over
N compositions drawn exactly as compose_scene draws them (environment, lighting, subjects and
their clips), in the same run by: one greedy pass at the config's group radius (what composition
did before), place_subjects with its retries (fresh picks, largest first, widening radius), and
composition's own placement (those retries, then new motions for subjects left out). The clips'
hulls are built once per composition and shared. Prints JSON.

    python bench/placement.py [--config configs/hps.yaml] [--n 20]
"""
import argparse
import json
import time
import warnings

import numpy as np


def drafts_of(cfg, seed):
    """What compose_scene draws before placing: (environment, drafts)."""
    from synmitsuba.compose.composition import _draft, checked_sources
    from synmitsuba.compose.environments import sample_lighting
    rng = np.random.default_rng(seed)
    envs, sources = checked_sources(cfg)
    env = envs[int(rng.integers(len(envs)))]
    sample_lighting(env, rng), int(rng.integers(2 ** 31))
    sc = cfg.subjects
    count = sc.count if isinstance(sc.count, int) else int(rng.integers(int(sc.count[0]), int(sc.count[1]) + 1))
    return env, [_draft(sc, sources, cfg.base, i, rng) for i in range(count)], sources


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default="configs/hps.yaml")
    ap.add_argument("--n", type=int, default=20)
    args = ap.parse_args(argv)
    from dataclasses import replace

    from synmitsuba.compose.composition import _place
    from synmitsuba.compose.environments import object_boxes
    from synmitsuba.compose.placement import place_subjects
    from synmitsuba.generate.config import load_generate_config
    cfg = load_generate_config(args.config).compose
    rows = []
    modes = {"one_pass": lambda hulls, env, boxes, drafts, sources, rng: place_subjects(
                 hulls, env.area, boxes, replace(cfg.placement, widen=1.0), rng, tries=1),
             "retries": lambda hulls, env, boxes, drafts, sources, rng: place_subjects(hulls, env.area, boxes, cfg.placement, rng),
             "compose": lambda hulls, env, boxes, drafts, sources, rng: _place(list(drafts), env, boxes, cfg, sources, rng)}
    for seed in range(args.n):
        env, drafts, sources = drafts_of(cfg, seed)
        hulls, boxes = [d.hulls for d in drafts], object_boxes(env)[:, [0, 2, 3, 5]]
        row = {"seed": seed, "environment": env.name, "asked": len(drafts)}
        for name, place in modes.items():
            t = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                placed = place(hulls, env, boxes, drafts, sources, np.random.default_rng([seed, 1]))
            row[name] = {"placed": len(placed), "seconds": round(time.perf_counter() - t, 3)}
        rows.append(row)
    full = {k: sum(r[k]["placed"] == r["asked"] for r in rows) / len(rows) for k in modes}
    out = {"config": args.config, "compositions": len(rows), "all_placed_share": full,
           "mean_seconds": {k: float(np.mean([r[k]["seconds"] for r in rows])) for k in modes},
           "short": [r for r in rows if min(r[k]["placed"] for k in modes) < r["asked"]]}
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
