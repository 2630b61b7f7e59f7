"""What a generated dataset holds: counts and the distributions users check first (visible
fraction, keypoint visibility, subject height, stature and body mass index, camera distance
and pitch, skin tone ITA, garment kinds, motions), as a dict (written as JSON) and one
matplotlib figure (PNG)."""
from __future__ import annotations

import collections
import json
import os

import numpy as np

from synmitsuba.io.listing import dataset_samples

VISIBILITY_NAMES = ("outside", "visible", "self_occluded", "occluded_by_subject", "occluded_by_object")


def _scenes(root: str) -> list[dict]:
    out = []
    for folder, _, files in os.walk(root):
        if "scene.json" in files and not folder.endswith(".partial"):
            with open(os.path.join(folder, "scene.json")) as fh:
                out.append(json.load(fh))
    return out


def dataset_stats(root: str) -> dict:
    """Counts and value lists of a dataset folder (see the module docstring)."""
    stems = dataset_samples(root)
    scenes = _scenes(root)
    vis_frac, dist, pitch, frames = [], [], [], set()
    vis_classes: collections.Counter = collections.Counter()
    for stem in stems:
        with open(f"{stem}.json") as fh:
            side = json.load(fh)
        meta, cam = side.get("meta", {}), side["camera"]
        frames.add((os.path.dirname(stem), meta.get("frame")))
        R, t = np.asarray(cam["R"]), np.asarray(cam["t"])
        eye = -R.T @ t
        pitch.append(float(np.degrees(np.arcsin(-R[2, 1]))))
        for rec in side.get("subjects", []):
            vis_frac.append(rec["visible_fraction"])
            vis_classes.update(VISIBILITY_NAMES[v] for v in rec["visibility"])
            dist.append(float(np.linalg.norm(np.asarray(rec["root_world"]) - eye)))
    subjects = [s for sc in scenes for s in sc["subjects"]]
    return {"sequences": len(scenes), "subjects": len(subjects), "frames": len(frames), "samples": len(stems),
            "views": sum(len(sc["views"]) for sc in scenes),
            "environments": dict(collections.Counter(sc["environment"] for sc in scenes)),
            "visible_fraction": vis_frac, "keypoint_visibility": dict(vis_classes),
            "subject_height_m": [s["height"] for s in subjects],
            **_body_measures([s["recipe"]["phenotypes"] for s in subjects]),
            "camera_distance_m": dist, "camera_pitch_deg": pitch,
            "skin_ita_deg": [s["recipe"]["skin"]["ita_deg"] for s in subjects],
            "garments": dict(collections.Counter(g["kind"] for s in subjects for g in s["recipe"]["garments"])),
            "motions": dict(collections.Counter(os.path.basename(s["motion"]["source"]) for s in subjects))}


def _body_measures(phenotypes: list[dict], chunk: int = 32) -> dict:
    """Each subject's stature (m, soles to crown at rest) and body mass index (kg/m^2) of its
    anny body: what ``sample_subject`` draws from population data."""
    from synmitsuba.body.anny_model import PHENOTYPES, measures
    rows = [{k: p.get(k, 0.5) for k in PHENOTYPES} for p in phenotypes]
    stature, mass = [], []
    for i in range(0, len(rows), chunk):
        s, m = measures(rows[i:i + chunk])
        stature += s.tolist()
        mass += m.tolist()
    return {"stature_m": stature, "bmi": [m / s ** 2 for s, m in zip(stature, mass)]}


def stats_figure(stats: dict, path: str) -> str:
    """One PNG with a panel per distribution (a bare ``Figure``: no pyplot, so the process's
    matplotlib backend is left as it was)."""
    from matplotlib.figure import Figure

    from synmitsuba.io.files import atomic_path
    hists = ("visible_fraction", "subject_height_m", "stature_m", "bmi", "camera_distance_m", "camera_pitch_deg",
             "skin_ita_deg")
    bars = ("keypoint_visibility", "garments", "motions")
    fig = Figure(figsize=(20, 7))
    axes = fig.subplots(2, 5)
    for ax, key in zip(axes.flat, hists + bars):
        if key in hists:
            ax.hist(stats[key], bins=20, color="#3a6ea5")
        else:
            names = sorted(stats[key])
            ax.bar(names, [stats[key][n] for n in names], color="#c46a2b")
            ax.tick_params(axis="x", rotation=45, labelsize=7)
        ax.set_title(key.replace("_", " "))
    fig.suptitle(f"{stats['sequences']} sequences, {stats['subjects']} subjects, {stats['frames']} frames, "
                 f"{stats['samples']} images")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=80, format="png")
    return path


def summarise(stats: dict, bins: int = 20) -> dict:
    """The stats with every value list as a histogram (edges, counts) and its mean: the JSON."""
    out = {}
    for k, v in stats.items():
        if isinstance(v, list):
            counts, edges = np.histogram(v, bins=bins) if v else (np.zeros(0, int), np.zeros(0))
            out[k] = {"n": len(v), "mean": float(np.mean(v)) if v else None, "edges": edges.round(6).tolist(),
                      "counts": counts.tolist()}
        else:
            out[k] = v
    return out
