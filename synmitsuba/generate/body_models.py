"""Body-model fits added to a dataset already generated: ``synmitsuba fit-smplx DIR``.

Each complete sequence's ``scene.json`` rebuilds its subjects and placed clips (no renderer);
every subject is fitted over the clip frames its samples show, then each sample's records gain
``smplx_world`` / ``smplx_cam`` (and ``smpl_*``), the same values a generation with ``smplx:
{enabled: true}`` writes. Samples are rewritten one at a time, each under a temporary name, so
an interrupted run leaves complete samples; rerunning redoes every sequence.
"""
from __future__ import annotations

import json
import os

from synmitsuba.annotate.records import body_model_params
from synmitsuba.annotate.smplx_fit import SMPLXOptions, fit_subject
from synmitsuba.compose.spec import SceneSpec
from synmitsuba.errors import ConfigError
from synmitsuba.generate.run import manifest_entries
from synmitsuba.io.listing import list_samples
from synmitsuba.io.exr import update_subjects
from synmitsuba.scene.camera import Camera


def fit_sequence(folder: str, options: SMPLXOptions) -> dict:
    """Fit every subject of one sequence folder and rewrite its samples; returns counts and
    the fits' error summary."""
    with open(os.path.join(folder, "scene.json")) as fh:
        spec = SceneSpec.from_json(fh.read())
    stems = list_samples(folder)
    sides = {}
    for stem in stems:
        with open(f"{stem}.json") as fh:
            sides[stem] = json.load(fh)
    frames = sorted({int(s["meta"]["frame"]) for s in sides.values()})
    placed = {p.instance: p for p in spec.placed_subjects()}
    for p in placed.values():
        p.fits = fit_subject(p.human, p.motion, frames, options)
    for stem, side in sides.items():
        camera, frame = Camera.from_dict(side["camera"]), int(side["meta"]["frame"])

        def update(records, camera=camera, frame=frame):
            for rec in records:
                p = placed.get(rec["instance"])
                if p is not None:
                    rec.update(body_model_params(p.fits, frame % p.motion.n_frames, camera))
        update_subjects(stem, update)
    fits = [f for p in placed.values() for f in p.fits.values()]
    return {"samples": len(stems), "subjects": len(placed), "frames": len(frames),
            "flagged": int(sum((~f.ok).sum() for f in fits)),
            "surface_mean_mm": max((float(f.surface_mean_mm.mean()) for f in fits), default=0.0)}


def add_body_model_fits(dataset: str, options: SMPLXOptions, progress: bool = True) -> list[dict]:
    """Fit and write body models for every complete sequence of ``dataset``."""
    if not options.enabled:
        options = SMPLXOptions.from_dict({**options.to_dict(), "enabled": True}, "smplx")
    entries = manifest_entries(os.fspath(dataset))
    if not entries:
        raise ConfigError("DATASET", dataset, "no complete sequence there (no manifest.jsonl entries); give a folder "
                          "synmitsuba generate wrote")
    from tqdm import tqdm
    out = []
    for i, e in tqdm(sorted(entries.items()), desc="sequences", unit="seq", disable=not progress):
        out.append({"sequence": i, **fit_sequence(os.path.join(dataset, e["folder"]), options)})
    return out
