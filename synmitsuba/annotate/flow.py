"""Exact optical flow between two frames of a scene.

Each pixel-centre ray of frame f hits a surface point (eye + t * ray): on a triangle at its
barycentric coordinates (meshes), or on a curve segment, a share along it and an offset from
its axis (hair). That same material point is taken to frame g (moved by its triangle's
corners or its segment's control points from f to g; unmoved shapes keep it exactly) and
projected with g's camera: flow = its pixel position at g minus the pixel centre at f. Flags
(uint8): 0 seen at g, 1 hidden at g (the ray from g's eye meets another surface first), 2
outside g's image or behind its camera, 3 nothing hit at f (background: flow 0).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from synmitsuba.engine.build import build
from synmitsuba.engine.raycast import cast, surface_hits
from synmitsuba.engine.rays import pixel_centre_rays
from synmitsuba.errors import ConfigError
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.scene import Scene

SEEN, HIDDEN, OUTSIDE, BACKGROUND = 0, 1, 2, 3
NO_TARGET = 4  # a loader's fill for a side with no frame to flow to (a sequence's first or last frame)


@dataclass
class Geometry:
    """A scene's moving shapes at one frame: mesh vertices (V, 3) and curve control points
    (N, K, 3) by name."""

    vertices: dict = field(default_factory=dict)
    curves: dict = field(default_factory=dict)


def points_at(scene: Scene, hits: dict, rays_o, rays_d, now: Geometry, then: Geometry) -> np.ndarray:
    """(N, 3) world positions at the other frame of the points hit now (nan where none)."""
    out = np.full((len(hits["t"]), 3), np.nan)
    order = np.argsort(hits["shape"], kind="stable")
    ids, starts = np.unique(hits["shape"][order], return_index=True)
    for idx, sel in zip(ids, np.split(order, starts[1:])):
        if idx < 0:
            continue
        name = hits["names"][idx]
        p = rays_o + hits["t"][sel, None] * rays_d[sel]  # exact on any triangle (still ground: flow 0)
        if name in scene.meshes:  # moved by its triangle's motion (barycentrics u, v of corners 1, 2)
            if name in then.vertices:
                faces = scene.meshes[name].faces[hits["prim"][sel]].astype(np.int64)
                u, v = hits["u"][sel, None], hits["v"][sel, None]

                def at(V):
                    tri = V[faces]
                    return (1 - u - v) * tri[:, 0] + u * tri[:, 1] + v * tri[:, 2]
                p = p + (at(then.vertices[name]) - at(now.vertices.get(name, scene.meshes[name].vertices)))
            out[sel] = p
        else:  # a curve: segment prim of strand prim // (K - 1), u along it; p lies a radius off its axis
            if name in then.curves:
                P0 = now.curves.get(name, scene.curves[name].points)
                k = P0.shape[1] - 1
                s, j, u = hits["prim"][sel] // k, hits["prim"][sel] % k, hits["u"][sel, None]

                def axis(P):
                    return (1 - u) * P[s, j] + u * P[s, j + 1]
                p = axis(then.curves[name]) + (p - axis(P0))
            out[sel] = p
    return out


def pixel_hits(scene: Scene, cam: Camera) -> dict:
    """``surface_hits`` of ``cam``'s pixel-centre rays, with the rays (``"rays"``): what
    ``exact_flow`` starts from, shared by a view's forward and backward flow."""
    d = pixel_centre_rays(cam).astype(np.float64)  # the exact passes' rays: flags agree with the instance pass
    return {**surface_hits(scene, cam.center, d), "rays": d}


def exact_flow(scene: Scene, cam: Camera, cam_other: Camera, now: Geometry, then: Geometry,
               scene_then: Scene | None = None, hits: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Flow (H, W, 2) in pixels from ``cam``'s frame to ``cam_other``'s and the flags (H, W).
    ``scene`` holds the geometry of ``cam``'s frame; ``now`` / ``then`` give the moving shapes at
    both frames. The visibility test at the other frame runs on ``scene_then`` (a scene already
    at that frame, see ``geometry_copy``) or else on ``scene`` moved there and back. ``hits``:
    ``pixel_hits(scene, cam)``, when already cast."""
    H, W = cam.height, cam.width
    hits = pixel_hits(scene, cam) if hits is None else hits
    d = hits["rays"]
    P = points_at(scene, hits, cam.center, d, now, then)
    ok = np.isfinite(P[:, 0])
    uv, z = cam_other.project(np.where(ok[:, None], P, 0.0))
    px = np.stack(np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5), -1).reshape(-1, 2)
    flow = np.where(ok[:, None], uv - px, 0.0)
    inside = ok & (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < W) & (uv[:, 1] >= 0) & (uv[:, 1] < H)
    flags = np.where(ok, OUTSIDE, BACKGROUND).astype(np.uint8)
    if inside.any():
        hidden = (_blocked(scene_then, cam_other.center, P[inside]) if scene_then is not None
                  else _hidden(scene, cam_other.center, P[inside], now, then))
        flags[inside] = np.where(hidden, HIDDEN, SEEN)
    return flow.reshape(H, W, 2).astype(np.float32), flags.reshape(H, W)


def _blocked(scene: Scene, eye, points, tol: float = 2e-3) -> np.ndarray:
    """Whether a surface of ``scene`` lies between ``eye`` and each point (beyond a tolerance)."""
    d = points - eye
    dist = np.linalg.norm(d, axis=1)
    _, t = cast(scene, eye, d / dist[:, None], dist)
    return t < dist - tol * np.maximum(dist, 1.0)


def geometry_copy(scene: Scene) -> Scene:
    """The shapes of ``scene`` with plain materials and their ids: a second scene to hold
    another frame's geometry for visibility tests (no textures, no lights)."""
    copy = Scene()
    for name, m in scene.meshes.items():
        copy.add_mesh(name, m.vertices, m.faces, instance=m.instance, layer=m.layer)
    for name, c in scene.curves.items():
        copy.add_curves(name, c.points, c.radius, instance=c.instance, layer=c.layer)
    return copy


def _apply(scene: Scene, geometry: Geometry) -> None:
    for name, v in geometry.vertices.items():
        scene.update_mesh(name, v)
    for name, p in geometry.curves.items():
        if name in scene.curves:
            scene.update_curves(name, p)


def subjects_geometry(subjects: list, frame: int) -> Geometry:
    """The moving shapes of placed subjects (``compose.subjects.PlacedSubject``) at ``frame``:
    every mesh layer's vertices and every curve layer's (hair, beard) control points."""
    g = Geometry()
    for p in subjects:
        if not 0 <= int(frame) < p.motion.n_frames:
            raise ConfigError("frame", frame, f"the clip has frames 0..{p.motion.n_frames - 1}: there is no flow "
                              "before the first frame or past the last")
        for layer in p.layers(int(frame)):
            if layer.is_curves:
                g.curves[f"{p.prefix}_{layer.name}"] = layer.points
            else:
                g.vertices[f"{p.prefix}_{layer.name}"] = layer.vertices
    return g


def _hidden(scene: Scene, eye, points, now: Geometry, then: Geometry) -> np.ndarray:
    """Whether each point, at the other frame, is behind another surface seen from ``eye``."""
    curves_now = {n: scene.curves[n].points for n in then.curves if n in scene.curves}
    with scene.keeping_previous():  # back to this frame, with the scene's own previous positions kept
        _apply(scene, then)
        try:
            return _blocked(scene, eye, points)
        finally:
            _apply(scene, now)
            for n, points_now in curves_now.items():
                scene.update_curves(n, points_now)


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

    def load(self) -> None:
        """Make and load the three copies (once): before the first frame is rendered, so every
        frame's path tracer is traced with the same Mitsuba objects alive. Loaded after it, the
        copies' materials joined the BSDF calls of every later frame's kernel: frame 0 compiled
        a kernel of its own (4-7 s on 2 cores) that no later frame could reuse."""
        if not self.copies:
            self.copies = [geometry_copy(self.scene) for _ in range(3)]
            for copy in self.copies:
                build(copy)
            self.at = [None] * 3

    def __call__(self, g: int, f: int):
        self.load()
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


class SequenceFlow:
    """Exact flow for the frames of a sequence rendered in order: the subjects' geometry and
    the neighbour scenes are kept for the few frames flow needs at a time."""

    def __init__(self, scene: Scene, placed: list):
        self.scene, self.geometry, self.neighbours = scene, _GeometryCache(placed), _Neighbours(scene, placed)

    def prepare(self) -> None:
        """Load the neighbour scenes now, before the sequence's first render (see ``_Neighbours.load``)."""
        self.neighbours.load()

    def add(self, sample, cameras: list, f: int, targets: dict) -> None:
        """Forward and backward flow of ``sample`` (frame ``f`` of a view whose camera at frame g
        is ``cameras[g]``) to ``targets`` (``flow_targets``), from one cast of the pixel-centre
        rays; the targets go to the meta's ``flow_frames``."""
        hits = pixel_hits(self.scene, cameras[f])
        for side, g in targets.items():
            flow, flags = exact_flow(self.scene, cameras[f], cameras[g], self.geometry(f), self.geometry(g),
                                     self.neighbours(g, f), hits)
            sample.passes[f"flow_{side}"], sample.passes[f"flow_{side}_flag"] = flow, flags
        sample.meta["flow_frames"] = dict(targets)
