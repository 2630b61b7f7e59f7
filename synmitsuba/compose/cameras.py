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
    side = np.cross(s.target - s.eye, [0.0, 1.0, 0.0])
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


@dataclass
class CameraConfig(Params):
    count: int = spec(4, POSITIVE, doc="views per scene")
    mode: str = spec("shell", Choice(("shell", "ring")), doc="ring: uniform azimuths around one subject (NeRF)")
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


def _smooth_noise(rng: np.random.Generator, n: int, dims: int) -> np.ndarray:
    """(n, dims) smooth noise in about [-1, 1]: three sinusoids of random frequency and phase."""
    t = np.linspace(0, 1, n)[:, None, None]
    freq = rng.uniform(0.5, 2.5, (1, dims, 3))
    phase = rng.uniform(0, 2 * np.pi, (1, dims, 3))
    return np.sin(2 * np.pi * freq * t + phase).sum(-1) / 3


@dataclass
class Trajectory:
    """A camera over the clip: eye, target, up (F, 3) and K (F, 3, 3)."""

    kind: str
    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    K: np.ndarray


def _direction(azimuth: float, pitch: float) -> np.ndarray:
    """Unit vector from the target to the eye for a camera looking down by ``pitch``."""
    return np.array([np.cos(pitch) * np.sin(azimuth), np.sin(pitch), np.cos(pitch) * np.cos(azimuth)])




def trajectory(kind: str, group: Group, azimuth: float, pitch: float, distance: float, K: np.ndarray,
               cfg: CameraConfig, rng: np.random.Generator) -> Trajectory:
    """One candidate camera over the clip (angles in radians)."""
    F = len(group.centres)
    t = np.linspace(0.0, 1.0, F)[:, None]
    target = np.repeat(group.centre[None], F, 0)
    eye = np.repeat((group.centre + distance * _direction(azimuth, pitch))[None], F, 0)
    shot = _Shot(eye, target, np.repeat([[0.0, 1.0, 0.0]], F, 0), np.repeat(K[None], F, 0))
    CAMERA_MOTIONS[kind].shape(shot, group, azimuth, pitch, distance, t, cfg, rng)
    return Trajectory(kind, shot.eye, shot.target, shot.up, shot.K)


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
    lmins = np.array([l_min(group, narrow_fov(K, cfg.width, cfg.height), cfg.fit_lambda) for K in traj.K[[0, -1]]])
    if not ((dist >= lmins.max() - 1e-9) & (dist <= cfg.distance_max + 1e-9)).all():
        return False
    if not ((pitch >= cfg.pitch_deg[0] - 1e-9) & (pitch <= cfg.pitch_deg[1] + 1e-9)).all():
        return False
    for f in range(len(traj.eye)):
        if inside_boxes(traj.eye[f:f + 1], np.concatenate([object_boxes.reshape(-1, 6), group.frame_boxes[f]]))[0]:
            return False
    return True


def sample_intrinsics(cfg: CameraConfig, rng: np.random.Generator) -> np.ndarray:
    shift = rng.uniform(-cfg.principal_jitter, cfg.principal_jitter, 2) if cfg.principal_jitter else (0.0, 0.0)
    return intrinsics(rng.uniform(*cfg.hfov_deg), cfg.width, cfg.height, shift)


@dataclass
class Optics:
    """A view's lens: distortion model and coefficients, thin-lens aperture radius (metres)."""

    lens: str = "brown_conrady"
    dist: np.ndarray | None = None
    aperture_radius: float = 0.0


def sample_optics(cfg: CameraConfig, rng: np.random.Generator, Ks: np.ndarray) -> Optics:
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
    reach = max(image_radius(K, cfg.width, cfg.height) for K in Ks)
    for _ in range(40):
        if not dist.any() or reach <= 0.9 * folded_radius(cfg.lens, dist):
            break
        dist *= 0.8
    aperture = float(rng.uniform(*cfg.aperture_radius)) if any(cfg.aperture_radius) else 0.0
    return Optics(cfg.lens, dist, aperture)


def candidates(group: Group, object_boxes: np.ndarray, cfg: CameraConfig, rng: np.random.Generator) -> list:
    """Every trajectory on the shell grid that passes the bounds at every frame."""
    out = []
    az0 = rng.uniform(0, 2 * np.pi / cfg.azimuths)
    pitches = np.linspace(cfg.pitch_deg[0], cfg.pitch_deg[1], cfg.pitches + 2)[1:-1]
    for a in range(cfg.azimuths):
        for p in pitches:
            for s in range(cfg.shells):
                K = sample_intrinsics(cfg, rng)
                kind = str(rng.choice(cfg.motion))
                lo = l_min(group, narrow_fov(K, cfg.width, cfg.height), cfg.fit_lambda)
                zooms = CAMERA_MOTIONS[kind].zooms
                if zooms:
                    lo *= max(1.0, 1.0 / cfg.zoom[0])
                hi = cfg.distance_max / (max(1.0, cfg.zoom[1]) if zooms else 1.0)
                if lo > hi:
                    continue
                dist = lo + (hi - lo) * (s + rng.uniform(0.1, 0.9)) / cfg.shells
                pitch = np.radians(p + rng.uniform(-0.4, 0.4) * np.diff(cfg.pitch_deg)[0] / (cfg.pitches + 1))
                traj = trajectory(kind, group, az0 + 2 * np.pi * a / cfg.azimuths, pitch, dist, K, cfg, rng)
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


def choose_views(scores: np.ndarray, azimuths: np.ndarray, count: int, tolerance: float) -> list[int]:
    """Indices of ``count`` views: the best score first, then repeatedly the candidate within
    ``tolerance`` of the best that is farthest in azimuth from the chosen ones (ties: score)."""
    order = np.argsort(-scores, kind="stable")
    pool = [i for i in order if scores[i] >= scores[order[0]] - tolerance]
    if len(pool) < count:
        pool = list(order)
    chosen = [pool[0]]
    while len(chosen) < min(count, len(pool)):
        rest = [i for i in pool if i not in chosen]
        gap = [min(abs((azimuths[i] - azimuths[j] + np.pi) % (2 * np.pi) - np.pi) for j in chosen) for i in rest]
        best = max(range(len(rest)), key=lambda k: (round(gap[k], 6), scores[rest[k]]))
        chosen.append(rest[best])
    return chosen


class NoViewFits(ConfigError):
    """No candidate camera frames the group within the bounds (composition then tightens the group)."""


def check_count(found: int, cfg: CameraConfig, group: Group) -> None:
    if found == 0:
        alpha = np.radians(cfg.hfov_deg[1]) * min(1.0, cfg.height / cfg.width)
        raise NoViewFits("cameras.distance_max", cfg.distance_max,
                          f"no camera passes the bounds (L_min is at least {l_min(group, alpha, cfg.fit_lambda):.2f} m "
                          f"for this group); raise distance_max, widen pitch_deg or hfov_deg, or lower fit_lambda")
