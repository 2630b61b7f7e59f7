"""Strand hair as Mitsuba curves, rooted on scalp regions and shaped by style.

Scalp regions (fringe, top, temporal, occipital, lower_back, and the beard area) are labelled
geometrically in a head frame (origin at the head centre, up, forward). Each style sets a
length per region, how strands fall (gravity), their volume, a parting and how much they clump.
A few hundred guide strands are grown in small steps that slide over the rest body and around
the face; thousands of thin, tapered children take the shape of their nearest guides (never
across the part), gathered towards one guide's tip in locks. Control points lie close together
at the root, where a strand bends round the head. An afro is shortened into a rounded envelope
(``ENVELOPES``); afro and curly strands wind in coils (``COILS``). Strands move with the head
bone down to the neck and with the body under them below it (``follow_weights``), kept from
stretching where they cross between the two (``limit_stretch``); the scalp
under them is tinted with the hair's colour (``hair_colour``, ``root_cover``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.schema import Choice, Number, Params, spec
from synmitsuba.geometry import frame, triangle_areas

REGIONS = ("fringe", "top", "temporal", "occipital", "lower_back", "beard")


@dataclass(frozen=True)
class HairStyle:
    """A hair style: strand length (m) per scalp region, how it falls and how often it is worn
    (our rough prior, not survey data)."""

    lengths: tuple  # metres per scalp region: fringe, top, temporal, occipital, lower_back
    gravity: float  # how far strands fall rather than follow the scalp (negative: stand out)
    volume: float   # how far they stand off the head
    odds_male: float
    odds_female: float


STYLES = {
    "bald": HairStyle((0, 0, 0, 0, 0), 0.0, 0.0, 0.08, 0.005),
    "buzz": HairStyle((0.008, 0.01, 0.008, 0.008, 0.006), 0.0, 0.3, 0.14, 0.015),
    "short": HairStyle((0.04, 0.05, 0.03, 0.04, 0.025), 0.4, 0.5, 0.26, 0.08),
    "crew": HairStyle((0.03, 0.06, 0.015, 0.02, 0.012), 0.2, 0.6, 0.20, 0.02),
    "bob": HairStyle((0.10, 0.16, 0.16, 0.17, 0.15), 0.9, 0.4, 0.02, 0.20),
    "shoulder": HairStyle((0.12, 0.26, 0.26, 0.28, 0.26), 1.0, 0.3, 0.06, 0.24),
    "long": HairStyle((0.16, 0.42, 0.42, 0.45, 0.42), 1.0, 0.25, 0.05, 0.22),
    "curly": HairStyle((0.08, 0.12, 0.10, 0.12, 0.10), 0.5, 0.9, 0.08, 0.10),
    "afro": HairStyle((0.09, 0.11, 0.10, 0.10, 0.08), -0.2, 1.0, 0.06, 0.05),
    "fringe": HairStyle((0.12, 0.10, 0.07, 0.08, 0.06), 0.8, 0.4, 0.05, 0.07),
}
HAIRLINE_TOP, BANGS_TOP = 0.45, 0.15  # relative heights over the head centre: hair over the face stops there
# (at most the head's own hairline: ``hairline_height``)
K = 10  # control points per strand: enough for a smooth fall and one or two curls
SUBSTEPS = 4  # growth steps per segment on average
# growth steps at which control points are kept: close together at the root, where a strand bends
# round the head (a 5 cm chord across the scalp would run inside it and bare a strip along a part),
# farther apart down the hanging length
KEPT_STEPS = np.array([0, 1, 3, 5, 8, 12, 17, 23, 29, (K - 1) * SUBSTEPS])
ARC = KEPT_STEPS / KEPT_STEPS[-1]  # each control point's share of the strand's length
BEARDS = {"none": 0.0, "stubble": 0.004, "goatee": 0.025, "mustache": 0.015, "full": 0.035}


@dataclass
class HairParams(Params):
    style: str = spec("short", Choice(tuple(STYLES)))
    beard: str = spec("none", Choice(tuple(BEARDS)))
    length: float = spec(1.0, Number(0.3, 2.0), doc="multiplies the style's lengths")
    curliness: float = spec(0.2, Number(0, 1), doc="0 straight .. 1 tight curls")
    density: float = spec(0.5, Number(0, 1), doc="0..1 -> strand count")
    melanin: float = spec(0.5, Number(0, 1), doc="0 blond .. 1 black")
    redness: float = spec(0.1, Number(0, 1), doc="pheomelanin share")
    seed: int = spec(0, Number(0, 2 ** 31, integer=True))


# Who wears what: style odds per sex in ``STYLES`` order (from each style's record), and beard
# odds for men by age in years (none, stubble, goatee, mustache, full); women and people under
# 18 get no beard.
STYLE_ODDS = {"male": tuple(s.odds_male for s in STYLES.values()),
              "female": tuple(s.odds_female for s in STYLES.values())}
BEARD_ODDS = ((18, (0.55, 0.20, 0.08, 0.04, 0.13)),   # from 18 years
              (30, (0.50, 0.18, 0.10, 0.06, 0.16)),   # from 30
              (50, (0.55, 0.10, 0.08, 0.12, 0.15)))   # from 50


def beard_odds(sex: str, years: float) -> tuple:
    """``BEARDS`` probabilities for a person of this sex and age."""
    if sex != "male" or years < 18:
        return (1.0, 0.0, 0.0, 0.0, 0.0)
    return [odds for start, odds in BEARD_ODDS if years >= start][-1]


def sample_hair(rng: np.random.Generator, sex: str = "male", years: float = 35.0) -> HairParams:
    """Hair for a person: style by ``STYLE_ODDS`` of the sex, beard by ``beard_odds``."""
    style = str(rng.choice(list(STYLES), p=STYLE_ODDS[sex]))
    beard = str(rng.choice(list(BEARDS), p=beard_odds(sex, years)))
    return HairParams(style=style, beard=beard, length=round(float(rng.uniform(0.7, 1.3)), 3),
                      curliness=round(float(rng.uniform(0.6, 1.0) if style in ("curly", "afro") else rng.uniform(0, 0.4)), 3),
                      density=round(float(rng.uniform(0.3, 1.0)), 3), melanin=round(float(rng.beta(2, 1.5)), 3),
                      redness=round(float(rng.uniform(0, 0.4)), 3), seed=int(rng.integers(0, 2 ** 31)))


@dataclass
class ScalpRegions:
    vertices: np.ndarray     # (V, 3) head vertices, rest pose, y up
    normals: np.ndarray
    faces: np.ndarray        # (F, 3) into vertices
    region: np.ndarray       # (V,) index into REGIONS, -1 for none (face, ears)
    origin: np.ndarray       # head centre
    up: np.ndarray
    forward: np.ndarray
    radii: np.ndarray        # head extents from the centre (right, up (the chin's side), forward)
    skull: np.ndarray        # semi-axes of the skull's proxy ellipsoid (right, up (to the top), forward)


def scalp_regions_from_head(vertices, normals, faces, head_center, up, forward) -> ScalpRegions:
    """Label head vertices by their direction from the head centre in the head frame."""
    right, up, fwd = frame(forward, up).T
    rel = np.asarray(vertices) - head_center
    x, y, z = rel @ right, rel @ up, rel @ fwd
    elev = np.degrees(np.arctan2(y, np.hypot(x, z)))
    azim = np.degrees(np.arctan2(x, z))  # 0 forward, +-180 back
    front = np.abs(azim) < 50
    side = (np.abs(azim) >= 50) & (np.abs(azim) < 120)
    back = np.abs(azim) >= 120
    region = -np.ones(len(rel), np.int64)
    region[front & (elev > 28)] = 0
    region[elev > 45] = 1
    region[side & (elev > 5) & (elev <= 45)] = 2
    region[back & (elev > -5) & (elev <= 45)] = 3
    region[back & (elev <= -5) & (elev > -40)] = 4
    beard_top = -12 - 22 * np.cos(np.radians(azim))  # from the sideburns down to above the upper lip
    region[(np.abs(azim) < 75) & (elev < beard_top) & (elev > -75) & (z > 0)] = 5
    radii = np.array([np.abs(x).max(), np.abs(y).max(), np.abs(z).max()]) * 0.93
    skull = np.array([np.abs(x).max(), y.max(), np.abs(z).max()]) * 0.93
    return ScalpRegions(np.asarray(vertices, float), np.asarray(normals, float), np.asarray(faces), region,
                        np.asarray(head_center, float), up, fwd, radii, skull)


@dataclass
class Strands:
    points: np.ndarray   # (N, K, 3) control points
    radius: np.ndarray   # (N, K)
    region: np.ndarray   # (N,)

    def transformed(self, R: np.ndarray, t: np.ndarray) -> "Strands":
        return Strands(self.points @ R.T + t, self.radius, self.region)

    def __len__(self) -> int:
        return len(self.points)

    def subset(self, keep: np.ndarray) -> "Strands":
        return Strands(self.points[keep], self.radius[keep], self.region[keep])

    @staticmethod
    def concat(parts: list["Strands"]) -> "Strands":
        """One set of strands; parts with fewer control points are resampled to the most any has."""
        parts = [p for p in parts if len(p)]
        if not parts:
            return Strands(np.zeros((0, K, 3)), np.zeros((0, K)), np.zeros(0, np.int64))
        k = max(p.points.shape[1] for p in parts)
        def fit(a):
            return a if a.shape[1] == k else resample(a, k)
        return Strands(np.concatenate([fit(p.points) for p in parts]), np.concatenate([fit(p.radius) for p in parts]),
                       np.concatenate([p.region for p in parts]))


def _sample_roots(scalp: ScalpRegions, mask_faces: np.ndarray, n: int, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    f = scalp.faces[mask_faces]
    tri = scalp.vertices[f]
    area = triangle_areas(tri)
    pick = rng.choice(len(f), n, p=area / area.sum())
    a, b = rng.random(n), rng.random(n)
    flip = a + b > 1
    a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
    w = np.stack([1 - a - b, a, b], 1)
    pts = np.einsum("nk,nka->na", w, tri[pick])
    nrm = np.einsum("nk,nka->na", w, scalp.normals[f[pick]])
    return pts, nrm / np.linalg.norm(nrm, axis=1, keepdims=True), pick


def _outside(scalp: ScalpRegions, p: np.ndarray, margin: float) -> np.ndarray:
    """Points pushed out of the head proxy ellipsoid grown by ``margin``."""
    B = frame(scalp.forward, scalp.up).T  # rows: right, up, forward
    local = (p - scalp.origin) @ B.T
    r = np.linalg.norm(local / (scalp.skull + margin), axis=-1, keepdims=True)
    local = local / np.maximum(r, 1e-9) * np.maximum(r, 1.0)
    return local @ B + scalp.origin


FACE_HALF_WIDTH = 0.85  # of the head's half width: hair in front of the face is moved beside it


def hairline_height(scalp: ScalpRegions) -> float:
    """Relative height (over the head centre, in ``radii``) of the front hairline, where the
    scalp's front region starts at the middle of the forehead: for hair combed from a part or
    back, the face that ``_clear_face`` keeps hair out of ends there. Above it lies scalp, where
    that hair is rooted and combed; moving it aside there too bared a wedge of scalp that
    widened down to the forehead."""
    B = frame(scalp.forward, scalp.up).T  # rows: right, up, forward
    local = (scalp.vertices - scalp.origin) @ B.T / scalp.radii
    front = (scalp.region == 0) & (np.abs(local[:, 0]) < 0.3)
    return float(local[front, 1].min()) if front.any() else HAIRLINE_TOP


def _clear_face(scalp: ScalpRegions, strands: np.ndarray, top: float) -> np.ndarray:
    """Strands (N, K, 3) with every point that hangs in front of the face moved sideways to its
    edge, on the side the strand lies on (mostly its root's): long hair falls beside the face, as combed hair does, instead of
    a curtain over the eyes. The face is an oval ahead of the head's centre: ``FACE_HALF_WIDTH``
    of the head's half width up to the centre's height, rounding off to ``top`` (relative
    height) above it, so hair sliding around it frames the face instead of cutting straight
    across the forehead. The move is spread along each strand (``_sweep``): a strand bends aside
    before the face and back after it instead of jumping there in one straight segment."""
    B = frame(scalp.forward, scalp.up).T  # rows: right, up, forward
    local = (strands - scalp.origin) @ B.T
    rx, ry, rz = scalp.radii
    side = np.where(local[..., 0].mean(1, keepdims=True) >= 0, 1.0, -1.0)  # the side the strand lies on, for all of it
    rise = np.clip(local[..., 1] / (top * ry), 0.0, None)
    half = FACE_HALF_WIDTH * rx * np.sqrt(np.clip(1.0 - rise ** 2, 0.0, None))
    window = (local[..., 2] > 0.2 * rz) & (np.abs(local[..., 0]) < half)
    need = np.where(window, np.abs(side * half - local[..., 0]), 0.0)
    shift = _sweep(need, np.linalg.norm(np.diff(strands, axis=1), axis=-1))
    shift[:, 0] = 0.0  # roots stay where they grew
    x = local[..., 0] + side * shift
    across = ~window & (local[..., 2] > 0.2 * rz) & (np.abs(x) < half)  # bent from the far side into the face
    local[..., 0] = np.where(across, local[..., 0], x)
    return local @ B + scalp.origin


SWEEP_SLOPE = 1.5  # metres sideways per metre of strand, at most, as hair bends round the face


def _sweep(need: np.ndarray, seg: np.ndarray, slope: float = SWEEP_SLOPE) -> np.ndarray:
    """Sideways moves (N, K) for strand points that ``need`` (N, K) at least that much, spread
    along each strand (segment lengths ``seg``, (N, K - 1)): each point moves at least as far
    as the points along the strand need, less ``slope`` x the arc to them, so a strand bends
    aside before the face and straightens after it (a root needs nothing: the window starts
    below the hairline, so no root has a straight jump to make)."""
    out = need.copy()
    for j in range(need.shape[1] - 2, -1, -1):  # bend before a point that needs it
        out[:, j] = np.maximum(out[:, j], out[:, j + 1] - slope * seg[:, j])
    for j in range(1, need.shape[1]):  # and straighten after it
        out[:, j] = np.maximum(out[:, j], out[:, j - 1] - slope * seg[:, j - 1])
    return out


CROWN_LIFT = 0.3  # curls over the forehead leave it upwards and back (as pushed back), not across the face


def _comb(scalp: ScalpRegions, roots: np.ndarray, parting: str, part_x: float) -> np.ndarray:
    """Direction each root's hair is combed (unnormalised, world): away from the part line on
    the top of the head (``side``/``centre``: x = ``part_x`` of the head's half width, running
    from the hairline back to the crown), radially from the crown behind it and on the sides,
    straight back for ``back``, out from the top for ``crown`` (curls and afros; over the
    forehead back and up, ``CROWN_LIFT``, as curls pushed back from the face)."""
    B = frame(scalp.forward, scalp.up).T  # rows: right, up, forward
    right, up, fwd = B
    local = (roots - scalp.origin) @ B.T / scalp.skull
    whorl = np.array([part_x, 0.75, -0.45])  # the crown, behind the top
    radial = local - whorl
    radial[:, 1] = np.minimum(radial[:, 1], 0.0)
    away = radial[:, :1] * right + radial[:, 1:2] * up * 0.5 + radial[:, 2:] * fwd
    if parting in ("side", "centre"):
        side = np.where(local[:, :1] >= part_x, 1.0, -1.0)
        ahead = np.clip((local[:, 2:] - whorl[2]) / 0.4, 0.0, 1.0) * (local[:, 1:2] > 0.2)
        brow = np.clip(local[:, 2:], 0.0, 1.0)  # swept back along the hairline instead of across the forehead
        away = (1 - ahead) * away / np.maximum(np.linalg.norm(away, axis=1, keepdims=True), 1e-9) + ahead * (
            side * right * (1 - 0.5 * brow) - (0.25 + 0.8 * brow) * fwd)
    elif parting == "back":
        away = np.where(local[:, 1:2] > 0.2, -fwd + 0.3 * np.sign(local[:, :1]) * right * np.abs(local[:, :1]), away)
    else:  # crown: away from the top of the head, and back from the face over the forehead
        ahead = np.clip(local[:, 2:], 0.0, None)
        away = local[:, :1] * right + ahead * (CROWN_LIFT * up - fwd) + 0.2 * (local[:, 2:] < 0) * -fwd
    front = np.clip(local[:, 2:], 0, None) * (local[:, 1:2] < 0.2)  # temples: towards the back, off the face
    return away - 1.2 * front * fwd - 0.3 * up


def _grow(scalp, roots, normals, lengths, gravity, volume, curl, rng, comb, body=None, face_top=None) -> np.ndarray:
    """Guide strands (N, K, 3) grown step by step: leaving the scalp along ``comb`` lifted by
    ``volume``, bending down with ``gravity`` (up and out when negative) and, the flatter the
    style, towards the head; each step slides over the head (``body``, a ``collide.Surface``,
    else the proxy ellipsoid) at a per-strand height (the hair's thickness) and, with
    ``face_top``, around the face (``_clear_face``) instead of across it."""
    down = -scalp.up
    tangent = comb - normals * (normals * comb).sum(1, keepdims=True)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-9)
    seg = lengths[:, None] / (K - 1)
    layer = 0.002 + 0.012 * volume * rng.random((len(roots), 1))  # strands lie on one another
    d = tangent + normals * (0.05 + 0.3 * volume)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pts = np.empty((len(roots), K, 3))
    pts[:, 0] = p = roots
    hug = 0.25 * max(0.0, 1.0 - volume)
    front = ((roots - scalp.origin) @ scalp.forward > 0) & (rng.random(len(roots)) < 0.5)
    fall = np.where(front, 1.0, -1.0)[:, None] * scalp.forward  # hair reaching a shoulder falls ahead of it or behind
    seg = seg / SUBSTEPS  # small steps: a long strand's first segment would cut through the head
    for j in range(1, (K - 1) * SUBSTEPS + 1):
        inward = scalp.origin - p
        above = np.clip(1.0 - inward @ scalp.up / 0.05, 0.0, 1.0)[:, None]  # the head's upper half only
        inward /= np.maximum(np.linalg.norm(inward, axis=1, keepdims=True), 1e-9)
        d = d + (0.45 * (gravity * down if gravity >= 0 else -gravity * normals) + hug * above * inward) / SUBSTEPS
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        _, n, blocked = _over_head(scalp, p + d * seg, layer, body)
        into = np.minimum((d * n).sum(1, keepdims=True), 0.0) * blocked
        slide = d - into * n + (0.05 * tangent + 0.5 * (1 - above) * fall) * blocked  # along the head, off a shoulder
        d = slide / np.maximum(np.linalg.norm(slide, axis=1, keepdims=True), 1e-12)
        p, _, _ = _over_head(scalp, p + d * seg, layer, body)
        if face_top is not None:
            q = _clear_face(scalp, np.stack([roots, p], 1), face_top)[:, 1]
            if (q != p).any():
                step = q - (p - d * seg)
                d = step / np.maximum(np.linalg.norm(step, axis=1, keepdims=True), 1e-12)
                p = q
        if j in KEPT_STEPS:
            pts[:, np.searchsorted(KEPT_STEPS, j)] = p
    if curl > 0:
        s = ARC[None, :]
        phase = rng.uniform(0, 2 * np.pi, (len(roots), 1))
        a = 2 * np.pi * (0.5 + 1.5 * curl) * s + phase
        side = np.cross(tangent, normals)
        amp = ((0.003 + 0.012 * curl) * np.minimum(1, lengths / 0.05))[:, None, None] * np.sqrt(s)[..., None]
        pts = pts + amp * (np.cos(a)[..., None] * side[:, None] + np.sin(a)[..., None] * normals[:, None])
    return pts


def _over_head(scalp, p, layer, body=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points ``p`` (N, 3) lifted to at least ``layer`` (N, 1) over the head (over the body
    surface when given, else over the proxy ellipsoid), the surface normal there and which
    points were lifted (N, 1)."""
    if body is not None:
        height, normal = body.depth(p)
        lift = np.clip(layer[:, 0] - height, 0, None)[:, None]
        return p + lift * normal, normal, lift > 0
    B = frame(scalp.forward, scalp.up).T
    local = (p - scalp.origin) @ B.T
    r = np.linalg.norm(local / (scalp.skull + layer), axis=1, keepdims=True)
    normal = (local / (scalp.skull + layer) ** 2) @ B
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    return np.where(r < 1, (local / np.maximum(r, 1e-9)) @ B + scalp.origin, p), normal, r < 1


def _children(guide_roots, guides, roots, key_g, key_c, clump, frizz, curl, rng) -> np.ndarray:
    """Strands (N, K, 3) rooted at ``roots``: the shape of their three nearest guides (inverse
    squared distance weights over ``key_*``, the roots with the part side as an extra
    coordinate, so no shape is averaged across the part), gathered towards the nearest guide
    towards the tip by ``clump``, with a per-strand length and a little ``frizz``."""
    from scipy.spatial import cKDTree
    k = min(3, len(guides))
    dist, near = cKDTree(key_g).query(key_c, k=k)
    dist, near = dist.reshape(len(roots), k), near.reshape(len(roots), k)
    w = 1.0 / (dist + 0.004) ** 2
    w /= w.sum(1, keepdims=True)
    shape = np.einsum("nk,nkja->nja", w, guides[near] - guide_roots[near][:, :, None])
    s = ARC[None, :, None]
    pts = roots[:, None] + shape * rng.uniform(0.8, 1.0, (len(roots), 1, 1))
    g = near[:, 0]
    clumped = guides[g] + (roots - guide_roots[g])[:, None] * 0.35
    gather = clump * rng.uniform(0.6, 1.0, (len(roots), 1, 1)) * s ** 1.5
    pts = pts + gather * (clumped - pts)
    wobble = rng.normal(0, 1, (len(roots), 2, 3))  # a low bend and per-point noise, both growing to the tip
    scale = np.clip(np.linalg.norm(np.diff(pts, axis=1), axis=2).sum(1) / 0.2, 0.05, 1.0)[:, None, None]  # short hair: less
    pts = pts + scale * (s * wobble[:, :1] * 0.004 * frizz + s ** 2 * rng.normal(0, 1, pts.shape) * (0.0015 + 0.006 * curl))
    pts[:, 0] = roots
    return pts


BODY_MARGIN = 0.003  # metres kept between a strand and the body's surface


TUCK_PUSH = 0.04  # metres: a strand point this far under the garments' shell goes under them, with the rest of its strand


def _off_body(strands: np.ndarray, body) -> np.ndarray:
    """Strands (N, K, 3) with every point but the root lifted ``BODY_MARGIN`` over the body
    (a ``collide.Surface``: height over the nearest vertex's tangent plane); the points that
    moved are checked again, four rounds in all, for the folds where the nearest vertex
    changes (neck, shoulders). From its first point ``TUCK_PUSH`` or more under the garments
    the surface is lifted by (a collar standing well off the nape), a strand stays under them,
    over the body alone: lifted over such a collar, a crew cut's nape hairs were stretched
    into 20 cm tails sticking out over it (a jacket's back, 1-3 cm over the body, is not deep
    enough: long hair lies over it)."""
    import dataclasses
    rest = strands[:, 1:].reshape(-1, 3)
    under = np.zeros(len(rest), bool)
    if body.lift is not None and len(rest):
        deep = (BODY_MARGIN - body.depth(rest)[0] > TUCK_PUSH).reshape(len(strands), -1)
        under = (np.cumsum(deep, axis=1) > 0).ravel()
    lifted = rest.copy()
    if (~under).any():
        lifted[~under] = _lift_over(rest[~under], body)
    if under.any():
        lifted[under] = _lift_over(rest[under], dataclasses.replace(body, lift=None))
    out = strands.copy()
    out[:, 1:] = lifted.reshape(len(strands), -1, 3)
    return out


def _lift_over(points: np.ndarray, body) -> np.ndarray:
    """Points (M, 3) lifted ``BODY_MARGIN`` over ``body`` (``_off_body``)."""
    rest = points.copy()
    todo = np.arange(len(rest))
    for _ in range(4):
        height, normals = body.depth(rest[todo])
        push = np.clip(BODY_MARGIN - height, 0.0, None)
        rest[todo] += push[:, None] * normals
        todo = todo[push > 0]
        if not len(todo):
            break
    return rest


EAR_CLEARANCE = 0.035  # metres kept between a strand point and an ear keypoint


def _over_ears(strands: np.ndarray, ears: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Strand points (roots aside) within ``EAR_CLEARANCE`` of an ear keypoint moved out to it,
    away from the ear: the ear is a thin fold whose inside the tangent-plane test of
    ``_off_body`` cannot see, so hair lies over it instead of through it. Each point moves along
    the ray from the sphere's innermost point (towards the head's ``centre``), not from the
    ear: two neighbouring points either side of the ear went to opposite sides of the sphere,
    a straight jump of up to 7 cm in a curl passing over it."""
    out = strands.copy()
    rest = out[:, 1:]
    for ear in np.asarray(ears, float).reshape(-1, 3):
        outward = (ear - centre) / max(float(np.linalg.norm(ear - centre)), 1e-9)
        inner = ear - EAR_CLEARANCE * outward  # on the sphere: its rays leave it once, on the far side
        u = rest - inner
        u /= np.maximum(np.linalg.norm(u, axis=-1, keepdims=True), 1e-12)
        onto = inner + 2 * EAR_CLEARANCE * np.clip((u * outward).sum(-1, keepdims=True), 0.0, None) * u
        rest[...] = np.where(np.linalg.norm(rest - ear, axis=-1, keepdims=True) < EAR_CLEARANCE, onto, rest)
    return out


def _part_side(scalp: ScalpRegions, roots: np.ndarray, parting: str, part_x: float) -> np.ndarray:
    """(N, 1): -1 or +1 on either side of the part line on the top of the head, else 0."""
    if parting not in ("side", "centre"):
        return np.zeros((len(roots), 1))
    B = frame(scalp.forward, scalp.up).T
    local = (roots - scalp.origin) @ B.T / scalp.skull
    return np.where(local[:, :1] >= part_x, 1.0, -1.0) * (local[:, 1:2] > 0.2)


def _strands(scalp, mask, n, length, look, rng, comb=None, keep=None, body=None, face_top=None) -> tuple[np.ndarray, np.ndarray]:
    """``n`` strands (and their root normals) rooted on the scalp faces ``mask``: guides grown
    one by one (one per ``GUIDE_SHARE`` strands), children interpolated between them.
    ``look``: (gravity, volume, curl, clump, frizz, parting, part_x); ``keep`` filters roots."""
    gravity, volume, curl, clump, frizz, parting, part_x = look
    g_roots, g_normals, _ = _sample_roots(scalp, mask, max(6, int(n * GUIDE_SHARE)), rng)
    roots, normals, _ = _sample_roots(scalp, mask, n, rng)
    if keep is not None:
        g_keep, c_keep = keep(g_roots), keep(roots)
        if g_keep.sum() < 3 or not c_keep.any():
            return np.zeros((0, K, 3)), np.zeros((0, 3))
        g_roots, g_normals, roots, normals = g_roots[g_keep], g_normals[g_keep], roots[c_keep], normals[c_keep]
    direction = _comb(scalp, g_roots, parting, part_x) if comb is None else np.broadcast_to(comb, g_roots.shape)
    lengths = length * rng.uniform(0.9, 1.1, len(g_roots))
    guides = _grow(scalp, g_roots, g_normals, lengths, gravity, volume, curl, rng, direction, body, face_top)

    def key(r):
        return np.concatenate([r, 0.1 * _part_side(scalp, r, parting, part_x)], 1)
    pts = _children(g_roots, guides, roots, key(g_roots), key(roots), clump, frizz, curl, rng)
    return pts, normals


GUIDE_SHARE = 1 / 40          # guides per strand
STRANDS = (4000, 12000)        # scalp strands at density 0 and 1
ROOT_RADIUS = 0.0005           # metres at the root; strands taper to a third of it at the tip
# style -> parting (side, centre, back: swept back, crown: out from the top) and clumping (0 loose .. 1 locks)
PARTING = {"bald": ("back", 0.0), "buzz": ("back", 0.1), "short": ("side", 0.3), "crew": ("back", 0.3),
           "bob": ("centre", 0.45), "shoulder": ("side", 0.5), "long": ("centre", 0.5), "curly": ("crown", 0.7),
           "afro": ("crown", 0.15), "fringe": ("side", 0.4)}


def _arc(k: int) -> np.ndarray:
    """Each of ``k`` control points' share of its strand's length: ``ARC`` for grown strands,
    even for resampled ones."""
    return ARC if k == K else np.linspace(0.0, 1.0, k)


def _taper(n: int, scale: float = 1.0, k: int = K) -> np.ndarray:
    return np.broadcast_to(ROOT_RADIUS * scale * (1.0 - 0.67 * _arc(k)), (n, k)).copy()


def resample(points: np.ndarray, k: int) -> np.ndarray:
    """Strands (N, K', ...) with ``k`` control points evenly spaced along their length instead."""
    x = np.interp(np.linspace(0.0, 1.0, k), _arc(points.shape[1]), np.arange(points.shape[1]))
    i = np.minimum(x.astype(int), points.shape[1] - 2)
    f = (x - i).reshape(1, -1, *([1] * (points.ndim - 2)))
    return points[:, i] * (1 - f) + points[:, i + 1] * f


# style -> coil radius (metres at curliness 1) of kinky hair: each strand winds round its path, one
# turn per segment of the grown strand, drawn with COIL_POINTS points a turn
COILS = {"afro": 0.004, "curly": 0.007}
COIL_POINTS = 4


def _coil(pts: np.ndarray, normals: np.ndarray, radius: float, rng) -> np.ndarray:
    """Strands (N, K, 3) wound into a helix round their path: (K - 1) turns, ``COIL_POINTS`` points
    a turn, a radius growing from the root to ``radius`` over the first fifth of the strand."""
    k = (pts.shape[1] - 1) * COIL_POINTS + 1
    path = resample(pts, k)
    t = np.gradient(path, axis=1)
    t /= np.maximum(np.linalg.norm(t, axis=2, keepdims=True), 1e-12)
    ref = np.broadcast_to(normals[:, None], t.shape)
    ref = np.where(np.abs((ref * t).sum(2, keepdims=True)) > 0.9, np.cross(t, [0.0, 1.0, 0.0]), ref)
    n1 = np.cross(t, ref)
    n1 /= np.maximum(np.linalg.norm(n1, axis=2, keepdims=True), 1e-12)
    n2 = np.cross(t, n1)
    angle = 2 * np.pi * np.arange(k)[None, :] / COIL_POINTS + rng.uniform(0, 2 * np.pi, (len(pts), 1))
    r = radius * rng.uniform(0.7, 1.3, (len(pts), 1)) * np.clip(np.linspace(0, 5, k), 0, 1)[None, :]
    return path + r[..., None] * (np.cos(angle)[..., None] * n1 + np.sin(angle)[..., None] * n2)


def reach(params: HairParams) -> float:
    """Metres the longest strand (hair or beard) of these parameters can run from its root."""
    return max(max(STYLES[params.style].lengths) * params.length, BEARDS[params.beard])


def grow_hair(params: HairParams, scalp: ScalpRegions, body=None, ears=None) -> Strands:
    """Strands for the style and beard, deterministic from ``params.seed``; with ``body`` (the
    rest body's ``collide.Surface``) no strand point but its root lies inside the body, and
    with ``ears`` (2, 3) keypoints none passes through an ear."""
    rng = np.random.default_rng(params.seed)
    style = STYLES[params.style]
    gravity, volume = style.gravity, style.volume
    parting, clump = PARTING[params.style]
    part_x = {"side": float(rng.choice([-0.4, 0.4])), "centre": 0.0}.get(parting, 0.0)
    look = (gravity, volume, params.curliness, clump, 0.3 + params.curliness, parting, part_x)
    corner = scalp.region[scalp.faces]  # a face belongs to the region of two of its corners: no bald seams
    face_region = np.where(corner[:, 1] == corner[:, 2], corner[:, 1], corner[:, 0])
    area = triangle_areas(scalp.vertices[scalp.faces])
    scalp_area = area[(face_region >= 0) & (face_region < 5)].sum()
    parts = []
    n_total = int(STRANDS[0] + (STRANDS[1] - STRANDS[0]) * params.density)
    top = BANGS_TOP if params.style == "fringe" else HAIRLINE_TOP  # bangs may reach the brows
    top = min(top, hairline_height(scalp))  # the scalp above the hairline keeps its hair
    for r_idx in range(5):
        L = style.lengths[r_idx] * params.length
        mask = face_region == r_idx
        if L <= 0 or not mask.any():
            continue
        n = max(40, int(n_total * area[mask].sum() / max(scalp_area, 1e-9)))
        comb = scalp.forward * 0.8 - scalp.up if (r_idx == 0 and params.style == "fringe") else None
        pts, normals = _strands(scalp, mask, n, L, look, rng, comb=comb, body=body, face_top=top)
        if params.style in ENVELOPES:
            pts = _inside_envelope(scalp, pts, np.array(ENVELOPES[params.style]) * params.length, rng)
        pts = _finish(scalp, pts, normals, top)
        if params.style in COILS:
            pts = _clear_face(scalp, _coil(pts, normals, COILS[params.style] * params.curliness, rng), top)
        parts.append(Strands(pts, _taper(len(pts), 1 + 0.3 * volume, pts.shape[1]), np.full(len(pts), r_idx)))
    L = BEARDS[params.beard]
    mask = face_region == 5
    if L > 0 and mask.any():
        def keep(roots):  # a goatee on the chin below the mouth, a mustache over the upper lip
            rel = roots - scalp.origin
            x, up = rel @ np.cross(scalp.up, scalp.forward), rel @ scalp.up
            if params.beard == "mustache":
                return (np.abs(x) < 0.035) & (up > np.percentile(all_up, 60))
            return (np.abs(x) < 0.025) & (up < np.percentile(all_up, 35))
        all_up = (scalp.vertices[np.unique(scalp.faces[mask])] - scalp.origin) @ scalp.up
        beard_look = (0.6, 0.2, params.curliness * 0.5, 0.2, 0.3, "back", 0.0)
        pts, normals = _strands(scalp, mask, int(800 + 1600 * params.density), L, beard_look, rng, comb=-scalp.up,
                                keep=None if params.beard in ("stubble", "full") else keep, body=body)
        if len(pts):
            pts = _finish(scalp, pts, normals, None)
            parts.append(Strands(pts, _taper(len(pts), 0.6), np.full(len(pts), 5)))
    hair = Strands.concat(parts)
    if ears is not None and len(hair):
        hair.points = _over_ears(hair.points, ears, scalp.origin)
    if body is not None and len(hair):
        hair.points = _off_body(hair.points, body)
    return hair


# style -> how far its mass reaches past the skull (metres at length 1: sides, top, front, back): an
# afro is a rounded volume, not strands standing out as far as they are long
ENVELOPES = {"afro": (0.07, 0.10, 0.06, 0.06)}
ENVELOPE_FUZZ = 0.15  # strands end up to this share of the reach short of the envelope: a soft edge


def _inside_envelope(scalp: ScalpRegions, pts: np.ndarray, reach: np.ndarray, rng) -> np.ndarray:
    """Strands (N, K, 3) shortened about their roots until they lie inside an ellipsoid around the
    head: the skull's semi-axes plus ``reach`` (sides, top, front, back), each strand's own
    envelope up to ``ENVELOPE_FUZZ`` of the reach smaller."""
    B = frame(scalp.forward, scalp.up).T
    local = (pts - scalp.origin) @ B.T
    root, d = local[:, :1], local - local[:, :1]
    fuzz = 1.0 - ENVELOPE_FUZZ * rng.random((len(pts), 1, 1))
    forward_reach = np.where(local[..., 2:] >= 0, reach[2], reach[3])
    axes = np.concatenate([np.broadcast_to(scalp.skull[:2] + reach[:2], local[..., :2].shape),
                           scalp.skull[2] + forward_reach], -1) * fuzz
    # largest c in [0, 1] with |(root + c d) / axes| <= 1, per point: a quadratic in c
    a = ((d / axes) ** 2).sum(-1)
    b = 2 * ((root / axes) * (d / axes)).sum(-1)
    c0 = ((root / axes) ** 2).sum(-1) - 1.0
    disc = np.sqrt(np.clip(b * b - 4 * a * c0, 0.0, None))
    c = np.where(a > 1e-12, (-b + disc) / np.maximum(2 * a, 1e-12), 1.0)
    scale = np.clip(c, 0.0, 1.0).min(1)[:, None, None]
    return (root + scale * d) @ B + scalp.origin


def _finish(scalp, pts, normals, face_top) -> np.ndarray:
    """Roots 2 mm under the scalp, the rest out of the head's proxy and, with ``face_top``, out
    of the face below that relative height (``_clear_face``)."""
    pts[:, 0] -= normals * 0.002
    pts[:, 1:] = _outside(scalp, pts[:, 1:].reshape(-1, 3), 0.002).reshape(len(pts), K - 1, 3)
    if face_top is not None:
        pts = _clear_face(scalp, pts, face_top)
    return pts


FOLLOW = (0.0, 0.06)  # metres under the head joint where strands start and finish following the body


def follow_weights(strands: Strands, head_joint: np.ndarray, head_bone: int, near_weights):
    """Skinning weights (N * K, J), sparse, for the strands' control points: rigid with the
    ``head_bone`` down to ``FOLLOW[0]`` under the ``head_joint``, then blended into the weights
    of the nearest body vertex (``near_weights(points)``: sparse (P, J)), fully from ``FOLLOW[1]``
    under it. Long hair rests on the shoulders and back and moves with them when the head turns
    or bends, instead of swinging into them; beards stay with the head."""
    from scipy import sparse
    pts = strands.points.reshape(-1, 3)
    drop = np.clip((head_joint[1] - FOLLOW[0] - pts[:, 1]) / (FOLLOW[1] - FOLLOW[0]), 0.0, 1.0)
    b = drop * drop * (3 - 2 * drop) * np.repeat(strands.region < 5, strands.points.shape[1])
    J = near_weights(pts[:1]).shape[1]
    rows = np.arange(len(pts))
    rigid = sparse.csr_matrix((1.0 - b, (rows, np.full(len(pts), head_bone))), shape=(len(pts), J))
    follow = np.flatnonzero(b > 0)
    if not len(follow):
        return rigid
    blended = sparse.diags(b[follow]) @ near_weights(pts[follow])
    return (rigid + _rows(blended, follow, len(pts))).tocsr()


STRETCH = 1.15  # a posed strand segment may be at most this many times its rest length
HAIR_CLEARANCE = 0.002  # metres a walked strand's points are kept off the posed body and its garments


def off_garments(points: np.ndarray, shell, body, margin: float = HAIR_CLEARANCE) -> np.ndarray:
    """Posed strand points (M, 3) moved ``margin`` over ``shell`` (the posed body lifted by the
    garments over it) along its nearest normal, except those ``TUCK_PUSH`` or more under it (under
    a collar standing off the nape, where ``_off_body`` left them at rest): those are kept
    ``margin`` over the ``body`` alone, instead of thrown out over the collar when a turned head
    stretches their strand and it is walked again (``limit_stretch``)."""
    height, normals = shell.depth(points)
    push = margin - height
    under = push > TUCK_PUSH
    if under.any():
        bare_height, normals[under] = body.depth(points[under])
        push[under] = margin - bare_height
    return points + np.clip(push, 0.0, None)[:, None] * normals


def limit_stretch(points: np.ndarray, rest: np.ndarray, clear=None, limit: float = STRETCH) -> np.ndarray:
    """Skinned strands (N, K, 3) whose segments grew past ``limit`` times their ``rest`` lengths
    (N, K - 1) walked again from the root out: each segment keeps its skinned direction and at
    most ``limit`` times its length; ``clear`` ((M, 3) points -> the same kept off the body)
    moves each new point before the next segment starts from it, and the segment into it is
    then cut back to length. Where a strand crosses from the head to the shoulders a turned
    head pulled it up to 2.5x long. Returns new points; the input is not changed."""
    seg = np.diff(points, axis=1)
    length = np.sqrt(np.einsum("nki,nki->nk", seg, seg))
    cap = limit * rest
    over = np.flatnonzero((length > cap).any(1))
    out = points.copy()
    if not len(over):
        return out
    p, seg, length, cap = out[over], seg[over], length[over], cap[over]
    walked = np.zeros(len(over), bool)  # from a point that moved: the rest of the strand is walked too
    for k in range(1, p.shape[1]):
        walked |= length[:, k - 1] > cap[:, k - 1]
        w = np.flatnonzero(walked)
        q = p[w, k - 1] + seg[w, k - 1] * np.minimum(1.0, cap[w, k - 1] / np.maximum(length[w, k - 1], 1e-12))[:, None]
        if clear is not None:
            d = clear(q) - p[w, k - 1]
            dl = np.sqrt(np.einsum("ni,ni->n", d, d))
            q = p[w, k - 1] + d * np.minimum(1.0, cap[w, k - 1] / np.maximum(dl, 1e-12))[:, None]
        p[w, k] = q
    out[over] = p
    return out


def _rows(m, rows: np.ndarray, n: int):
    """Sparse (n, J) holding ``m``'s rows at ``rows``, zeros elsewhere."""
    from scipy import sparse
    m = m.tocoo()
    return sparse.csr_matrix((m.data, (rows[m.row], m.col)), shape=(n, m.shape[1]))


def hair_colour(params: HairParams) -> np.ndarray:
    """Linear RGB of a mass of this hair seen diffusely: half the transmittance through two fibre
    diameters under the absorption of ``hair_material``, used to tint the scalp under the hair."""
    from synmitsuba.scene.materials import hair_sigma_a
    return 0.5 * np.exp(-2.0 * hair_sigma_a(params.melanin, params.redness))


STRAND_SHADE = 0.06  # standard deviation of a strand's melanin around the recipe's


def strand_melanin(params: HairParams, n: int) -> np.ndarray:
    """(n,) melanin per strand: the recipe's, varied by ``STRAND_SHADE`` (deterministic)."""
    rng = np.random.default_rng([params.seed, 1])
    return np.clip(params.melanin + STRAND_SHADE * rng.standard_normal(n), 0.0, 1.0)


def root_cover(vertices: np.ndarray, roots: np.ndarray, radius: float = 0.008) -> np.ndarray:
    """(V,) in [0, 1]: how densely strands are rooted around each vertex (3 roots within
    ``radius`` count as covered): where the scalp lies under hair."""
    from scipy.spatial import cKDTree
    if not len(roots):
        return np.zeros(len(vertices))
    counts = cKDTree(roots).query_ball_point(vertices, radius, return_length=True)
    return np.clip(np.asarray(counts) / 3.0, 0.0, 1.0)


def hair_material(params: HairParams, melanin: np.ndarray | None = None):
    """Mitsuba's hair BSDF for the recipe; ``melanin`` (N,) varies it strand by strand."""
    from synmitsuba.scene.materials import Material
    return Material(kind="hair", melanin=float(params.melanin), redness=float(params.redness), strand_melanin=melanin)
