"""Feet in procedural steps (issue 34, item 3: "the sole on the ground plane when the foot is
planted"): sampled subjects in flat shoes (or barefoot), each clip placed as composition
places it (its lowest point over the clip on the ground), retargeted two ways in the same run:
``sm.retarget_to_subject`` (planted on the subject's soles) and plain ``sm.retarget`` with the
heels' pitch (the source's root path scaled by pelvis height, what composition did before).

Per clip, from the fully posed shoe layer (or the body's lowest 5 cm barefoot), not from the
planting's own sole points: the lowest sole point per frame (median and worst: how far the
planted foot floats), the worst move in a frame of a sole point on the ground at both ends of it
(how far a planted foot slides), the feet's pitch range (heel strike to toe-off), and the
seconds each way takes. ``--mocap``: the same clips with their joints named as a CMU BVH's, so
retargeting takes them for mocap, whose soles are estimated from the ankles and toes
(``motion.contacts``). Prints JSON.

    python bench/feet.py [--subjects 4] [--motions walk,jog,run] [--seconds 1.0] [--source-root-only] [--mocap]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from reference import named_as  # noqa: E402

TOUCH = 0.002  # metres: a sole point this close to the ground is on it


def _clip(human, source, planted: bool):
    import synmitsuba as sm
    from synmitsuba.compose.subjects import with_heels
    t = time.perf_counter()
    clip = sm.retarget_to_subject(source, human) if planted else \
        with_heels(sm.retarget(source, human.skeleton), human.heels)
    return clip, time.perf_counter() - t


def _soles(human, clip) -> np.ndarray:
    """(F, V, 3) posed sole vertices (the shoes', or the body's lowest 5 cm at rest), placed as
    composition places the clip."""
    from synmitsuba.body.garments import GARMENTS
    from synmitsuba.compose.subjects import clip_bounds
    _, _, lift = clip_bounds(human, clip)
    shoe = next((p.name for p in human.parts if p.name in GARMENTS and GARMENTS[p.name].footwear), None)
    body = human.parts[0].rest
    rows = slice(None) if shoe else body[:, 1] < body[:, 1].min() + 0.05
    out = []
    for f in range(clip.n_frames):
        layers = {lay.name: lay for lay in human.pose(*clip.frame(f), resolve=False)}
        out.append(layers[shoe or "body"].vertices[rows])
    return np.stack(out) + [0.0, lift, 0.0]


def _pitch(human, clip) -> tuple[float, float]:
    """The left foot bone's pitch against its rest (degrees, toe up > 0), min and max."""
    G = clip.global_rotations()[:, human.skeleton.index("foot.L")]
    pitch = np.degrees(np.arcsin(np.clip(G[:, 1, 2], -1, 1)))
    return round(float(pitch.min()), 1), round(float(pitch.max()), 1)


def measure(seed: int, motion: str, seconds: float, ways=(False, True), mocap: bool = False) -> list[dict]:
    import synmitsuba as sm
    outfit = ["tshirt", "trousers", "sneakers"] if seed % 4 != 3 else ["tshirt", "shorts"]
    recipe = sm.sample_subject(np.random.default_rng(seed), {"outfit": outfit, "jacket": False, "texture_size": 64,
                                                             "accessories": []})
    if seed % 4 == 3:  # one subject in four barefoot
        from dataclasses import replace
        from synmitsuba.body.garments import GARMENTS
        recipe = replace(recipe, garments=[g for g in recipe.garments if not GARMENTS[g.kind].footwear])
    human = sm.build_subject(recipe)
    source = sm.procedural_motion(motion, np.random.default_rng(seed), seconds=seconds)
    source = named_as(source, "cmu") if mocap else source
    rows = []
    for planted in ways:
        clip, secs = _clip(human, source, planted)
        v = _soles(human, clip)
        low = 1000 * v[..., 1].min(1)
        down = (v[1:, :, 1] < TOUCH) & (v[:-1, :, 1] < TOUCH)
        step = np.linalg.norm((v[1:] - v[:-1])[..., [0, 2]], axis=-1)
        slide = 1000 * np.where(down, step, 0.0).max(1)
        rows.append({"seed": seed, "motion": motion, "planted": planted,
                     "shoes": [g.kind for g in recipe.garments if g.kind in ("sneakers", "boots", "dress_shoes", "sandals")],
                     "lowest_mm_median": round(float(np.median(low)), 1), "lowest_mm_max": round(float(low.max()), 1),
                     "slide_mm_max": round(float(slide.max()), 1), "slide_mm_median": round(float(np.median(slide[down.any(1)])), 1),
                     "pitch_deg": _pitch(human, clip), "seconds": round(secs, 3)})
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=4)
    ap.add_argument("--motions", default="walk,jog,run")
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--source-root-only", action="store_true",
                    help="only the plain retarget (runs on code from before retarget_to_subject)")
    ap.add_argument("--mocap", action="store_true", help="the clips with a CMU BVH's joint names (mocap to retargeting)")
    args = ap.parse_args()
    ways = (False,) if args.source_root_only else (False, True)
    rows = [r for s in range(args.subjects) for m in args.motions.split(",") for r in measure(s, m, args.seconds, ways, args.mocap)]
    summary = {}
    for planted in ways:
        mine = [r for r in rows if r["planted"] == planted]
        walks = [r for r in mine if r["motion"] == "walk"]
        summary["planted" if planted else "source_root"] = {
            "walk_lowest_mm_median": float(np.median([r["lowest_mm_median"] for r in walks])) if walks else None,
            "walk_lowest_mm_worst": max((r["lowest_mm_max"] for r in walks), default=None),
            "slide_mm_worst_by_motion": {m: max(r["slide_mm_max"] for r in mine if r["motion"] == m)
                                         for m in args.motions.split(",")},
            "seconds_median": float(np.median([r["seconds"] for r in mine]))}
    print(json.dumps({"mocap": args.mocap, "rows": rows, "summary": summary}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
