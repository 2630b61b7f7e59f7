"""A probe, not a feature: a t-shirt simulated over trousers (issue 34 asks every garment
simulated; today's cloth stage simulates skirts and dresses only). The t-shirt is registered
as a cloth kind here alone (jersey, held from 4 cm under the shoulder joints up), against
one of two colliders:

- ``body``: the body alone, as the cloth stage has it for skirts;
- ``layered``: the body and the skinned trousers under the shirt (their openings capped by the
  stage's own ``_collider_parts``), as Deliver 1 asks ("layered garments against each other").

Prints one JSON line per subject x motion x collider: seconds per clip frame, the largest
distance from the skinned shirt (a hem thrown off shows here), and how much of the shirt lies
inside the trousers (signed distance by pseudonormal within 3 cm; the skinned shirt's own
figure is printed as the baseline). ``--images DIR`` writes front, side and back views,
skinned over simulated, at three frames.

    python bench/cloth_tops_probe.py --seeds 5 --motions walk --colliders body layered
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

import synmitsuba as sm
from synmitsuba.body.binding import MeshIndex
from synmitsuba.cloth import simulate as S
from synmitsuba.cloth.kinds import CLOTH_KINDS, ClothKind


def yoke(rest: np.ndarray, regions) -> np.ndarray:
    """Held: the shirt from 4 cm under the shoulder joints up, inside their width (2 cm more)."""
    sx, sy = regions.shoulder
    return (rest[:, 1] >= sy - 0.04) & (np.abs(rest[:, 0] - regions.neck_xz[0]) <= sx + 0.02)


def layered(human, clip, col: S.Collider, inner: int) -> S.Collider:
    """``col`` with the skinned garment ``inner`` (a part index) posed beside the body."""
    faces, nb = human.parts[inner].faces, len(col.at(0)[0])
    arms = S.arm_joints(human.skeleton)

    def at(frame: int):
        body, q = col.at(frame)
        return np.concatenate([body, human.pose(*clip.frame(frame))[inner].vertices]), q

    def lead(w: float):
        body, q = col.lead(w)
        return np.concatenate([body, human.pose(*S.arms_from_rest(clip.frame(0), arms, w))[inner].vertices]), q

    return S.Collider(np.concatenate([col.faces, faces + nb]), at, col.fps, col.n_frames,
                      lambda v, q: col.project(v[:nb], q), lead,
                      slippery=np.concatenate([col.slippery, np.zeros(len(faces), bool)]))


def simulate(human, clip, collider: str) -> np.ndarray:
    s = S.ClothSettings()
    garments, col = S.cloth_inputs(human, clip, s)
    (g,) = garments
    use = layered(human, clip, col, _part(human, "trousers")) if collider == "layered" else col
    q = S.drape([g.piece], use, s, names=[g.name])
    frames = {g.name: S._with_band(g, q[:, g.index])}
    return S._outside_body(frames, col, s)[g.name]


def _part(human, name: str) -> int:
    return next(k for k, p in enumerate(human.parts) if p.name == name)


def in_trousers(human, clip, shirt: np.ndarray | None) -> tuple[float, float]:
    """(deepest mm, share % deeper than 3 mm) of shirt vertices inside the skinned trousers."""
    ti, si, deepest, inside, total = _part(human, "trousers"), _part(human, "tshirt"), 0.0, 0, 0
    for f in range(clip.n_frames):
        layers = human.pose(*clip.frame(f))
        v = layers[si].vertices if shirt is None else shirt[f]
        sd = MeshIndex(layers[ti].vertices, human.parts[ti].faces).signed_distance(v)
        near = np.abs(sd) < 0.03
        deepest = max(deepest, float(-sd[near].min()) if near.any() else 0.0)
        inside, total = inside + int((near & (sd < -0.003)).sum()), total + len(v)
    return round(1000 * deepest, 1), round(100 * inside / total, 3)


def views(human, clip, shirt: np.ndarray, out: str) -> None:
    import imageio.v3 as iio
    scene = sm.Scene()
    scene.set_environment(sm.SunSky(sun_direction=(0.4, 0.8, 0.5)))
    for f in (0, clip.n_frames // 2, clip.n_frames - 1):
        rows = []
        for garments in (None, {"tshirt": shirt[f]}):
            human.add_to(scene, *clip.frame(f), garments=garments)
            c = clip.frame(f)[1] + np.array([0, 1.2, 0])
            rows.append(np.concatenate([sm.render(scene, sm.Camera.look_at(
                eye=tuple(c + np.array(e)), target=tuple(c - [0, 0.1, 0]), fov_y_deg=40, width=256, height=320),
                spp=16, seed=0).rgb for e in ((0, 0, 2.4), (2.4, 0, 0.3), (0.3, 0, -2.4))], 1))
        iio.imwrite(f"{out}_{f}.png", (np.clip(np.concatenate(rows, 0), 0, 1) ** (1 / 2.2) * 255).astype(np.uint8))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[5])
    ap.add_argument("--motions", nargs="+", default=["walk"])
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--colliders", nargs="+", default=["body", "layered"], choices=["body", "layered"])
    ap.add_argument("--images", default=None, help="folder for the views (none: no renders)")
    a = ap.parse_args(argv)
    CLOTH_KINDS["tshirt"] = ClothKind("jersey", yoke)  # this process only
    for seed in a.seeds:
        recipe = sm.sample_subject(np.random.default_rng(seed), {
            "outfit": ["tshirt", "trousers"], "jacket": False, "shoes": True, "cloth": "simulated",
            "texture_size": 256 if a.images else 64})
        human = sm.build_subject(recipe)
        for motion in a.motions:
            clip = sm.retarget(sm.procedural_motion(motion, np.random.default_rng(0), seconds=a.seconds),
                               human.skeleton)
            deep, share = in_trousers(human, clip, None)
            row = {"seed": seed, "motion": motion, "frames": clip.n_frames, "skinned_in_trousers_mm": deep,
                   "skinned_in_trousers_pct": share}
            for collider in a.colliders:
                t = time.perf_counter()
                shirt = simulate(human, clip, collider)
                cost = (time.perf_counter() - t) / clip.n_frames
                skinned = np.stack([human.pose(*clip.frame(f))[_part(human, "tshirt")].vertices
                                    for f in range(clip.n_frames)])
                deep, share = in_trousers(human, clip, shirt)
                row[collider] = {"s_per_frame": round(cost, 2), "finite": bool(np.isfinite(shirt).all()),
                                 "max_drift_m": round(float(np.linalg.norm(shirt - skinned, axis=2).max()), 3),
                                 "in_trousers_mm": deep, "in_trousers_pct": share}
                if a.images:
                    views(human, clip, shirt, f"{a.images}/tee_{seed}_{motion}_{collider}")
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
