"""``thigh_web``: a closed slab of the body's own vertices spanning the gap between the thighs
under the crotch, for the collider of a top that hangs to there. Against the body and the
trousers alone, a t-shirt's back hem at crotch height hung into that gap, was pinched between
the thighs as they scissored in a walk and thrown 0.3 m behind (bench/RESULTS.md, session 90).
Cloth hanging over the legs bridges them; the web lets the collider do the same. Its corners
are body vertices on the inner thighs, so it moves, stretches and tilts with the legs."""
from __future__ import annotations

import numpy as np

LEVELS = 6        # rings of the web, the crotch down
STEP = 0.03       # metres between them
BAND = 0.012      # metres above and below a level where its corners are looked for
INNER = 0.02     # metres from the thigh's innermost vertex (|x|) that its corners may lie


def thigh_web(vertices: np.ndarray, group: np.ndarray, crotch_y: float) -> tuple[np.ndarray, np.ndarray]:
    """(body vertex of each web corner, (T, 3) faces over the corners, wound outward) from the
    rest body's ``vertices`` and vertex ``group`` names; empty when the thighs have no vertices
    at those heights."""
    corners = []
    for j in range(LEVELS):
        y = crotch_y - 0.01 - STEP * j
        ring = [_corner(vertices, group, y, side, front) for side in (1, -1) for front in (True, False)]
        if any(c is None for c in ring):
            break
        corners.append(ring)  # left front, left back, right front, right back
    if len(corners) < 2:
        return np.zeros(0, np.int64), np.zeros((0, 3), np.int64)
    index = np.asarray(corners, np.int64)
    n = len(index)
    k = np.arange(4 * n).reshape(n, 4)
    quads = [(k[j, a], k[j, b], k[j + 1, b], k[j + 1, a]) for j in range(n - 1)
             for a, b in ((0, 2), (2, 3), (3, 1), (1, 0))]  # front, right end, back, left end
    quads += [(k[0, 0], k[0, 1], k[0, 3], k[0, 2]), (k[-1, 0], k[-1, 2], k[-1, 3], k[-1, 1])]
    faces = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], np.int64)  # wound alike
    return index.reshape(-1), _outward(vertices[index.reshape(-1)], faces)


def _corner(v: np.ndarray, group: np.ndarray, y: float, side: int, front: bool) -> int | None:
    """The front-most (or back-most) thigh vertex on ``side`` (1: +x, the left) within ``BAND``
    of height ``y`` and ``INNER`` of the one nearest the body's middle (x = 0): the ends of the
    inner thigh's face there."""
    leg = np.flatnonzero((group == "upperleg") & (np.sign(v[:, 0]) == side) & (np.abs(v[:, 1] - y) <= BAND))
    if not len(leg):
        return None
    inner = leg[np.abs(v[leg, 0]) <= np.abs(v[leg, 0]).min() + INNER]
    return int(inner[np.argmax(v[inner, 2])] if front else inner[np.argmin(v[inner, 2])])


def _outward(points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``faces`` (consistently wound) turned over if they enclose a negative volume."""
    a, b, c = (points[faces[:, i]] for i in range(3))
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6
    return faces if volume >= 0 else faces[:, ::-1].copy()
