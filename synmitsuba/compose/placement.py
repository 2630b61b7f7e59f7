"""Whole-clip subject placement (SynBody, Scene Placement): a subject is the smallest ground box
that envelops its per-frame boxes over the whole clip; subjects are placed one at a time by grid
search over positions and yaws with zero overlap with objects and subjects already placed, a
distance constraint that keeps the group together, and a random pick among valid solutions.

Boxes on the ground are ``(x_min, z_min, x_max, z_max)`` metres.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from synmitsuba.errors import ConfigError, SynMitsubaWarning
from synmitsuba.schema import Number, Params, POSITIVE, spec


@dataclass
class PlacementConfig(Params):
    grid_step: float = spec(0.1, Number(0.01, 2.0), doc="metres between candidate positions")
    yaw_steps: int = spec(8, POSITIVE, doc="candidate headings per position (evenly spaced, random offset)")
    group_radius: float = spec(3.0, Number(0.1, 100), doc="max metres from a subject's box centre to the group's")
    margin: float = spec(0.05, Number(0, 5), doc="clearance kept around every box, metres")
    widen: float = spec(2.0, Number(1, 10), doc="when subjects do not fit, later tries widen group_radius up to "
                        "this factor before leaving any out")


def frame_hulls(xz_per_frame) -> list[np.ndarray]:
    """Per frame, the ground-plane convex hull of a subject's points (all layers): boxes under
    any yaw come from these few points exactly."""
    from scipy.spatial import ConvexHull
    out = []
    for pts in xz_per_frame:
        pts = _outer(np.asarray(pts, np.float64))
        out.append(pts[ConvexHull(pts).vertices] if len(pts) >= 3 else pts)
    return out


def _outer(pts: np.ndarray) -> np.ndarray:
    """``pts`` less those strictly inside the polygon of its extreme points in eight directions
    (Akl-Toussaint): none of them is a hull vertex, and Qhull then sorts hundreds of points, not
    a whole posed subject's tens of thousands. One coordinate array at a time (a posed subject
    with long hair has 130,000 points: 2 ms, against 30 ms as (N, 8) matrices)."""
    if len(pts) < 16:
        return pts
    x, z = np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1])
    s, q = x + z, x - z
    # the extreme points along x, x+z, z, z-x, -x, -x-z, -z, x-z: counter-clockwise, as the directions turn
    at = np.array([x.argmax(), s.argmax(), z.argmax(), q.argmin(), x.argmin(), s.argmin(), z.argmin(), q.argmax()])
    at = at[np.r_[True, at[1:] != at[:-1]]]
    poly = pts[at[:-1] if len(at) > 1 and at[-1] == at[0] else at]
    if len(poly) < 3:
        return pts
    edge = np.roll(poly, -1, 0) - poly
    inward = np.stack([-edge[:, 1], edge[:, 0]], 1)  # left of each counter-clockwise edge
    keep = np.zeros(len(pts), bool)
    for (a, b), c in zip(inward, np.einsum("ij,ij->i", inward, poly)):
        keep |= x * a + z * b - c <= 1e-9  # the margin keeps every point rounding might put on an edge
    return pts[keep]


def stack_hulls(hulls: list[np.ndarray]) -> np.ndarray:
    """(F, V, 2) per-frame hulls in one array, each padded to the longest with its own first
    point (which changes no box): what ``frame_boxes`` turns in one go."""
    if not len(hulls):
        return np.zeros((0, 1, 2))
    n = max(len(h) for h in hulls)
    return np.stack([np.concatenate([h, np.repeat(h[:1], n - len(h), 0)]) for h in hulls]).astype(np.float64)


def frame_boxes(hulls, yaw_deg: float = 0.0, offset=(0.0, 0.0)) -> np.ndarray:
    """(F, 4) per-frame ground boxes of hull points (a list of (V, 2), or ``stack_hulls``'s
    array: placement turns one subject's hulls hundreds of times) turned by ``yaw_deg`` about
    the origin (as ``Motion.moved`` turns a clip) and shifted by ``offset`` (x, z)."""
    h = hulls if isinstance(hulls, np.ndarray) else stack_hulls(hulls)
    a = np.radians(yaw_deg)
    c, s = np.cos(a), np.sin(a)
    # Motion.moved applies R_y(a) to [x, y, z]: x' = cos a x + sin a z, z' = -sin a x + cos a z
    x = h[..., 0] * c + h[..., 1] * s + offset[0]
    z = h[..., 1] * c - h[..., 0] * s + offset[1]
    return np.stack([x.min(1), z.min(1), x.max(1), z.max(1)], 1)


def envelope(boxes: np.ndarray) -> np.ndarray:
    """The smallest box enveloping (N, 4) boxes."""
    b = np.asarray(boxes).reshape(-1, 4)
    return np.array([b[:, 0].min(), b[:, 1].min(), b[:, 2].max(), b[:, 3].max()])


def overlap_area(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Overlap areas of boxes ``a`` (..., 4) and ``b`` (..., 4), broadcast."""
    w = np.minimum(a[..., 2], b[..., 2]) - np.maximum(a[..., 0], b[..., 0])
    h = np.minimum(a[..., 3], b[..., 3]) - np.maximum(a[..., 1], b[..., 1])
    return np.clip(w, 0, None) * np.clip(h, 0, None)


def _candidates(area, step: float) -> np.ndarray:
    xs = np.round(area[0] + step * np.arange(int(np.floor((area[2] - area[0]) / step + 1e-9)) + 1), 9)
    zs = np.round(area[1] + step * np.arange(int(np.floor((area[3] - area[1]) / step + 1e-9)) + 1), 9)
    return np.stack(np.meshgrid(xs, zs, indexing="ij"), -1).reshape(-1, 2)


def _valid(cands: np.ndarray, box: np.ndarray, area, obstacles: np.ndarray, centres: list, cfg: PlacementConfig):
    """Mask of candidate positions where the clip box (at the origin: ``box``) stays inside the
    area, clear of every obstacle box by the margin and near enough to the group."""
    boxes = box[None, :] + np.concatenate([cands, cands], 1)
    inside = (boxes[:, 0] >= area[0]) & (boxes[:, 1] >= area[1]) & (boxes[:, 2] <= area[2]) & (boxes[:, 3] <= area[3])
    ok = inside.copy()
    if len(obstacles):
        grown = obstacles + np.array([-1, -1, 1, 1]) * cfg.margin
        ok &= ~(overlap_area(boxes[:, None, :], grown[None, :, :]) > 0).any(1)
    if centres:
        mid = (boxes[:, :2] + boxes[:, 2:]) / 2
        ok &= np.linalg.norm(mid - np.mean(centres, 0), axis=1) <= cfg.group_radius
    return ok


PLACEMENT_TRIES = 24  # whole placements tried before subjects are left out (fresh headings and picks)


@dataclass
class Placement:
    position: tuple      # (x, z) metres: where the clip's mean root position goes
    yaw_deg: float
    footprint: np.ndarray  # (4,) whole-clip box
    frames: np.ndarray     # (F, 4) per-frame boxes
    index: int = 0         # which of the subjects asked for


def _options(hulls, cands: np.ndarray, area, obstacles: np.ndarray, placed: list, cfg: PlacementConfig,
             rng: np.random.Generator) -> list:
    """Every (yaw, position) that fits one subject now (headings evenly spaced, random offset)."""
    yaws = (rng.uniform(0, 360 / cfg.yaw_steps) + np.arange(cfg.yaw_steps) * 360 / cfg.yaw_steps) % 360 - 180
    centres = [(p.footprint[:2] + p.footprint[2:]) / 2 for p in placed]
    options = []
    for yaw in yaws:
        box = envelope(frame_boxes(hulls, yaw))
        ok = _valid(cands, box, area, obstacles, centres, cfg)
        options += [(float(yaw), c) for c in cands[ok]]
    return options


CLUSTER_GAP_M = 0.6  # a clustered subject's box stands at most this far from one already placed


def _box_gap(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Ground distances (N,) from a box (4,) to boxes (N, 4): 0 where they touch."""
    dx = np.maximum(0, np.maximum(boxes[:, 0] - box[2], box[0] - boxes[:, 2]))
    dz = np.maximum(0, np.maximum(boxes[:, 1] - box[3], box[1] - boxes[:, 3]))
    return np.hypot(dx, dz)


def _clustered(options: list, hulls, placed: list) -> list:
    """The options whose whole-clip box stands within ``CLUSTER_GAP_M`` of a placed subject's
    (all of them when none does)."""
    placed_boxes = np.stack([p.footprint for p in placed])
    at_origin = {yaw: envelope(frame_boxes(hulls, yaw)) for yaw in {o[0] for o in options}}
    boxes = np.stack([at_origin[yaw] + np.concatenate([pos, pos]) for yaw, pos in options])
    gaps = np.stack([_box_gap(b, boxes) for b in placed_boxes]).min(0)
    near = [o for o, g in zip(options, gaps) if g <= CLUSTER_GAP_M]
    return near or options


def _attempt(hulls_per_subject: list, order: list, area, obstacles: np.ndarray, cands: np.ndarray,
             cfg: PlacementConfig, rng: np.random.Generator, cluster: float = 0.0) -> tuple[list, list]:
    """One placement pass over the subjects in ``order``: each placed at a random fitting
    (yaw, position), one that fits nowhere skipped (later ones are still tried); with odds
    ``cluster`` a subject stands next to one already placed. Returns the placements and the
    indices left out."""
    placed: list[Placement] = []
    left = []
    for i in order:
        hulls = hulls_per_subject[i]
        options = _options(hulls, cands, area, obstacles, placed, cfg, rng)
        if not options:
            left.append(i)
            continue
        if cluster > 0 and placed and rng.random() < cluster:
            options = _clustered(options, hulls, placed)
        yaw, pos = options[int(rng.integers(len(options)))]
        frames = frame_boxes(hulls, yaw, pos)
        placed.append(Placement((float(pos[0]), float(pos[1])), yaw, envelope(frames), frames, i))
        obstacles = np.concatenate([obstacles, envelope(frames)[None]], 0)
    return placed, left


def place_subjects(hulls_per_subject: list, area, object_boxes: np.ndarray, cfg: PlacementConfig,
                   rng: np.random.Generator, tries: int = PLACEMENT_TRIES, cluster: float = 0.0) -> list[Placement]:
    """Place subjects (their per-frame hulls centred on the clip's mean root position), one
    at a time, every one tried. When some do not fit, the whole placement is tried again (up
    to ``tries`` times) with fresh headings and picks, the largest whole-clip boxes first and
    the group radius widened step by step up to ``cfg.widen`` times; the best pass is kept.
    ``cluster``: odds that a subject stands next to one already placed (occlusion targets).
    Returns the placements in subject order (``Placement.index``): all of them, or fewer with a
    warning naming who was left out; a ConfigError when none fits."""
    obstacles = np.asarray(object_boxes, np.float64).reshape(-1, 4)
    hulls_per_subject = [stack_hulls(h) for h in hulls_per_subject]
    cands = _candidates(area, cfg.grid_step)
    n = len(hulls_per_subject)
    sizes = [np.prod(np.diff(envelope(frame_boxes(h)).reshape(2, 2), axis=0)) for h in hulls_per_subject]
    order = list(range(n))  # the first pass as given: a scene where all fit composes as it always has
    best: list[Placement] = []
    left = order
    for k in range(tries):
        widened = replace(cfg, group_radius=cfg.group_radius * (1 + (cfg.widen - 1) * k / max(tries - 1, 1)))
        placed, missing = _attempt(hulls_per_subject, order, area, obstacles, cands, widened, rng, cluster)
        if len(placed) > len(best):
            best, left = placed, missing
        if not left:
            break
        order = sorted(range(n), key=lambda i: -sizes[i])
    why = (f"no position in area {list(area)} with step {cfg.grid_step} m keeps the whole-clip box clear of "
           f"{len(obstacles)} boxes and the other subjects by {cfg.margin} m within {cfg.group_radius} m of the group")
    if not best:
        raise ConfigError("subjects", n, f"no subject fits ({why}); choose shorter or slower motions, a larger "
                          "environment area or fewer objects")
    if left:
        warnings.warn(f"subjects {sorted(left)} do not fit after {tries} tries ({why}); placing {len(best)} of {n} "
                      "subjects (raise placement.group_radius or pick fewer subjects)", SynMitsubaWarning, stacklevel=2)
    return sorted(best, key=lambda p: p.index)
