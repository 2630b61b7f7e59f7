"""The frames of a scene, rendered and labelled: ``render_sequence`` takes any ``SceneSpec``
(``sm.compose_scene`` or a scene file's ``sm.scene_spec``) and yields each frame's samples.

    for frame, view, sample in sm.render_sequence(spec, frames=range(0, 60, 10), spp=16, seed=3):
        sm.write_sample(sample, f"out/{view}_{frame:04d}")
"""
from __future__ import annotations

import numpy as np

from synmitsuba.annotate.flow import SequenceFlow, flow_targets
from synmitsuba.annotate.records import Annotator
from synmitsuba.annotate.smplx_fit import SMPLXOptions, fit_subject
from synmitsuba.compose.backdrop import centre_backdrop, view_projection_point
from synmitsuba.compose.spec import SceneSpec
from synmitsuba.engine.build import settle_frame_memory
from synmitsuba.errors import ConfigError
from synmitsuba.motion_blur import Exposure, blurred_rgbs
from synmitsuba.rendering.passes import render
from synmitsuba.schema import POSITIVE, Number
from synmitsuba.rendering.photo import Photo, develop
from synmitsuba.seeds import photo_rng


def _project(scene, view) -> None:
    """An HDRI backdrop projected from above the view's camera (``compose.backdrop``)."""
    centre_backdrop(scene, view_projection_point(view.cameras))


def _backdrop_meta(scene) -> dict:
    dome = getattr(scene.environment, "dome", None)
    return {} if dome is None else {"backdrop_centre": [float(c) for c in dome.centre]}


def render_sequence(spec: SceneSpec, frames=None, views=None, spp: int = 16, seed: int = 0, annotate: bool = True,
                    body_models: SMPLXOptions | None = None, flow: str | int = "rendered", shutter: float = 0.0,
                    subframes: int = 8, photo: Photo | None = None, **render_args):
    """Yield ``(frame, view name, Sample)`` for every frame (default all) and view (default
    all) of a scene (composed or a scene file's), frame by frame; subjects move in place (vertices and hair
    curves), so no frame after the first reloads the Mitsuba scene. The sample of frame f
    is rendered with seed ``seed + f``; its meta holds the frame, view, camera motion kind
    and each subject's occlusion, in-view share and validity in that view; with ``annotate``
    its ``subjects`` hold each subject's labels (``synmitsuba.annotate``: keypoints and their
    visibility, amodal mask, boxes, body parameters in world and camera frames; with
    ``body_models`` enabled, SMPL-X (and SMPL) parameters fitted to each subject over these
    frames before the first is rendered) and exact flow: ``flow="rendered"`` to the previous
    and next frame of ``frames`` (the samples flow pairs with), an int k to clip frames f - k
    and f + k; the targets are in the meta's ``flow_frames``. ``shutter`` > 0 (the exposure, a
    share of the frame interval: 0.5 is a 180 degree shutter) blurs the RGB with motion:
    ``subframes`` renders across the exposure (``motion_blur.blurred_rgbs``); every label stays the one at
    the exposure centre, frame f. ``photo`` develops the RGB into a photo (``rendering.photo``:
    exposure, white balance, sensor noise, JPEG; noise seeded per frame and view), keeping the
    rendered radiance as ``rgb_clean``."""
    if not isinstance(spec, SceneSpec):
        raise ConfigError("spec", type(spec).__name__, "give a SceneSpec (sm.compose_scene or SceneSpec.from_json)")
    names = [v.name for v in spec.views] if views is None else [spec.view(n).name for n in views]
    frames = range(spec.n_frames) if frames is None else frames
    for f in frames:
        if isinstance(f, bool) or not isinstance(f, (int, np.integer)) or not 0 <= f < spec.n_frames:
            raise ConfigError("frames", f, f"give frame indices in [0, {spec.n_frames - 1}]")
    targets = flow_targets(list(frames), spec.n_frames, flow)
    shutter = Number(0, 1)("shutter", shutter)
    subframes = POSITIVE("subframes", subframes)
    scene, placed = spec.build()
    if annotate and body_models is not None:
        for p in placed:
            p.fits = fit_subject(p.human, p.motion, [int(f) for f in frames], body_models)
    annotator = Annotator(placed) if annotate else None
    flows = SequenceFlow(scene, placed)
    if annotator is not None and any(targets):
        flows.prepare()
    for k, f in enumerate(frames):
        for p in placed:
            p.pose_in(scene, int(f))
        blurred = (blurred_rgbs(scene, placed, [spec.view(n) for n in names], int(f), shutter, subframes, spp, seed,
                                render_args, motion=annotate, before_view=lambda v: _project(scene, v))
                   if shutter > 0 else {})
        for name in names:
            view = spec.view(name)
            _project(scene, view)
            exposure = blurred.get(name, Exposure(None))
            sample = render(scene, view.cameras[f], spp=spp, seed=seed + int(f), rgb=exposure.rgb,
                            denoise_guides=exposure.guides, dome_cameras=exposure.cameras, **render_args)
            if shutter > 0:
                sample.meta.update(shutter=shutter, subframes=min(subframes, spp))
            _camera_effects(sample, exposure, photo, photo_rng(seed + int(f), names.index(name)))
            sample.meta.update(_backdrop_meta(scene))
            sample.meta.update(frame=int(f), view=name, camera_motion=view.kind,
                               subjects=[{"instance": s.instance, "occlusion": float(o), "in_view": float(i),
                                          "valid": bool(v)} for s, o, i, v in
                                         zip(spec.subjects, view.occlusion, view.in_view, view.valid)])
            if annotator is not None:
                annotator.annotate(sample, scene, int(f), valid=view.valid, visible_min=view.visible_min)
                flows.add(sample, view.cameras, int(f), targets[k])
            yield int(f), name, sample
        settle_frame_memory()


def _camera_effects(sample, exposure: Exposure, photo: Photo | None, rng) -> None:
    """The blur vectors of a motion-blurred sample, and its RGB developed into a photo (the
    rendered radiance kept as ``rgb_clean``)."""
    if exposure.motion is not None:
        sample.passes["motion_blur"] = exposure.motion
    if photo is not None:
        sample.passes["rgb_clean"] = sample.passes["rgb"]
        sample.passes["rgb"] = develop(sample.passes["rgb"], photo, rng)
        sample.meta["photo"] = photo.to_dict()
