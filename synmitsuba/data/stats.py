"""What a generated dataset holds: counts and the distributions users check first (visible
fraction with the share partly hidden against the composition's target, keypoint visibility,
subject height, stature and body mass index, camera distance, pitch, height and field of view,
camera kinds and orientations, skin tone ITA, garment kinds, motions), as a dict (written as
JSON) and one matplotlib figure (PNG)."""
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
    vis_frac, dist, pitch, height, hfov, frames = [], [], [], [], [], set()
    vis_classes: collections.Counter = collections.Counter()
    kinds: collections.Counter = collections.Counter()
    valid = 0
    for stem in stems:
        with open(f"{stem}.json") as fh:
            side = json.load(fh)
        meta, cam = side.get("meta", {}), side["camera"]
        frames.add((os.path.dirname(stem), meta.get("frame")))
        R, t = np.asarray(cam["R"]), np.asarray(cam["t"])
        eye = -R.T @ t
        pitch.append(float(np.degrees(np.arcsin(-R[2, 1]))))
        height.append(float(eye[1]))
        hfov.append(float(np.degrees(2 * np.arctan(cam["width"] / 2 / np.asarray(cam["K"])[0][0]))))
        kinds[f"{meta.get('camera_motion', 'static')} {'portrait' if cam['height'] > cam['width'] else 'landscape'}"] += 1
        for rec in side.get("subjects", []):
            vis_frac.append(rec["visible_fraction"])
            valid += bool(rec.get("valid", True))
            vis_classes.update(VISIBILITY_NAMES[v] for v in rec["visibility"])
            dist.append(float(np.linalg.norm(np.asarray(rec["root_world"]) - eye)))
    subjects = [s for sc in scenes for s in sc["subjects"]]
    return {"sequences": len(scenes), "subjects": len(subjects), "frames": len(frames), "samples": len(stems),
            "views": sum(len(sc["views"]) for sc in scenes),
            "environments": dict(collections.Counter(sc["environment"] for sc in scenes)),
            "visible_fraction": vis_frac, "keypoint_visibility": dict(vis_classes),
            "subject_height_m": [s["height"] for s in subjects],
            **_body_measures([s["recipe"]["phenotypes"] for s in subjects]),
            "occlusion": occlusion_summary(vis_frac, valid, scenes),
            "camera_distance_m": dist, "camera_pitch_deg": pitch, "camera_height_m": height, "camera_hfov_deg": hfov,
            "cameras": dict(kinds),
            "skin_ita_deg": [s["recipe"]["skin"]["ita_deg"] for s in subjects],
            "garments": dict(collections.Counter(g["kind"] for s in subjects for g in s["recipe"]["garments"])),
            "motions": dict(collections.Counter(os.path.basename(s["motion"]["source"]) for s in subjects))}


def occlusion_summary(visible_fraction: list, valid: int, scenes: list[dict]) -> dict:
    """The share of subject records whose visible fraction lies in the configured partly hidden
    range (compose.occlusion.visible; [0.3, 0.8] when the scenes name none), beside the target
    share the scenes were composed for (0: none), and the share of valid records."""
    targets = {json.dumps(sc.get("config", {}).get("occlusion", {}), sort_keys=True) for sc in scenes}
    target = json.loads(targets.pop()) if len(targets) == 1 else {}
    lo, hi = target.get("visible", [0.3, 0.8])
    v = np.asarray(visible_fraction, float)
    return {"visible": [lo, hi], "target_share": target.get("share", 0.0) if target else None,
            "share": float(((v >= lo) & (v <= hi)).mean()) if len(v) else None,
            "fully_visible_share": float((v >= 0.99).mean()) if len(v) else None,
            "valid_share": valid / len(v) if len(v) else None}


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


HISTOGRAMS = ("visible_fraction", "subject_height_m", "stature_m", "bmi", "camera_distance_m", "camera_pitch_deg",
              "camera_height_m", "camera_hfov_deg", "skin_ita_deg")
BARS = ("keypoint_visibility", "cameras", "garments", "motions")


def stats_figure(stats: dict, path: str) -> str:
    """One PNG with a panel per distribution (a bare ``Figure``: no pyplot, so the process's
    matplotlib backend is left as it was)."""
    from matplotlib.figure import Figure

    from synmitsuba.io.files import atomic_path
    hists = [k for k in HISTOGRAMS if k in stats]
    bars = [k for k in BARS if k in stats]
    fig = Figure(figsize=(20, 3.5 * -(-len(hists + bars) // 5)))
    axes = fig.subplots(-(-len(hists + bars) // 5), 5)
    for ax, key in zip(axes.flat, hists + bars):
        if key in hists:
            ax.hist(stats[key], bins=20, color="#3a6ea5")
        else:
            names = sorted(stats[key])
            ax.bar(names, [stats[key][n] for n in names], color="#c46a2b")
            ax.tick_params(axis="x", rotation=45, labelsize=7)
        ax.set_title(key.replace("_", " "))
        if key == "visible_fraction" and stats.get("occlusion", {}).get("share") is not None:
            o = stats["occlusion"]
            ax.axvspan(*o["visible"], color="#c46a2b", alpha=0.15)
            target = f" (target {o['target_share']:.2f})" if o.get("target_share") else ""
            ax.set_title(f"visible fraction: {o['share']:.2f} in {o['visible']}{target}")
    for ax in list(axes.flat)[len(hists + bars):]:
        ax.set_visible(False)
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
