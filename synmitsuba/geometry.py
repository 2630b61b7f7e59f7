"""Geometry shared by every stage, from scipy and trimesh where they already do it.

Rotations (vector alignment included) are scipy's ``Rotation``/``Slerp`` behind names that
state our conventions (BVH's intrinsic Euler order); normals and areas are trimesh's. The
two things written here are ours alone: the orthonormal frame from an up and a forward
direction, and the camera-ray matrix ``R^T K^-1`` every camera consumer uses.
"""
from __future__ import annotations

from typing import Any

import numpy as np


# -- rotations ---------------------------------------------------------------------------
def _Rotation():
    from scipy.spatial.transform import Rotation
    return Rotation


def _batched(fn, arr: np.ndarray, tail: int, out_tail: tuple) -> np.ndarray:
    """Apply a scipy constructor over leading axes: (..., tail) -> (..., *out_tail)."""
    arr = np.asarray(arr, dtype=np.float64)
    lead = arr.shape[:arr.ndim - tail] if tail else arr.shape
    flat = arr.reshape((-1,) + arr.shape[len(lead):])
    out = fn(flat) if len(flat) else np.zeros((0,) + out_tail)
    return np.asarray(out).reshape(lead + out_tail)


def axis_rotation(axis: str, angle) -> np.ndarray:
    """Rotation matrices (..., 3, 3) about 'x', 'y' or 'z' by ``angle`` radians."""
    a = np.asarray(angle, dtype=np.float64)
    return _batched(lambda x: _Rotation().from_euler(axis.lower(), x[:, None]).as_matrix(), a, 0, (3, 3))


def euler_to_matrix(angles, order: str) -> np.ndarray:
    """Intrinsic rotations applied in ``order`` (BVH convention): for order 'ZXY',
    R = Rz(a0) @ Rx(a1) @ Ry(a2). ``angles`` (..., len(order)) in radians."""
    # scipy: upper-case axes are intrinsic, which is exactly BVH's channel order
    return _batched(lambda x: _Rotation().from_euler(order.upper(), x).as_matrix(), angles, 1, (3, 3))


def axis_angle_to_matrix(v) -> np.ndarray:
    """Rotation vectors (..., 3) -> matrices (..., 3, 3)."""
    return _batched(lambda x: _Rotation().from_rotvec(x).as_matrix(), v, 1, (3, 3))


def matrix_to_axis_angle(R) -> np.ndarray:
    """Matrices (..., 3, 3) -> rotation vectors (..., 3)."""
    return _batched(lambda x: _Rotation().from_matrix(x).as_rotvec(), R, 2, (3,))


def slerp_matrices(rotations: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Rotations (F, ..., 3, 3) keyed at frames 0..F-1, sampled at fractional frame ``times``
    (T,) by spherical interpolation per element (scipy's ``Slerp``) -> (T, ..., 3, 3)."""
    from scipy.spatial.transform import Slerp
    R = np.asarray(rotations, dtype=np.float64)
    F, inner = R.shape[0], R.shape[1:-2]
    flat = R.reshape(F, -1, 3, 3)
    times = np.clip(np.asarray(times, dtype=np.float64), 0, F - 1)
    if F == 1:
        return np.broadcast_to(R[0], (len(times),) + R.shape[1:]).copy()
    out = np.empty((len(times), flat.shape[1], 3, 3))
    for j in range(flat.shape[1]):
        out[:, j] = Slerp(np.arange(F), _Rotation().from_matrix(flat[:, j]))(times).as_matrix()
    return out.reshape((len(times),) + inner + (3, 3))


def align_vectors(a, b) -> np.ndarray:
    """The smallest rotation (3, 3) taking direction ``a`` to direction ``b`` (scipy's
    ``Rotation.align_vectors`` with one pair; trimesh's ``align_vectors`` is not the smallest:
    it may add a twist about ``b``, which retargeting must not)."""
    R, _ = _Rotation().align_vectors([np.asarray(b, float)], [np.asarray(a, float)])
    return R.as_matrix()


# -- frames ------------------------------------------------------------------------------
def frame(forward, up, keep: str = "up") -> np.ndarray:
    """Right-handed orthonormal frame (3, 3) whose columns are (side, up, forward) with
    side = up x forward. ``keep`` names the direction kept exactly ("up" for a head or body
    frame, "forward" for a camera or a light); the other is made perpendicular to it.
    Raises ValueError when the two are parallel."""
    u = np.asarray(up, dtype=np.float64)
    f = np.asarray(forward, dtype=np.float64)
    u, f = u / np.linalg.norm(u), f / np.linalg.norm(f)
    side = np.cross(u, f)
    if np.linalg.norm(side) < 1e-9:
        raise ValueError("forward is parallel to up")
    side /= np.linalg.norm(side)
    if keep == "up":
        f = np.cross(side, u)
    else:
        u = np.cross(f, side)
    return np.stack([side, u, f], 1)


def rigid_fit(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rotation R, translation t) with b ~ a @ R.T + t, least squares (Kabsch, no reflection).
    Sums by einsum, not BLAS: the same bits whatever the thread count (the cloth stage fits one
    a frame)."""
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd(np.einsum("ni,nj->ij", a - ca, b - cb))
    d = np.sign(np.linalg.det(u @ vt))
    rot = (u @ np.diag([1.0, 1.0, d]) @ vt).T
    return rot, cb - np.einsum("j,ij->i", ca, rot)


def bounds(points) -> tuple[np.ndarray, np.ndarray]:
    """(min (D,), max (D,)) of ``points`` (N, D), column by column: ``points.min(0)`` on a
    (140k, 3) array takes 3.7 ms, a column at a time 0.15 ms."""
    pts = np.asarray(points)
    return (np.array([pts[:, k].min() for k in range(pts.shape[1])]),
            np.array([pts[:, k].max() for k in range(pts.shape[1])]))


# -- meshes ------------------------------------------------------------------------------
def ground_grid(half_size: float, cell: float = 10.0, near: float = 100.0) -> tuple[np.ndarray, np.ndarray]:
    """A square ground at y = 0 (vertices (V, 3), faces (F, 3) facing +y) out to ``half_size``:
    ``cell``-metre squares within ``near`` of the origin, then squares doubling in size. A point
    interpolated on a triangle in float32 (Mitsuba's uv, texture lookups) is off by about the
    triangle's size times 1e-7: 2-6 mm on one 40 km triangle, under 2 um on 10 m cells."""
    ring, step = list(np.arange(0.0, min(near, half_size), cell)), cell
    edge = ring[-1]
    while edge < half_size:
        step = step * 2 if edge >= near else step
        edge = min(edge + step, half_size)
        ring.append(edge)
    xs = np.concatenate([-np.array(ring[:0:-1]), ring])
    n = len(xs)
    gx, gz = np.meshgrid(xs, xs, indexing="ij")
    vertices = np.stack([gx.ravel(), np.zeros(n * n), gz.ravel()], 1)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a, b, c, d = (i * n + j).ravel(), ((i + 1) * n + j).ravel(), ((i + 1) * n + j + 1).ravel(), (i * n + j + 1).ravel()
    faces = np.concatenate([np.stack([a, d, c], 1), np.stack([a, c, b], 1)])
    return vertices, faces


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (trimesh's mean of the unnormalised face normals)."""
    import trimesh
    v = np.asarray(vertices, dtype=np.float64)
    cross = trimesh.triangles.cross(v[faces])
    return trimesh.geometry.mean_vertex_normals(len(v), faces, cross)


def face_cross(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F, 3) cross products of each triangle's two edges from its first corner: twice its area
    along its normal. By components: np.cross on a (F, 3, 3) gather took half again as long."""
    v = np.asarray(vertices, dtype=np.float64)
    a = v[faces[:, 0]]
    e1, e2 = v[faces[:, 1]] - a, v[faces[:, 2]] - a
    cross = np.empty_like(e1)
    cross[:, 0] = e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1]
    cross[:, 1] = e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2]
    cross[:, 2] = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    return cross


def unique_rows(rows: np.ndarray, return_index: bool = False, return_inverse: bool = False,
                return_counts: bool = False):
    """``np.unique(rows, axis=0, ...)`` for an (N, K) integer array, the same rows in the same
    order with the same index, (N,) inverse and counts, from one int64 key a row (mixed radix
    over each column's range; numpy's own axis=0 path when that key would overflow). numpy
    sorts rows as structured records: 7x slower on a body's 85,000 corner pairs."""
    rows = np.asarray(rows)
    flags: dict[str, Any] = dict(return_index=return_index, return_inverse=return_inverse, return_counts=return_counts)
    if rows.ndim != 2 or not len(rows) or rows.dtype.kind not in "iu":
        return np.unique(rows, axis=0, **flags)
    lo = rows.min(0).astype(np.int64)
    span = rows.max(0).astype(np.int64) - lo + 1
    if np.sum(np.log2(span.astype(np.float64))) >= 62:
        return np.unique(rows, axis=0, **flags)
    stride = np.concatenate([np.cumprod(span[::-1])[::-1][1:], [1]])
    key = (rows.astype(np.int64) - lo) @ stride
    out = np.unique(key, **flags)
    first = out[0] if isinstance(out, tuple) else out
    unique = (first[:, None] // stride % span + lo).astype(rows.dtype)
    return (unique, *out[1:]) if isinstance(out, tuple) else unique


class SmoothNormals:
    """Area-weighted unit vertex normals of a fixed triangulation, summed over the vertices
    ``weld`` maps to one index (``body.topology.weld``: the copies of a vertex along uv seams),
    so shading runs smoothly across seams; a copy keeps its own side's normal where its group's
    faces cancel at ``rest`` (two sheets through the same points facing away from each other).
    The sums are sparse products set up once: about 1 ms a frame for a body."""

    def __init__(self, faces: np.ndarray, weld: np.ndarray, rest: np.ndarray):
        from scipy import sparse
        self.faces = np.asarray(faces)
        n, f = len(weld), len(self.faces)
        own = sparse.csr_matrix((np.ones(3 * f), (self.faces.ravel(), np.repeat(np.arange(f), 3))), shape=(n, f))
        to_group = sparse.csr_matrix((np.ones(n), (weld, np.arange(n))), shape=(n, n))
        self.group = (to_group.T @ (to_group @ own)).tocsr()  # each vertex: its whole group's faces
        cross = face_cross(rest, self.faces)
        self.alone = np.flatnonzero(np.linalg.norm(self.group @ cross, axis=1)
                                    <= 0.25 * np.linalg.norm(own @ cross, axis=1))
        self.own = own[self.alone]

    def __call__(self, vertices: np.ndarray) -> np.ndarray:
        cross = face_cross(vertices, self.faces)
        n = self.group @ cross
        n[self.alone] = self.own @ cross
        return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def face_normals(triangles: np.ndarray) -> np.ndarray:
    """Unit normals (N, 3) of triangles (N, 3, 3); zero for degenerate ones."""
    import trimesh
    cross = trimesh.triangles.cross(np.asarray(triangles, dtype=np.float64))
    return cross / np.maximum(np.linalg.norm(cross, axis=1, keepdims=True), 1e-12)


def triangle_areas(triangles: np.ndarray) -> np.ndarray:
    """Areas (N,) of triangles (N, 3, 3)."""
    import trimesh
    return trimesh.triangles.area(np.asarray(triangles, dtype=np.float64))


# -- cameras -----------------------------------------------------------------------------
def camera_ray_matrix(K: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``R^T K^-1``: maps homogeneous pixel coordinates [u, v, 1] (pixel centres at integer +
    0.5) to the world direction of the ray through them. Used by the sensor, the exact passes
    and ``Camera.pixel_rays`` alike."""
    return np.asarray(R, dtype=np.float64).T @ np.linalg.inv(np.asarray(K, dtype=np.float64))
