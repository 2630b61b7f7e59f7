"""Per-frame collision resolution for skinned garments: after linear blend skinning, garment
vertices that went into the posed body (or into an inner garment) are pushed back out along the
surface normal to a margin, and the pushes are spread to their neighbours so that the cloth
does not crease where it was pushed.

Three passes, each a push along a normal:
1. the vertex's own bound body point (its closest point at rest, posed): the garment stays over
   the body part it belongs to however far skinning took it in;
2. the nearest posed body vertex (a k-d tree), for another part pressing in (an arm against the
   torso, one thigh against the other);
3. the nearest vertex of each inner garment within ``REACH``, by ``LAYER_MARGIN``.
Depth is the height over the tangent plane at that point (area-weighted vertex normals): exact
on flat patches, and cheap enough for a few milliseconds per garment and frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SMOOTHING = 2         # rounds of spreading each push to the neighbouring vertices
REACH = 0.03          # metres: an inner garment farther than this from a vertex is not its collider
LAYER_MARGIN = 0.002  # metres kept between a garment and the garment under it


def incidence(faces: np.ndarray, n_vertices: int):
    """Sparse (V, F) vertex-face incidence: summing face normals into vertex normals is one
    product (np.add.at took most of a frame)."""
    from scipy import sparse
    faces = np.asarray(faces)
    return sparse.csr_matrix((np.ones(faces.size), (faces.ravel(), np.repeat(np.arange(len(faces)), 3))),
                             shape=(n_vertices, len(faces)))


def _normals(vertices: np.ndarray, faces: np.ndarray, vf) -> np.ndarray:
    """Area-weighted vertex normals (``vf``: the faces' ``incidence``)."""
    tri = vertices[faces]
    n = vf @ np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def _spread(faces: np.ndarray, n: int):
    """Row-normalised vertex adjacency (sparse) of a mesh, self included."""
    from scipy import sparse
    i = np.concatenate([faces[:, [0, 1, 2, 1, 2, 0]].ravel(), np.arange(n)])
    j = np.concatenate([faces[:, [1, 2, 0, 0, 1, 2]].ravel(), np.arange(n)])
    A = sparse.csr_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    A.data[:] = 1.0  # duplicate edges count once
    return sparse.diags(1.0 / np.asarray(A.sum(1)).ravel()) @ A


@dataclass
class Surface:
    """A posed surface that garments are pushed out of."""

    vertices: np.ndarray
    normals: np.ndarray
    tree: object

    @classmethod
    def of(cls, vertices: np.ndarray, faces: np.ndarray, vf) -> "Surface":
        """The surface of a posed mesh; ``vf`` its faces' ``incidence`` (fixed per mesh)."""
        from scipy.spatial import cKDTree
        return cls(vertices, _normals(vertices, faces, vf), cKDTree(vertices))

    def depth(self, points: np.ndarray, reach: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
        """(signed height over the nearest vertex's tangent plane (N,), that normal (N, 3));
        points farther than ``reach`` from every vertex get +inf."""
        dist, near = self.tree.query(points, distance_upper_bound=reach)
        found = np.isfinite(dist)
        near = np.where(found, near, 0)
        n = self.normals[near]
        h = np.einsum("ij,ij->i", points - self.vertices[near], n)
        return np.where(found, h, np.inf), n


class GarmentCollider:
    """One garment's per-frame resolution: its margin over the body, its binding (body
    triangle's vertices and barycentric coordinates per garment vertex) and spreading matrix."""

    def __init__(self, faces: np.ndarray, n_vertices: int, margin: float, bound_vertices: np.ndarray,
                 barycentric: np.ndarray):
        self.margin = float(margin)
        self.spread = _spread(np.asarray(faces), n_vertices)
        self.incidence = incidence(np.asarray(faces), n_vertices)
        self.bound_vertices, self.barycentric = np.asarray(bound_vertices), np.asarray(barycentric)

    def resolve(self, points: np.ndarray, body: Surface, inner: list[Surface] = (), calibrate: bool = False):
        """``points`` pushed out of ``body`` by the margin and out of each ``inner`` garment by
        ``LAYER_MARGIN``; returns new points (the input is not changed). No vertex is asked for
        more clearance than it had at rest: ``calibrate`` (on the rest pose, once) records each
        pass's heights, so the rest pose is left exactly as built and only what motion pushed
        in comes out."""
        out = points.copy()
        checks = [(lambda p: self._over_bound_point(p, body), self.margin), (body.depth, self.margin)]
        checks += [(lambda p, s=s: s.depth(p, REACH), LAYER_MARGIN) for s in inner]
        if calibrate:
            self.floors = []
        for k, (check, margin) in enumerate(checks):
            height, normals = check(out)
            if calibrate:
                self.floors.append(np.minimum(margin, height))
            else:
                self._push(out, height, normals, self.floors[k])
        return out

    def _over_bound_point(self, points: np.ndarray, body: Surface) -> tuple[np.ndarray, np.ndarray]:
        """Heights over each vertex's own bound body point (posed) and the normal there."""
        at = np.einsum("nk,nka->na", self.barycentric, body.vertices[self.bound_vertices])
        n = np.einsum("nk,nka->na", self.barycentric, body.normals[self.bound_vertices])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        return np.einsum("ij,ij->i", points - at, n), n

    def _push(self, points: np.ndarray, height: np.ndarray, normals: np.ndarray, floor: np.ndarray) -> None:
        """Move points below ``floor`` (heights over their surface) up to it along ``normals``;
        a height of +inf marks a point with no surface to answer to."""
        push = np.clip(floor - height, 0.0, None)  # +inf height: no push
        if not push.any():
            return
        for _ in range(SMOOTHING):  # neighbours follow part of the way: no crease at the edge
            push = np.maximum(push, self.spread @ push)
        points += (push * np.isfinite(height))[:, None] * normals
