"""Independent reference computations that tests (and bench scripts) check the package
against; not shipped, since nothing in the package needs them."""
from __future__ import annotations

import numpy as np


def winding_numbers(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray, chunk: int = 2 ** 22) -> np.ndarray:
    """Generalised winding numbers (N,) of ``points`` in a closed mesh: the triangles' signed
    solid angles over 4 pi (van Oosterom and Strackee). ~1 inside, ~0 outside, and still so
    where a posed body folds or runs into itself, where the closest triangle's side does not
    say inside. O(points x faces): for the few points a cheaper test flags."""
    v, f = np.asarray(vertices, dtype=np.float64), np.asarray(faces)
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.empty(len(points))
    step = max(1, chunk // max(1, len(f)))
    for s in range(0, len(points), step):
        a, b, c = (v[f[:, i]][None] - points[s:s + step, None] for i in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        det = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("pfi,pfi->pf", a, b) * lc + np.einsum("pfi,pfi->pf", b, c) * la
               + np.einsum("pfi,pfi->pf", c, a) * lb)
        out[s:s + step] = np.arctan2(det, den).sum(1) / (2 * np.pi)
    return out


def bound_points(binding, body_vertices, body_faces) -> np.ndarray:
    """The bound body points for (possibly posed) body vertices."""
    return np.einsum("nk,nka->na", binding.barycentric, body_vertices[body_faces[binding.triangle]])
