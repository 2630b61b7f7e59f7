"""Fold relief for skinned garments: the creases cloth keeps where it gathers (the inside of an
elbow, the back of a knee, a cuff or a trouser hem stacked on the wrist or ankle, a top bunched
over the hips; drag lines from the armpits, a trouser's whiskers) and the soft undulation of
cloth that never lies flat, as a height field in metres over the garment's rest surface. A
skinned shell is smooth; this relief shades it as folded cloth (a bump map and darker creases),
without moving its vertices, so labels, layers and the cloth stage see the same meshes. Skirts
and dresses (simulated, folding for themselves, or hanging free) take none."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FoldZone:
    """Folds round a limb or the trunk near a joint. The zone's axis runs from the mean of the
    COCO keypoints ``at`` toward the mean of ``toward``; its centre lies ``shift`` metres along
    it; folds run across the axis every ``wavelength`` metres, ``depth`` metres from crest to
    crease at the centre, fading over ``reach`` metres along the axis (a Gaussian's sigma) and ending
    ``radius`` metres from it. ``gather``: the rest-pose direction of the side they crowd on
    (the front of an elbow, the back of a knee), or None for all round."""

    at: tuple[int, ...]
    toward: tuple[int, ...]
    shift: float
    reach: float
    radius: float
    depth: float
    wavelength: float
    gather: tuple[float, float, float] | None = None


_FRONT, _BACK = (0.0, 0.0, 1.0), (0.0, 0.0, -1.0)
# COCO-17: 5/6 shoulders, 7/8 elbows, 9/10 wrists, 11/12 hips, 13/14 knees, 15/16 ankles (left, right)
FOLD_ZONES: dict[str, FoldZone] = {
    **{f"elbow_{s}": FoldZone((e,), (w,), 0.0, 0.06, 0.085, 0.024, 0.034, _FRONT)
       for s, e, w in (("l", 7, 9), ("r", 8, 10))},
    **{f"cuff_{s}": FoldZone((w,), (e,), 0.05, 0.04, 0.075, 0.014, 0.024) for s, e, w in (("l", 7, 9), ("r", 8, 10))},
    **{f"knee_{s}": FoldZone((k,), (a,), 0.0, 0.07, 0.11, 0.022, 0.036, _BACK) for s, k, a in (("l", 13, 15), ("r", 14, 16))},
    **{f"ankle_{s}": FoldZone((a,), (k,), 0.07, 0.055, 0.10, 0.022, 0.03) for s, k, a in (("l", 13, 15), ("r", 14, 16))},
    **{f"lap_{s}": FoldZone((h,), (k,), 0.06, 0.05, 0.12, 0.014, 0.032, _FRONT) for s, h, k in (("l", 11, 13), ("r", 12, 14))},
    "waist": FoldZone((11, 12), (5, 6), 0.1, 0.06, 0.3, 0.014, 0.045),
}


@dataclass(frozen=True)
class FoldFan:
    """Drag folds radiating from a point where cloth hangs from the body (an armpit): ridges
    along rays from the mean of the COCO keypoints ``at`` (moved ``shift`` of the way toward
    ``down``), fanning ``spread`` radians either side of the direction toward ``toward``, one
    every ``spacing`` radians, ``depth`` metres from crest to crease, fading over ``reach``
    metres from the point (starting 2 cm out from it)."""

    at: tuple[int, ...]
    down: tuple[int, ...]
    shift: float
    toward: tuple[int, ...]
    spread: float
    spacing: float
    reach: float
    depth: float


FOLD_FANS: dict[str, FoldFan] = {
    **{f"armpit_{s}": FoldFan((sh,), (hip,), 0.22, (5, 6), 0.6, 0.24, 0.1, 0.012)
       for s, sh, hip in (("l", 5, 11), ("r", 6, 12))},
    # a trouser's whiskers: from the crotch up and out over each thigh toward its hip
    **{f"crotch_{s}": FoldFan((11, 12), (13, 14), 0.12, (hip,), 0.5, 0.2, 0.09, 0.008) for s, hip in (("l", 11), ("r", 12))},
}
FOLD_MAP_SIZE = 512  # texels across at most: a larger atlas takes the relief scaled up
FOLD_STREAM = 11  # a garment's relief draws from default_rng([its texture seed, FOLD_STREAM])
UNDULATION = (0.0015, 0.07, 0.2)  # metres deep, shortest and longest wavelength of the soft relief everywhere
WAVES = 8  # plane waves summed for it
REACHES = 3.5  # a zone's folds end this many reaches along its axis (their weight under 0.22 %)
FOLDS_PER_ZONE = 16  # folds a zone draws its own strength and arc for (more repeat them)


def fold_relief(points: np.ndarray, keypoints: np.ndarray, rng: np.random.Generator, looseness: float = 1.0,
                zones: dict[str, FoldZone] | None = None, fans: dict[str, FoldFan] | None = None,
                texel: float = 0.0) -> np.ndarray:
    """Height in metres (N,) over rest ``points`` (N, 3) of a garment, ``keypoints`` the body's
    COCO keypoints at rest: each zone's and fan's folds plus the soft undulation, scaled by
    ``looseness`` (1: a garment of ordinary ease; tighter cloth folds less). Folds under 6
    ``texel``s (metres a texel of the map spans) apart fade out, as a pattern's bump does, rather
    than alias. Deterministic from ``rng`` (the undulation draws first, then the zones, then the
    fans, each in name order)."""
    zones = FOLD_ZONES if zones is None else zones
    fans = FOLD_FANS if fans is None else fans
    out = resolved(UNDULATION[1], texel) * _undulation(points, rng)
    for name in sorted(zones):  # a fixed order: the draws do not depend on the dict's
        z = zones[name]
        a, b = keypoints[list(z.at)].mean(0), keypoints[list(z.toward)].mean(0)
        axis = (b - a) / max(float(np.linalg.norm(b - a)), 1e-9)
        centre = a + z.shift * axis
        d = points - centre
        s = d @ axis
        near = np.flatnonzero((np.abs(s) < REACHES * z.reach) & (np.einsum("nd,nd->n", d, d) - s * s < z.radius ** 2))
        fold = _zone(z, d[near], s[near], axis, rng)  # the zone's draws are made whether or not any point is near
        out[near] += resolved(z.wavelength, texel) * fold
    for name in sorted(fans):
        f = fans[name]
        out += resolved(f.spacing * f.reach, texel) * _fan(f, points, keypoints, rng)
    return looseness * out


def resolved(period: float, texel: float) -> float:
    """1 for folds ``period`` metres apart on a map of ``texel``-metre texels, fading to 0 from 6
    texels a period down to 2 (``textures._height``'s rule for a pattern's bump)."""
    return float(np.clip((period / texel - 2.0) / 4.0, 0.0, 1.0)) if texel > 0 else 1.0


def _fan(f: FoldFan, points: np.ndarray, keypoints: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One fan's ridges, in the body's frontal plane (front and back alike): each reaches its own
    length and strength (they meet at the creases between them, where each is zero)."""
    top, low = keypoints[list(f.at)].mean(0), keypoints[list(f.down)].mean(0)
    centre = top + f.shift * (low - top)
    aim = keypoints[list(f.toward)].mean(0) - centre
    aim[2] = 0.0
    aim /= max(float(np.linalg.norm(aim)), 1e-9)
    side = np.cross([0.0, 0.0, 1.0], aim)
    d = points - centre
    s, t = d @ aim, d @ side
    r = np.hypot(s, t)
    phi = np.arctan2(t, s)
    x = phi / f.spacing + 0.15 * np.sin(r / 0.03 + rng.uniform(0, 2 * np.pi)) + rng.uniform(0, 1)
    ridges = FOLDS_PER_ZONE
    strength, length = rng.uniform(0.3, 1.0, ridges), rng.uniform(0.5, 1.5, ridges)
    i = np.floor(x).astype(np.int64) % ridges
    start = np.clip((r - 0.02) / 0.03, 0, 1) * np.clip((f.spread - np.abs(phi)) / 0.2, 0, 1)
    ridge = start * np.exp(-0.5 * (r / (f.reach * length[i])) ** 2) * strength[i] * np.abs(np.sin(np.pi * x))
    level = 1 / np.pi * strength.mean() * start * np.exp(-0.5 * (r / f.reach) ** 2)  # about the ridges' mean
    return f.depth * (ridge - level)


def _undulation(points: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A sum of ``WAVES`` plane waves of random directions, wavelengths and phases."""
    depth, shortest, longest = UNDULATION
    d = rng.normal(size=(WAVES, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    k = 2 * np.pi / rng.uniform(shortest, longest, WAVES)
    phase = rng.uniform(0, 2 * np.pi, WAVES)
    return depth * np.sqrt(2.0 / WAVES) * np.sin(points @ (d * k[:, None]).T + phase).sum(1)


def _zone(z: FoldZone, d: np.ndarray, s: np.ndarray, axis: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One zone's folds at points ``d`` (N, 3) from its centre, ``s`` (N,) of them along its
    ``axis``: rows across the axis, unevenly spaced and wavering round it, each a rounded ridge
    between sharp creases that reaches only part of the way round (its own strength and arc; the
    ridges meet at the creases, where each is zero, so the relief stays continuous), deeper on
    the ``gather`` side."""
    radial = d - s[:, None] * axis
    r = np.linalg.norm(radial, axis=1)
    ref = np.cross(axis, [0.0, 1.0, 0.0]) if abs(axis[1]) < 0.9 else np.cross(axis, [1.0, 0.0, 0.0])
    ref /= np.linalg.norm(ref)
    theta = np.arctan2(radial @ np.cross(axis, ref), radial @ ref)
    amp, off = rng.uniform(0.3, 0.9, 3), rng.uniform(0, 2 * np.pi, 3)
    waver = sum(amp[i] / (i + 1) * np.sin((i + 1) * theta + off[i]) for i in range(3))
    uneven = 0.3 * np.sin(2 * np.pi * s / (2.7 * z.wavelength) + rng.uniform(0, 2 * np.pi))  # spacing
    x = s / z.wavelength + uneven + waver + rng.uniform(0, 1)  # folds from crease to crease: x in [i, i + 1)
    ridge = np.abs(np.sin(np.pi * x))  # rounded crests, sharp creases
    folds = FOLDS_PER_ZONE
    strength, spread, centre = rng.uniform(0.2, 1.0, folds), rng.uniform(0.3, 1.2, folds), rng.uniform(-np.pi, np.pi, folds)
    i = np.floor(x).astype(np.int64) % folds
    arc = np.clip(0.5 + spread[i] * np.cos(theta - centre[i]), 0, 1) * strength[i]
    weight = np.exp(-0.5 * (s / z.reach) ** 2) * np.clip((z.radius - r) / 0.02, 0, 1)
    if z.gather is not None:
        side = radial @ np.asarray(z.gather) / np.maximum(r, 1e-9)
        weight *= 0.35 + 0.65 * np.clip(side, 0, 1)
    level = 2 / np.pi * 0.5 * strength.mean()  # about the folds' mean, so the zone neither swells nor sinks
    return z.depth * weight * (arc * ridge - level)  # each fold is zero at its creases: no steps between them


def fold_looseness(ease: float) -> float:
    """How deep a garment's folds are against an ordinary one's, from its ease (metres of
    looseness, 0 .. 0.06): a snug garment folds about half as deep, a baggy one half again."""
    return float(np.clip(0.6 + 25.0 * ease, 0.5, 1.6))


def crease_shade(height: np.ndarray, depth: float = 0.006, darkest: float = 0.8) -> np.ndarray:
    """An albedo factor from a fold ``height`` field (metres): 1 on crests, down to ``darkest``
    ``depth`` metres into a crease (light reaches less of it)."""
    return 1.0 - (1.0 - darkest) * np.clip(-height / depth, 0, 1)
