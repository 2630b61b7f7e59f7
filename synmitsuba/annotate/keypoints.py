"""Keypoint visibility by ray tests against the full layered scene.

Class per keypoint (``VISIBILITY``): 0 outside the image (or behind the camera), 1 visible,
2 self-occluded, 3 occluded by another subject, 4 occluded by an object or the ground.
Keypoints lie inside the body; the ray from the eye to keypoint k counts as reaching it when its
first hit is no nearer than ``|k - eye| - d_k - clothing`` where d_k is the keypoint's distance
to the body surface and ``clothing`` (metres) lets garments and hair lying on the body there
count as the body; an earlier hit decides the class by whose surface it is. The visible
fraction repeats the test for rays to ``rays`` points on a sphere of radius ``radius`` around
the keypoint.
"""
from __future__ import annotations

import numpy as np

from synmitsuba.engine.raycast import cast
from synmitsuba.scene.camera import Camera

VISIBILITY = {0: "outside", 1: "visible", 2: "self_occluded", 3: "occluded_by_subject", 4: "occluded_by_object"}
# The one mapping of these classes onto COCO's flags (2 visible, 1 in the image but occluded, 0
# not labelled): the COCO export, HumanData and SynDataset(visibility="coco") all read it.
COCO_FLAGS = np.array([0, 2, 1, 1, 1], np.uint8)


def coco_flags(classes) -> np.ndarray:
    """COCO keypoint flags of ``VISIBILITY`` classes."""
    return COCO_FLAGS[np.asarray(classes, np.int64)]


def _sphere(n: int) -> np.ndarray:
    """``n`` evenly spread unit vectors (Fibonacci sphere)."""
    i = np.arange(n) + 0.5
    y = 1 - 2 * i / n
    r, phi = np.sqrt(1 - y * y), np.pi * (3 - np.sqrt(5)) * i
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], 1)


def _classify(scene, eye, points, depth_to_body, instance, subjects, clothing):
    """(class 1..4, hit-free) for rays from ``eye`` to ``points`` (N, 3)."""
    d = points - eye
    dist = np.linalg.norm(d, axis=1)
    ids, t = cast(scene, eye, d / dist[:, None], dist)
    reached = (ids == 0) | (t >= dist - depth_to_body - clothing)
    cls = np.where(ids == instance, 2, np.where(np.isin(ids, list(subjects)), 3, 4))
    return np.where(reached, 1, cls)


def keypoint_visibility(scene, camera: Camera, points, body_vertices, instance: int, subjects,
                        clothing: float = 0.05, rays: int = 16, radius: float = 0.03) -> tuple[np.ndarray, np.ndarray]:
    """Visibility classes (K,) and visible fractions (K,) of world keypoints (K, 3) of the
    subject ``instance`` whose posed body vertices are ``body_vertices``; ``subjects`` is the
    set of every subject's instance id."""
    from scipy.spatial import cKDTree
    pts = np.asarray(points, np.float64)
    uv, z = camera.project(pts)
    inside = (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < camera.width) & (uv[:, 1] >= 0) & (uv[:, 1] < camera.height)
    depth = cKDTree(body_vertices).query(pts)[0]
    eye = camera.center
    cls = _classify(scene, eye, pts, depth, instance, subjects, clothing)
    ring = (pts[:, None, :] + radius * _sphere(rays)[None]).reshape(-1, 3)
    around = _classify(scene, eye, ring, np.repeat(depth, rays) + radius, instance, subjects, clothing)
    frac = (around.reshape(-1, rays) == 1).mean(1)
    return np.where(inside, cls, 0).astype(np.uint8), np.where(inside, frac, 0.0)
