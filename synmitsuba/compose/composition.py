"""``compose_scene(config, rng) -> SceneSpec``: an environment with its lighting drawn, subjects
sampled and placed over their whole clips, cameras placed and scored by ray-cast occlusion.
The config is a ``ComposeConfig`` or its dict (YAML: ``configs/compose.yaml`` shows every key)."""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, replace

import numpy as np

from synmitsuba.body.eyes import EYE_BONES, GazeTarget
from synmitsuba.body.recipe import SubjectConfig, SubjectRecipe, sample_subject
from synmitsuba.body.subject import LayeredHuman, build_subject
from synmitsuba.compose import cameras as cams
from synmitsuba.compose.environments import (environment_names, keep_out_boxes, load_environment, object_boxes,
                                             sample_lighting)
from synmitsuba.compose.instances import OBJECT_INSTANCE, first_subject_instance
from synmitsuba.compose.occlusion import score_frames, score_views
from synmitsuba.compose.placement import PlacementConfig, frame_hulls, place_subjects
from synmitsuba.compose.spec import SceneSpec, ViewSpec, resolve_environment
from synmitsuba.compose.subjects import MotionSpec, SubjectSpec, aimed, clip_bounds, performed_clip
from synmitsuba.compose.visibility import VisibilityTarget, choose_for_target, lines_of_sight
from synmitsuba.errors import ConfigError, SynMitsubaWarning
from synmitsuba.motion.faces import FaceTrack
from synmitsuba.motion.hands import HandTrack
from synmitsuba.schema import AnyOf, ListOf, Nested, Number, Params, Range, Text, optional, read_yaml, spec


@dataclass
class SubjectsConfig(Params):
    count: int | list = spec(2, AnyOf((Number(1, 32, integer=True), Range(1, 32)), "give a count or [min, max] in 1..32"))
    motions: list = spec(factory=lambda: ["walk", "idle", "wave", "jog", "side_step", "gesture"],
                         check=ListOf(Text(), 1), doc="procedural kinds, .bvh/.npz files or folders of them")
    seconds: float = spec(2.0, Number(0.1, 60), doc="clip length")
    fps: float = spec(30.0, Number(1, 240))
    config: SubjectConfig | None = spec(None, optional(Nested(SubjectConfig)), doc="what sampled subjects fix")


@dataclass
class ComposeConfig(Params):
    environments: list = spec(factory=lambda: environment_names(), check=ListOf(Text(), 1),
                              doc="names in scenes/environments (or files); one is drawn per scene")
    subjects: SubjectsConfig = spec(factory=SubjectsConfig, check=Nested(SubjectsConfig))
    placement: PlacementConfig = spec(factory=PlacementConfig, check=Nested(PlacementConfig))
    cameras: cams.CameraConfig = spec(factory=cams.CameraConfig, check=Nested(cams.CameraConfig))
    occlusion: VisibilityTarget = spec(factory=VisibilityTarget, check=Nested(VisibilityTarget),
                                       doc="a share of subject records partly hidden, met by placement and views")
    base: str = spec("", doc="folder relative motion paths start from (a config file's own)")


def checked_sources(cfg: ComposeConfig, where: str = "") -> tuple[list, list[str]]:
    """The config's environments, loaded, and its motion sources with folders expanded into
    their files (sorted: the same on every machine); every name and file is checked, and errors
    name the key path under ``where`` (``compose.environments[0]``), so a run can check them
    all before any work starts."""
    from synmitsuba.motion.sources import check_motion_source, motion_files
    at = f"{where}." if where else ""
    check_framing(cfg.cameras, f"{at}cameras")
    if cfg.occlusion.on and cfg.cameras.mode == "ring":
        raise ConfigError(f"{at}occlusion.share", cfg.occlusion.share, "ring views are fixed round one subject, so no "
                          "share can be chosen for; set 0, or use cameras.mode shell or head")
    envs = [load_environment(n, f"{at}environments[{i}]") for i, n in enumerate(cfg.environments)]
    sources = []
    for i, m in enumerate(cfg.subjects.motions):
        path, key = os.path.join(cfg.base, m), f"{at}subjects.motions[{i}]"
        if os.path.isdir(path):
            files = motion_files(path)
            if not files:
                raise ConfigError(key, m, "the folder holds no .bvh or .npz files")
            sources += files
        else:
            check_motion_source(m, cfg.base, key)
            sources.append(m)
    return envs, sources


STANDING_RADIUS_M = 0.8  # box radius of a 1.5 m person standing still on a 0.4 x 0.3 m footprint


def check_framing(cfg: cams.CameraConfig, where: str = "cameras") -> None:
    """Refuse camera bounds that cannot frame even one person standing still (every
    composition would fail): the reason names distance_max and the reach it allows."""
    reach = cams.frame_reach(cfg) if cfg.mode == "shell" else np.inf
    if reach < STANDING_RADIUS_M:
        raise ConfigError(f"{where}.distance_max", cfg.distance_max,
                          f"no view can frame one standing person: at most {reach:.2f} m of the "
                          f"{STANDING_RADIUS_M} m needed fits the widest field of view at that distance; raise "
                          "distance_max or hfov_deg, or lower fit_lambda")


def _group(subjects: list[SubjectSpec], target_height: float) -> cams.Group:
    fr = np.stack([s.frames for s in subjects], 1)                         # (F, S, 4)
    h = np.array([s.height for s in subjects])
    frame_boxes = np.stack([fr[..., 0], np.zeros_like(fr[..., 0]), fr[..., 1], fr[..., 2],
                            np.broadcast_to(h, fr.shape[:2]), fr[..., 3]], -1)  # (F, S, 6)
    boxes = np.stack([np.concatenate([[s.footprint[0], 0.0, s.footprint[1]], [s.footprint[2], s.height, s.footprint[3]]])
                      for s in subjects])
    mid = lambda b: np.stack([(b[..., 0] + b[..., 2]) / 2, np.full(b.shape[:-1], target_height), (b[..., 1] + b[..., 3]) / 2], -1)  # noqa: E731
    centres = mid(fr).mean(1)
    centre = mid(np.stack([s.footprint for s in subjects])).mean(0)
    return cams.Group(centres, centre, boxes, frame_boxes)


def _camera_at(t: cams.Trajectory, f: int, cfg: cams.CameraConfig, optics: cams.Optics | None = None,
               focus_at: np.ndarray | None = None):
    """The trajectory's camera at frame f; with ``optics``, its lens, focused at the depth of
    ``focus_at`` (the subjects' centre at that frame)."""
    from synmitsuba.scene.camera import Camera
    cam = Camera.look_at(t.eye[f], t.target[f], t.up[f], width=t.width, height=t.height, K=t.K[f])
    if optics is None:
        return cam
    focused = optics.aperture_radius > 0 and focus_at is not None
    focus = max(float((cam.R @ focus_at + cam.t)[2]), 0.1) if focused else 1.0
    return Camera(cam.K, cam.R, cam.t, cam.width, cam.height, optics.lens, optics.dist, optics.aperture_radius, focus)


def _azimuth(t: cams.Trajectory, centre: np.ndarray) -> float:
    d = t.eye[0] - centre
    return float(np.arctan2(d[0], d[2]))


def compose_scene(config, rng: np.random.Generator, seed: int | None = None) -> SceneSpec:
    """Compose one scene (see the module docstring); ``seed`` is only recorded in the spec."""
    cfg = config if isinstance(config, ComposeConfig) else ComposeConfig.from_dict(config, "")
    if not isinstance(rng, np.random.Generator):
        raise ConfigError("rng", type(rng).__name__, "give a numpy.random.Generator (np.random.default_rng(seed))")
    envs, sources = checked_sources(cfg)  # every name checked before anything is drawn
    pick = int(rng.integers(len(envs)))
    name, env = cfg.environments[pick], envs[pick]
    lighting, ground_seed = sample_lighting(env, rng), int(rng.integers(2 ** 31))
    sc = cfg.subjects
    count = sc.count if isinstance(sc.count, int) else int(rng.integers(int(sc.count[0]), int(sc.count[1]) + 1))
    reach = cams.frame_reach(cfg.cameras) if cfg.cameras.mode == "shell" else np.inf
    drafts = [_draft(sc, sources, cfg.base, i, rng, reach) for i in range(count)]
    boxes = object_boxes(env)
    camera_boxes = np.concatenate([boxes, keep_out_boxes(env)])  # and where no camera may go (over a ceiling)

    def composed(shrink: float, least: int) -> SceneSpec:  # cams.NoViewFits: fewer than least views fit
        placing = cfg if shrink == 1.0 else replace(
            cfg, placement=replace(cfg.placement, group_radius=cfg.placement.group_radius * shrink))
        pool = list(drafts)  # _place draws new motions into it for subjects left out
        placements = _place(pool, env, boxes[:, [0, 2, 3, 5]], placing, sources, rng)
        placed = [pool[p.index] for p in placements]  # all, unless placement warned
        spec_ = SceneSpec(resolve_environment(name), lighting, ground_seed, _subject_specs(placed, placements, env), [],
                          len(placements[0].frames), sc.fps, [], seed, cfg.to_dict())
        spec_.build([d.human for d in placed])
        spec_.views, spec_.scored_frames = _views(spec_, camera_boxes, cfg.cameras, rng, cfg.occlusion, least,
                                                  env.backdrop)
        _direct(spec_, rng)
        return spec_
    for redraw in range(MOTION_REDRAWS + 1):
        for shrink in GROUP_SHRINK:  # while too few cameras frame the group, place it tighter
            last = redraw == MOTION_REDRAWS and shrink == GROUP_SHRINK[-1]
            try:  # the last try takes what views there are (with a warning)
                return composed(shrink, 1 if last else cfg.cameras.count)
            except cams.NoViewFits:
                if last:
                    raise
        # then the clip that covers the most ground gets a new motion
        widest = max(range(len(drafts)), key=lambda i: clip_radius(drafts[i]))
        drafts[widest] = _redraw_motion(drafts[widest], sc, sources, cfg.base, widest, rng)
    raise AssertionError("unreachable")


GROUP_SHRINK = (1.0, 0.6, 0.35)  # group radii tried, times placement.group_radius, while no camera frames the group


def _subject_specs(drafts: list, placements: list, env) -> list:
    first = first_subject_instance(OBJECT_INSTANCE + len(env.objects) - 1)
    return [SubjectSpec(d.recipe, d.motion, p.position, p.yaw_deg, first + i, p.footprint, p.frames, d.height, d.lift,
                        hands=d.hands, face=d.face) for i, (d, p) in enumerate(zip(drafts, placements))]


@dataclass
class _Draft:
    """A sampled subject before placement: its clip's per-frame hulls decide where it fits."""

    recipe: SubjectRecipe
    motion: MotionSpec
    human: LayeredHuman
    hands: HandTrack
    face: FaceTrack
    hulls: list
    height: float
    lift: float


MOTION_REDRAWS = 3  # rounds of new motions for subjects that placement left out


def _place(drafts: list, env, boxes: np.ndarray, cfg: ComposeConfig, sources: list, rng) -> list:
    """``place_subjects``, and while it leaves subjects out, those subjects' motions drawn anew
    (another source and seed: a clip that may cover less ground) and everyone placed again, up
    to ``MOTION_REDRAWS`` rounds; only the last round's shortfall is warned about."""
    cluster = cfg.occlusion.cluster if cfg.occlusion.on else 0.0
    for _ in range(MOTION_REDRAWS):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SynMitsubaWarning)
            try:
                placements = place_subjects([d.hulls for d in drafts], env.area, boxes, cfg.placement, rng,
                                            cluster=cluster)
            except ConfigError:   # not one fits (a lone subject's 10 s walk in a gallery): all drawn anew
                placements = []
        placed = {p.index for p in placements}
        if len(placed) == len(drafts):
            return placements
        for i in sorted(set(range(len(drafts))) - placed):
            drafts[i] = _redraw_motion(drafts[i], cfg.subjects, sources, cfg.base, i, rng)
    return place_subjects([d.hulls for d in drafts], env.area, boxes, cfg.placement, rng, cluster=cluster)


def _redraw_motion(d: _Draft, sc: SubjectsConfig, sources: list, base: str, i: int, rng) -> _Draft:
    source, mseed = sources[int(rng.integers(len(sources)))], int(rng.integers(2 ** 31))
    motion = MotionSpec(source, mseed, sc.seconds, sc.fps, base)
    return _drafted(d.recipe, motion, d.human, i)


def _draft(sc: SubjectsConfig, sources: list, base: str, i: int, rng, reach: float = np.inf) -> _Draft:
    """A sampled subject and clip; a clip no camera could frame (it covers more ground than
    ``reach`` allows, say a 2-second run past a 10 m distance_max) gets new motions, up to
    ``FRAMING_REDRAWS`` times: compositions that could succeed are drawn as before."""
    recipe = sample_subject(np.random.default_rng(int(rng.integers(2 ** 31))), sc.config)
    source, mseed = sources[int(rng.integers(len(sources)))], int(rng.integers(2 ** 31))
    d = _drafted(recipe, MotionSpec(source, mseed, sc.seconds, sc.fps, base), build_subject(recipe), i)
    for _ in range(FRAMING_REDRAWS):
        if clip_radius(d) <= reach:
            break
        d = _redraw_motion(d, sc, sources, base, i, rng)
    return d


FRAMING_REDRAWS = 8  # new motions drawn for a clip no camera of the config can frame


def clip_radius(d: _Draft) -> float:
    """A lower bound of the radius max_i |pv_i - p̄| of any group holding this clip, under any
    heading: half the distance between the opposite corners of its box, whose ground diagonal
    is at least the clip's ground diameter."""
    from scipy.spatial.distance import pdist
    pts = np.concatenate(d.hulls)
    pts = frame_hulls([pts])[0]  # the farthest pair are hull vertices: the same diameter, bit for bit
    diameter = float(pdist(pts).max()) if len(pts) > 1 else 0.0
    return float(np.hypot(diameter, d.height)) / 2


def _drafted(recipe: SubjectRecipe, motion: MotionSpec, human: LayeredHuman, i: int) -> _Draft:
    clip, hands, face = performed_clip(human, motion, f"subjects[{i}].motion")
    return _Draft(recipe, motion, human, hands, face, *clip_bounds(human, clip))


def _on_floor(trajs: list, group: cams.Group, backdrop, rotation_deg: float) -> list:
    """The trajectories whose backdrop projection point (the camera at the middle frame,
    ``backdrop.view_projection_point``) sees every subject's clip box on the photo's open floor
    (``Backdrop.floor_reach`` along each corner's panorama azimuth) and stands within
    ``camera_rise_m`` of the shooting height: a ground-projected photo shows floor only so far
    from where it was shot, and what stands beyond, or on it, lies flat there."""
    if backdrop is None:
        return trajs
    from synmitsuba.scene.panorama import azimuth_deg
    corners = group.boxes[:, [[0, 2], [0, 5], [3, 2], [3, 5]]].reshape(-1, 2)
    kept = []
    for t in trajs:
        eye = t.eye[len(t.eye) // 2]
        if abs(eye[1] - backdrop.height_m) > backdrop.camera_rise_m:
            continue
        d = corners - eye[[0, 2]]
        dirs = np.stack([d[:, 0], np.zeros(len(d)), d[:, 1]], -1)
        if (np.hypot(d[:, 0], d[:, 1]) <= backdrop.floor_reach(azimuth_deg(dirs, rotation_deg))).all():
            kept.append(t)
    return kept


def _views(spec_: SceneSpec, boxes: np.ndarray, cfg: cams.CameraConfig, rng,
           target: VisibilityTarget | None = None, least: int = 1, backdrop=None) -> tuple[list, list]:
    """The scene's views and the frames they were scored at; NoViewFits when fewer than
    ``least`` candidates pass the bounds (and, under a ``backdrop``, keep the subjects on the
    photo's open floor), a warning when fewer than ``cfg.count`` do."""
    group = _group(spec_.subjects, cfg.target_height)
    sizes = cams.view_sizes(cfg, cfg.count, rng)
    scene, placed = spec_.build()
    trajs = _trajectories(group, placed, boxes, cfg, rng, sizes)
    if target is not None and target.on and cfg.mode == "shell":
        trajs += lines_of_sight(group, boxes, cfg, rng, sizes)
    trajs = _on_floor(trajs, group, backdrop, getattr(spec_.lighting, "rotation_deg", 0.0))
    cams.check_count(len(trajs), cfg, group, least)
    if len(trajs) < cfg.count:
        warnings.warn(f"only {len(trajs)} of cameras.count = {cfg.count} views frame the group within the bounds; "
                      "raise cameras.distance_max or lower placement.group_radius", SynMitsubaWarning, stacklevel=2)
    frames = score_frames(spec_.n_frames, cfg.score_frames)
    at = [lambda f, t=t: (t.eye[f], _camera_at(t, f, cfg)) for t in trajs]
    scores = score_views(scene, placed, at, frames, cfg.points, rng)
    occ, seen = scores.occlusion, scores.in_view
    # worn cameras go to whoever sees the others best, not round the group
    azimuths = np.zeros(len(trajs)) if cfg.mode == "head" else np.array([_azimuth(t, group.centre) for t in trajs])
    classes = np.array([int(t.portrait) for t in trajs])
    wanted = [int(h > w) for w, h in sizes]
    if cfg.mode in FIXED_VIEWS:
        chosen = list(range(len(trajs)))
    elif target is not None and target.on:
        chosen = choose_for_target(scores.visible, seen, azimuths, cfg.count, cfg.score_tolerance, target,
                                   cfg.in_view_min, classes, wanted)
    else:
        chosen = cams.choose_views(((1 - occ) * seen).mean(1), azimuths, cfg.count, cfg.score_tolerance,
                                   classes, wanted)
    views = []
    for k, c in enumerate(chosen):
        t = trajs[c]
        valid = (occ[c] <= cfg.occlusion_max) & (seen[c] >= cfg.in_view_min)
        optics = cams.sample_optics(cfg, rng, t.K, (t.width, t.height))
        views.append(ViewSpec(f"cam{k}", t.kind, [_camera_at(t, f, cfg, optics, group.centres[f])
                                                  for f in range(spec_.n_frames)], occ[c], seen[c], valid,
                              1 - cfg.occlusion_max))
    for p in placed:
        p.pose_in(scene, 0)
    return views, frames


FIXED_VIEWS = ("ring",)  # modes whose views are all taken, unscored for choice


def _trajectories(group: cams.Group, placed: list, boxes: np.ndarray, cfg: cams.CameraConfig, rng,
                  sizes: list) -> list:
    """The candidate cameras of the config's mode: the shell grid, a ring around the first
    subject, or cameras worn on the subjects' heads (chosen like the grid's, by what they see)."""
    if cfg.mode == "ring":
        return cams.ring(group, 0, cfg, rng)
    if cfg.mode == "head":
        return cams.head_mounted([_head(p.motion) for p in placed], cfg, rng, sizes)
    return cams.candidates(group, boxes, cfg, rng, sizes)


def _head(motion) -> tuple:
    """A placed clip's eyes' midpoint (F, 3) and head bone world rotations (F, 3, 3)."""
    from synmitsuba.body.skeleton import forward_kinematics
    sk = motion.skeleton
    rotations, positions = forward_kinematics(sk, motion.rotations, motion.root_translation)  # once for both
    return positions[:, [sk.index(b) for b in EYE_BONES]].mean(1), rotations[:, sk.index(cams.HEAD_BONE)]


def _direct(spec_: SceneSpec, rng) -> None:
    """Draw where each subject looks (drawn after the views: the first view's camera is a
    target) and turn the built subjects' eyes there (their hands and faces came with their clips)."""
    scene, placed = spec_.build()
    mid = spec_.n_frames // 2
    camera = spec_.views[0].cameras[mid].center
    heads = [p.motion.joint_positions()[mid][[p.motion.skeleton.index(b) for b in EYE_BONES]].mean(0) for p in placed]
    # who wears the first view's camera, if anyone: the subject whose eyes are nearest it
    wearer = int(np.argmin([np.linalg.norm(h - camera) for h in heads])) if spec_.views[0].kind == "head" else -1
    for i, (s, p) in enumerate(zip(spec_.subjects, placed)):
        s.gaze = draw_gaze(rng, None if i == wearer else camera, heads[:i] + heads[i + 1:], p.motion.duration)
        p.motion = aimed(p.motion, s.gaze)
        p.pose_in(scene, 0)


def _at_camera(rng, camera: np.ndarray | None, others: list) -> GazeTarget:
    if camera is None:  # the camera is on this subject's own head: ahead instead
        return _ahead(rng, camera, others)
    return GazeTarget("camera", tuple(float(x) for x in camera))


def _at_subject(rng, camera: np.ndarray | None, others: list) -> GazeTarget:
    if not others:  # alone: the camera instead
        return _at_camera(rng, camera, others)
    return GazeTarget("subject", tuple(float(x) for x in others[int(rng.integers(len(others)))]))


def _ahead(rng, camera: np.ndarray | None, others: list) -> GazeTarget:
    yaw, pitch = np.clip(rng.normal(0, 12), -25, 25), np.clip(rng.normal(-4, 8), -20, 15)
    return GazeTarget("ahead", None, round(float(yaw), 3), round(float(pitch), 3), round(float(rng.uniform(1.5, 8)), 3))


# where subjects look, and how often: the first view's camera, another subject's eyes (at the
# clip's middle frame), or ahead of the head, turned up to 25 degrees, 1.5-8 m away
GAZE_DRAWS = {"camera": (0.4, _at_camera), "subject": (0.2, _at_subject), "ahead": (0.4, _ahead)}


def draw_gaze(rng: np.random.Generator, camera: np.ndarray | None, others: list, seconds: float = 2.0) -> GazeTarget:
    """A gaze target drawn by ``GAZE_DRAWS``' odds (``others`` are the other subjects' eyes),
    with glances away and back over a clip of ``seconds`` (``draw_glances``)."""
    odds = [p for p, _ in GAZE_DRAWS.values()]
    _, draw = list(GAZE_DRAWS.values())[int(rng.choice(len(odds), p=odds))]
    return replace(draw(rng, camera, others), shifts=draw_glances(rng, seconds))


FIXATION_S = (0.4, 2.5)  # how long the eyes rest on a point between saccades
GLANCE_ODDS = 0.35       # a fixation off the target (else back on it)


def draw_glances(rng: np.random.Generator, seconds: float) -> tuple:
    """Saccades over a clip: fixations of ``FIXATION_S``, each off the target (up to 12 deg aside,
    6 deg up or down) with ``GLANCE_ODDS``, else back on it."""
    shifts, t, away = [], float(rng.uniform(*FIXATION_S)) * rng.random(), False
    while t < seconds:
        go = rng.random() < GLANCE_ODDS
        if go:
            shifts.append((round(t, 4), round(float(rng.uniform(-12, 12)), 3), round(float(rng.uniform(-6, 6)), 3)))
        elif away:
            shifts.append((round(t, 4), 0.0, 0.0))
        away = go
        t += float(rng.uniform(*FIXATION_S))
    return tuple(shifts)


def load_compose_config(path: str) -> ComposeConfig:
    """A composition config from YAML (``configs/compose.yaml``); motion paths in it are taken
    from the file's folder. Every key is checked; errors name the key path."""
    data = read_yaml(path, "config file", "environments, subjects, cameras, ...")
    data.setdefault("base", os.path.dirname(os.path.abspath(path)))
    return ComposeConfig.from_dict(data, "")
