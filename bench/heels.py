"""Heels in motion (issue 34, item 3): sampled subjects in a skirt or a dress and heels, each
clip placed as composition places it (its lowest point over the clip on the ground). Per
subject: the heel's height and the pitch it holds the foot at, and the ball's drop; per frame:
the lowest sole point (never under the ground), how far the heel's tip and the forefoot's sole
of the lower foot are off the ground (both planted: a heel stands on both), and the share of
the toes (the body's vertices in front of the vamp's opening) inside the shoe (winding number
over 1/2). Standing (``LayeredHuman.standing``) the tip and the forefoot are on the ground
exactly; the clip's figures say how a walk's rolling foot and a jump's pointed toes leave it.
Build cost: the pair of heels against a pair of dress shoes on the same body. Prints JSON.

    python bench/heels.py [--subjects 6] [--seconds 1.0] [--stride 2] [--full-roll]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))

MOTIONS = ("walk", "run", "squat", "jump", "turn")


def _toes(human, shoe_rest: np.ndarray) -> np.ndarray:
    """Body (split render mesh) rows of the toes: foot vertices in front of the vamp's opening."""
    from synmitsuba.body.shoes import SHOE_STYLES
    style, sk, body = SHOE_STYLES["heels"], human.skeleton, human.body
    bones = np.array([("foot" in n or "toe" in n) for n in sk.names])
    foot = bones[body.weights.argmax(1)]
    rows = []
    for side in (1.0, -1.0):
        ids = np.flatnonzero(foot & (np.sign(body.vertices[:, 0]) == side))
        z = body.vertices[ids, 2]
        start = style.throat + style.vamp / np.ptp(z) + 0.05
        rows.append(ids[z > z.min() + start * np.ptp(z)])
    return np.isin(human.split.source, np.concatenate(rows))


def measure(seed: int, motion: str, seconds: float, stride: int, full_roll: bool = False) -> dict:
    import synmitsuba as sm
    from reference import winding_numbers
    from synmitsuba.compose.subjects import clip_bounds, heeled_roll
    outfit = ["tshirt", "skirt", "heels"] if seed % 2 else ["dress", "heels"]
    recipe = sm.sample_subject(np.random.default_rng(seed), {"outfit": outfit, "jacket": False, "texture_size": 64})
    human = sm.build_subject(recipe)
    roll = 1.0 if full_roll else heeled_roll(human.heels)
    clip = sm.retarget_to_subject(sm.procedural_motion(motion, np.random.default_rng(seed), seconds=seconds, roll=roll), human)
    _, _, lift = clip_bounds(human, clip)
    part = next(p for p in human.parts if p.name == "heels")
    block = part.rest[:, 1] < -1e-6
    fore = (np.abs(part.rest[:, 1]) < 1e-9) & (human.heels[0].ahead(part.rest) > 0.03) & (part.rest[:, 0] > 0) | \
           (np.abs(part.rest[:, 1]) < 1e-9) & (human.heels[1].ahead(part.rest) > 0.03) & (part.rest[:, 0] < 0)
    toes = _toes(human, part.rest)
    rows = []
    for f in range(0, clip.n_frames, stride):
        layers = {lay.name: lay for lay in human.pose(*clip.frame(f), resolve=False)}
        v = layers["heels"].vertices + [0.0, lift, 0.0]
        side = 1.0 if v[part.rest[:, 0] > 0, 1].min() < v[part.rest[:, 0] < 0, 1].min() else -1.0
        mine = np.sign(part.rest[:, 0]) == side
        inside = winding_numbers(layers["heels"].vertices, layers["heels"].faces, layers["body"].vertices[toes])
        rows.append((v[:, 1].min(), v[block & mine, 1].min(), v[fore & mine, 1].min(), float((inside > 0.5).mean())))
    a = np.array(rows)
    pitch = np.degrees(np.arccos((np.trace(human.heels[0].rotation) - 1) / 2))
    return {"seed": seed, "motion": motion, "heel_mm": round(1000 * human.heels[0].height, 1),
            "pitch_deg": round(float(pitch), 1), "ball_drop_mm": round(1000 * human.heels[0].drop, 1),
            "lowest_mm_min": round(1000 * a[:, 0].min(), 2),
            "tip_off_ground_mm_median": round(1000 * float(np.median(a[:, 1])), 1),
            "forefoot_off_ground_mm_median": round(1000 * float(np.median(a[:, 2])), 1),
            "both_within_5mm_share": round(float(((a[:, 1] < 0.005) & (a[:, 2] < 0.005)).mean()), 3),
            "toes_inside_min": round(float(a[:, 3].min()), 4), "roll": round(roll, 3)}


def build_cost(seed: int) -> dict:
    """Seconds to build the same subject in heels and in dress shoes (the whole subject; the
    difference is the pair)."""
    import synmitsuba as sm
    out = {}
    for kind in ("dress_shoes", "heels"):
        recipe = sm.sample_subject(np.random.default_rng(seed), {"outfit": ["dress", kind], "texture_size": 64})
        t = time.perf_counter()
        sm.build_subject(recipe)
        out[kind] = round(time.perf_counter() - t, 2)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=6)
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--stride", type=int, default=2)
    ap.add_argument("--full-roll", action="store_true",
                    help="the clip rolls its feet as barefoot (what composition did before heeled_roll)")
    args = ap.parse_args()
    rows = [measure(s, m, args.seconds, args.stride, args.full_roll) for s in range(args.subjects) for m in MOTIONS]
    print(json.dumps({"rows": rows, "build_seconds": build_cost(0),
                      "lowest_mm_min": min(r["lowest_mm_min"] for r in rows),
                      "toes_inside_min": min(r["toes_inside_min"] for r in rows),
                      "both_planted_share_median": float(np.median([r["both_within_5mm_share"] for r in rows
                                                                      if r["motion"] in ("walk", "turn")]))},
                     indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
