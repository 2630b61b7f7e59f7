"""Strand hair as Mitsuba B-spline curves, rooted on scalp regions and shaped by style.

Scalp regions (fringe, top, temporal, occipital, lower_back, and the beard area) are labelled
geometrically in a head frame (origin at the head centre, up, forward). Each style sets a
length per region, how strands fall (gravity), and curliness; strands are pushed out of a head
proxy ellipsoid so they never enter the head. Strands are rigid with the head bone.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.schema import Choice, Number, Params, spec
from synmitsuba.geometry import frame, triangle_areas

REGIONS = ("fringe", "top", "temporal", "occipital", "lower_back", "beard")
# style -> length (m) per scalp region (fringe, top, temporal, occipital, lower_back), gravity, volume
STYLES = {
    "bald": (0, 0, 0, 0, 0, 0.0, 0.0),
    "buzz": (0.008, 0.01, 0.008, 0.008, 0.006, 0.0, 0.3),
    "short": (0.04, 0.05, 0.03, 0.04, 0.025, 0.4, 0.5),
    "crew": (0.03, 0.06, 0.015, 0.02, 0.012, 0.2, 0.6),
    "bob": (0.10, 0.16, 0.16, 0.17, 0.15, 0.9, 0.4),
    "shoulder": (0.12, 0.26, 0.26, 0.28, 0.26, 1.0, 0.3),
    "long": (0.16, 0.42, 0.42, 0.45, 0.42, 1.0, 0.25),
    "curly": (0.08, 0.12, 0.10, 0.12, 0.10, 0.5, 0.9),
    "afro": (0.09, 0.11, 0.10, 0.10, 0.08, -0.2, 1.0),
    "fringe": (0.12, 0.10, 0.07, 0.08, 0.06, 0.8, 0.4),
}
HAIRLINE_TOP, BANGS_TOP = 0.45, 0.15  # relative heights over the head centre: hair over the face stops there
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


def sample_hair(rng: np.random.Generator, beard_allowed: bool = True) -> HairParams:
    style = str(rng.choice(list(STYLES)))
    beard = str(rng.choice(list(BEARDS), p=[0.6, 0.1, 0.1, 0.1, 0.1])) if beard_allowed else "none"
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
    radii: np.ndarray        # head proxy ellipsoid semi-axes (right, up, forward)


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
    region[(np.abs(azim) < 75) & (elev < -20) & (elev > -75) & (z > 0)] = 5
    radii = np.array([np.abs(x).max(), np.abs(y).max(), np.abs(z).max()]) * 0.93
    return ScalpRegions(np.asarray(vertices, float), np.asarray(normals, float), np.asarray(faces), region,
                        np.asarray(head_center, float), up, fwd, radii)


@dataclass
class Strands:
    points: np.ndarray   # (N, K, 3) control points
    radius: np.ndarray   # (N, K)
    region: np.ndarray   # (N,)

    def transformed(self, R: np.ndarray, t: np.ndarray) -> "Strands":
        return Strands(self.points @ R.T + t, self.radius, self.region)

    def __len__(self) -> int:
        return len(self.points)

    @staticmethod
    def concat(parts: list["Strands"]) -> "Strands":
        parts = [p for p in parts if len(p)]
        if not parts:
            return Strands(np.zeros((0, 6, 3)), np.zeros((0, 6)), np.zeros(0, np.int64))
        return Strands(np.concatenate([p.points for p in parts]), np.concatenate([p.radius for p in parts]),
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


def _outside(scalp: ScalpRegions, p: np.ndarray, margin: float, hug: float | None = None) -> np.ndarray:
    """Push points out of the head proxy ellipsoid (grown by ``margin``); with ``hug``, points
    above the ears are also pulled onto the shell at most ``hug`` (relative) above it."""
    B = frame(scalp.forward, scalp.up).T  # rows: right, up, forward
    local = (p - scalp.origin) @ B.T
    r = np.linalg.norm(local / (scalp.radii + margin), axis=-1, keepdims=True)
    target = np.maximum(r, 1.0)
    if hug is not None:
        above = local[:, 1:2] > -0.2 * scalp.radii[1]
        target = np.where(above, np.minimum(target, 1.0 + hug), target)
    local = local / np.maximum(r, 1e-9) * target
    return local @ B + scalp.origin


FACE_HALF_WIDTH = 0.85  # of the head's half width: hair in front of the face is moved beside it


def _clear_face(scalp: ScalpRegions, strands: np.ndarray, top: float) -> np.ndarray:
    """Strands (N, K, 3) with every point that hangs in front of the face (ahead of the head's
    centre, below ``top`` (relative height) and within ``FACE_HALF_WIDTH`` of its mid-line)
    moved sideways to that edge, on its root's side: long hair falls beside the face, as
    combed hair does, instead of a curtain over the eyes."""
    B = frame(scalp.forward, scalp.up).T  # rows: right, up, forward
    local = (strands - scalp.origin) @ B.T
    rx, ry, rz = scalp.radii
    side = np.where(local[:, :1, 0] >= 0, 1.0, -1.0)  # the root's side, for the whole strand
    window = (local[..., 2] > 0.2 * rz) & (local[..., 1] < top * ry) & (np.abs(local[..., 0]) < FACE_HALF_WIDTH * rx)
    window[:, 0] = False  # roots stay where they grew
    x = np.where(window, side * FACE_HALF_WIDTH * rx, local[..., 0])
    local = np.concatenate([x[..., None], local[..., 1:]], -1)
    return local @ B + scalp.origin


def _grow(scalp, roots, normals, lengths, gravity, volume, curl, rng, k=6, comb=None,
          face_top: float | None = None) -> np.ndarray:
    """Strands that leave the scalp along it (combed towards ``comb``, default down and back),
    lift off it by ``volume`` and bend down with ``gravity``, staying outside the head (and,
    with ``face_top``, out of the face below that relative height: ``_clear_face``)."""
    down = -scalp.up
    if comb is None:  # fall away from the crown, parted away from the face
        radial = roots - scalp.origin
        radial -= np.outer(radial @ scalp.up, scalp.up)
        radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-9)
        front = np.clip(radial @ scalp.forward, 0, None)[:, None]
        radial = radial - front * scalp.forward * 1.2
        comb = radial + 0.5 * down
    else:
        comb = np.broadcast_to(comb, roots.shape)
    tangent = comb - normals * (normals * comb).sum(1, keepdims=True)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-9)
    seg = lengths[:, None] / (k - 1)
    pts = np.empty((len(roots), k, 3))
    pts[:, 0] = roots
    lift = 0.05 + 0.3 * volume
    for j in range(1, k):
        s = j / (k - 1)
        g = np.clip(gravity, -1, 1) * s
        d = tangent * (1 - abs(g)) + normals * lift * (1 - s) + down * max(g, 0) + normals * max(-g, 0)
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        pts[:, j] = pts[:, j - 1] + d * seg
    if curl > 0:
        s = np.linspace(0, 1, k)[None, :]
        phase = rng.uniform(0, 2 * np.pi, (len(roots), 1))
        a = 2 * np.pi * (1 + 4 * curl) * s + phase
        side = np.cross(tangent, normals)
        amp = ((0.003 + 0.01 * curl) * np.minimum(1, lengths / 0.05))[:, None, None] * (s[..., None] > 0)
        pts = pts + amp * (np.cos(a)[..., None] * side[:, None] + np.sin(a)[..., None] * normals[:, None])
    pts[:, 0] = roots - normals * 0.002  # roots just under the scalp surface
    hug = None if volume >= 0.9 else 0.05 + 0.25 * volume
    pts[:, 1:] = _outside(scalp, pts[:, 1:].reshape(-1, 3), 0.003, hug).reshape(len(roots), k - 1, 3)
    if face_top is not None:
        pts = _clear_face(scalp, pts, face_top)
        pts[:, 1:] = _outside(scalp, pts[:, 1:].reshape(-1, 3), 0.003).reshape(len(roots), k - 1, 3)
    return pts


BODY_MARGIN = 0.003  # metres kept between a strand and the body's surface


def _off_body(strands: np.ndarray, body) -> np.ndarray:
    """Strands (N, K, 3) with every point but the root lifted ``BODY_MARGIN`` over the body
    (a ``collide.Surface``: height over the nearest vertex's tangent plane), three rounds for
    the folds where the nearest vertex changes (neck, shoulders)."""
    out = strands.copy()
    rest = out[:, 1:].reshape(-1, 3)
    for _ in range(3):
        height, normals = body.depth(rest)
        push = np.clip(BODY_MARGIN - height, 0.0, None)
        rest += push[:, None] * normals
    out[:, 1:] = rest.reshape(len(out), -1, 3)
    return out


def grow_hair(params: HairParams, scalp: ScalpRegions, body=None) -> Strands:
    """Strands for the style and beard, deterministic from ``params.seed``; with ``body`` (the
    rest body's ``collide.Surface``) no strand point but its root lies inside the body."""
    rng = np.random.default_rng(params.seed)
    lengths = STYLES[params.style]
    gravity, volume = lengths[5], lengths[6]
    face_region = scalp.region[scalp.faces]
    area = triangle_areas(scalp.vertices[scalp.faces])
    scalp_area = area[(face_region[:, 0] >= 0) & (face_region[:, 0] < 5) & (face_region == face_region[:, :1]).all(1)].sum()
    parts = []
    n_total = int(1500 + 3500 * params.density)
    for r_idx in range(5):
        L = lengths[r_idx] * params.length
        mask = (face_region == r_idx).all(1)
        if L <= 0 or not mask.any():
            continue
        n = max(20, int(n_total * area[mask].sum() / max(scalp_area, 1e-9)))
        roots, normals, _ = _sample_roots(scalp, mask, n, rng)
        lens = L * rng.uniform(0.85, 1.15, n)
        comb = scalp.forward * 0.8 - scalp.up if (r_idx == 0 and params.style == "fringe") else None
        top = BANGS_TOP if params.style == "fringe" else HAIRLINE_TOP  # bangs may reach the brows
        pts = _grow(scalp, roots, normals, lens, gravity, volume, params.curliness, rng, comb=comb, face_top=top)
        radius = np.linspace(0.0016, 0.0008, pts.shape[1])[None].repeat(n, 0) * (1 + 0.5 * volume)
        parts.append(Strands(pts, radius, np.full(n, r_idx)))
    L = BEARDS[params.beard]
    mask = (face_region == 5).all(1)
    if L > 0 and mask.any():
        n = int(400 + 800 * params.density)
        roots, normals, _ = _sample_roots(scalp, mask, n, rng)
        if params.beard in ("goatee", "mustache"):  # keep a narrow band around the mouth
            rel = roots - scalp.origin
            x = rel @ np.cross(scalp.up, scalp.forward)
            keep = np.abs(x) < (0.03 if params.beard == "goatee" else 0.035)
            if params.beard == "mustache":
                keep &= (rel @ scalp.up) > np.percentile(rel @ scalp.up, 60)
            roots, normals = roots[keep], normals[keep]
        if len(roots):
            pts = _grow(scalp, roots, normals, L * rng.uniform(0.8, 1.2, len(roots)), 0.6, 0.2, params.curliness * 0.5,
                        rng, comb=-scalp.up)
            radius = np.full(pts.shape[:2], 0.0009)
            parts.append(Strands(pts, radius, np.full(len(roots), 5)))
    hair = Strands.concat(parts)
    if body is not None and len(hair):
        hair.points = _off_body(hair.points, body)
    return hair


def hair_material(params: HairParams):
    from synmitsuba.scene.materials import Material
    return Material(kind="hair", melanin=float(params.melanin), redness=float(params.redness))
