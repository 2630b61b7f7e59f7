"""Occlusion by ray casting (SynBody): rays from a camera to points sampled uniformly (by area)
on a subject's body surface; the share that first hits another instance is its occlusion."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.engine.raycast import first_hits
from synmitsuba.scene.camera import Camera


@dataclass
class SurfaceSamples:
    """Fixed points on a mesh: triangle indices and barycentric weights, so the same points
    follow the surface as it is posed."""

    faces: np.ndarray     # (N, 3) vertex indices of each point's triangle
    weights: np.ndarray   # (N, 3) barycentric weights

    def on(self, vertices: np.ndarray) -> np.ndarray:
        return np.einsum("nk,nkd->nd", self.weights, vertices[self.faces])


def surface_samples(vertices, faces, n: int, rng: np.random.Generator) -> SurfaceSamples:
    """``n`` points uniform by area on the mesh (vertices (V, 3), faces (F, 3))."""
    from synmitsuba.geometry import triangle_areas
    areas = triangle_areas(np.asarray(vertices)[np.asarray(faces)])
    tri = rng.choice(len(faces), size=n, p=areas / areas.sum())
    r1, r2 = np.sqrt(rng.random(n)), rng.random(n)
    w = np.stack([1 - r1, r1 * (1 - r2), r1 * r2], 1)
    return SurfaceSamples(np.asarray(faces)[tri], w)


def occluded(scene, eyes: np.ndarray, points: np.ndarray, instance: int) -> np.ndarray:
    """(C, P) whether the ray from each eye (C, 3) to each point (P, 3) first hits an instance
    other than ``instance`` (and other than nothing)."""
    C, P = len(eyes), len(points)
    ids = first_hits(scene, np.repeat(eyes, P, 0), np.tile(points, (C, 1))).reshape(C, P)
    return (ids != 0) & (ids != instance)


def occlusion(scene, eyes: np.ndarray, points: np.ndarray, instance: int) -> np.ndarray:
    """(C,) share of rays from each eye (C, 3) to the points (P, 3) that first hit an instance
    other than ``instance`` (and other than nothing)."""
    return occluded(scene, eyes, points, instance).mean(1)


def inside_image(camera: Camera, points: np.ndarray) -> np.ndarray:
    """(P,) whether each point is in front of the camera and inside its image."""
    uv, z = camera.project(points)
    return (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < camera.width) & (uv[:, 1] >= 0) & (uv[:, 1] < camera.height)


def in_view(camera: Camera, points: np.ndarray) -> float:
    """Share of points in front of the camera and inside its image."""
    return float(inside_image(camera, points).mean())


def score_frames(n_frames: int, count: int) -> list[int]:
    """Up to ``count`` clip frames spread evenly over ``n_frames``, where views are scored."""
    return sorted({int(round(x)) for x in np.linspace(0, n_frames - 1, min(count, n_frames))})


@dataclass
class ViewScores:
    """What ray casting says of every candidate view (V) and subject (S): ``occlusion`` and
    ``in_view`` (V, S), means over the scored frames (all the subject's points; those inside
    the image); ``visible`` (V, S, F): per scored frame, the share of the subject's points
    inside the image that nothing else hides (0 when none is inside), the estimate of a
    record's ``visible_fraction``."""

    occlusion: np.ndarray
    in_view: np.ndarray
    visible: np.ndarray


def score_views(scene, placed: list, views: list, frames: list, points: int,
                rng: np.random.Generator) -> ViewScores:
    """Ray-cast scores of every view for every placed subject at ``frames``; a view is a
    function of the frame giving ``(eye (3,), Camera)``. Leaves the subjects posed at the last
    frame."""
    samples = [surface_samples(p.human.parts[0].rest, p.human.parts[0].faces, points, rng) for p in placed]
    V, S, F = len(views), len(placed), len(frames)
    occ, seen, visible = np.zeros((V, S, F)), np.zeros((V, S, F)), np.zeros((V, S, F))
    for k, f in enumerate(frames):
        for p in placed:
            p.pose_in(scene, f)
        at = [view(f) for view in views]
        eyes = np.stack([eye for eye, _ in at])
        for s, (p, smp) in enumerate(zip(placed, samples)):
            pts = smp.on(scene.meshes[f"{p.prefix}_body"].vertices)  # posed just above
            hidden = occluded(scene, eyes, pts, p.instance)
            inside = np.stack([inside_image(cam, pts) for _, cam in at])
            n = inside.sum(1)
            occ[:, s, k], seen[:, s, k] = hidden.mean(1), n / len(pts)
            visible[:, s, k] = np.where(n > 0, (inside & ~hidden).sum(1) / np.maximum(n, 1), 0.0)
    return ViewScores(occ.mean(2), seen.mean(2), visible)
