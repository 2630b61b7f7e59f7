"""One sequence from a config and an index: what a generation executor (a local process pool or
a Ray worker) calls per task. Every seed derives from (``config.seed``, ``index``) alone, so a
sequence is the same whoever renders it, in whatever order.

    cfg = sm.SequenceConfig(scene="scenes/demo.yaml", frames=4, stride=5)
    stems = sm.render_sequence_index(cfg, index=7, out="out/dataset")   # out/dataset/seq_000007/...

A composed scene (``sm.compose_scene``) renders with ``render_sequence``:

    for frame, view, sample in sm.render_sequence(spec, frames=range(0, 60, 10), spp=16, seed=3):
        sm.write_sample(sample, f"out/{view}_{frame:04d}")
"""
from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass

import numpy as np

from synmitsuba.annotate.flow import exact_flow, geometry_copy, pixel_hits, subjects_geometry
from synmitsuba.annotate.records import Annotator
from synmitsuba.annotate.smplx_fit import SMPLXOptions, fit_subject
from synmitsuba.compose.scenefile import read_scene_doc, scene_from_doc
from synmitsuba.compose.spec import SceneSpec
from synmitsuba.compose.subjects import add_subjects
from synmitsuba.engine.build import build, settle_frame_memory
from synmitsuba.errors import ConfigError
from synmitsuba.io.exr import write_sample
from synmitsuba.rendering.passes import render
from synmitsuba.schema import POSITIVE, Number, Params, Text, optional, spec


@dataclass
class SequenceConfig(Params):
    """A sequence: the scene file whose objects, lights and cameras it uses, how many frames of
    its subjects' clips to render, and what to override."""

    scene: str = spec(check=Text(), doc="scene file (YAML); its subjects without a seed are sampled per sequence")
    frames: int = spec(4, POSITIVE, doc="frames rendered per sequence")
    stride: int = spec(1, POSITIVE, doc="clip frames between rendered frames")
    seed: int = spec(0, Number(0, 2 ** 32 - 1, integer=True), doc="global seed")
    spp: int | None = spec(None, optional(POSITIVE), doc="default: the scene file's render.spp")
    width: int | None = spec(None, optional(POSITIVE), doc="default: each camera's own")
    height: int | None = spec(None, optional(POSITIVE))


def sequence_seeds(seed: int, index: int) -> dict:
    """The seeds of sequence ``index``: subjects, motions and rendering, from (seed, index) only."""
    state = np.random.SeedSequence([int(seed), int(index)]).generate_state(3)
    return {"subjects": int(state[0]), "motions": int(state[1]), "render": int(state[2] % 2 ** 31)}


def _subject_entries(doc, seeds: dict) -> list:
    """Scene-file subjects; those without a seed get one from the sequence, so each sequence
    has its own people (explicit seeds keep the same person in every sequence)."""
    rng = np.random.default_rng(seeds["subjects"])
    picks = rng.integers(0, 2 ** 31, len(doc.subjects))
    return [e if e.seed is not None else dataclasses.replace(e, seed=int(p)) for e, p in zip(doc.subjects, picks)]


def render_sequence_index(config: SequenceConfig | dict, index: int, out: str | None = None) -> list:
    """Build and render sequence ``index`` of ``config``: the scene, its subjects (moved in
    place frame by frame), every camera at every frame. With ``out``, writes
    ``out/seq_XXXXXX/fFFFF_<camera>`` samples and returns their stems; else returns
    ``[(frame, camera name, Sample)]``."""
    cfg = config if isinstance(config, SequenceConfig) else SequenceConfig.from_dict(config, "config")
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
        raise ConfigError("index", index, "give a sequence index >= 0")
    doc = read_scene_doc(cfg.scene)  # checked in full before any building
    seeds = sequence_seeds(cfg.seed, index)
    sf = scene_from_doc(doc, cfg.scene, subjects=False)
    base = os.path.dirname(os.path.abspath(cfg.scene))
    placed = add_subjects(sf.scene, _subject_entries(doc, seeds), seed=seeds["motions"], base=base)
    spp = cfg.spp or sf.settings.spp
    folder = os.path.join(out, f"seq_{index:06d}") if out is not None else None
    results = []
    for k in range(cfg.frames):
        for s in placed:
            s.pose_in(sf.scene, s.frame + k * cfg.stride)
        for name, cam in sf.cameras:
            if cfg.width or cfg.height:
                cam = cam.resized(cfg.width or cam.width, cfg.height or cam.height)
            sample = render(sf.scene, cam, spp=spp, seed=seeds["render"] + k, max_depth=sf.settings.max_depth,
                            sampler=sf.settings.sampler, denoise=sf.settings.denoise)
            sample.meta.update(sequence=index, frame=k, camera=name)
            if folder is None:
                results.append((k, name, sample))
            else:
                stem = os.path.join(folder, f"f{k:04d}_{name}")
                write_sample(sample, stem)
                results.append(stem)
        settle_frame_memory()
    return results


def render_sequence(spec: SceneSpec, frames=None, views=None, spp: int = 16, seed: int = 0, annotate: bool = True,
                    body_models: SMPLXOptions | None = None, flow: str | int = "rendered", **render_args):
    """Yield ``(frame, view name, Sample)`` for every frame (default all) and view (default
    all) of a composed scene, frame by frame; subjects move in place (vertices and hair
    curves), so no frame after the first reloads the Mitsuba scene. The sample of frame f
    is rendered with seed ``seed + f``; its meta holds the frame, view, camera motion kind
    and each subject's occlusion, in-view share and validity in that view; with ``annotate``
    its ``subjects`` hold each subject's labels (``synmitsuba.annotate``: keypoints and their
    visibility, amodal mask, boxes, body parameters in world and camera frames; with
    ``body_models`` enabled, SMPL-X (and SMPL) parameters fitted to each subject over these
    frames before the first is rendered) and exact flow: ``flow="rendered"`` to the previous
    and next frame of ``frames`` (the samples flow pairs with), an int k to clip frames f - k
    and f + k; the targets are in the meta's ``flow_frames``."""
    if not isinstance(spec, SceneSpec):
        raise ConfigError("spec", type(spec).__name__, "give a SceneSpec (sm.compose_scene or SceneSpec.from_json)")
    names = [v.name for v in spec.views] if views is None else [spec.view(n).name for n in views]
    frames = range(spec.n_frames) if frames is None else frames
    for f in frames:
        if isinstance(f, bool) or not isinstance(f, (int, np.integer)) or not 0 <= f < spec.n_frames:
            raise ConfigError("frames", f, f"give frame indices in [0, {spec.n_frames - 1}]")
    targets = flow_targets(list(frames), spec.n_frames, flow)
    scene, placed = spec.build()
    if annotate and body_models is not None:
        for p in placed:
            p.fits = fit_subject(p.human, p.motion, [int(f) for f in frames], body_models)
    annotator = Annotator(placed) if annotate else None
    geometry, neighbours = _GeometryCache(placed), _Neighbours(scene, placed)
    for k, f in enumerate(frames):
        for p in placed:
            p.pose_in(scene, int(f))
        for name in names:
            view = spec.view(name)
            sample = render(scene, view.cameras[f], spp=spp, seed=seed + int(f), **render_args)
            sample.meta.update(frame=int(f), view=name, camera_motion=view.kind,
                               subjects=[{"instance": s.instance, "occlusion": float(o), "in_view": float(i),
                                          "valid": bool(v)} for s, o, i, v in
                                         zip(spec.subjects, view.occlusion, view.in_view, view.valid)])
            if annotator is not None:
                annotator.annotate(sample, scene, int(f), valid=view.valid)
                _add_flow(sample, scene, placed, view, int(f), targets[k], geometry, neighbours)
            yield int(f), name, sample
        settle_frame_memory()


class _GeometryCache:
    """Subjects' geometry by frame, kept for the three frames flow needs at a time."""

    def __init__(self, placed):
        self.placed, self.frames = placed, {}

    def __call__(self, frame: int):
        if frame not in self.frames:
            if len(self.frames) > 3:  # drop the frame farthest from this one
                self.frames.pop(max(self.frames, key=lambda k: abs(k - frame)))
            self.frames[frame] = subjects_geometry(self.placed, frame)
        return self.frames[frame]


class _Neighbours:
    """Plain copies of the scene held at neighbouring frames for flow's visibility tests. Three
    of them, each kept at its frame while it is still of use: frame f asks for the next and
    previous ones, and the previous one is the copy moved to it for that frame's forward flow,
    so one copy moves a frame (two did with a copy for each side: each move is a BVH rebuilt, 30-70 ms with hair)."""

    def __init__(self, scene, placed):
        self.placed, self.scene, self.copies, self.at = placed, scene, [], []

    def __call__(self, g: int, f: int):
        if not self.copies:  # all at once: every load happens on the first frame
            self.copies = [geometry_copy(self.scene) for _ in range(3)]
            for copy in self.copies:
                build(copy)
            self.at = [None] * 3
        if g not in self.at:  # move the copy whose frame lies farthest from f (or none yet)
            k = max(range(3), key=lambda k: np.inf if self.at[k] is None else abs(self.at[k] - f))
            for p in self.placed:
                p.pose_in(self.copies[k], g)
            self.at[k] = g
        return self.copies[self.at.index(g)]


def flow_targets(frames: list, n_frames: int, flow: str | int) -> list[dict]:
    """Per rendered frame, the frames its flow goes to: ``{"fwd": g, "bwd": h}`` (a side left
    out where there is none). ``"rendered"``: the next and previous entries of ``frames``; an
    int k: clip frames f + k and f - k inside the clip."""
    if flow == "rendered":
        return [{**({"fwd": int(frames[i + 1])} if i + 1 < len(frames) else {}),
                 **({"bwd": int(frames[i - 1])} if i > 0 else {})} for i in range(len(frames))]
    if isinstance(flow, bool) or not isinstance(flow, (int, np.integer)) or flow < 1:
        raise ConfigError("flow", flow, "give 'rendered' (to the neighbouring rendered frames) or a number of clip "
                          "frames >= 1")
    return [{side: int(f + s * flow) for side, s in (("fwd", 1), ("bwd", -1)) if 0 <= f + s * flow < n_frames}
            for f in frames]


def _add_flow(sample, scene, placed, view, f: int, targets: dict, geometry, neighbours) -> None:
    """Exact forward and backward flow to ``targets`` (``flow_targets``), from one cast of the
    view's pixel-centre rays; the targets go to the meta's ``flow_frames``."""
    hits = pixel_hits(scene, view.cameras[f])
    for side, g in targets.items():
        flow, flags = exact_flow(scene, view.cameras[f], view.cameras[g], geometry(f), geometry(g), neighbours(g, f),
                                 hits)
        sample.passes[f"flow_{side}"], sample.passes[f"flow_{side}_flag"] = flow, flags
    sample.meta["flow_frames"] = dict(targets)
