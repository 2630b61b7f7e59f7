"""The cloth stage against skinned garments (issue 34's goals), per subject x motion clip.

Each subject wears a skirt or a dress (alternately; with a t-shirt under a skirt), or with
``--garments tshirt`` (``longsleeve``) a t-shirt (long sleeve) over trousers (both simulated, the
top against the trousers as simulated), or with ``trousers`` the trousers under a t-shirt, or with
``coat`` a coat over a long sleeve (skinned) and trousers (simulated before it), built once
for simulation (``cloth: simulated``: its skirt ``SIMULATED_DENSITY`` times finer each way) and
once skinned (``cloth: skinned``, today's mesh), and put through each motion; per clip the cloth
stage simulates the garment (``synmitsuba.simulate_cloth``) and, on the same frames, the skinned
garment is posed as before ("skinned"), and so is the simulation subject's own finer garment
("same_mesh": a stricter comparison for the folds, whose measure grows on a finer mesh).
Printed as JSON, each for the simulated and the skinned garments:
- penetration: the share of garment vertices inside the posed body (candidates within 3 cm of a
  body vertex and under 5 mm in front of its tangent plane, confirmed by a winding number over
  0.5: tests/reference.py), away from the body's own self-overlaps (where the closest body
  vertex, 2 mm out along its normal, is itself inside: a thigh run into the buttock; or where
  the closest point on the body's triangles, 2 mm past it, is: a raised thigh in the belly),
  and the deepest (exact distance to the body's triangles), worst frame per clip;
- garment against garment (a skirt over the t-shirt tucked into it, which ends 3 cm below the
  waist; a top over the trousers): the share of the skirt's vertices under the t-shirt's torso (closest point on its
  triangles, sign from that triangle's normal, within 3 cm; not where that triangle touches the
  t-shirt's open edges or its hem's fold: below its end nothing is covered) and the deepest,
  worst frame; apart from it, under its sleeves (an arm hanging against the skirt's hips, not a
  layering);
- folds: the mean squared mean curvature left after taking out its average over 7.5 cm (so the
  body-scale shape, hips and a flare's cone, drops out and folds 2-15 cm across remain), over
  the hanging cloth (not a held waistband or bodice), hem band left out; median over frames;
- rise: how far the hanging cloth's highest vertex is over the held part's lowest, worst frame
  (a skirt's hem thrown up; ``--start-at-rest`` measures the cloth started at rest, as before
  it took its held part's velocity when the clip starts);
- hem lag (walk, jog, run, turn): the lag in ms that best lines up the simulated hem's
  horizontal velocity with the same mesh skinned's (which moves with the body), both less their mean
  (the travel), searched over 0-300 ms;
- seconds per simulated frame (settling included), and the first clip's seconds (Warp loads,
  or with ``--cold-cache`` compiles, Newton's kernels).

    python bench/cloth.py [--subjects 10] [--motions walk,run,squat,jump,turn] [--seconds 1.0] [--cold-cache]
                          [--start-at-rest]
"""
import argparse
import json
import os
import sys
import tempfile
import time
from dataclasses import replace
from types import SimpleNamespace

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def closed_body(human, layers) -> np.ndarray:
    body = np.empty_like(human.body.vertices)
    body[human.split.source] = layers[0].vertices
    return body


def inside(points, body, faces) -> tuple[float, float]:
    """(share of ``points`` inside the closed body, deepest metres)."""
    import trimesh
    from reference import winding_numbers
    from scipy.spatial import cKDTree
    d, i = cKDTree(body).query(points)
    normals = trimesh.Trimesh(body, faces, process=False).vertex_normals
    near = np.flatnonzero((d < 0.03) & (np.einsum("ij,ij->i", points - body[i], normals[i]) < 0.005))
    ins = near[winding_numbers(body, faces, points[near]) > 0.5] if len(near) else near
    if len(ins):  # not where the body runs into itself (a thigh into the buttock): its own surface is inside there
        own = body[i[ins]] + 0.002 * normals[i[ins]]
        ins = ins[winding_numbers(body, faces, own) < 0.5]
    tri, keep, deep = body[faces], [], 0.0
    for k in ins:  # nor where the closest point's outside is inside the body (a raised thigh in the belly)
        near_tri = tri[(np.linalg.norm(tri - points[k], axis=2) < 0.05).any(1)]
        c = trimesh.triangles.closest_point(near_tri, np.repeat(points[k:k + 1], len(near_tri), 0))
        dist = np.linalg.norm(c - points[k], axis=1)
        j = int(dist.argmin())
        beyond = c[j] + 0.002 * (c[j] - points[k]) / max(dist[j], 1e-12)
        if winding_numbers(body, faces, beyond[None])[0] < 0.5:
            keep.append(k)
            deep = max(deep, float(dist[j]))
    ins = np.array(keep, dtype=int)
    return len(ins) / len(points), deep


INNER = ("tshirt", "longsleeve")  # worn with a skirt, a top is tucked in: it ends 3 cm below the waist
# what each measured garment is worn with, and which of that is under it (the garment-against-garment goal)
OUTFITS = {"skirt": ["tshirt", "skirt"], "dress": ["dress"], "tshirt": ["tshirt", "trousers"],
           "longsleeve": ["longsleeve", "trousers"], "trousers": ["tshirt", "trousers"],
           "coat": ["longsleeve", "trousers", "coat"]}
UNDER = {"skirt": INNER, "dress": (), "tshirt": ("trousers",), "longsleeve": ("trousers",), "trousers": (),
         "coat": ("trousers",)}
ARMS = ("upperarm", "lowerarm", "hand")


def under(points, inner, faces, skip, body=None) -> tuple[float, float]:
    """(share of ``points``, an outer garment's, under an inner garment's surface, deepest
    metres): the closest point on its triangles, sign from that triangle's normal (the garment's
    outside), for points within 3 cm; not where the closest triangle is one of ``skip`` (those
    that touch its open edges: past a hem or a waist nothing is covered), nor outside the inner
    garment closed (each opening fanned; winding number): where it folds over itself (trousers
    at a squat's hip) the closest triangle can face away from a point outside it (a held coat
    vertex "29 mm under" them, outside their volume; bench/RESULTS.md, session 97), nor inside
    ``body`` ((vertices, faces), closed), when given: those are ``inside``'s to count, or lie
    where the body runs into itself (a running thigh into the belly), the garment under them
    in there too."""
    import trimesh
    from reference import closed_shell, winding_numbers
    from scipy.spatial import cKDTree
    d, _ = cKDTree(inner).query(points)
    near = np.flatnonzero(d < 0.03)
    if not len(near):
        return 0.0, 0.0
    mesh = trimesh.Trimesh(inner, faces, process=False)
    p = points[near]
    _, cand = cKDTree(mesh.triangles_center).query(p, k=16)  # the nearest triangles' centres: candidates
    c = trimesh.triangles.closest_point(mesh.triangles[cand.ravel()], np.repeat(p, cand.shape[1], 0))
    dists = np.linalg.norm(c - np.repeat(p, cand.shape[1], 0), axis=1).reshape(cand.shape)
    best = dists.argmin(1)
    rows = np.arange(len(p))
    tri, dist, closest = cand[rows, best], dists[rows, best], c.reshape(*cand.shape, 3)[rows, best]
    below = np.einsum("ij,ij->i", p - closest, mesh.face_normals[tri]) < 0
    hit = below & ~skip[tri]
    if hit.any():
        hit[hit] = winding_numbers(*closed_shell(inner, faces), p[hit]) > 0.5
    if hit.any() and body is not None:
        hit[hit] = winding_numbers(*body, p[hit]) < 0.5
    return float(hit.sum()) / len(points), float(dist[hit].max()) if hit.any() else 0.0


def edge_faces_of(faces: np.ndarray, rest: np.ndarray, fold=()) -> np.ndarray:
    """(T,) bool: the triangles with a vertex on an open edge or on ``fold`` (a hem's fold line:
    its turned-in band's open edge is inside), seam copies welded by position."""
    from synmitsuba.body.garments import open_edges
    from synmitsuba.body.topology import weld
    rep = weld(rest)
    edge = np.zeros(len(rest), bool)
    edge[rep[np.unique(open_edges(faces, rep))]] = True
    edge[rep[np.asarray(fold, dtype=int)]] = True
    return edge[rep[faces]].any(1)


def fold_of(human, name: str) -> np.ndarray:
    """A garment's hem fold line: the shell's edge vertices its turned-in band hangs from."""
    from synmitsuba.body.garments import hem_sources
    return hem_sources(next(g for g in human.garments if g.params.kind == name))


def sleeve_faces_of(human, part) -> np.ndarray:
    """(T,) bool: a top's triangles over the arms (their centre's closest rest body vertex is an
    arm's or a hand's)."""
    from scipy.spatial import cKDTree
    _, near = cKDTree(human.body.vertices).query(part.rest[part.faces].mean(1))
    return np.isin(human.regions.group[near], ARMS)


class Surface:
    """A garment's cloth without its hem band, welded: neighbours for the curvature."""

    def __init__(self, human, name: str):
        from synmitsuba.body.topology import weld
        part = next(p for p in human.parts if p.name == name)
        mesh = next(g for g in human.garments if g.params.kind == name)
        n_cloth = len(part.rest) - mesh.hem[1]
        faces = part.faces[:len(part.faces) - mesh.hem[0]]
        rep = weld(part.rest[:n_cloth])
        self.rows, index = np.unique(rep, return_inverse=True)
        self.faces = index.reshape(-1)[faces]
        n = len(self.rows)
        from scipy import sparse
        e = np.concatenate([self.faces[:, [0, 1]], self.faces[:, [1, 2]], self.faces[:, [2, 0]]])
        adj = sparse.coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), (n, n)).tocsr()
        adj.data[:] = 1.0
        self.mean = sparse.diags(1.0 / np.asarray(adj.sum(1)).ravel()) @ adj
        from synmitsuba.cloth import CLOTH_KINDS  # the cloth that hangs (a dress's skirt, not its bodice)
        self.free = ~CLOTH_KINDS[name].held(part.rest[self.rows], human.regions)
        rest = part.rest[self.rows]
        self.low = rest[:, 1] < rest[:, 1].min() + 0.01  # the hem's ring

    def rise(self, vertices: np.ndarray) -> float:
        """Metres the hanging cloth's highest vertex is over the held part's lowest (a skirt's
        hem thrown up)."""
        x = vertices[self.rows][:, 1]
        return float(x[self.free].max() - x[~self.free].min())

    def hem(self, vertices: np.ndarray) -> np.ndarray:
        """The centroid of the hem's ring."""
        return vertices[self.rows][self.low].mean(0)

    def fold_energy(self, vertices: np.ndarray) -> float:
        """Mean squared (mean curvature less its 7.5 cm average), 1/m^2."""
        import trimesh
        from scipy.spatial import cKDTree
        x = vertices[self.rows]
        n = trimesh.Trimesh(x, self.faces, process=False).vertex_normals
        lap = self.mean @ x - x
        edge2 = np.maximum(self.mean @ np.einsum("ij,ij->i", x, x) - 2 * np.einsum("ij,ij->i", self.mean @ x, x)
                           + np.einsum("ij,ij->i", x, x), 1e-12)  # mean squared edge length per vertex
        h = 4 * np.einsum("ij,ij->i", lap, n) / edge2
        balls = cKDTree(x).query_ball_point(x, 0.075)
        local = np.array([h[b].mean() for b in balls])
        return float(np.mean(((h - local) ** 2)[self.free]))


def hem_lag_ms(hem: np.ndarray, body: np.ndarray, fps: float) -> float:
    """The lag (ms, 0-300) that best lines up the simulated hem centroid's horizontal velocity
    with the skinned hem's (which moves with the body, lag 0 by construction), both less their
    mean (the travel)."""
    vh, vb = np.diff(hem[:, [0, 2]], axis=0), np.diff(body[:, [0, 2]], axis=0)
    vh, vb = vh - vh.mean(0), vb - vb.mean(0)
    best, lag = -np.inf, 0
    for k in range(0, min(int(0.3 * fps), len(vb) - 5) + 1):
        c = float(np.sum(vb[:len(vb) - k] * vh[k:]) / max(len(vb) - k, 1))
        if c > best:
            best, lag = c, k
    return 1000.0 * lag / fps


def clip_measures(sm, humans: dict, garment: str, motion: str, seconds: float, surfaces: dict,
                  keep: str | None = None, reuse: bool = False) -> dict:
    """One clip's measures: ``humans``/``surfaces`` hold the subject built for simulation
    ("sim", its finer skirt) and as skinned ("skinned", today's mesh); "same_mesh" is the sim
    subject's own garment skinned (a stricter comparison for the folds). ``keep``: a .npz path
    the simulated garments' vertices per frame (and the simulation's seconds) are saved to, or,
    with ``reuse``, read from when it is there (measured again, not simulated)."""
    human = humans["sim"]
    clip = sm.retarget(sm.procedural_motion(motion, np.random.default_rng(0), seconds=seconds), human.skeleton)
    if keep and reuse and os.path.exists(keep):
        saved = dict(np.load(keep))
        sim_s, track = float(saved.pop("sim_s")), SimpleNamespace(frames=saved)
    else:
        t = time.perf_counter()
        track = sm.simulate_cloth(human, clip)
        sim_s = time.perf_counter() - t
        if keep:
            np.savez_compressed(keep, sim_s=sim_s, **track.frames)
    settle = int(round(sm.ClothSettings().settle_s * clip.fps))
    kinds = ("sim", "skinned", "same_mesh")
    out: dict = {k: {"inside": [], "deepest": [], "folds": [], "rise": [], "under": [], "under_deepest": [], "sleeve": [],
                     "sleeve_deepest": []} for k in kinds}
    hems: dict = {k: [] for k in kinds}
    inner = {k: next(((p.name, p.faces, edge_faces_of(p.faces, p.rest, fold_of(humans[k], p.name)),
                       sleeve_faces_of(humans[k], p)) for p in humans[k].parts if p.name in UNDER[garment]), None)
             for k in ("sim", "skinned")}
    for f in range(clip.n_frames):
        posed = {k: humans[k].pose(*clip.frame(f)) for k in ("sim", "skinned")}
        body = closed_body(human, posed["sim"])
        for kind in kinds:
            h, layers = ("skinned", posed["skinned"]) if kind == "skinned" else ("sim", posed["sim"])
            v = track.frames[garment][f] if kind == "sim" else next(la.vertices for la in layers if la.name == garment)
            share, deep = inside(v, body, human.body.faces)
            out[kind]["inside"].append(share)
            out[kind]["deepest"].append(deep)
            out[kind]["folds"].append(surfaces[h].fold_energy(v))
            out[kind]["rise"].append(surfaces[h].rise(v))
            hems[kind].append(surfaces[h].hem(v))
            if inner[h] is not None and kind != "same_mesh":
                name, faces, edge, sleeve = inner[h]
                top = next(la.vertices for la in layers if la.name == name)
                if kind == "sim" and name in track.frames:  # simulated too (trousers under a top): as simulated
                    top = track.frames[name][f]
                for key, skip in (("under", edge | sleeve), ("sleeve", edge | ~sleeve)):
                    share, deep = under(v, top, faces, skip, (body, human.body.faces))
                    out[kind][key].append(share)
                    out[kind][f"{key}_deepest"].append(deep)
    res = {"seconds_per_frame": sim_s / (clip.n_frames + settle), "sim_s": sim_s}
    for kind in kinds:
        o = out[kind]
        res[kind] = {"inside_share_worst_frame": max(o["inside"]), "deepest_m": max(o["deepest"]),
                     "fold_energy": float(np.median(o["folds"])), "rise_m": max(o["rise"])}
        if o["under"]:
            res[kind].update(under_inner_share_worst_frame=max(o["under"]), under_inner_deepest_m=max(o["under_deepest"]),
                             under_sleeve_share_worst_frame=max(o["sleeve"]), under_sleeve_deepest_m=max(o["sleeve_deepest"]))
    if motion in ("walk", "jog", "run", "turn"):
        res["sim"]["hem_lag_ms"] = hem_lag_ms(np.array(hems["sim"]), np.array(hems["same_mesh"]), clip.fps)
    return res


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--subjects", type=int, default=10)
    ap.add_argument("--motions", default="walk,run,squat,jump,turn")
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--cold-cache", action="store_true", help="compile Warp's kernels afresh (a temporary cache)")
    ap.add_argument("--first", type=int, default=0, help="the first subject (seed 100 + first): split a run over processes")
    ap.add_argument("--rows", help="append each clip's row here (JSON lines)")
    ap.add_argument("--tracks", help="save each clip's simulated garments here (SEED_GARMENT_MOTION.npz)")
    ap.add_argument("--reuse-tracks", action="store_true", help="measure the clips saved in --tracks again")
    ap.add_argument("--garments", default="skirt,dress",
                    help="skirt and dress: only the subjects wearing these (alternate subjects; skirt: the layered "
                         "ones); tshirt, longsleeve (over trousers), trousers (under a t-shirt), coat (over a long sleeve "
                         "and trousers): every subject wears them in turn")
    ap.add_argument("--summarize", nargs="+", help="print the summary of these rows files and stop")
    ap.add_argument("--start-at-rest", action="store_true",
                    help="start the cloth at rest when the clip starts (as before it took its held part's velocity)")
    args = ap.parse_args(argv)
    if args.reuse_tracks and not args.tracks:
        ap.error("--reuse-tracks: no --tracks DIR to read the saved clips from; add --tracks DIR")
    if args.summarize:
        rows = [json.loads(line) for path in args.summarize for line in open(path) if line.strip()]
        return summarize(rows, {"seconds": args.seconds, "cold_cache": False, "first_clip_s": None})
    if args.cold_cache:
        os.environ["WARP_CACHE_PATH"] = tempfile.mkdtemp(prefix="warp-cold-")
    import synmitsuba as sm
    sm.set_variant()
    if args.start_at_rest:
        import synmitsuba.cloth.simulate as simulate
        simulate._start_velocity = lambda pieces, q, *_: np.zeros_like(q, dtype=np.float32)
    rows, first_s = [], None
    for i in range(args.first, args.first + args.subjects):
        wanted = args.garments.split(",")
        tops = [g for g in wanted if g not in ("skirt", "dress")]
        garment = tops[i % len(tops)] if tops else ("skirt", "dress")[i % 2]
        if garment not in wanted:
            continue
        recipe = sm.sample_subject(np.random.default_rng(100 + i), {
            "outfit": OUTFITS[garment], "jacket": False, "shoes": True, "cloth": "simulated", "texture_size": 64})
        humans = {"sim": sm.build_subject(recipe), "skinned": sm.build_subject(replace(recipe, cloth="skinned"))}
        surfaces = {k: Surface(h, garment) for k, h in humans.items()}
        for motion in args.motions.split(","):
            keep = os.path.join(args.tracks, f"{100 + i}_{garment}_{motion}.npz") if args.tracks else None
            r = clip_measures(sm, humans, garment, motion, args.seconds, surfaces, keep, args.reuse_tracks)
            first_s = r["sim_s"] if first_s is None else first_s
            rows.append({"subject": i, "garment": garment, "motion": motion, **r})
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
            if args.rows:
                with open(args.rows, "a") as out:
                    out.write(json.dumps(rows[-1]) + "\n")
    return summarize(rows, {"seconds": args.seconds, "cold_cache": args.cold_cache, "first_clip_s": round(first_s or 0.0, 1)})


def summarize(rows: list, head: dict) -> dict:
    summary: dict = {"bench": "cloth", "clips": len(rows), "subjects": len({r["subject"] for r in rows}), **head,
                     "seconds_per_frame_median": round(float(np.median([r["seconds_per_frame"] for r in rows[1:] or rows])), 3)}
    for kind in ("sim", "skinned", "same_mesh"):
        if not all(kind in r for r in rows):
            continue  # rows written before the skinned mesh was measured apart
        summary[kind] = {
            "inside_share_median": float(np.median([r[kind]["inside_share_worst_frame"] for r in rows])),
            "inside_share_max": float(max(r[kind]["inside_share_worst_frame"] for r in rows)),
            "deepest_m_max": round(float(max(r[kind]["deepest_m"] for r in rows)), 4),
            "fold_energy_median": round(float(np.median([r[kind]["fold_energy"] for r in rows])), 2)}
        rises = [r[kind]["rise_m"] for r in rows if "rise_m" in r[kind]]  # rows before it was measured lack it
        if rises:
            summary[kind].update(rise_m_median=round(float(np.median(rises)), 3), rise_m_max=round(max(rises), 3))
        layered = [r[kind] for r in rows if "under_inner_deepest_m" in r[kind]]
        if layered:
            summary[kind].update(layered_clips=len(layered), under_inner_share_max=max(
                r["under_inner_share_worst_frame"] for r in layered), under_inner_deepest_m_max=round(
                max(r["under_inner_deepest_m"] for r in layered), 4))
            sleeves = [r for r in layered if "under_sleeve_deepest_m" in r]  # rows before sleeves were apart
            if sleeves:
                summary[kind].update(under_sleeve_share_max=max(r["under_sleeve_share_worst_frame"] for r in sleeves),
                                     under_sleeve_deepest_m_max=round(max(r["under_sleeve_deepest_m"] for r in sleeves), 4))
        lags = [r[kind]["hem_lag_ms"] for r in rows if "hem_lag_ms" in r[kind]]
        if lags:
            summary[kind]["hem_lag_ms_median"] = round(float(np.median(lags)), 1)
    for kind in ("skinned", "same_mesh"):
        if kind in summary:
            summary[f"fold_ratio_sim_over_{kind}"] = round(summary["sim"]["fold_energy_median"] /
                                                           max(summary[kind]["fold_energy_median"], 1e-12), 2)
    print(json.dumps(summary, indent=1))
    return summary


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(HERE, "..", "tests"))  # reference.py: the independent inside test
    main()
