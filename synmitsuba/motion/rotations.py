"""Rotation helpers, vectorized over leading axes: Euler angles in any order, axis-angle,
quaternions (w, x, y, z) and slerp."""
from __future__ import annotations

import numpy as np


def axis_rotation(axis: str, angle) -> np.ndarray:
    """Rotation matrices (..., 3, 3) about 'x', 'y' or 'z' by ``angle`` radians."""
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    rows = {"x": [[o, z, z], [z, c, -s], [z, s, c]],
            "y": [[c, z, s], [z, o, z], [-s, z, c]],
            "z": [[c, -s, z], [s, c, z], [z, z, o]]}[axis.lower()]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def euler_to_matrix(angles, order: str) -> np.ndarray:
    """Intrinsic rotations applied in ``order`` (BVH convention): for order 'ZXY',
    R = Rz(a0) @ Rx(a1) @ Ry(a2). ``angles`` (..., len(order)) in radians."""
    angles = np.asarray(angles, dtype=np.float64)
    R = np.broadcast_to(np.eye(3), angles.shape[:-1] + (3, 3)).copy()
    for k, axis in enumerate(order):
        R = R @ axis_rotation(axis, angles[..., k])
    return R


def axis_angle_to_matrix(v) -> np.ndarray:
    """Rodrigues: rotation vectors (..., 3) -> matrices (..., 3, 3)."""
    v = np.asarray(v, dtype=np.float64)
    theta = np.linalg.norm(v, axis=-1, keepdims=True)
    k = v / np.where(theta > 1e-12, theta, 1.0)
    K = np.zeros(v.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -k[..., 2], k[..., 1], -k[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = k[..., 2], -k[..., 1], k[..., 0]
    t = theta[..., None]
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * (K @ K)


def matrix_to_quat(R) -> np.ndarray:
    """Matrices (..., 3, 3) -> unit quaternions (..., 4) as (w, x, y, z), w >= 0."""
    R = np.asarray(R, dtype=np.float64)
    m = R.reshape(-1, 3, 3)
    tr = np.trace(m, axis1=1, axis2=2)
    cand = np.stack([1 + tr, 1 + 2 * m[:, 0, 0] - tr, 1 + 2 * m[:, 1, 1] - tr, 1 + 2 * m[:, 2, 2] - tr], 1)
    best = cand.argmax(1)
    q = np.empty((len(m), 4))
    s = np.sqrt(np.maximum(cand[np.arange(len(m)), best], 1e-300))
    for b in range(4):
        sel = best == b
        if not sel.any():
            continue
        mm, ss = m[sel], s[sel]
        w = (mm[:, 2, 1] - mm[:, 1, 2], mm[:, 0, 2] - mm[:, 2, 0], mm[:, 1, 0] - mm[:, 0, 1])
        if b == 0:
            q[sel] = np.stack([ss, w[0] / ss, w[1] / ss, w[2] / ss], 1)
        elif b == 1:
            q[sel] = np.stack([w[0] / ss, ss, (mm[:, 0, 1] + mm[:, 1, 0]) / ss, (mm[:, 0, 2] + mm[:, 2, 0]) / ss], 1)
        elif b == 2:
            q[sel] = np.stack([w[1] / ss, (mm[:, 0, 1] + mm[:, 1, 0]) / ss, ss, (mm[:, 1, 2] + mm[:, 2, 1]) / ss], 1)
        else:
            q[sel] = np.stack([w[2] / ss, (mm[:, 0, 2] + mm[:, 2, 0]) / ss, (mm[:, 1, 2] + mm[:, 2, 1]) / ss, ss], 1)
    q *= 0.5
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(R.shape[:-2] + (4,))


def quat_to_matrix(q) -> np.ndarray:
    q = np.asarray(q, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def slerp(q0, q1, w) -> np.ndarray:
    """Spherical interpolation between quaternions (..., 4) with weights w (...) in [0, 1]."""
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    w = np.asarray(w, float)[..., None]
    dot = (q0 * q1).sum(-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin = np.sin(theta)
    small = sin < 1e-6
    a = np.where(small, 1 - w, np.sin((1 - w) * theta) / np.where(small, 1, sin))
    b = np.where(small, w, np.sin(w * theta) / np.where(small, 1, sin))
    out = a * q0 + b * q1
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def angle_between(R1, R2) -> np.ndarray:
    """Geodesic angle (radians) between rotation matrices."""
    tr = np.trace(np.swapaxes(R1, -1, -2) @ R2, axis1=-2, axis2=-1)
    return np.arccos(np.clip((tr - 1) / 2, -1.0, 1.0))
