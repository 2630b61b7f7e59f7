"""Closest-point binding (the SynBody paper's garment method): every garment vertex is bound to
its closest point on the body surface and takes the skinning weights interpolated there."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.geometry import face_normals


@dataclass
class Binding:
    triangle: np.ndarray     # (N,) body face index
    barycentric: np.ndarray  # (N, 3)
    weights: np.ndarray      # (N, J) interpolated skinning weights


def _incident_faces(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """(V, max valence) face indices around each vertex, padded with -1."""
    order = np.argsort(faces.ravel(), kind="stable")
    vert = faces.ravel()[order]
    face = order // 3
    counts = np.bincount(vert, minlength=n_vertices)
    table = -np.ones((n_vertices, max(1, counts.max())), np.int64)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.arange(len(vert)) - start[vert]
    table[vert, slot] = face
    return table


def closest_points(vertices, faces, points, k: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(closest point (N, 3), face index (N,), barycentric (N, 3)) on the mesh, searched among
    the faces around the ``k`` nearest vertices (exact for points near the surface)."""
    import trimesh
    from scipy.spatial import cKDTree
    points = np.asarray(points, dtype=np.float64)
    _, near = cKDTree(vertices).query(points, k=k)
    cand = _incident_faces(faces, len(vertices))[near.reshape(len(points), -1)].reshape(len(points), -1)
    valid = cand >= 0
    tri = vertices[faces[np.where(valid, cand, 0)]]                     # (N, C, 3, 3)
    q = np.broadcast_to(points[:, None], cand.shape + (3,))
    cp = trimesh.triangles.closest_point(tri.reshape(-1, 3, 3), q.reshape(-1, 3)).reshape(cand.shape + (3,))
    dist = np.where(valid, np.linalg.norm(cp - q, axis=-1), np.inf)
    best = dist.argmin(1)
    rows = np.arange(len(points))
    closest, face = cp[rows, best], cand[rows, best]
    bary = trimesh.triangles.points_to_barycentric(vertices[faces[face]], closest)
    return closest, face, bary


def signed_distance(vertices, faces, points) -> np.ndarray:
    """Distance to the surface, negative inside (sign from the closest triangle's normal)."""
    closest, tri, _ = closest_points(vertices, faces, points)
    n = face_normals(vertices[faces[tri]])
    d = np.linalg.norm(points - closest, axis=1)
    return np.where(((points - closest) * n).sum(1) < 0, -d, d)


def bind(body_vertices, body_faces, body_weights, points) -> Binding:
    closest, tri, bary = closest_points(body_vertices, body_faces, points)
    w = np.einsum("nk,nkj->nj", bary, body_weights[body_faces[tri]])
    w /= np.maximum(w.sum(1, keepdims=True), 1e-12)
    return Binding(tri, bary, w.astype(np.float32))


def bound_points(binding: Binding, body_vertices, body_faces) -> np.ndarray:
    """The bound body points for (possibly posed) body vertices."""
    return np.einsum("nk,nka->na", binding.barycentric, body_vertices[body_faces[binding.triangle]])
