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


def incident_faces(faces: np.ndarray, n_vertices: int) -> np.ndarray:
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


def closest_points(vertices, faces, points, k: int = 4, tree=None, around=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(closest point (N, 3), face index (N,), barycentric (N, 3)) on the mesh, searched among
    the faces around the ``k`` nearest vertices (exact for points near the surface). ``tree``
    (a cKDTree of ``vertices``) and ``around`` (``incident_faces``) save rebuilding them."""
    from scipy.spatial import cKDTree
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    _, near = (cKDTree(vertices) if tree is None else tree).query(points, k=k)
    around = incident_faces(faces, len(vertices)) if around is None else around
    return closest_on_faces(vertices, faces, points, around[near.reshape(len(points), -1)].reshape(len(points), -1))


def closest_on_faces(vertices, faces, points, cand) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``closest_points`` among given candidate faces (N, C) per point, -1 for none. A face
    listed twice for a point (around two of its nearest vertices) is measured once, and ties go
    to the face listed first (nearest vertex first), as when every listing was measured: sorting
    the faces instead broke ties by face index and moved a few pushed vertices by 5 mm under a
    rigid move of the whole pose."""
    import trimesh
    cand = np.array(cand, copy=True)
    order = np.argsort(cand, axis=1, kind="stable")  # a stable sort puts a face's first listing first
    ranked = np.take_along_axis(cand, order, 1)
    again = np.zeros(cand.shape, bool)
    np.put_along_axis(again, order[:, 1:], ranked[:, 1:] == ranked[:, :-1], 1)
    cand[again] = -1  # O(C log C) a point: comparing every pair of columns took a third of the call
    rows, cols = np.nonzero(cand >= 0)
    cp = trimesh.triangles.closest_point(vertices[faces[cand[rows, cols]]], points[rows])
    dist = np.full(cand.shape, np.inf)
    dist[rows, cols] = np.einsum("ij,ij->i", cp - points[rows], cp - points[rows])
    best = dist.argmin(1)
    slot = np.full(cand.shape, -1)
    slot[rows, cols] = np.arange(len(rows))
    n = np.arange(len(points))
    closest, face = cp[slot[n, best]], cand[n, best]
    bary = trimesh.triangles.points_to_barycentric(vertices[faces[face]], closest)
    return closest, face, bary


class MeshIndex:
    """A triangle mesh's lookup structures for closest points and signed distance (a k-d tree,
    the faces around each vertex, face, edge and vertex pseudonormals), each built on first use
    and kept: a subject's build queries its rest body a few dozen times (0.4 s a subject when
    every query rebuilt them). Valid while ``vertices`` is not changed in place."""

    def __init__(self, vertices, faces):
        self.source = vertices  # the array given, so an owner can tell when its mesh was replaced
        self.vertices, self.faces = np.asarray(vertices, dtype=np.float64), np.asarray(faces)
        self._tree = self._around = self._normals = None

    @property
    def tree(self):
        if self._tree is None:
            from scipy.spatial import cKDTree
            self._tree = cKDTree(self.vertices)
        return self._tree

    @property
    def around(self) -> np.ndarray:
        if self._around is None:
            self._around = incident_faces(self.faces, len(self.vertices))
        return self._around

    def closest(self, points, k: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``closest_points`` on this mesh."""
        return closest_points(self.vertices, self.faces, points, k, self.tree, self.around)

    def pseudonormals(self, face, barycentric, tol: float = 1e-6) -> np.ndarray:
        """Pseudonormals (N, 3) of the closest features given as (``face``, ``barycentric``): the
        face's normal inside it, the sum of the two faces' normals on an edge, the angle-weighted
        normal at a vertex (Baerentzen and Aanaes, 2005). The sign of (point - closest) against
        it is exact on a closed mesh; against one face's normal it is not where the closest
        point is a vertex or edge of a saddle or a fold (an armpit, a crotch): such points read
        as inside."""
        fn, vn, uniq, en, keys = self._feature_normals()
        bary = np.asarray(barycentric)
        zero = bary < tol
        out = fn[face].copy()
        on_edge = zero.sum(1) == 1
        corner = zero[on_edge].argmax(1)
        out[on_edge] = en[np.searchsorted(uniq, keys[face[on_edge], corner])]
        at_vertex = zero.sum(1) >= 2
        out[at_vertex] = vn[self.faces[face[at_vertex], bary[at_vertex].argmax(1)]]
        return out

    def _feature_normals(self) -> tuple:
        if self._normals is None:
            vertices, faces = self.vertices, self.faces
            tri = vertices[faces]
            fn = face_normals(tri)
            vn = np.zeros_like(vertices)
            for c in range(3):  # the angle at each corner weighs its face's normal
                a, b = tri[:, (c + 1) % 3] - tri[:, c], tri[:, (c + 2) % 3] - tri[:, c]
                cos = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1),
                                                               1e-30)
                np.add.at(vn, faces[:, c], np.arccos(np.clip(cos, -1, 1))[:, None] * fn)
            V = len(vertices)
            ends = np.stack([faces[:, [1, 2, 0]], faces[:, [2, 0, 1]]], -1)  # edge opposite each corner
            keys = ends.min(-1) * V + ends.max(-1)                              # (F, 3)
            uniq, inv = np.unique(keys.ravel(), return_inverse=True)
            en = np.zeros((len(uniq), 3))
            np.add.at(en, inv, np.repeat(fn, 3, axis=0))
            self._normals = (fn, vn, uniq, en, keys)
        return self._normals

    def signed_distance(self, points, k: int = 4) -> np.ndarray:
        """Distance to the surface, negative inside (sign from the closest feature's pseudonormal)."""
        points = np.asarray(points, dtype=np.float64)
        closest, tri, bary = self.closest(points, k)
        n = self.pseudonormals(tri, bary)
        d = np.linalg.norm(points - closest, axis=1)
        return np.where(((points - closest) * n).sum(1) < 0, -d, d)


def local_pseudonormals(vertices, faces, around, face, barycentric, tol: float = 1e-6) -> np.ndarray:
    """``MeshIndex.pseudonormals`` (unnormalised) computed for the given features alone, from the
    faces ``around`` (``incident_faces``) each: for a posed mesh, where building every edge's
    and vertex's normal each frame would cost more than the few queries need."""
    tri = vertices[faces[face]]
    out = _unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    zero = np.asarray(barycentric) < tol
    edge = np.flatnonzero(zero.sum(1) == 1)
    if len(edge):  # the face across the edge opposite the zero corner
        c = zero[edge].argmax(1)
        a, b = faces[face[edge], (c + 1) % 3], faces[face[edge], (c + 2) % 3]
        cand = around[a]
        hit = (cand >= 0) & (cand != face[edge, None]) & (faces[np.maximum(cand, 0)] == b[:, None, None]).any(-1)
        other = cand[np.arange(len(edge)), hit.argmax(1)]
        t = vertices[faces[other]]
        out[edge] += np.where(hit.any(1)[:, None], _unit(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])), 0.0)
    corner = np.flatnonzero(zero.sum(1) >= 2)
    if len(corner):  # the angle-weighted normal of the faces around the vertex
        v = faces[face[corner], np.asarray(barycentric)[corner].argmax(1)]
        cand = around[v]
        f = faces[np.maximum(cand, 0)]                                   # (n, m, 3)
        t = vertices[f]
        k = (f == v[:, None, None]).argmax(-1)                           # v's corner in each face
        pick = np.take_along_axis
        p0 = pick(t, k[..., None, None].repeat(3, -1), 2)[:, :, 0]
        p1 = pick(t, ((k + 1) % 3)[..., None, None].repeat(3, -1), 2)[:, :, 0]
        p2 = pick(t, ((k + 2) % 3)[..., None, None].repeat(3, -1), 2)[:, :, 0]
        e1, e2 = _unit(p1 - p0), _unit(p2 - p0)
        angle = np.arccos(np.clip((e1 * e2).sum(-1), -1, 1)) * (cand >= 0)
        out[corner] = (angle[..., None] * _unit(np.cross(t[:, :, 1] - t[:, :, 0], t[:, :, 2] - t[:, :, 0]))).sum(1)
    return out


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), 1e-30)


def signed_distance(vertices, faces, points, k: int = 4) -> np.ndarray:
    """``MeshIndex.signed_distance`` of a mesh queried once."""
    return MeshIndex(vertices, faces).signed_distance(points, k)


def bind(body_vertices, body_faces, body_weights, points, index: MeshIndex | None = None) -> Binding:
    """Bind ``points`` to their closest body points (``index``: the body's, to reuse)."""
    closest, tri, bary = (index or MeshIndex(body_vertices, body_faces)).closest(points)
    w = np.einsum("nk,nkj->nj", bary, body_weights[body_faces[tri]])
    w /= np.maximum(w.sum(1, keepdims=True), 1e-12)
    return Binding(tri, bary, w.astype(np.float32))
