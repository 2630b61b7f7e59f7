"""Camera placement (SynBody, Camera Placement) and camera motion (BEDLAM 2.0).

Candidates lie on hemisphere shells around the group centre p̄ (at ``target_height``): a grid
of distances in [L_min, L_max], azimuths and pitches. A candidate is a whole trajectory (one
camera per frame: static, tracking, orbit, dolly_zoom or handheld) and is kept only if, at
every frame, its eye is outside every object and subject box, its pitch is in ``pitch_deg``
and its distance to p̄ lies in [L_min, L_max], with
``L_min = lambda / sin(alpha / 2) * max_i |pv_i - p̄|`` (alpha the narrower field of view,
pv_i the corners of the subjects' 3D clip boxes: footprint corners at the ground and at head
height). Occlusion of subject s in a view = the fraction of rays from the eye to points
sampled on s's body surface that first hit another instance (an object or another subject;
s's own garments and hair do not count), cast with Mitsuba on the loaded scene at
``score_frames`` frames. Views are chosen by score = mean over subjects of
(1 - occlusion) * in_view: the best first, then, among candidates within ``score_tolerance``
of the best, the one farthest in azimuth from those chosen (diversity), repeatedly.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.scene.lens import LENS_MODELS, folded_radius, image_radius
from synmitsuba.schema import Choice, ListOf, Number, Params, POSITIVE, Range, spec

@dataclass
class _Shot:
    """A camera's arrays over the clip while its motion shapes them: eye, target, up (F, 3), K (F, 3, 3)."""

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    K: np.ndarray


def _orbit(s: _Shot, group: Group, azimuth: float, pitch: float, distance: float, t, cfg, rng) -> None:
    sweep = np.radians(rng.uniform(*cfg.orbit_deg)) * rng.choice([-1, 1])
    s.eye = s.target + distance * np.stack([_direction(azimuth + sweep * u, pitch) for u in t[:, 0]])


def _tracking(s: _Shot, group: Group, azimuth: float, pitch: float, distance: float, t, cfg, rng) -> None:
    s.target = group.centres.copy()


def _dolly_zoom(s: _Shot, group: Group, azimuth: float, pitch: float, distance: float, t, cfg, rng) -> None:
    """Focal length and distance change together: the group keeps its size."""
    scale = 1 + (rng.uniform(*cfg.zoom) - 1) * t
    s.K = s.K.copy()
    s.K[:, 0, 0] *= scale[:, 0]
    s.K[:, 1, 1] *= scale[:, 0]
    s.eye = s.target + (s.eye - s.target) * scale


def _handheld(s: _Shot, group: Group, azimuth: float, pitch: float, distance: float, t, cfg, rng) -> None:
    F = len(t)
    s.eye = s.eye + cfg.shake_m * _smooth_noise(rng, F, 3)
    s.target = s.target + distance * np.tan(np.radians(cfg.shake_deg)) * _smooth_noise(rng, F, 3)
    roll = np.radians(cfg.shake_deg) * _smooth_noise(rng, F, 1)[:, 0]
    side = np.cross(s.target - s.eye, s.up)
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    s.up = np.cos(roll)[:, None] * s.up + np.sin(roll)[:, None] * side


@dataclass(frozen=True)
class CameraMotion:
    """A camera motion: ``shape(shot, group, azimuth, pitch, distance, t (F, 1) in [0, 1], cfg,
    rng)`` moves a static shot in place; ``zooms``: its focal length grows over the clip, so
    the distances it may start from are narrowed by ``cfg.zoom``."""

    shape: Callable
    zooms: bool = False


# A new camera motion is one entry here (CameraConfig.motion accepts every name).
CAMERA_MOTIONS: dict[str, CameraMotion] = {
    "static": CameraMotion(lambda *args: None), "tracking": CameraMotion(_tracking), "orbit": CameraMotion(_orbit),
    "dolly_zoom": CameraMotion(_dolly_zoom, zooms=True), "handheld": CameraMotion(_handheld),
}
MOTIONS = tuple(CAMERA_MOTIONS)
MODES = ("shell", "ring", "head")


@dataclass
class CameraConfig(Params):
    count: int = spec(4, POSITIVE, doc="views per scene")
    mode: str = spec("shell", Choice(MODES), doc="ring: uniform azimuths around one subject (NeRF); head: worn "
                     "on subjects' heads, looking ahead (egocentric)")
    width: int = spec(320, POSITIVE)
    height: int = spec(240, POSITIVE)
    hfov_deg: list = spec(factory=lambda: [30.0, 90.0], check=Range(5, 150), doc="horizontal field of view range")
    principal_jitter: float = spec(0.0, Number(0, 0.25), doc="max principal-point shift, fraction of the image size")
    pitch_deg: list = spec(factory=lambda: [-5.0, 30.0], check=Range(-89, 89), doc="down is positive")
    distance_max: float = spec(10.0, Number(0.1, 1000), doc="L_max, metres")
    fit_lambda: float = spec(1.0, Number(0.1, 10), doc="lambda in L_min: larger keeps subjects further inside")
    target_height: float = spec(0.9, Number(0, 3), doc="height of the point cameras look at, metres")
    motion: list = spec(factory=lambda: ["static"], check=ListOf(Choice(CAMERA_MOTIONS), 1), doc="kinds drawn per view")
    shells: int = spec(4, POSITIVE, doc="candidate distances")
    azimuths: int = spec(24, POSITIVE, doc="candidate azimuths")
    pitches: int = spec(3, POSITIVE, doc="candidate pitches")
    points: int = spec(128, POSITIVE, doc="occlusion rays per subject and frame")
    score_frames: int = spec(4, POSITIVE, doc="frames the occlusion is scored at")
    occlusion_max: float = spec(0.8, Number(0, 1), doc="above it a subject is not valid in that view")
    in_view_min: float = spec(0.3, Number(0, 1), doc="below it (share of its points inside the image) not valid")
    score_tolerance: float = spec(0.1, Number(0, 1), doc="how far below the best view a diverse view may score")
    ring_distance: float = spec(3.0, Number(0.1, 100), doc="ring: metres from the subject")
    ring_pitch_deg: float = spec(10.0, Number(-89, 89))
    orbit_deg: list = spec(factory=lambda: [30.0, 90.0], check=Range(0, 360), doc="orbit: sweep over the clip")
    zoom: list = spec(factory=lambda: [0.7, 1.4], check=Range(0.2, 5), doc="dolly_zoom: final/initial focal length")
    shake_m: float = spec(0.03, Number(0, 1), doc="handheld: position noise amplitude, metres")
    shake_deg: float = spec(1.0, Number(0, 10), doc="handheld: rotation noise amplitude, degrees")
    lens: str = spec("brown_conrady", Choice(tuple(LENS_MODELS)), doc="distortion model (OpenCV's): or fisheye")
    distortion: list = spec(factory=lambda: [0.0, 0.0], check=Range(-0.5, 0.5),
                            doc="k1 range per view (0 = off; negative: barrel)")
    distortion_k2: list = spec(factory=lambda: [0.0, 0.0], check=Range(-0.2, 0.2), doc="k2 range per view")
    tangential: float = spec(0.0, Number(0, 0.01), doc="brown_conrady: max |p1|, |p2| per view")
    aperture_radius: list = spec(factory=lambda: [0.0, 0.0], check=Range(0, 0.1),
                                 doc="thin-lens aperture radius range, metres (0 = all in focus); focus on the subjects")
    portrait: float = spec(0.0, Number(0, 1), doc="share of views in portrait (width and height swapped)")
    framing_max: float = spec(1000.0, Number(1, 1000), doc="a view stands at most this many times L_min from the "
                              "group: with a wide hfov_deg range, narrow and wide lenses frame the group alike")
    height_m: list = spec(factory=lambda: [0.0, 1000.0], check=Range(0, 1000),
                          doc="camera height above the ground at every frame, metres")
    head_pitch_deg: list = spec(factory=lambda: [10.0, 35.0], check=Range(-60, 89),
                                doc="head mode: how far below the head's forward the camera looks")
    head_offset_m: float = spec(0.12, Number(0.05, 1), doc="head mode: camera in front of the eyes, metres")


@dataclass
class Group:
    """What cameras frame: per-frame group centres (F, 3), the clip's mean centre, the
    subjects' 3D clip boxes (S, 6) and per-frame 3D boxes (F, S, 6)."""

    centres: np.ndarray
    centre: np.ndarray
    boxes: np.ndarray
    frame_boxes: np.ndarray


def intrinsics(hfov_deg: float, width: int, height: int, shift=(0.0, 0.0)) -> np.ndarray:
    f = 0.5 * width / np.tan(np.radians(hfov_deg) / 2)
    return np.array([[f, 0, width / 2 + shift[0] * width], [0, f, height / 2 + shift[1] * height], [0, 0, 1.0]])


def narrow_fov(K: np.ndarray, width: int, height: int) -> float:
    """The narrower full field of view (radians) of a centred K at this size."""
    return 2 * np.arctan(min(width / (2 * K[0, 0]), height / (2 * K[1, 1])))


def l_min(group: Group, alpha: float, lam: float) -> float:
    """SynBody's L_min = lambda / sin(alpha/2) * max_i |pv_i - p̄|."""
    b = group.boxes
    corners = np.stack(np.meshgrid([0, 3], [1, 4], [2, 5], indexing="ij"), -1).reshape(-1, 3)
    pts = np.concatenate([b[:, c] for c in corners])
    return lam / np.sin(alpha / 2) * float(np.linalg.norm(pts - group.centre, axis=1).max())


def frame_reach(cfg: CameraConfig) -> float:
    """The largest radius max_i |pv_i - p̄| any view of this config can frame: the widest field
    of view at the farthest distance any of its camera motions may start from (L_min <=
    distance_max). A group (or one clip) that reaches further cannot be framed at all."""
    sizes = ([(cfg.width, cfg.height)] if cfg.portrait < 1 else []) + ([(cfg.height, cfg.width)] if cfg.portrait else [])
    alpha = max(narrow_fov(intrinsics(cfg.hfov_deg[1], w, h), w, h) for w, h in sizes)
    reach = 0.0
    for kind in cfg.motion:
        zooms = CAMERA_MOTIONS[kind].zooms
        far = cfg.distance_max / (max(1.0, cfg.zoom[1]) * max(1.0, 1.0 / cfg.zoom[0]) if zooms else 1.0)
        reach = max(reach, far * np.sin(alpha / 2) / cfg.fit_lambda)
    return float(reach)


def _smooth_noise(rng: np.random.Generator, n: int, dims: int) -> np.ndarray:
    """(n, dims) smooth noise in about [-1, 1]: three sinusoids of random frequency and phase."""
    t = np.linspace(0, 1, n)[:, None, None]
    freq = rng.uniform(0.5, 2.5, (1, dims, 3))
    phase = rng.uniform(0, 2 * np.pi, (1, dims, 3))
    return np.sin(2 * np.pi * freq * t + phase).sum(-1) / 3


@dataclass
class Trajectory:
    """A camera over the clip: eye, target, up (F, 3), K (F, 3, 3) and its image size."""

    kind: str
    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    K: np.ndarray
    width: int = 320
    height: int = 240

    @property
    def portrait(self) -> bool:
        return self.height > self.width


def _direction(azimuth: float, pitch: float) -> np.ndarray:
    """Unit vector from the target to the eye for a camera looking down by ``pitch``."""
    return np.array([np.cos(pitch) * np.sin(azimuth), np.sin(pitch), np.cos(pitch) * np.cos(azimuth)])


STEEP_DEG = 75.0  # above this pitch the image's up is tilted with the view (world up nears the view axis)


def _up(azimuth: float, pitch: float) -> np.ndarray:
    """World up, or for a view steeper than ``STEEP_DEG`` (overhead) the unit vector square to
    the view in its vertical plane: the image's top points away from the camera's side."""
    if abs(np.degrees(pitch)) <= STEEP_DEG:
        return np.array([0.0, 1.0, 0.0])
    return np.array([-np.sin(pitch) * np.sin(azimuth), np.cos(pitch), -np.sin(pitch) * np.cos(azimuth)])




def trajectory(kind: str, group: Group, azimuth: float, pitch: float, distance: float, K: np.ndarray,
               cfg: CameraConfig, rng: np.random.Generator, size: tuple | None = None) -> Trajectory:
    """One candidate camera over the clip (angles in radians); ``size`` (width, height): the
    config's unless given (a portrait view)."""
    F = len(group.centres)
    t = np.linspace(0.0, 1.0, F)[:, None]
    target = np.repeat(group.centre[None], F, 0)
    eye = np.repeat((group.centre + distance * _direction(azimuth, pitch))[None], F, 0)
    shot = _Shot(eye, target, np.repeat(_up(azimuth, pitch)[None], F, 0), np.repeat(K[None], F, 0))
    CAMERA_MOTIONS[kind].shape(shot, group, azimuth, pitch, distance, t, cfg, rng)
    w, h = size or (cfg.width, cfg.height)
    return Trajectory(kind, shot.eye, shot.target, shot.up, shot.K, w, h)


def inside_boxes(points: np.ndarray, boxes: np.ndarray, margin: float = 0.1) -> np.ndarray:
    """(P,) whether each point lies inside any (N, 6) box grown by ``margin``."""
    if len(boxes) == 0:
        return np.zeros(len(points), bool)
    lo, hi = boxes[None, :, :3] - margin, boxes[None, :, 3:] + margin
    p = points[:, None, :]
    return np.asarray(((p >= lo) & (p <= hi)).all(-1), bool).any(1)  # type: ignore[return-value]  # numpy's stubs


def bounds_ok(traj: Trajectory, group: Group, object_boxes: np.ndarray, cfg: CameraConfig) -> bool:
    """Distance, pitch and outside-every-box at every frame."""
    rel = traj.eye - group.centre
    dist = np.linalg.norm(rel, axis=1)
    view = traj.target - traj.eye
    pitch = np.degrees(np.arcsin(-view[:, 1] / np.linalg.norm(view, axis=1)))
    lmins = np.array([l_min(group, narrow_fov(K, traj.width, traj.height), cfg.fit_lambda) for K in traj.K[[0, -1]]])
    far = min(cfg.distance_max, cfg.framing_max * lmins.min())
    if not ((dist >= lmins.max() - 1e-9) & (dist <= far + 1e-9)).all():
        return False
    if not ((traj.eye[:, 1] >= cfg.height_m[0] - 1e-9) & (traj.eye[:, 1] <= cfg.height_m[1] + 1e-9)).all():
        return False
    if not ((pitch >= cfg.pitch_deg[0] - 1e-9) & (pitch <= cfg.pitch_deg[1] + 1e-9)).all():
        return False
    for f in range(len(traj.eye)):
        if inside_boxes(traj.eye[f:f + 1], np.concatenate([object_boxes.reshape(-1, 6), group.frame_boxes[f]]))[0]:
            return False
    return True


def sample_intrinsics(cfg: CameraConfig, rng: np.random.Generator, size: tuple | None = None) -> np.ndarray:
    """K for a field of view drawn from ``hfov_deg`` (horizontal, of the image ``size``:
    (width, height), the config's unless given) and a principal point within the jitter."""
    w, h = size or (cfg.width, cfg.height)
    shift = rng.uniform(-cfg.principal_jitter, cfg.principal_jitter, 2) if cfg.principal_jitter else (0.0, 0.0)
    return intrinsics(rng.uniform(*cfg.hfov_deg), w, h, shift)


def view_sizes(cfg: CameraConfig, count: int, rng: np.random.Generator) -> list[tuple]:
    """(width, height) of ``count`` views: portrait (swapped) with odds ``cfg.portrait``;
    nothing is drawn when every view is landscape."""
    if not cfg.portrait:
        return [(cfg.width, cfg.height)] * count
    return [(cfg.height, cfg.width) if rng.random() < cfg.portrait else (cfg.width, cfg.height) for _ in range(count)]


@dataclass
class Optics:
    """A view's lens: distortion model and coefficients, thin-lens aperture radius (metres)."""

    lens: str = "brown_conrady"
    dist: np.ndarray | None = None
    aperture_radius: float = 0.0


def sample_optics(cfg: CameraConfig, rng: np.random.Generator, Ks: np.ndarray, size: tuple | None = None) -> Optics:
    """A view's optics drawn from the config's ranges; nothing is drawn for what is off, so a
    config without lens effects composes exactly as before they existed. A distortion that
    would fold back inside the image at any of the view's intrinsics ``Ks`` (F, 3, 3) is scaled
    down until it does not (a wide view takes less barrel)."""
    n = len(LENS_MODELS[cfg.lens].coefficients)
    dist = np.zeros(n)
    if any(cfg.distortion) or any(cfg.distortion_k2):
        dist[0], dist[1] = rng.uniform(*cfg.distortion), rng.uniform(*cfg.distortion_k2)
    if cfg.tangential and cfg.lens == "brown_conrady":
        dist[2:4] = rng.uniform(-cfg.tangential, cfg.tangential, 2)
    w, h = size or (cfg.width, cfg.height)
    reach = max(image_radius(K, w, h) for K in Ks)
    for _ in range(40):
        if not dist.any() or reach <= 0.9 * folded_radius(cfg.lens, dist):
            break
        dist *= 0.8
    aperture = float(rng.uniform(*cfg.aperture_radius)) if any(cfg.aperture_radius) else 0.0
    return Optics(cfg.lens, dist, aperture)


def candidates(group: Group, object_boxes: np.ndarray, cfg: CameraConfig, rng: np.random.Generator,
               sizes: list | None = None) -> list:
    """Every trajectory on the shell grid that passes the bounds at every frame; with several
    image ``sizes`` (landscape and portrait), grid cells take them in turn."""
    sizes = sorted(set(sizes or [(cfg.width, cfg.height)]))
    out = []
    az0 = rng.uniform(0, 2 * np.pi / cfg.azimuths)
    pitches = np.linspace(cfg.pitch_deg[0], cfg.pitch_deg[1], cfg.pitches + 2)[1:-1]
    cell = 0
    for a in range(cfg.azimuths):
        for p in pitches:
            for s in range(cfg.shells):
                size = sizes[cell % len(sizes)]
                cell += 1
                K = sample_intrinsics(cfg, rng, size)
                kind = str(rng.choice(cfg.motion))
                lo = l_min(group, narrow_fov(K, *size), cfg.fit_lambda)
                zooms = CAMERA_MOTIONS[kind].zooms
                if zooms:
                    lo *= max(1.0, 1.0 / cfg.zoom[0])
                hi = min(cfg.distance_max / (max(1.0, cfg.zoom[1]) if zooms else 1.0), cfg.framing_max * lo)
                if lo > hi:
                    continue
                dist = lo + (hi - lo) * (s + rng.uniform(0.1, 0.9)) / cfg.shells
                pitch = np.radians(p + rng.uniform(-0.4, 0.4) * np.diff(cfg.pitch_deg)[0] / (cfg.pitches + 1))
                traj = trajectory(kind, group, az0 + 2 * np.pi * a / cfg.azimuths, pitch, dist, K, cfg, rng, size)
                if bounds_ok(traj, group, object_boxes, cfg):
                    out.append(traj)
    return out


def ring(group: Group, subject: int, cfg: CameraConfig, rng: np.random.Generator) -> list:
    """``cfg.count`` static cameras at uniform azimuths and ``ring_distance`` around one
    subject's clip-box centre, all with the same intrinsics."""
    b = group.boxes[subject]
    centre = np.array([(b[0] + b[3]) / 2, cfg.target_height, (b[2] + b[5]) / 2])
    one = Group(np.repeat(centre[None], len(group.centres), 0), centre, group.boxes, group.frame_boxes)
    K = sample_intrinsics(cfg, rng)
    az0 = rng.uniform(0, 2 * np.pi)
    return [trajectory("static", one, az0 + 2 * np.pi * k / cfg.count, np.radians(cfg.ring_pitch_deg),
                       cfg.ring_distance, K, cfg, rng) for k in range(cfg.count)]


HEAD_BONE = "head"


def head_mounted(heads: list, cfg: CameraConfig, rng: np.random.Generator, sizes: list) -> list:
    """Candidate cameras worn on the subjects' heads, ``head_offset_m`` in front of the eyes,
    looking along the head's forward turned down by a pitch drawn from ``head_pitch_deg``
    (egocentric rigs look down to see the hands): per subject as many as there are views plus
    one, taking the image ``sizes`` in turn, so views may go to the wearers who see the others
    best. ``heads``: per subject, the eyes' midpoint (F, 3) and the head bone's world rotations
    (F, 3, 3) (forward is their z column, up their y)."""
    out = []
    sizes = sorted(set(sizes))
    for eyes, R in heads:
        forward, up = R[:, :, 2], R[:, :, 1]
        eye = eyes + cfg.head_offset_m * forward
        for k in range(cfg.count + 1):
            size = sizes[k % len(sizes)]
            pitch = np.radians(rng.uniform(*cfg.head_pitch_deg))
            view = np.cos(pitch) * forward - np.sin(pitch) * up
            K = sample_intrinsics(cfg, rng, size)
            out.append(Trajectory("head", eye, eye + view, np.sin(pitch) * forward + np.cos(pitch) * up,
                                  np.repeat(K[None], len(eye), 0), *size))
    return out


def tolerance_pools(quality: np.ndarray, tolerance: float, classes: np.ndarray, wanted: list) -> dict:
    """Per class of candidate (an image size), its candidates best ``quality`` first, cut to
    those within ``tolerance`` of the class's best unless fewer remain than slots want it."""
    pools = {}
    for c in set(wanted) | set(classes.tolist()):
        idx = np.flatnonzero(classes == c)
        order = [int(i) for i in idx[np.argsort(-quality[idx], kind="stable")]]
        pool = [i for i in order if quality[i] >= quality[order[0]] - tolerance] if order else []
        pools[c] = pool if len(pool) >= wanted.count(c) else order
    return pools


def slot_options(pools: dict, want, chosen: list) -> list:
    """The candidates left for a slot that wants class ``want``: that class's pool, or when it
    is used up, every other pool's (in class order)."""
    rest = [i for i in pools.get(want, []) if i not in chosen]
    return rest or [i for c in sorted(pools) for i in pools[c] if i not in chosen]


def azimuth_gaps(options: list, chosen: list, azimuths: np.ndarray) -> np.ndarray:
    """Each option's smallest azimuth difference to the chosen views (radians, rounded)."""
    return np.round([min(abs((azimuths[i] - azimuths[j] + np.pi) % (2 * np.pi) - np.pi) for j in chosen)
                     for i in options], 6)


def choose_views(scores: np.ndarray, azimuths: np.ndarray, count: int, tolerance: float,
                 classes: np.ndarray | None = None, wanted: list | None = None) -> list[int]:
    """Indices of ``count`` views: the best score first, then repeatedly the candidate within
    ``tolerance`` of the best that is farthest in azimuth from the chosen ones (ties: score).
    ``classes`` (V,) and ``wanted`` (one class per view) keep each view to its image size."""
    classes = np.zeros(len(scores), int) if classes is None else np.asarray(classes)
    wanted = [int(classes[0]) if len(classes) else 0] * count if wanted is None else list(wanted)
    pools = tolerance_pools(scores, tolerance, classes, wanted)
    chosen: list[int] = []
    for want in wanted:
        rest = slot_options(pools, want, chosen)
        if not rest:
            break
        if not chosen:
            chosen.append(rest[0])
            continue
        gap = azimuth_gaps(rest, chosen, azimuths)
        chosen.append(rest[max(range(len(rest)), key=lambda k: (gap[k], scores[rest[k]]))])
    return chosen


class NoViewFits(ConfigError):
    """No candidate camera frames the group within the bounds (composition then tightens the group)."""


def check_count(found: int, cfg: CameraConfig, group: Group, least: int = 1) -> None:
    """NoViewFits when fewer than ``least`` candidates pass the bounds."""
    if found < least:
        alpha = np.radians(cfg.hfov_deg[1]) * min(1.0, cfg.height / cfg.width)
        what = "no camera passes" if found == 0 else f"only {found} of the {least} views asked for pass"
        raise NoViewFits("cameras.distance_max", cfg.distance_max,
                          f"{what} the bounds (L_min is at least {l_min(group, alpha, cfg.fit_lambda):.2f} m "
                          f"for this group); raise distance_max, widen pitch_deg or hfov_deg, or lower fit_lambda")
