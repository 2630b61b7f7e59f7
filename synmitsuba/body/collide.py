"""Per-frame collision resolution for skinned garments: after linear blend skinning, garment
vertices that went into the posed body (or into an inner garment) are pushed back out along the
surface normal to a margin, and the pushes are spread to their neighbours so that the cloth
does not crease where it was pushed.

Three passes, each a push along a normal:
1. the vertex's own bound body point (its closest point at rest, posed): the garment stays over
   the body part it belongs to however far skinning took it in;
2. the posed body near the vertex, for another part pressing in (an arm against the torso, one
   thigh against the other): the lowest height over the tangent planes of its 4 nearest body
   vertices, and, where that is within ``EXACT_BAND`` of the margin, the exact closest point on
   the triangles around them, its side from the closest feature's pseudonormal. One nearest
   vertex is not enough: in a crease (armpit, hip) its tangent plane is tilted, and said "2 cm
   outside" of vertices 2 cm inside the torso;
3. the nearest vertex of each inner garment within ``REACH``, by ``LAYER_MARGIN``.
Then the vertices a neighbour's push carried more than ``CARRIED`` past their own, or an inner
garment moved, get pass 2 again without spreading: along their own normal they can go into the
next body part (a dress between belly and thigh in a squat, a jacket out of a sleeve into the
chest). Last, a moved vertex still inside (pushed by the margin out of one thigh into the other)
is set just over the surface it is in, exactly, a few times over. Heights over tangent planes
(area-weighted vertex normals) are exact on flat patches and cheap for every vertex; the exact
test costs ~10 us a vertex, so it goes only where it can matter.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from synmitsuba.geometry import face_cross

SMOOTHING = 2         # rounds of spreading each push to the neighbouring vertices
REACH = 0.03          # metres: an inner garment farther than this from a vertex is not its collider
LAYER_MARGIN = 0.002  # metres kept between a garment and the garment under it
EXACT_BAND = 0.004    # metres over the margin under which a vertex gets the exact closest-point test
CARRIED = 0.002       # metres a neighbour's push may carry a vertex past its own before it is checked again:
                      # at most that deep into the next body part
SETTLE = 0.001        # metres over the surface that a vertex still inside after the pushes is set
SETTLE_ROUNDS = 3     # times that is tried: out of one thigh can be into the other


def incidence(faces: np.ndarray, n_vertices: int):
    """Sparse (V, F) vertex-face incidence: summing face normals into vertex normals is one
    product (np.add.at took most of a frame)."""
    from scipy import sparse
    faces = np.asarray(faces)
    return sparse.csr_matrix((np.ones(faces.size), (faces.ravel(), np.repeat(np.arange(len(faces)), 3))),
                             shape=(n_vertices, len(faces)))


def _normals(vertices: np.ndarray, faces: np.ndarray, vf) -> np.ndarray:
    """Area-weighted vertex normals (``vf``: the faces' ``incidence``)."""
    n = vf @ face_cross(vertices, faces)
    return n / np.maximum(np.sqrt(np.einsum("ij,ij->i", n, n)), 1e-12)[:, None]


def neighbour_mean(faces: np.ndarray, n: int):
    """Row-normalised vertex adjacency (sparse) of a mesh, self included."""
    return pair_mean(faces[:, [0, 1, 2]].ravel(), faces[:, [1, 2, 0]].ravel(), n)


def pair_mean(i: np.ndarray, j: np.ndarray, n: int):
    """Row-normalised (sparse) mean over each of ``n`` points and the points it is paired with
    (pairs ``i[k]``, ``j[k]`` either way; a pair given twice counts once)."""
    from scipy import sparse
    a, b = np.concatenate([i, j, np.arange(n)]), np.concatenate([j, i, np.arange(n)])
    A = sparse.csr_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    A.data[:] = 1.0
    return sparse.diags(1.0 / np.asarray(A.sum(1)).ravel()) @ A


COVER_NEAR = 0.5  # a garment point is over a vertex if the body vertex nearest it is this x its height from it, or nearer


def cover_heights(vertices: np.ndarray, normals: np.ndarray, layers: list, where: np.ndarray | None = None,
                  lateral: float = 0.015, highest: float = 0.15) -> np.ndarray:
    """(V,) how far the garments worn over each body vertex stand out along its normal: the
    farthest that the tangent planes at the 8 nearest vertices of each garment (``layers``:
    (rest vertices, faces) pairs) meet the normal's line, counting the vertices within
    ``lateral`` metres of the line (a collar's edge is beside the neck, not over it) and
    nearest the body near the vertex: within ``lateral`` or ``COVER_NEAR`` x that height of it
    (a top's chest, 12 cm along the normal under the chin, lies over the chest, not the chin;
    a collar 8 cm below the back of the skull lies over the neck). Hair is laid over this shell:
    3 mm over the body, long hair went under a jacket at the back and came out at its tips.
    Only at the vertices ``where`` (a mask) when given, 0 elsewhere."""
    from pykdtree.kdtree import KDTree
    out = np.zeros(len(vertices))
    body = KDTree(np.ascontiguousarray(vertices, dtype=np.float64))
    ids = np.arange(len(vertices)) if where is None else np.flatnonzero(where)
    v, normals = np.ascontiguousarray(vertices[ids], dtype=np.float64), normals[ids]
    lift = np.zeros(len(ids))
    for g, faces in layers:
        g = np.ascontiguousarray(g, dtype=np.float64)
        under = vertices[body.query(g, k=1)[1].astype(np.int64)]  # (G, 3): the body vertex each lies over
        _, near = KDTree(g).query(v, k=8)  # not only the nearest: under a rolled hem that is its inside
        near = near.astype(np.int64)
        d = g[near] - v[:, None]
        n = normals[:, None]
        h = np.einsum("nki,nki->nk", d, np.broadcast_to(n, d.shape))
        side = np.sqrt(np.maximum(np.einsum("nki,nki->nk", d, d) - h * h, 0.0))
        gn = _normals(g, np.asarray(faces), incidence(faces, len(g)))[near]
        facing = np.einsum("nki,nki->nk", np.broadcast_to(n, gn.shape), gn)
        h = np.where(facing > 0.5, np.einsum("nki,nki->nk", d, gn) / np.maximum(facing, 0.5), h)  # curved shells
        off = np.linalg.norm(under[near] - v[:, None], axis=2)
        over = (h > 0) & (h < highest) & (side < lateral) & (off <= np.maximum(lateral, COVER_NEAR * h))
        lift = np.maximum(lift, np.where(over, h, 0.0).max(1))
    out[ids] = lift
    return out


@dataclass
class Surface:
    """A posed surface that garments are pushed out of."""

    vertices: np.ndarray
    normals: np.ndarray
    tree: Any
    faces: np.ndarray | None = None
    around: np.ndarray | None = None  # binding.incident_faces, for ``clearance``
    lift: np.ndarray | None = None  # (V,) metres the surface stands over each vertex (``lifted``)

    @classmethod
    def of(cls, vertices: np.ndarray, faces: np.ndarray, vf, around=None) -> "Surface":
        """The surface of a posed mesh; ``vf`` its faces' ``incidence`` and ``around`` their
        ``incident_faces`` (both fixed per mesh)."""
        from pykdtree.kdtree import KDTree  # built and queried 2.5-3x faster than scipy's cKDTree, the same
        vertices = np.ascontiguousarray(vertices, dtype=np.float64)  # answers (queries in OpenMP threads)
        return cls(vertices, _normals(vertices, faces, vf), KDTree(vertices), np.asarray(faces), around)

    def lifted(self, lift: np.ndarray) -> "Surface":
        """This surface raised by ``lift`` (V,) metres over each vertex: the body under the
        garments worn over it (``cover_heights``), which hair lies on."""
        return dataclasses.replace(self, lift=np.asarray(lift, dtype=np.float64))

    def _raise(self, height: np.ndarray, near: np.ndarray) -> np.ndarray:
        return height if self.lift is None else height - self.lift[near]

    def clearance(self, points: np.ndarray, band: float, k: int = 4,
                  under: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(height (N,), outward normal (N, 3)): the lowest over the tangent planes of the ``k``
        nearest vertices, made exact (closest point on the triangles around the nearest and
        the lowest; around the 2 nearest where those are one) where it is under ``band``.
        ``under`` (N,) bool, when given, is set where a plane is under the point whatever
        the exact test read: around two vertices it can miss the closest face."""
        near, h = self.planes(points, k)
        low = h.argmin(1)
        rows = np.arange(len(points))
        height, normals = h[rows, low], self.normals[near[rows, low]]
        if under is not None:
            under |= height < 0
        look = np.flatnonzero(height < band)
        if len(look):
            around = np.stack([near[look, 0], near[look, np.where(low[look] == 0, 1, low[look])]], 1)
            height[look], normals[look] = self._exact(points[look], around)
            height[look] = self._raise(height[look], near[look, 0])
        return height, normals

    def planes(self, points: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The ``k`` nearest vertices (N, k) and the heights (N, k) over their tangent planes."""
        _, near = self.tree.query(np.ascontiguousarray(points, dtype=np.float64), k=k)
        near = near.astype(np.int64)
        return near, self._raise(np.einsum("nka,nka->nk", points[:, None] - self.vertices[near], self.normals[near]), near)

    def _exact(self, points: np.ndarray, near: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Signed distance to the closest point on the faces around ``near`` vertices and the
        outward direction there (the side from the closest feature's pseudonormal: interpolated
        vertex normals read a point inside an arm as outside the chest beside it)."""
        from synmitsuba.body.binding import closest_on_faces, local_pseudonormals
        c, face, bary = closest_on_faces(self.vertices, self.faces, points,
                                         np.asarray(self.around)[near].reshape(len(points), -1))
        n = local_pseudonormals(self.vertices, self.faces, self.around, face, bary)
        d = points - c
        dist = np.linalg.norm(d, axis=1)
        side = np.where(np.einsum("ij,ij->i", d, n) < 0, -1.0, 1.0)
        n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        out = np.where(dist[:, None] > 1e-9, d * (side / np.maximum(dist, 1e-9))[:, None], n)
        return side * dist, out

    def depth(self, points: np.ndarray, reach: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
        """(signed height over the nearest vertex's tangent plane (N,), that normal (N, 3));
        points farther than ``reach`` from every vertex get +inf."""
        dist, near = self.tree.query(np.ascontiguousarray(points, dtype=np.float64), k=2, distance_upper_bound=reach)
        near = near.astype(np.int64)
        tie = (dist[:, 1] <= dist[:, 0] + 1e-7) & (near[:, 1] < near[:, 0])  # equally near: the lower index,
        dist, near = dist[:, 0], np.where(tie, near[:, 1], near[:, 0])      # so a rigid move keeps the choice
        found = np.isfinite(dist)
        near = np.where(found, near, 0)
        n = self.normals[near]
        h = self._raise(np.einsum("ij,ij->i", points - self.vertices[near], n), near)
        return np.where(found, h, np.inf), n


class GarmentCollider:
    """One garment's per-frame resolution: its margin over the body, its binding (body
    triangle's vertices and barycentric coordinates per garment vertex) and spreading matrix."""

    def __init__(self, faces: np.ndarray, n_vertices: int, margin: float, bound_vertices: np.ndarray,
                 barycentric: np.ndarray):
        self.margin = float(margin)
        self.spread = neighbour_mean(np.asarray(faces), n_vertices)
        self.incidence = incidence(np.asarray(faces), n_vertices)
        self.bound_vertices, self.barycentric = np.asarray(bound_vertices), np.asarray(barycentric)

    def resolve(self, points: np.ndarray, body: Surface, inner: Sequence[Surface] = (), calibrate: bool = False):
        """``points`` pushed out of ``body`` by the margin and out of each ``inner`` garment by
        ``LAYER_MARGIN``; returns new points (the input is not changed). No vertex is asked for
        more clearance than it had at rest: ``calibrate`` (on the rest pose, once) records each
        pass's heights, so the rest pose is left exactly as built and only what motion pushed
        in comes out."""
        out = points.copy()
        doubt = np.zeros(len(out), bool)  # under a tangent plane of the body, whatever the exact test read
        checks = [(lambda p: self._over_bound_point(p, body), self.margin),
                  (lambda p: body.clearance(p, self.margin + EXACT_BAND, under=doubt), self.margin)]
        checks += [(functools.partial(s.depth, reach=REACH), LAYER_MARGIN) for s in inner]
        if calibrate:
            self.floors = []
        carried = np.zeros(len(out), bool)  # moved by something other than their own body clearance
        pushed = np.zeros(len(out), bool)   # moved at all
        for k, (check, margin) in enumerate(checks):
            height, normals = check(out)
            if calibrate:
                self.floors.append(np.minimum(margin, height))
                continue
            own, moved = self._push(out, height, normals, self.floors[k])
            pushed |= moved > 0
            if k == 1:
                carried |= moved > own + CARRIED  # farther than it asked
            elif k > 1:
                carried |= moved > 0
        if calibrate:  # the settle step's rest readings: what was inside at rest stays as built
            self.lowest = np.minimum(self.floors[1], 0.0)
            ids, height, _ = self._under(out, np.flatnonzero(doubt), body)
            self.lowest[ids] = np.minimum(self.lowest[ids], height)
            return out
        if carried.any():
            self._back_out(out, np.flatnonzero(carried), body)
        self._settle(out, np.flatnonzero(pushed | doubt), body)
        return out

    def _back_out(self, points: np.ndarray, carried: np.ndarray, body: Surface) -> None:
        """The body's clearance again, without smoothing, for vertices ``carried`` by their
        neighbours' push or out of an inner layer: along their own normal can be into the next
        body part (a dress between belly and thigh in a squat; out of a sleeve, into the chest)."""
        height, normals = body.clearance(points[carried], self.margin + EXACT_BAND, k=8)
        push = np.clip(self.floors[1][carried] - height, 0.0, None)
        points[carried] += push[:, None] * normals

    def _settle(self, points: np.ndarray, ids: np.ndarray, body: Surface) -> None:
        """Vertices ``ids`` (moved, or under a tangent plane in pass 2) still inside the body,
        set ``SETTLE`` over the surface they are in, again up to ``SETTLE_ROUNDS`` times:
        pushed by the margin out of one thigh, a vertex of the crotch went into the other, and
        the test around two vertices read some 2-30 mm inside as outside (it can miss the
        closest face). Vertices inside at rest are only kept from going deeper (``lowest``)."""
        for _ in range(SETTLE_ROUNDS):
            ids, height, normals = self._under(points, ids, body)
            low = height < self.lowest[ids]
            ids, height, normals = ids[low], height[low], normals[low]
            if not len(ids):
                return
            points[ids] += (self.lowest[ids] + SETTLE - height)[:, None] * normals

    @staticmethod
    def _under(points: np.ndarray, ids: np.ndarray, body: Surface) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Of the vertices ``ids``, those more than ``SETTLE`` under a tangent plane of one of
        their 8 nearest body vertices (about one in ten of those asked about), with their exact
        height and normal: the closest point among the faces around all 8 (27 us a vertex)."""
        if len(ids):
            near, h = body.planes(points[ids], 8)
            under = h.min(1) < -SETTLE
            ids, near = ids[under], near[under]
        if not len(ids):
            return ids, np.zeros(0), np.zeros((0, 3))
        return (ids, *body._exact(points[ids], near))

    def _over_bound_point(self, points: np.ndarray, body: Surface) -> tuple[np.ndarray, np.ndarray]:
        """Heights over each vertex's own bound body point (posed) and the normal there."""
        at = np.einsum("nk,nka->na", self.barycentric, body.vertices[self.bound_vertices])
        n = np.einsum("nk,nka->na", self.barycentric, body.normals[self.bound_vertices])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        return np.einsum("ij,ij->i", points - at, n), n

    def _push(self, points: np.ndarray, height: np.ndarray, normals: np.ndarray, floor: np.ndarray):
        """Move points below ``floor`` (heights over their surface) up to it along ``normals``;
        a height of +inf marks a point with no surface to answer to. Returns (N,) the push each
        point asked for and how far it moved."""
        own = np.clip(floor - height, 0.0, None)  # +inf height: no push
        if not own.any():
            return own, own
        push = own
        for _ in range(SMOOTHING):  # neighbours follow part of the way: no crease at the edge
            push = np.maximum(push, self.spread @ push)
        push = push * np.isfinite(height)
        points += push[:, None] * normals
        return own, push
