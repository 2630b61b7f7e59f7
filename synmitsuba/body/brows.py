"""Eyebrows and eyelashes: short strands on the brow ridge and along the lid margins.

Both are found from each eyeball's centre by casting rays at the skin round it (the body
without its eye helpers): the lid margin is, round the gaze axis, where the rays out of the
lids' opening first meet skin; the brow is the outer skin along an arch of directions above the
eye. Lashes curl out and away from the eye (upper up, lower down); brow hairs lie almost flat,
rising at the inner end and sweeping outwards along the arch. Deterministic from the recipe.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.geometry import face_normals
from synmitsuba.schema import Number, Params, spec

LASH_RADIUS = 0.00007   # metres at the root (a lash is about 0.1-0.15 mm thick), tapering to a third
BROW_RADIUS = 0.00006
LASH_CLEARANCE = 0.0004  # metres from a lash's root to the eyeball under it (the cornea bulges 0.8 mm more)
POINTS = 5              # control points per lash or brow hair
UPPER_LASHES, LOWER_LASHES = 100, 30  # per eye (people: about 100-150 and 50-80)


@dataclass
class BrowParams(Params):
    density: float = spec(0.5, Number(0, 1), doc="0 sparse (250 hairs a brow) .. 1 dense (650)")
    thickness: float = spec(0.5, Number(0, 1), doc="0 thin (5 mm at the inner end) .. 1 bushy (12 mm)")
    arch: float = spec(0.5, Number(0, 1), doc="0 straight .. 1 high arch")
    length: float = spec(0.5, Number(0, 1), doc="hair length: 0 short (5 mm) .. 1 long (10 mm)")
    lashes: float = spec(0.5, Number(0, 1), doc="lash length: 0 short (6 mm upper) .. 1 long (11 mm)")
    seed: int = spec(0, Number(0, 2 ** 31, integer=True))


def sample_brows(rng: np.random.Generator, female: bool) -> BrowParams:
    """Brows and lashes for a woman (thinner, higher arches, longer lashes) or a man."""
    def draw(lo, hi):
        return round(float(rng.uniform(lo, hi)), 3)
    if female:
        return BrowParams(draw(0.2, 0.8), draw(0.1, 0.6), draw(0.4, 1.0), draw(0.1, 0.6), draw(0.4, 1.0),
                          int(rng.integers(0, 2 ** 31)))
    return BrowParams(draw(0.4, 1.0), draw(0.4, 1.0), draw(0.0, 0.6), draw(0.3, 1.0), draw(0.1, 0.7),
                      int(rng.integers(0, 2 ** 31)))


# -- rays against the skin -------------------------------------------------------------------
def ray_distances(origin: np.ndarray, dirs: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(N, M) distance along each unit ray (N, 3) from ``origin`` to each triangle (M, 3, 3) it
    crosses, inf where it misses (Moller-Trumbore, its triple products regrouped so each is a
    product of the rays (N, 3) with a per-triangle vector (3, M): (d x e2) . e1 = d . (e2 x e1),
    (d x e2) . s = d . (e2 x s); 3x faster than the (N, M, 3) cross products)."""
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    s = origin - tri[:, 0]
    q = np.cross(s, e1)
    det = dirs @ np.cross(e2, e1).T
    ok = np.abs(det) > 1e-14
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    u = (dirs @ np.cross(e2, s).T) * inv
    v = (dirs @ q.T) * inv
    t = np.einsum("mi,mi->m", e2, q)[None] * inv
    return np.where(ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9), t, np.inf)


def _directions(frame: np.ndarray, yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """Unit directions (N, 3) at ``yaw`` (towards the frame's x) and ``pitch`` (towards y) from its z."""
    d = np.stack([np.cos(pitch) * np.sin(yaw), np.sin(pitch), np.cos(pitch) * np.cos(yaw)], -1)
    return d @ frame.T


@dataclass
class EyeRegion:
    """One eye's surroundings at rest: its eyeball's centre and radius, the head frame (columns:
    outwards (away from the nose), up, forward) and the skin triangles within 5 cm."""

    centre: np.ndarray
    radius: float
    frame: np.ndarray
    skin: np.ndarray  # (M, 3, 3)


def eye_region(centre: np.ndarray, radius: float, side: float, vertices: np.ndarray, faces: np.ndarray) -> EyeRegion:
    """``side`` +1 for the left eye (at +x: outwards is +x), -1 for the right."""
    near = faces[(np.linalg.norm(vertices[faces] - centre, axis=2) < 0.05).all(1)]
    frame = np.array([[side, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]).T
    return EyeRegion(centre, float(radius), frame, vertices[near])


def lid_margin(eye: EyeRegion, count: int = 64, iterations: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Points (count, 3) round the lids' margin and their azimuth about the forward axis (0
    outwards, pi/2 up): along each azimuth, where rays from the centre first meet skin (the
    edge of the open cone, bisected between 2 and 50 degrees from the forward axis)."""
    psi = 2 * np.pi * np.arange(count) / count
    tri = eye.skin[(np.linalg.norm(eye.skin - eye.centre, axis=2) < 0.03).all(1)]  # the lids

    def cast(theta):
        local = np.stack([np.sin(theta) * np.cos(psi), np.sin(theta) * np.sin(psi), np.cos(theta)], -1)
        d = local @ eye.frame.T
        return d, ray_distances(eye.centre, d, tri).min(1)
    lo, hi = np.full(count, np.radians(2.0)), np.full(count, np.radians(50.0))
    for _ in range(iterations):
        mid = (lo + hi) / 2
        covered = np.isfinite(cast(mid)[1])
        lo, hi = np.where(covered, lo, mid), np.where(covered, mid, hi)
    d, t = cast(hi)
    ok = np.isfinite(t)
    return eye.centre + d[ok] * t[ok, None], psi[ok]


def _along(points: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Points at fractions ``u`` of the arc length of a polyline (N, 3)."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)]) / max(seg.sum(), 1e-12)
    return np.stack([np.interp(u, s, points[:, k]) for k in range(3)], -1)


def grow_lashes(eye: EyeRegion, p: BrowParams, rng: np.random.Generator) -> np.ndarray:
    """Lashes (N, POINTS, 3) on the upper and lower lid margins, thinning towards the corners
    (none at the inner corner), curling away from the eye."""
    margin, psi = lid_margin(eye)
    out, up = eye.frame[:, 0], eye.frame[:, 1]
    strands = []
    for upper, count, length in ((True, UPPER_LASHES, 0.006 + 0.005 * p.lashes),
                                 (False, LOWER_LASHES, 0.002 + 0.002 * p.lashes)):
        arc = np.sin(psi) > 0.25 if upper else np.sin(psi) < -0.35
        order = np.argsort(np.cos(psi[arc]))  # from the inner corner outwards
        line = margin[arc][order]
        u = np.sort(rng.beta(1.6, 1.3, count)) * (0.92 if upper else 0.85) + (0.04 if upper else 0.12)
        roots = _along(line, u)
        radial = roots - eye.centre
        dist = np.linalg.norm(radial, axis=1, keepdims=True)
        radial /= dist
        roots = eye.centre + radial * np.maximum(dist, eye.radius + LASH_CLEARANCE)  # the lids' margins
        # touch the eyeball, some within it: every lash starts outside it
        mid = 1.0 - 1.6 * (u - 0.55) ** 2  # longest in the middle of the lid
        L = length * mid * rng.uniform(0.75, 1.1, count)
        curl = (0.9 if upper else -0.7) * up + 0.25 * out * (u - 0.4)[:, None]
        strands.append(_curve(roots, radial, curl, L, rng))
    return np.concatenate(strands)


def _curve(roots: np.ndarray, start: np.ndarray, bend: np.ndarray, length: np.ndarray,
           rng: np.random.Generator) -> np.ndarray:
    """Quadratic curves (N, POINTS, 3) leaving ``roots`` along ``start`` and turning towards
    ``start + bend`` over ``length``."""
    tip = start + bend + rng.normal(0, 0.08, roots.shape)
    tip /= np.linalg.norm(tip, axis=1, keepdims=True)
    s = np.linspace(0.0, 1.0, POINTS)[None, :, None]
    a, b = start[:, None], tip[:, None]
    half = (length / 2)[:, None, None]
    return roots[:, None] + half * (2 * s * (1 - s) * a + s ** 2 * (a + b))


def brow_arch(p: BrowParams, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(yaw, pitch) radians from the eye's centre of the brow's middle line at ``s`` (0 inner end,
    1 tail): over the eye, rising to the arch's peak two thirds along, dropping at the tail."""
    yaw = np.radians(-20.0 + 62.0 * s)
    pitch = np.radians(24.0 + (3.0 + 8.0 * p.arch) * np.sin(np.pi * np.clip(s / 0.66, 0, 1) / 2)
                       - 14.0 * np.clip((s - 0.66) / 0.34, 0, 1) ** 1.5)
    return yaw, pitch


def grow_brows(eye: EyeRegion, p: BrowParams, rng: np.random.Generator) -> np.ndarray:
    """Brow hairs (N, POINTS, 3): roots over a band round ``brow_arch``, widest at the inner end;
    hairs rise at the inner end and sweep outwards along the arch, lying on the skin."""
    n = int(250 + 400 * p.density)
    s = rng.beta(1.1, 1.4, n)
    band = np.radians(12.0 + 12.0 * p.thickness) * (1.0 - 0.6 * s)  # angular height of the band
    yaw, pitch = brow_arch(p, s)
    pitch = pitch + band * rng.uniform(-0.35, 0.65, n)
    dirs = _directions(eye.frame, yaw, pitch)
    t = ray_distances(eye.centre, dirs, eye.skin)
    t = np.where(t < 0.045, t, -np.inf)
    face = t.argmax(1)  # the outermost skin: the brow, not the socket
    t = t[np.arange(n), face]
    keep = np.isfinite(t)
    roots, dirs, s, tri = eye.centre + dirs[keep] * t[keep, None], dirs[keep], s[keep], eye.skin[face[keep]]
    normal = face_normals(tri)
    normal *= np.sign(np.einsum("ni,ni->n", normal, dirs))[:, None]  # facing away from the eye
    y2, p2 = brow_arch(p, np.clip(s + 0.05, 0, 1))
    along = _directions(eye.frame, y2, p2) * t[keep, None] + eye.centre - roots
    up = eye.frame[:, 1]
    sweep = np.where((s < 0.12)[:, None], up + 1.2 * along / np.linalg.norm(along, axis=1, keepdims=True), along)
    sweep -= np.einsum("ni,ni->n", sweep, normal)[:, None] * normal  # in the skin's tangent plane
    sweep /= np.linalg.norm(sweep, axis=1, keepdims=True)
    L = (0.005 + 0.005 * p.length) * rng.uniform(0.6, 1.1, len(roots)) * (1.0 - 0.3 * s) * np.clip(0.5 + 3 * s, 0, 1)
    return _curve(roots + 0.0003 * normal, sweep + 0.25 * normal, -0.45 * normal, L, rng)


def taper(n: int, root: float) -> np.ndarray:
    """(n, POINTS) radii from ``root`` to a third of it at the tip."""
    return np.broadcast_to(root * (1.0 - 0.67 * np.linspace(0, 1, POINTS)), (n, POINTS)).copy()
