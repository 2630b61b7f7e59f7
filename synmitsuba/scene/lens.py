"""Lens distortion models in OpenCV's conventions, written once for numpy and for drjit.

A model maps normalised pinhole coordinates (x, y) = (X / Z, Y / Z) of a camera-frame point to
distorted normalised coordinates (``distort``; the pixel is then ``K @ [xd, yd, 1]``), and a
distorted (xd, yd) back to the camera-frame direction of its ray (``direction``, by Newton's
method). ``ops`` holds the maths functions of the array type in use (``NUMPY_OPS`` or
``drjit_ops()``), so the sensor, the exact passes and ``Camera.project`` share one formula.

- ``brown_conrady``: coefficients (k1, k2, p1, p2, k3), ``cv2.projectPoints``'s ``distCoeffs``.
- ``fisheye``: coefficients (k1, k2, k3, k4) of ``cv2.fisheye.projectPoints``: the angle from
  the axis theta is bent to theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8).
"""
from __future__ import annotations

import types
from dataclasses import dataclass
from typing import Callable

import numpy as np

NEWTON_STEPS = 12  # float32 converges in 4-6 for the sampled ranges; more costs little

NUMPY_OPS = types.SimpleNamespace(sqrt=np.sqrt, atan=np.arctan, sin=np.sin, cos=np.cos, where=np.where)


def drjit_ops():
    import drjit as dr
    return types.SimpleNamespace(sqrt=dr.sqrt, atan=dr.atan, sin=dr.sin, cos=dr.cos, where=dr.select)


def _brown(x, y, k, ops):
    k1, k2, p1, p2, k3 = k
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    return (x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
            y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)


def _brown_direction(xd, yd, k, ops):
    """Newton on the 2D map from (xd, yd): its Jacobian written out."""
    k1, k2, p1, p2, k3 = k
    x, y = xd, yd
    for _ in range(NEWTON_STEPS):
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        g = 2 * (k1 + r2 * (2 * k2 + 3 * k3 * r2))  # d radial / d r2, twice
        fx, fy = _brown(x, y, k, ops)
        a = radial + x * x * g + 2 * p1 * y + 6 * p2 * x
        b = x * y * g + 2 * p1 * x + 2 * p2 * y
        d = radial + y * y * g + 6 * p1 * y + 2 * p2 * x
        det = a * d - b * b
        ex, ey = fx - xd, fy - yd
        x, y = x - (d * ex - b * ey) / det, y - (a * ey - b * ex) / det
    return x, y, x * 0 + 1


def _theta_d(theta, k):
    t2 = theta * theta
    return theta * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))))


def _fisheye(x, y, k, ops):
    r = ops.sqrt(x * x + y * y)
    scale = ops.where(r > 1e-12, _theta_d(ops.atan(r), k) / ops.where(r > 1e-12, r, 1), 1)
    return x * scale, y * scale


def _fisheye_direction(xd, yd, k, ops):
    rd = ops.sqrt(xd * xd + yd * yd)
    theta = rd
    for _ in range(NEWTON_STEPS):
        t2 = theta * theta
        slope = 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])))
        theta = theta - (_theta_d(theta, k) - rd) / slope
    s = ops.where(rd > 1e-12, ops.sin(theta) / ops.where(rd > 1e-12, rd, 1), 1)
    return xd * s, yd * s, ops.cos(theta)


def _first_root(coefficients) -> float:
    """The smallest positive real root of the polynomial (lowest power first), else inf."""
    roots = np.roots(np.asarray(coefficients, np.float64)[::-1]) if np.any(coefficients[1:]) else np.array([])
    real = [r.real for r in roots if abs(r.imag) < 1e-12 and r.real > 0]
    return min(real, default=np.inf)


def _brown_fold(k) -> float:
    """r^2 where the radial distortion stops growing: d(r (1 + k1 r^2 + k2 r^4 + k3 r^6)) / dr = 0."""
    k1, k2, _, _, k3 = (float(c) for c in k)
    return _first_root([1.0, 3 * k1, 5 * k2, 7 * k3])


def _fisheye_fold(k) -> float:
    """r^2 (of the pinhole coordinates) where theta_d stops growing, or the horizon."""
    t2 = _first_root([1.0] + [(2 * i + 3) * float(c) for i, c in enumerate(k)])
    return float(np.tan(min(np.sqrt(t2), np.pi / 2 - 1e-6)) ** 2)


@dataclass(frozen=True)
class LensModel:
    coefficients: tuple[str, ...]
    distort: Callable       # (x, y, k, ops) -> (xd, yd)
    direction: Callable     # (xd, yd, k, ops) -> camera-frame ray direction (dx, dy, dz), not unit
    fold: Callable          # (k) -> r^2 = x^2 + y^2 beyond which the image folds back (inf: never)


LENS_MODELS: dict[str, LensModel] = {
    "brown_conrady": LensModel(("k1", "k2", "p1", "p2", "k3"), _brown, _brown_direction, _brown_fold),
    "fisheye": LensModel(("k1", "k2", "k3", "k4"), _fisheye, _fisheye_direction, _fisheye_fold),
}


def image_radius(K: np.ndarray, width: int, height: int) -> float:
    """The largest distorted radius (normalised coordinates) among the image's corners."""
    corners = np.array([[0, 0, 1], [width, 0, 1], [0, height, 1], [width, height, 1]], np.float64)
    n = corners @ np.linalg.inv(K).T
    return float(np.hypot(n[:, 0], n[:, 1]).max())


def folded_radius(lens: str, k) -> float:
    """The largest distorted radius the lens reaches (where it folds; inf when it never does)."""
    model = LENS_MODELS[lens]
    r2 = model.fold(k)
    if not np.isfinite(r2):
        return np.inf
    r = np.sqrt(r2)
    xd, yd = model.distort(np.array([r]), np.array([0.0]), [*k[:2], 0.0, 0.0, *k[4:]] if lens == "brown_conrady" else k,
                           NUMPY_OPS)
    return float(np.hypot(xd, yd)[0])
