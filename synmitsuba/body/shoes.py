"""Shoes built round each foot of the rest body: a flat sole that stands on the ground and an
upper with a toe box, a heel counter, a collar, a throat with laces, and (boots) a shaft.

A shoe is one grid of rings along the foot, heel to toe. Every ring runs along the ground
under the foot, up the sole's edge (standing ``WELT`` out from the upper), then over the foot as
a rounded arch; the rings' ends are capped. The opening the foot goes in (and a sandal's gaps
between straps) is cut along a level set (``topology.cut``), so the top line is a smooth curve.
uv: u along the foot, v round the ring, the sole in ``v < SOLE_V`` and the upper above, so one
texture holds both. The body stands on the sole: ``LayeredHuman`` lifts it by the sole's height.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.body.textures import GarmentTextureParams, grid_noise, lab_to_linear_rgb
from synmitsuba.body.topology import closed_tube, cut, merge_meshes

STATIONS = 30          # rings along the shoe
ARCH = 24              # points of a ring's arch over the foot
WELT = 0.003           # metres the sole stands out from the upper
SOLE_V = 0.25          # the sole's share of v; the upper starts at UPPER_V (a crisp colour edge)
UPPER_V = 0.3
CAP = 0.035            # metres over which the toe and the heel round off in plan
BACK = 0.006           # metres the heel counter reaches behind the heel
ALLOWANCE = 0.004      # metres an upper keeps from the foot with no ease
LACE_PITCH, LACE_SPAN, LACE_HALF_V = 0.035, 0.22, 0.07  # uv: laces every LACE_PITCH of u over the throat's
# first LACE_SPAN, reaching LACE_HALF_V either side of the arch's top (where shoe_texture paints them)
LACE_WIDTH, LACE_THICK = 0.002, 0.0008  # metres: a flat lace's half width and half thickness


@dataclass(frozen=True)
class ShoeStyle:
    """What a shoe kind looks like. Heights are metres over the insole (the top of the sole);
    ``GarmentParams.length`` picks the collar (and a boot's shaft) within its range, and
    ``thickness`` is the sole's height, which the body stands on."""

    collar: tuple[float, float]     # the top line's height at the heel
    throat: float                   # share of the foot's length (from the heel) where the closed vamp starts
    toe: float                      # metres the toe box reaches past the toes
    point: float                    # the toe's plan shape: 2 round, > 2 square, < 2 pointed
    laces: bool = False
    shaft: tuple[float, float] = (0.0, 0.0)  # boots: the shaft's top over the insole
    straps: tuple[float, ...] = ()  # sandals: straps across the foot (shares of its length); nothing else covers it
    uppers: tuple = ()              # LAB colours the upper takes
    soles: tuple = ()               # and the sole
    roughness: tuple[float, float] = (0.6, 0.45)  # upper, sole
    vamp: float = 0.0               # metres the throat's edge dips towards the toes over the instep (a pump's U)
    heel: tuple[float, float] = (0.0, 0.0)  # heels: the heel's height over the ball's, metres (by ``length``)
    tip: tuple[float, float] = (0.0, 0.0)   # and the half-width and half-length of its tip on the ground


BLACK, WHITE, GREY, NAVY = [12, 0, 0], [93, 0, 2], [55, 0, 0], [22, 5, -25]
BROWN, TAN, OXBLOOD, GUM = [28, 10, 18], [55, 12, 30], [25, 28, 12], [52, 14, 38]
SHOE_STYLES: dict[str, ShoeStyle] = {
    "sneakers": ShoeStyle((0.055, 0.075), 0.42, 0.015, 2.2, laces=True,
                          uppers=(WHITE, WHITE, BLACK, GREY, NAVY, [45, 40, 30], [60, -30, 20], [40, 10, -45]),
                          soles=(WHITE, WHITE, [88, 2, 10], GUM, BLACK), roughness=(0.75, 0.6)),
    "boots": ShoeStyle((0.075, 0.09), 0.45, 0.018, 2.4, laces=True, shaft=(0.12, 0.24),
                       uppers=(BLACK, BROWN, TAN, [35, 8, 20], GREY), soles=(BLACK, BROWN, [30, 4, 8]),
                       roughness=(0.55, 0.7)),
    "dress_shoes": ShoeStyle((0.035, 0.05), 0.5, 0.028, 1.7, laces=True,
                             uppers=(BLACK, BLACK, BROWN, OXBLOOD, TAN), soles=(BLACK, BROWN, [20, 3, 6]),
                             roughness=(0.32, 0.5)),
    "sandals": ShoeStyle((0.012, 0.02), 0.35, 0.008, 2.0, straps=(0.6, 0.8),
                         uppers=(BROWN, TAN, BLACK, [70, 8, 25]), soles=(TAN, BROWN, BLACK, [80, 4, 14]),
                         roughness=(0.6, 0.8)),
    "heels": ShoeStyle((0.03, 0.045), 0.6, 0.035, 1.3, vamp=0.04, heel=(0.05, 0.09), tip=(0.006, 0.007),
                       uppers=(BLACK, BLACK, [45, 55, 30], [68, 12, 20], NAVY, WHITE, OXBLOOD),
                       soles=(BLACK, [20, 3, 6]), roughness=(0.28, 0.4)),
}


def _sections(points: np.ndarray, z: np.ndarray, sole: float, cap_y: np.ndarray, ends: tuple):
    """Half-width, centre x and top y of the foot at each ``z``, from vertices within 1 cm
    (under the station's ``cap_y``: behind the throat, the leg above the collar is not the
    foot), smoothed along the foot.
    Past ``ends`` (where the toe box and the heel counter round off) a station takes the
    section at that end: the toes' uneven lengths would pull the tip sideways."""
    zz = np.clip(z, *ends)
    out = []
    for zk, cap in zip(zz, cap_y):
        s = points[(np.abs(points[:, 2] - zk) < 0.01) & (points[:, 1] < cap)]
        lo, hi = s[:, 0].min(), s[:, 0].max()
        out.append(((hi - lo) / 2, (hi + lo) / 2, s[:, 1].max()))
    half, centre, top = (np.convolve(np.pad(c, 1, mode="edge"), np.ones(3) / 3, "valid") for c in np.array(out).T)
    return half, centre, np.maximum(top, sole + 0.02)


def _ring(half: float, centre: float, top: float, sole: float, welt: float = WELT) -> tuple[np.ndarray, np.ndarray]:
    """One ring (x, y) and its v: the sole along the ground and up its edges, the upper as a
    rounded arch over the foot from the sole's edge (the colours change across the welt's
    ledge). The last point is the first again with the upper's v: the ring's uv seam."""
    w = half + welt
    bottom = np.linspace(-1, 1, 7)
    # +x wall top, down, along the ground, up the -x wall
    sole_pts = [(centre + w, sole), (centre + w, sole * 0.5), *[(centre + w * b, 0.0) for b in bottom[::-1]],
                (centre - w, sole * 0.5), (centre - w, sole)]
    a = np.linspace(np.pi, 0.0, ARCH)  # -x side, over the top, to the +x side
    c, s = np.cos(a), np.sin(a)
    e = 2 / 2.6  # a squarish arch: a toe box, not a tube
    arch = np.column_stack([centre + half * np.sign(c) * np.abs(c) ** e, sole + (top - sole) * np.abs(s) ** e])
    xy = np.concatenate([np.array(sole_pts), [(centre - half, sole)], arch[1:-1], [(centre + half, sole)],
                         [sole_pts[0]]])
    n_sole = len(sole_pts)
    v = np.concatenate([np.linspace(0, SOLE_V, n_sole), np.linspace(UPPER_V, 1.0, len(xy) - n_sole)])
    return xy, v


def _plan(z: np.ndarray, heel: float, toes: float, toe: float, point: float) -> np.ndarray:
    """Share of the foot's half-width the shoe keeps at each ``z``: 1 along the foot, rounding
    off to 0 at the heel counter's back and at the toe box's tip (superellipse, ``point``)."""
    front = (toes - CAP * 0.6, toes + toe)
    back = (heel + CAP * 0.5, heel - BACK)
    t_f = np.clip((z - front[0]) / (front[1] - front[0]), 0, 1)
    t_b = np.clip((back[0] - z) / (back[0] - back[1]), 0, 1)
    return np.minimum((1 - t_f ** point) ** (1 / point), (1 - t_b ** 2.2) ** (1 / 2.2))


def _grid(rings: list, vs: np.ndarray, u: np.ndarray):
    """Faces between consecutive rings (each closed through its seam), fans capping both ends:
    (vertices, faces, uv)."""
    k, m = len(rings), len(rings[0])
    v = np.concatenate(rings)
    i, j = np.meshgrid(np.arange(k - 1), np.arange(m - 1), indexing="ij")
    a = (i * m + j).reshape(-1)
    f = np.concatenate([np.stack([a, a + m, a + 1], 1), np.stack([a + 1, a + m, a + m + 1], 1)])  # facing out
    uv = np.column_stack([np.repeat(u, m), np.tile(vs, k)])
    caps: list[tuple[np.ndarray, np.ndarray]] = []
    for r, flip in ((0, False), (k - 1, True)):
        centre = len(v) + len(caps)
        ids = r * m + np.arange(m - 1)
        fan = np.stack([np.full(m - 1, centre), ids, np.roll(ids, -1)], 1)
        caps.append((rings[r][:-1].mean(0), fan[:, [0, 2, 1]] if flip else fan))
    v = np.concatenate([v, [c[0] for c in caps]])
    f = np.concatenate([f, *[c[1] for c in caps]])
    uv = np.concatenate([uv, [[u[0], 0.1], [u[-1], 0.1]]])
    return v, f, uv


def foot_points(body, regions, side: float) -> np.ndarray:
    """The rest body's foot and its leg up to 32 cm on one side (+1 left, -1 right): vertices,
    and points over its faces (the shin's vertices lie rings apart, and a ring fitted to them
    alone cuts the skin between)."""
    v = body.vertices
    leg = np.isin(regions.group, ["foot", "lowerleg"]) & (np.sign(v[:, 0]) == side)
    keep = leg & ((regions.group == "foot") | (v[:, 1] < v[:, 1].min() + 0.32))
    tri = v[body.faces[keep[body.faces].all(1)]]
    bary = np.array([[2, 1, 1], [1, 2, 1], [1, 1, 2], [1, 1, 0], [0, 1, 1], [1, 0, 1]], float)
    bary /= bary.sum(1, keepdims=True)
    return np.concatenate([v[keep], np.einsum("bk,fkd->fbd", bary, tri).reshape(-1, 3)])


def shoe_mesh(points: np.ndarray, style: ShoeStyle, sole: float, allowance: float, length: float):
    """One shoe round ``points`` (a foot from ``foot_points``): (vertices, faces, uv)."""
    foot = points[points[:, 1] < sole + 0.16]
    heel, toes = foot[:, 2].min(), foot[:, 2].max()
    collar = sole + style.collar[0] + (style.collar[1] - style.collar[0]) * length
    s = np.linspace(0, 1, STATIONS)
    u = (1 - np.cos(np.pi * s)) / 2  # denser at the toe and the heel, where the shoe turns
    z = heel - BACK + u * (toes + style.toe - heel + BACK)
    cap = np.where(z < heel + style.throat * (toes - heel), collar + 0.03, np.inf)
    half, centre, top = _sections(foot, z, sole, cap, (heel + CAP * 0.5, toes - CAP * 0.6))
    plan = _plan(z, heel, toes, style.toe, style.point)
    tip = np.clip((z - (toes - CAP)) / (CAP + style.toe), 0, 1)
    low = sole + 0.022
    top = np.where(top > low, top + (low - top) * tip ** 1.5, top)  # the toe box lowers to its tip
    rings = []
    for k in range(STATIONS):
        # the welt narrows with the plan at the tip and the heel: the end caps close to a sliver
        xy, vs = _ring(max((half[k] + allowance) * plan[k], 2e-4), centre[k], top[k] + allowance, sole,
                       WELT * min(1.0, 4 * plan[k]))
        rings.append(np.column_stack([xy, np.full(len(xy), z[k])]))
    v, f, uv = _grid(rings, vs, u)  # every ring has the same v
    phi = _opening(v, uv, style, sole, collar, (heel, toes))
    f, v, uv = cut(f, phi, v, uv)
    return v, f, uv


def _opening(v: np.ndarray, uv: np.ndarray, style: ShoeStyle, sole: float, collar: float, ends) -> np.ndarray:
    """Level set of what the shoe keeps (>= 0): the sole, and the upper under the collar
    behind the throat and (sandals) along the straps; a boot's collar is its shaft's job."""
    heel, toes = ends
    along = (v[:, 2] - heel) / (toes - heel)
    y = v[:, 1]
    if style.straps:
        straps = np.max([0.011 - np.abs(along - s) * (toes - heel) for s in style.straps], axis=0)
        rim = np.minimum(collar - y, (0.35 - along) * (toes - heel))  # a low cup round the heel
        keep = np.maximum(straps, rim)
    else:
        dip = collar - 0.012 * np.clip(along / style.throat, 0, 1)  # the top line falls a little to the throat
        over = np.clip((y - dip) / 0.025, 0.0, 1.0)  # how far up the instep, from the collar's height
        keep = np.maximum(dip - y, (along - style.throat) * (toes - heel) - style.vamp * over)
    # the sole is kept whole; an end cap's centre (the sole's v, but up in the ring) is cut like
    # the upper round it (kept, it drew a sliver up to the ring's top over a low collar)
    return np.where((uv[:, 1] < UPPER_V) & (y <= sole + 1e-9), 1.0, keep)


def surface_at(v: np.ndarray, f: np.ndarray, uv: np.ndarray, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (Q, 3) and unit normals of the mesh where its uv is ``query`` (Q, 2): the
    barycentric position in the first face whose uv triangle holds it (nan where none does)."""
    from synmitsuba.geometry import vertex_normals
    t = uv[f]                                               # (F, 3, 2)
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    ok = np.abs(det) > 1e-14
    d = query[:, None] - t[None, :, 0]                      # (Q, F, 2)
    a = np.where(ok, (d[..., 0] * e2[:, 1] - d[..., 1] * e2[:, 0]) / np.where(ok, det, 1), -1)
    b = np.where(ok, (e1[:, 0] * d[..., 1] - e1[:, 1] * d[..., 0]) / np.where(ok, det, 1), -1)
    inside = (a >= 0) & (b >= 0) & (a + b <= 1)
    face = np.argmax(inside, 1)
    hit = inside[np.arange(len(query)), face]
    w = np.stack([1 - a - b, a, b], -1)[np.arange(len(query)), face]      # (Q, 3)
    corners = f[face]
    n = vertex_normals(v, f)[corners]
    n = (w[..., None] * n).sum(1)
    points = np.where(hit[:, None], (w[..., None] * v[corners]).sum(1), np.nan)
    return points, np.where(hit[:, None], n / np.linalg.norm(n, axis=1, keepdims=True), np.nan)


def lace_mesh(v: np.ndarray, f: np.ndarray, uv: np.ndarray, style: ShoeStyle, steps: int = 11, sides: int = 8):
    """Laces as flat cords over the throat of a shoe (its cut mesh), where ``shoe_texture``
    paints them: one across every ``LACE_PITCH`` of u, from eyestay to eyestay, bowed 2 mm over
    the tongue, its ends sunk into the upper as through eyelets; uv on the painted lace, so a
    cord takes the laces' colour. (vertices, faces, uv); nothing for a style without laces."""
    if not style.laces:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros((0, 2))
    mid = (UPPER_V + 1) / 2
    t = np.linspace(0.0, 1.0, steps)
    ang = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    cords, at = [], []
    for k in range(int(LACE_SPAN / LACE_PITCH)):
        u = style.throat + LACE_PITCH * (k + 0.5)
        p, n = surface_at(v, f, uv, np.column_stack([np.full(steps, u), mid + LACE_HALF_V * (2 * t - 1)]))
        if np.isnan(p).any():
            continue
        path = p + (-0.0005 + 0.0025 * np.sin(np.pi * t) ** 0.5)[:, None] * n
        across = np.cross(np.gradient(path, axis=0), n)
        across /= np.linalg.norm(across, axis=1, keepdims=True)
        rings = (path[:, None] + LACE_THICK * np.cos(ang)[None, :, None] * n[:, None]
                 + LACE_WIDTH * np.sin(ang)[None, :, None] * across[:, None])
        cords.append(closed_tube(rings))
        at.append(np.tile([u, mid], (len(cords[-1][0]), 1)))
    if not cords:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros((0, 2))
    cv, cf = merge_meshes(cords)
    return cv, cf, np.concatenate(at)


def shaft_mesh(points: np.ndarray, sole: float, top: float, allowance: float, n: int = 32):
    """A boot's shaft: a tube round the ankle and shin from the shoe's collar up to ``top``
    (metres over the ground), the leg's reach in each direction plus ``allowance``; uv continues
    the upper's. (vertices, faces, uv); open at both ends."""
    heights = np.linspace(sole + 0.05, top, 10)
    heel, toes = points[:, 2].min(), points[:, 2].max()
    instep = (points[:, 2] > heel + 0.55 * (toes - heel)) & (points[:, 1] < sole + 0.12)
    leg = points[(points[:, 1] > sole + 0.04) & ~instep]
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    d = np.stack([np.sin(ang), np.cos(ang)], 1)
    rings = []
    for h in heights:
        band = leg[np.abs(leg[:, 1] - h) < 0.015][:, [0, 2]]
        c = (band.max(0) + band.min(0)) / 2
        reach = (band - c) @ d.T
        tuck = 0.004 * (h < sole + 0.08)  # the lowest rings go inside the shoe's collar: a seam, not a step
        r = reach.max(0)
        r = np.maximum(r, np.convolve(np.pad(r, 2, mode="wrap"), np.ones(5) / 5, "valid")) + allowance - tuck
        rings.append(np.column_stack([c[0] + r * d[:, 0], np.full(n, h), c[1] + r * d[:, 1]]))
    m = len(ang) + 1  # a seam: the first point repeated with v = 1
    v = np.concatenate([np.vstack([r, r[:1]]) for r in rings])
    i, j = np.meshgrid(np.arange(len(heights) - 1), np.arange(m - 1), indexing="ij")
    a = (i * m + j).reshape(-1)
    f = np.concatenate([np.stack([a, a + 1, a + m], 1), np.stack([a + 1, a + m + 1, a + m], 1)])  # facing out
    uv = np.column_stack([np.repeat(np.linspace(0, 0.4, len(heights)), m),
                          np.tile(np.linspace(UPPER_V, 1.0, m), len(heights))])
    return v, f, uv


def shoe_colours(style: ShoeStyle, seed: int) -> tuple:
    """(upper, sole, laces) LAB colours of a pair, drawn from the style's palettes by ``seed``."""
    rng = np.random.default_rng([seed, 11])
    upper = list(style.uppers[int(rng.integers(len(style.uppers)))])
    sole = list(style.soles[int(rng.integers(len(style.soles)))])
    laces = upper if rng.random() < 0.5 else (WHITE if upper[0] < 50 else BLACK)
    return upper, sole, list(laces)


def shoe_texture(style: ShoeStyle, p: GarmentTextureParams, size: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """Albedo (linear RGB) and roughness over the shoe's uv square: the sole's colour under
    ``SOLE_V``, the upper's (``p.base_lab``) above, with faint mottling, laces crossing the throat."""
    _, sole, laces = shoe_colours(style, p.seed)
    upper = p.base_lab
    v = 1 - (np.arange(size) + 0.5) / size            # row 0 is v = 1
    u = (np.arange(size) + 0.5) / size
    V, U = np.meshgrid(v, u, indexing="ij")
    noise = grid_noise(size, 6.0, p.seed) - 0.5
    albedo = np.where((V < (SOLE_V + UPPER_V) / 2)[..., None], lab_to_linear_rgb(sole),
                      lab_to_linear_rgb(upper))
    albedo = albedo * (1 + 0.12 * noise[..., None])
    rough = np.where(V < (SOLE_V + UPPER_V) / 2, style.roughness[1], style.roughness[0]) + 0.08 * noise
    if style.laces:  # over the throat (u from the throat forward, v over the arch's top): a darker
        # tongue between two eyestays' edges, laces crossing it
        mid = (UPPER_V + 1) / 2
        along = (U > style.throat) & (U < style.throat + 0.22)
        off = np.abs(V - mid)
        albedo = np.where((along & (off < 0.07))[..., None], albedo * 0.7, albedo)
        albedo = np.where((along & (off >= 0.07) & (off < 0.082))[..., None], albedo * 0.45, albedo)
        bars = along & (off < 0.075) & (np.abs(((U - style.throat) / 0.035) % 1 - 0.5) < 0.16)
        albedo = np.where(bars[..., None], lab_to_linear_rgb(laces), albedo)
    return np.clip(albedo, 0, 1).astype(np.float32), np.clip(rough, 0.05, 1).astype(np.float32)



def sample_shoe_texture(style: ShoeStyle, rng: np.random.Generator) -> GarmentTextureParams:
    """A pair's colours: the upper's from the style's palette as ``base_lab`` (the sole's and
    the laces' follow from ``seed``), plain."""
    seed = int(rng.integers(0, 2 ** 31))
    upper = shoe_colours(style, seed)[0]
    return GarmentTextureParams(base_lab=[float(x) for x in upper], seed=seed)


def shoe_material(style: ShoeStyle, p: GarmentTextureParams, size: int = 256):
    """The pair's principled material: ``shoe_texture``'s albedo and roughness."""
    from synmitsuba.scene.materials import Material
    albedo, rough = shoe_texture(style, p, size)
    return Material(texture=albedo, kind="principled", roughness_map=rough, specular=0.4)


# -- heels: the foot pitched up on a heel --------------------------------------------------------
# A heeled shoe is built round the rest (flat) foot like any other; the pose holds the foot turned
# about the ankle so the heel rises over the ball (``HeelPitch``) and the toes turned back so they
# stay flat, and the heel is a block under the heel cup reaching the ground in that pose.
@dataclass(frozen=True)
class HeelPitch:
    """How a heeled shoe holds one foot: bone ``foot``'s local rotation is followed by
    ``rotation`` (rest axes, about the ankle: the heel rises ``height`` metres over the ball) and
    the ``toes``' first bones are turned back by its inverse first; the ball line (through the
    first and fifth toes' joints, ``ball``) drops about ``drop`` metres (the middle toe's joint
    exactly: the shoe's front follows it)."""

    foot: int
    toes: tuple[int, ...]
    rotation: np.ndarray
    pivot: np.ndarray
    ball: np.ndarray     # (2, 3) rest points on the ball line
    height: float
    drop: float

    def pitched(self, points: np.ndarray) -> np.ndarray:
        """Rest points turned as the foot turns them."""
        return (points - self.pivot) @ self.rotation.T + self.pivot

    def unpitched(self, points: np.ndarray) -> np.ndarray:
        return (points - self.pivot) @ self.rotation + self.pivot

    def ahead(self, points: np.ndarray) -> np.ndarray:
        """Metres each rest point lies in front of the ball line (along the ground)."""
        along = self.ball[1] - self.ball[0]
        n = np.array([-along[2], 0.0, along[0]])
        n *= np.sign(n[2]) / np.linalg.norm(n)  # forward: +z
        return (points - self.ball[0]) @ n


def pitch_feet(rotations: np.ndarray, heels) -> np.ndarray:
    """Local rotations (..., J, 3, 3) with each foot of ``heels`` (``HeelPitch`` records) pitched on
    its heel and its toes turned back flat (a copy; the same for none)."""
    rot = np.array(rotations, dtype=np.float64)
    for h in heels:
        rot[..., h.foot, :, :] = rot[..., h.foot, :, :] @ h.rotation
        for toe in h.toes:
            rot[..., toe, :, :] = h.rotation.T @ rot[..., toe, :, :]
    return rot


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def heel_pitch(skeleton, points: np.ndarray, side: float, height: float) -> HeelPitch:
    """The pitch that raises the back of the heel of ``points`` (``foot_points``, one side:
    +1 left) ``height`` metres over the ball line, turning about an axis along that line (so
    every toe's joint drops alike and the forefoot stays level) through the ankle."""
    s = "L" if side > 0 else "R"
    toes = tuple(skeleton.index(f"toe{k}-1.{s}") for k in range(1, 6))
    ball = skeleton.rest_positions[[toes[0], toes[-1]]]
    pivot = skeleton.rest_positions[skeleton.index(f"foot.{s}")]
    axis = np.array([ball[1, 0] - ball[0, 0], 0.0, ball[1, 2] - ball[0, 2]])
    under = points[points[:, 1] < pivot[1]]  # the foot under the ankle (the calf reaches further back)
    back = under[np.argmin(under[:, 2])]
    flat = HeelPitch(skeleton.index(f"foot.{s}"), toes, np.eye(3), pivot, ball, 0.0, 0.0)
    reach = -float(flat.ahead(back[None])[0])  # metres from the heel's back to the ball line
    angle = float(np.arcsin(min(height / reach, 0.6)))
    rot = _axis_rotation(axis, angle)
    if ((back - pivot) @ rot.T)[1] < (back - pivot)[1]:  # the heel must go up
        rot = rot.T
    mid = skeleton.rest_positions[toes[2]]  # the toe a shoe's front follows (``garments._flexing_feet``)
    drop = float(mid[1] - ((mid - pivot) @ rot.T + pivot)[1])
    return HeelPitch(flat.foot, toes, rot, pivot, ball, height, drop)


HEEL_RINGS, HEEL_SIDES = 10, 20


def heel_height(style: ShoeStyle, length: float) -> float:
    """A heeled style's heel height for a pair's ``length`` (0..1)."""
    return style.heel[0] + (style.heel[1] - style.heel[0]) * length


def heel_mesh(points: np.ndarray, pitch: HeelPitch, style: ShoeStyle, embed: float = 0.003):
    """The heel under one shoe (its foot ``points``), in rest coordinates: from an oval under the
    heel cup (sunk ``embed`` into the sole) down to ``style.tip`` on the ground the pitched
    forefoot stands on, straight down in that pose, narrowing fast under the cup (a slim heel).
    (vertices, faces, uv), uv in the sole's colour."""
    under = points[points[:, 1] < pitch.pivot[1]]  # the foot under the ankle (the calf reaches further back)
    heel = under[:, 2].min()
    cup = under[under[:, 2] < heel + 0.05]
    half = (cup[:, 0].max() - cup[:, 0].min()) / 2
    cx, az = (cup[:, 0].max() + cup[:, 0].min()) / 2, 0.032
    cz = heel - BACK + az + 0.002
    ang = np.linspace(0, 2 * np.pi, HEEL_SIDES, endpoint=False)
    top = np.column_stack([cx + 0.6 * half * np.cos(ang), np.full(HEEL_SIDES, embed), cz + az * np.sin(ang)])
    top_p = pitch.pitched(top)
    ground = -pitch.drop  # the forefoot's sole, rest y = 0, drops with the ball
    centre = top_p.mean(0)
    centre[2] -= 0.3 * az  # the tip sits under the back half of the cup
    bottom = np.column_stack([centre[0] + style.tip[0] * np.cos(ang), np.full(HEEL_SIDES, ground),
                              centre[2] + style.tip[1] * np.sin(ang)])
    t = np.linspace(0, 1, HEEL_RINGS)[:, None, None]
    w = 1 - (1 - t) ** 3  # the outline narrows fast under the cup
    rings = top_p + (bottom - top_p) * w
    rings[..., 1] = (top_p[..., 1] + (bottom[..., 1] - top_p[..., 1]) * t[..., 0])
    v, f = closed_tube(pitch.unpitched(rings.reshape(-1, 3)).reshape(rings.shape))
    uv = np.column_stack([np.full(len(v), 0.03), np.linspace(0.02, SOLE_V * 0.8, len(v))])
    return v, f, uv
