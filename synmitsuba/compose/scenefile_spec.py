"""A scene file compiled to a ``SceneSpec`` like a composed scene: its objects and lights are
the stage (``compose.scenefile.static_scene``), each camera a static view, its subjects placed
as written; so it renders and is labelled by the same ``render_sequence``, and generates
through the same per-sequence task."""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.compose.scenefile import SceneDoc, SceneFile, read_scene_doc, scene_cameras, static_scene
from synmitsuba.compose.spec import SceneSpec, ViewSpec
from synmitsuba.compose.subjects import subject_specs


def load_scene_file(path: str, seed: int | None = None, subjects: bool = True) -> SceneFile:
    """Parse a YAML scene file into a Scene with its objects, lights, environment and (unless
    ``subjects=False``) its subjects posed at their first frame; plus its cameras and render
    settings. ``seed`` (default ``render.seed``) is the global seed of ``scene_spec``."""
    doc = read_scene_doc(path)
    if not subjects:
        return SceneFile(static_scene(doc, path), scene_cameras(doc), doc.render, [], os.fspath(path))
    from synmitsuba.seeds import sequence_rng
    spec_ = scene_spec(doc, path, sequence_rng(doc.render.seed if seed is None else seed, 0))
    scene, placed = spec_.build()
    return SceneFile(scene, scene_cameras(doc), doc.render, placed, os.fspath(path))


def scene_spec(doc: SceneDoc | str, path: str, rng: np.random.Generator, seed: int | None = None) -> SceneSpec:
    """The scene file as a ``SceneSpec``: its subjects built from ``rng`` (a recipe seed for
    those without one, a motion seed each) and placed as written, each camera a static view
    scored for occlusion like a composed scene's. ``seed`` is only recorded."""
    from synmitsuba.compose.cameras import CameraConfig
    from synmitsuba.compose.occlusion import score_frames, score_views
    doc = read_scene_doc(doc) if isinstance(doc, str) else doc
    path = os.path.abspath(path)
    subjects, humans = subject_specs(doc.subjects, rng, set(doc.object_instances()), os.path.dirname(path), doc.clip)
    n_frames = len(subjects[0].frames) if subjects else max(1, int(round(doc.clip.seconds * doc.clip.fps)))
    spec_ = SceneSpec(path, None, 0, subjects, [], n_frames, doc.clip.fps, [], seed, stage="scene_file")
    scene, placed = spec_.build(humans)
    cams, cfg = scene_cameras(doc), CameraConfig()
    frames = score_frames(n_frames, cfg.score_frames)
    at = [lambda f, c=c: (c.center, c) for _, c in cams]
    scores = score_views(scene, placed, at, frames, cfg.points, rng)
    occ, seen = scores.occlusion, scores.in_view
    spec_.views = [ViewSpec(name, "static", [cam] * n_frames, occ[k], seen[k],
                            (occ[k] <= cfg.occlusion_max) & (seen[k] >= cfg.in_view_min), 1 - cfg.occlusion_max)
                   for k, (name, cam) in enumerate(cams)]
    spec_.scored_frames = frames
    for p in placed:
        p.pose_in(scene, 0)
    return spec_
