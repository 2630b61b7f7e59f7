"""Procedural PBR ground materials at real-world scale: albedo, height (for a normal map) and
roughness maps drawn from a seed, plus a wide blend mask so that a ground does not repeat.

Each kind in ``GROUND_MATERIALS`` is a ``GroundKind``: a builder that draws one tile of
``period_m`` metres (structure from ``layout``, tones and noise from ``tone``) and its default
period. ``ground_material`` draws two tiles that share their structure (joints, planks, bricks)
but not their tones, and blends them with a mask that repeats only every ``MACRO_M`` metres;
kinds without structure (asphalt, grass, sand, carpet) lay the second tile at ``GOLDEN`` times
the first's size. No shift of the ground shows the same pattern twice over 30 m.
"""
from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import Callable

import numpy as np

MACRO_M = 41.3      # metres the blend mask repeats over (incommensurate with every tile period)
TILE_PX = 1024      # pixels across one tile
MACRO_PX = 512
GOLDEN = (1 + 5 ** 0.5) / 2
NORMAL_STRENGTH = 1.0


@dataclass
class GroundMaps:
    """One tile of ``period_m`` metres: albedo (n, n, 3) linear RGB, height (n, n) metres,
    roughness (n, n) in [0, 1]."""

    albedo: np.ndarray
    height: np.ndarray
    roughness: np.ndarray
    period_m: float


@dataclass
class GroundKind:
    """``build(base_rgb, layout_rng, tone_rng, n, period_m) -> GroundMaps`` and its period."""

    build: Callable
    period_m: float
    wear: tuple = (0.86, 0.84, 0.8)   # the second tile's tint: worn, dusty, dry or wet patches
    doc: str = ""
    structured: bool = True           # joints, planks or bricks: both tiles share one scale


# -- noise and layouts ----------------------------------------------------------------------
def periodic_noise(rng: np.random.Generator, n: int, beta: float, low: float = 3.0) -> np.ndarray:
    """Seamlessly tiling noise: white noise shaped by 1/f^beta, standardised to mean 0, deviation
    1. Frequencies under ``low`` cycles per tile are removed: a feature as large as the tile
    would mark its repeats from afar (large-scale variation is the macro mask's)."""
    f = np.fft.fftfreq(n) * n
    r = np.hypot(*np.meshgrid(f, f, indexing="ij"))
    amp = np.where(r > max(low, 0.5), 1.0 / np.maximum(r, 1.0) ** beta, 0.0)
    img = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * amp))
    return (img - img.mean()) / (img.std() + 1e-12)


def _grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Texel-centre coordinates (u along axis 0, v along axis 1) in [0, 1)."""
    u = (np.arange(n) + 0.5) / n
    return np.meshgrid(u, u, indexing="ij")


def _bricks(n: int, rows: int, cols: int, shift: np.ndarray, joint: float):
    """A running-bond layout: rows along u, each row of ``cols`` elements shifted by ``shift``
    (one value per row, in elements). Returns element ids (n, n) and the distance to the nearest
    joint in units of the element's short side (0 on a joint)."""
    U, V = _grid(n)
    r = np.minimum((U * rows).astype(int), rows - 1)
    fu = U * rows - r
    x = V * cols + shift[r]
    c = np.floor(x).astype(int) % cols
    fv = x - np.floor(x)
    du = np.minimum(fu, 1 - fu)
    dv = np.minimum(fv, 1 - fv) * (rows / cols)
    ids = r * cols + c
    return ids, np.minimum(du, dv) - joint


def _rgb(base, tint) -> np.ndarray:
    return np.asarray(base, np.float64)[None, None, :] * tint


def _tones(rng, count, spread) -> np.ndarray:
    """Per-element RGB multipliers around 1 (a shared brightness and a small hue shift)."""
    return (1 + spread * rng.uniform(-1, 1, (count, 1))) * (1 + 0.25 * spread * rng.uniform(-1, 1, (count, 3)))


def _bevel(dist, width) -> np.ndarray:
    """0 in a joint, rising smoothly to 1 across ``width`` (same units as ``dist``)."""
    t = np.clip(dist / width, 0, 1)
    return t * t * (3 - 2 * t)


# -- kinds ----------------------------------------------------------------------------------
def _asphalt(base, layout, tone, n, period):
    grain, stones, patch = periodic_noise(tone, n, 0.1), periodic_noise(tone, n, 0.4), periodic_noise(tone, n, 0.8)
    chips = np.clip((stones - 1.6) * 2.5, 0, 1)               # light aggregate showing through
    shade = 1 + 0.08 * grain + 0.12 * patch + 0.9 * chips
    height = 0.0015 * (0.6 * grain + stones)
    return GroundMaps(_rgb(base, shade[..., None]), height, np.clip(0.88 - 0.2 * chips + 0.03 * grain, 0, 1), period)


def _concrete(base, layout, tone, n, period):
    k = max(int(round(period / 1.5)), 1)                    # 1.5 m slabs
    ids, dist = _bricks(n, k, k, np.zeros(k), 0.006)
    blot, fine = periodic_noise(tone, n, 0.8), periodic_noise(tone, n, 0.3)
    slab = _tones(tone, k * k, 0.07)[ids]
    joint = _bevel(dist, 0.01)
    shade = slab * (1 + 0.08 * blot + 0.05 * fine)[..., None] * (0.45 + 0.55 * joint)[..., None]
    height = 0.004 * joint + 0.0004 * fine
    return GroundMaps(_rgb(base, shade), height, np.clip(0.82 + 0.05 * blot, 0, 1), period)


def _paving(base, layout, tone, n, period):
    rows = max(int(round(period / 0.1)), 2)                 # 20 x 10 cm bricks in running bond
    cols = max(rows // 2, 1)
    ids, dist = _bricks(n, rows, cols, (np.arange(rows) % 2) * 0.5, 0.06)
    fine, patch = periodic_noise(tone, n, 0.5), periodic_noise(tone, n, 0.8)
    brick = _tones(tone, rows * cols, 0.16)[ids]
    edge = _bevel(dist, 0.12)
    sand = np.array([1.25, 1.2, 1.05])
    shade = np.where((dist > 0)[..., None], brick * (1 + 0.05 * fine + 0.06 * patch)[..., None],
                     sand * (1 + 0.1 * fine)[..., None])
    height = 0.006 * edge + 0.0003 * fine
    return GroundMaps(_rgb(base, shade), height, np.clip(0.8 + 0.1 * (1 - edge) + 0.03 * fine, 0, 1), period)


def _grass(base, layout, tone, n, period):
    blades, clumps = periodic_noise(tone, n, 0.05), periodic_noise(tone, n, 0.7)
    dry = np.clip(0.5 + 0.5 * clumps, 0, 1)[..., None] * np.array([0.25, 0.12, -0.05])
    shade = (1 + 0.22 * blades + 0.15 * clumps)[..., None] * (1 + dry)
    height = 0.004 * (0.6 * blades + 0.4 * clumps)
    return GroundMaps(_rgb(base, np.clip(shade, 0.2, None)), height, np.clip(0.93 + 0.03 * blades, 0, 1), period)


def _sand(base, layout, tone, n, period):
    U, V = _grid(n)
    k = max(int(round(period / 0.09)), 1)                   # ripples 9 cm apart, an integer count per tile
    warp = periodic_noise(tone, n, 1.8)
    ripple = np.sin(2 * np.pi * (k * U + 3 * V) + 1.2 * warp)
    grain, patch = periodic_noise(tone, n, 0.0), periodic_noise(tone, n, 0.8)
    shade = 1 + 0.04 * ripple + 0.05 * grain + 0.08 * patch
    height = 0.006 * (0.5 + 0.5 * ripple) ** 1.5 + 0.0002 * grain
    return GroundMaps(_rgb(base, shade[..., None]), height, np.clip(0.95 + 0.02 * grain, 0, 1), period)


def _gravel(base, layout, tone, n, period):
    from scipy.spatial import cKDTree
    count = int((period / 0.028) ** 2)                      # stones about 2.8 cm across
    seeds = layout.random((count, 2))
    U, V = _grid(n)
    d, idx = cKDTree(seeds, boxsize=1.0).query(np.stack([U.ravel(), V.ravel()], 1), k=2)
    gap = ((d[:, 1] - d[:, 0]) * np.sqrt(count)).reshape(n, n)   # 0 on a cell border, ~0.5 inside
    stone = _tones(tone, count, 0.3)[idx[:, 0].reshape(n, n)]
    fine = periodic_noise(tone, n, 0.2)
    dome = _bevel(gap, 0.35)
    shade = stone * (0.55 + 0.45 * dome)[..., None] * (1 + 0.05 * fine)[..., None]
    height = 0.01 * np.sqrt(dome)
    return GroundMaps(_rgb(base, shade), height, np.clip(0.75 + 0.15 * (1 - dome), 0, 1), period)


def _wood(base, layout, tone, n, period):
    rows = max(int(round(period / 0.15)), 1)                # planks 15 cm wide, 1.2 m long, staggered
    cols = max(int(round(period / 1.2)), 1)
    ids, dist = _bricks(n, rows, cols, layout.random(rows), 0.02)
    U, V = _grid(n)
    plank = _tones(tone, rows * cols, 0.18)[ids]
    phase = tone.random(rows * cols)[ids] * 40
    warp = periodic_noise(tone, n, 1.6)
    grain = np.sin(2 * np.pi * (rows * U * 7 + phase + 2.5 * warp))
    fine = periodic_noise(tone, n, 0.2)
    shade = plank * (1 + 0.07 * grain + 0.03 * fine)[..., None] * (0.4 + 0.6 * _bevel(dist, 0.04))[..., None]
    height = 0.0015 * _bevel(dist, 0.06) + 0.0001 * grain
    return GroundMaps(_rgb(base, shade), height, np.clip(0.45 + 0.06 * grain + 0.05 * fine, 0, 1), period)


def _carpet(base, layout, tone, n, period):
    pile, mottled = periodic_noise(tone, n, 0.0), periodic_noise(tone, n, 0.8)
    shade = 1 + 0.1 * pile + 0.05 * mottled
    height = 0.0012 * pile
    return GroundMaps(_rgb(base, shade[..., None]), height, np.full((n, n), 0.98), period)


def _plaster(base, layout, tone, n, period):
    trowel, grain = periodic_noise(tone, n, 0.9), periodic_noise(tone, n, 0.0)
    shade = 1 + 0.035 * trowel + 0.02 * grain
    return GroundMaps(_rgb(base, shade[..., None]), 0.0004 * trowel + 0.0001 * grain, np.full((n, n), 0.9), period)


def _tiles(base, layout, tone, n, period):
    k = max(int(round(period / 0.6)), 1)                    # 60 cm tiles, 3 mm grout
    ids, dist = _bricks(n, k, k, np.zeros(k), 0.005)
    veins = np.abs(periodic_noise(tone, n, 1.0))
    fine = periodic_noise(tone, n, 0.4)
    tile = _tones(tone, k * k, 0.05)[ids] * (1 - 0.06 * np.clip(1.5 - veins, 0, 1) ** 4)[..., None]
    grout = np.array([0.9, 0.88, 0.85]) * 0.8
    shade = np.where((dist > 0)[..., None], tile * (1 + 0.02 * fine)[..., None], grout)
    height = 0.002 * _bevel(dist, 0.006)
    return GroundMaps(_rgb(base, shade), height, np.where(dist > 0, 0.22 + 0.05 * fine, 0.9).clip(0, 1), period)


GROUND_MATERIALS: dict[str, GroundKind] = {
    "asphalt": GroundKind(_asphalt, 4.0, (1.35, 1.33, 1.3), "dark asphalt with light aggregate and patches", structured=False),
    "concrete": GroundKind(_concrete, 6.0, (0.78, 0.76, 0.72), "1.5 m concrete slabs with joints and blotches"),
    "paving": GroundKind(_paving, 2.4, (0.8, 0.8, 0.78), "20 x 10 cm bricks in running bond with sand joints"),
    "grass": GroundKind(_grass, 3.0, (1.3, 1.08, 0.75), "short grass with clumps and dry patches", structured=False),
    "sand": GroundKind(_sand, 4.0, (0.82, 0.8, 0.78), "sand with wind ripples 9 cm apart", structured=False),
    "gravel": GroundKind(_gravel, 2.0, (0.8, 0.8, 0.8), "loose stones about 3 cm across"),
    "wood": GroundKind(_wood, 3.6, (0.85, 0.82, 0.8), "15 cm floor planks, 1.2 m long, staggered"),
    "carpet": GroundKind(_carpet, 1.0, (0.88, 0.88, 0.88), "short-pile carpet", structured=False),
    "plaster": GroundKind(_plaster, 2.0, (0.95, 0.94, 0.92), "painted plaster for walls", structured=False),
    "tiles": GroundKind(_tiles, 2.4, (0.9, 0.89, 0.87), "60 cm glazed floor tiles with grout"),
}


# -- the blended material ---------------------------------------------------------------------
def normal_map(height: np.ndarray, period_m: float, strength: float = NORMAL_STRENGTH) -> np.ndarray:
    """A tangent-space normal map ([0, 1]-encoded (n, n, 3)) of a periodic height field in metres:
    n = normalise(-dh/du, -dh/dv, 1) with u, v in metres."""
    n = height.shape[0]
    step = period_m / n
    du = (np.roll(height, -1, 0) - np.roll(height, 1, 0)) / (2 * step)
    dv = (np.roll(height, -1, 1) - np.roll(height, 1, 1)) / (2 * step)
    nrm = np.stack([-strength * du, -strength * dv, np.ones_like(du)], -1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    return ((nrm + 1) / 2).astype(np.float32)


def macro_mask(rng: np.random.Generator, n: int = MACRO_PX) -> np.ndarray:
    """Patches of wear over ``MACRO_M`` metres: 0 (one tile's tones) .. 1 (the other's)."""
    w = periodic_noise(rng, n, 1.7)
    return np.clip(0.5 + 0.45 * w, 0, 1).astype(np.float32)


def ground_material(kind: str, base_rgb, rng: np.random.Generator, period_m: float | None = None,
                    n: int = TILE_PX, roughness_scale: float = 1.0):
    """A ``Blend`` of two tiles of ``kind`` (same layout, own tones) under a ``MACRO_M`` mask,
    with the first tile's normal map; ``period_m``: metres one tile covers (the kind's default
    when None). Returns (material, period_m), the same objects for the same arguments and
    ``rng`` state (``_MADE``), with ``rng`` moved on as drawing them moves it: a composition
    builds its environment again on every try (placement, cameras) and a worker the objects'
    looks for every sequence, 0.1-1 s each. Treat the material as read-only."""
    key = (kind, tuple(np.asarray(base_rgb, dtype=float).ravel().tolist()), repr(rng.bit_generator.state),
           period_m, n, roughness_scale)
    if key not in _MADE:
        made = _ground_material(kind, base_rgb, rng, period_m, n, roughness_scale)
        _MADE[key] = (made, rng.bit_generator.state, _nbytes(made[0]))
        while len(_MADE) > 1 and sum(e[2] for e in _MADE.values()) > MADE_BYTES:
            _MADE.popitem(last=False)
    _MADE.move_to_end(key)
    made, after, _ = _MADE[key]
    rng.bit_generator.state = after
    return made


_MADE: OrderedDict = OrderedDict()  # (arguments, rng state) -> ((material, period), rng state after, bytes)
MADE_BYTES = 96 * 2 ** 20  # the most recent within this: a 1024-px ground's maps are 44 MB, an object's 256-px
# look's 3 MB (city_street: a ground and 7 looks); a new sequence's ground pushes out the one before last


def _nbytes(blend) -> int:
    return sum(a.nbytes for m in (blend, blend.a, blend.b) for a in vars(m).values() if isinstance(a, np.ndarray))


def _ground_material(kind: str, base_rgb, rng: np.random.Generator, period_m: float | None, n: int,
                     roughness_scale: float):
    from synmitsuba.scene.materials import Blend, Material
    entry = GROUND_MATERIALS[kind]
    period = float(period_m or entry.period_m)
    layout_seed = int(rng.integers(2 ** 31))
    a, b = (entry.build(base_rgb, np.random.default_rng(layout_seed),
                        np.random.default_rng(int(rng.integers(2 ** 31))), n, period) for _ in range(2))
    nmap = normal_map(a.height, period)

    def one(maps: GroundMaps, tint, repeat: float) -> Material:
        return Material(texture=np.clip(maps.albedo * tint, 0, 1).astype(np.float32), kind="principled",
                        roughness_map=np.clip(maps.roughness * roughness_scale, 0, 1).astype(np.float32),
                        texture_repeat=(repeat, repeat), specular=0.4, name="ground")

    mask = macro_mask(rng)
    second = 1.0 if entry.structured else 1.0 / GOLDEN
    return Blend(one(a, 1.0, 1.0), one(b, np.asarray(entry.wear), second), mask, (period / MACRO_M, period / MACRO_M),
                 normal_map=nmap, name="ground"), period
