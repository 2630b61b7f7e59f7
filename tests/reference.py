"""Independent reference computations that tests (and bench scripts) check the package
against; not shipped, since nothing in the package needs them."""
from __future__ import annotations

import numpy as np


def winding_numbers(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray, chunk: int = 2 ** 16) -> np.ndarray:
    """Generalised winding numbers (N,) of ``points`` in a closed mesh: the triangles' signed
    solid angles over 4 pi (van Oosterom and Strackee). ~1 inside, ~0 outside, and still so
    where a posed body folds or runs into itself, where the closest triangle's side does not
    say inside. O(points x faces): for the few points a cheaper test flags. Written by
    coordinates on (points, faces) arrays of ``chunk`` entries, which stay in cache: 9x faster
    than (points, faces, 3) arrays with ``np.cross`` and norms (the suite's many calls)."""
    v, f = np.asarray(vertices, dtype=np.float64), np.asarray(faces)
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.empty(len(points))
    corners = [v[f[:, i]].T for i in range(3)]  # each (3, F)
    step = max(1, chunk // max(1, len(f)))
    for s in range(0, len(points), step):
        p = points[s:s + step]
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = ([c[k][None] - p[:, k, None] for k in range(3)] for c in corners)
        la, lb, lc = np.sqrt(ax * ax + ay * ay + az * az), np.sqrt(bx * bx + by * by + bz * bz), np.sqrt(cx * cx + cy * cy + cz * cz)
        det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc + (bx * cx + by * cy + bz * cz) * la
               + (cx * ax + cy * ay + cz * az) * lb)
        out[s:s + step] = np.arctan2(det, den).sum(1) / (2 * np.pi)
    return out


def bound_points(binding, body_vertices, body_faces) -> np.ndarray:
    """The bound body points for (possibly posed) body vertices."""
    return np.einsum("nk,nka->na", binding.barycentric, body_vertices[body_faces[binding.triangle]])


def point_triangle_distances(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(N, M) exact distance from each point (N, 3) to each triangle (M, 3, 3): to its plane where
    the projection falls inside it, else to the nearest of its three edges (brute force)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    rel = points[:, None] - a[None]                                  # (N, M, 3)
    h = np.einsum("nmi,mi->nm", rel, n)
    proj = points[:, None] - h[..., None] * n[None]
    inside = np.ones(h.shape, bool)
    for p, q in ((a, b), (b, c), (c, a)):  # same side of every edge as the normal says
        inside &= np.einsum("nmi,mi->nm", np.cross(q - p, proj - p[None]), n) >= 0

    def segment(p, q):
        d = q - p
        s = np.clip(np.einsum("nmi,mi->nm", points[:, None] - p[None], d) / np.einsum("mi,mi->m", d, d), 0, 1)
        return np.linalg.norm(points[:, None] - (p[None] + s[..., None] * d[None]), axis=2)
    edges = np.minimum(np.minimum(segment(a, b), segment(b, c)), segment(c, a))
    return np.where(inside, np.abs(h), edges)


def crossings(origin: np.ndarray, dirs: np.ndarray, tri: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """How many triangles (M, 3, 3) each ray (N, 3) from ``origin`` (3,) crosses before ``reach``
    (N,), written for the tests: the hit on each triangle's plane, kept when it lies on the inner
    side of all three edges. Edge test at the hit o + t d, expanded so no (N, M, 3) array is
    made: ((q - p) x (o + t d - p)) . n = ((q - p) x (o - p)) . n + t d . (n x (q - p))."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    denom = dirs @ n.T                                            # (N, M)
    t = np.einsum("mi,mi->m", a - origin, n)[None] / np.where(np.abs(denom) > 1e-14, denom, np.nan)
    inside = np.ones(t.shape, bool)
    for p, q in ((a, b), (b, c), (c, a)):
        at_origin = np.einsum("mi,mi->m", np.cross(q - p, origin - p), n)
        inside &= at_origin[None] + t * (dirs @ np.cross(n, q - p).T) >= 0
    return (inside & (t > 0) & (t < reach[:, None])).sum(1)


def first_hits(origins: np.ndarray, direction: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance along the unit ``direction`` (3,) from each of ``origins`` (N, 3) to the nearest
    of the triangles (M, 3, 3) it meets, inf where none (Moller-Trumbore), written for the tests."""
    if not len(tri):
        return np.full(len(origins), np.inf)
    a, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    pv = np.cross(direction, e2)
    det = np.einsum("mi,mi->m", e1, pv)
    inv = np.where(np.abs(det) > 1e-14, 1.0 / np.where(np.abs(det) > 1e-14, det, 1.0), 0.0)
    tv = origins[:, None, :] - a[None]
    u = np.einsum("nmi,mi->nm", tv, pv) * inv
    qv = np.cross(tv, e1[None])
    v = (qv @ direction) * inv
    t = np.einsum("nmi,mi->nm", qv, e2) * inv
    hit = (inv != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return np.where(hit, t, np.inf).min(1)


def hang_shelf(vertices: np.ndarray, faces: np.ndarray, xs: np.ndarray, top: float, bottom: float,
               slope: float = 1.0, step: float = 0.005) -> float:
    """Metres a mesh seen straight on from the front (+z), down each column x in ``xs`` from
    ``top`` to ``bottom`` every ``step``, lies behind the line falling in at ``slope`` (metres in
    per metre down) from any point of the same column over it, at most: a shelf under a bust
    that cloth would hang straight down from. Only faces turned to the front are met
    (``first_hits``): a ray through an opening counts as no point."""
    tri = vertices[faces]
    tri = tri[np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2] > 0]
    ys = np.arange(top, bottom, -step)
    worst = 0.0
    for x in xs:
        o = np.stack([np.full_like(ys, x), ys, np.full_like(ys, 2.0)], 1)
        z = 2.0 - first_hits(o, np.array([0.0, 0.0, -1.0]), tri)
        hang = -np.inf
        for y, zi in zip(ys, z):
            hang -= slope * step
            if np.isfinite(zi):
                worst = max(worst, hang - zi)
                hang = max(hang, zi)
    return worst


def middle_notch(layers: list, top: int, middle: float, crotch: float) -> float:
    """Metres the top (``layers[top]``; layers are (vertices, faces), the body first), seen
    straight on from the front and from behind at the middle between the legs (x = ``middle``
    and 1 cm either side), lies behind its own front-most (back-most) point within 8 cm of that
    middle, at each height from 1 cm under the ``crotch`` to 1.5 cm over its hem there, at
    most; inf if another layer is met first (``first_hits``)."""
    v = layers[top][0]
    worst = 0.0
    for side in (1.0, -1.0):
        near = np.abs(v[:, 0] - middle) < 0.08
        for y in np.arange(crotch - 0.01, v[near & (np.abs(v[:, 0] - middle) < 0.05), 1].min() + 0.015, -0.01):
            o = np.array([[middle + dx, y, side] for dx in (-0.01, 0.0, 0.01)])
            dist = np.array([first_hits(o, np.array([0.0, 0.0, -side]), w[f][(w[f][:, :, 1].min(1) <= y)
                                                                           & (w[f][:, :, 1].max(1) >= y)])
                             for w, f in layers])
            front = (side * v[near & (np.abs(v[:, 1] - y) < 0.01), 2]).max()
            worst = max(worst, np.inf if (dist.argmin(0) != top).any() else float(front - (1.0 - dist[top].max())))
    return worst


def segments_through_triangles(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(N,) whether each segment ``p``-``q`` (N, 3) passes through the triangle ``a``-``b``-``c``
    (each (N, 3)): the barycentric hit of its line (Moller and Trumbore) within the triangle and
    the segment."""
    d, e1, e2 = q - p, b - a, c - a
    h = np.cross(d, e2)
    det = (e1 * h).sum(1)
    ok = np.abs(det) > 1e-14
    inv = 1.0 / np.where(ok, det, 1.0)
    s = p - a
    u = (s * h).sum(1) * inv
    k = np.cross(s, e1)
    w = (d * k).sum(1) * inv
    t = (e2 * k).sum(1) * inv
    return ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (t >= 0) & (t <= 1)


def self_crossing(vertices: np.ndarray, faces: np.ndarray, among: np.ndarray | None = None) -> np.ndarray:
    """(F,) whether each face (of those ``among``, a mask; all when None) passes through another
    of them not touching it: an edge of one through the other (``segments_through_triangles``),
    over the pairs whose centres are nearer than twice the farthest any corner is from its centre."""
    from scipy.spatial import cKDTree
    f, v = np.asarray(faces), np.asarray(vertices, dtype=np.float64)
    c = v[f].mean(1)
    ids = np.arange(len(f)) if among is None else np.flatnonzero(among)
    out = np.zeros(len(f), bool)
    if len(ids) < 2:
        return out
    reach = 2 * np.linalg.norm(v[f[ids]] - c[ids, None], axis=2).max()
    i, j = ids[cKDTree(c[ids]).query_pairs(reach, output_type="ndarray").T]
    apart = ~(f[i][:, :, None] == f[j][:, None, :]).any((1, 2))
    i, j = i[apart], j[apart]
    hit = np.zeros(len(i), bool)
    for x, y in ((i, j), (j, i)):
        for k in range(3):
            hit |= segments_through_triangles(v[f[x, k]], v[f[x, (k + 1) % 3]], v[f[y, 0]], v[f[y, 1]], v[f[y, 2]])
    out[i[hit]] = out[j[hit]] = True
    return out


def unit_weights(**units: float) -> np.ndarray:
    """The 52 ARKit face unit weights with the named ones set (``jawOpen=0.7``), the rest 0."""
    from synmitsuba.body.expressions import FACE_UNITS
    w = np.zeros(len(FACE_UNITS))
    for name, v in units.items():
        w[FACE_UNITS.index(name)] = v
    return w


def named_as(motion, family: str):
    """``motion`` with its joints renamed as mocap ``family`` (``motion.names.FAMILIES``, e.g.
    "cmu" as a CMU BVH names them) where the family has a name for them: the same skeleton and
    frames, which retargeting then takes for that family's mocap."""
    from dataclasses import replace
    from synmitsuba.body.skeleton import Skeleton
    from synmitsuba.motion.names import FAMILIES
    named = {canon: name for name, canon in FAMILIES[family].items()}
    sk = motion.skeleton
    return replace(motion, skeleton=Skeleton(tuple(named.get(n, n) for n in sk.names), sk.parents, sk.rest_positions))


def uv_to_rest(v: np.ndarray, f: np.ndarray, uv: np.ndarray, q: np.ndarray) -> np.ndarray | None:
    """The rest point of the mesh (v, f, uv) at texture coordinates ``q`` (2,): the first face
    whose uv triangle holds it, barycentrically; None where none does."""
    a, b, c = (uv[f[:, i]] for i in range(3))
    d = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    d = np.where(d == 0, np.nan, d)
    l1 = ((q[0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (q[1] - a[:, 1])) / d
    l2 = ((b[:, 0] - a[:, 0]) * (q[1] - a[:, 1]) - (q[0] - a[:, 0]) * (b[:, 1] - a[:, 1])) / d
    hit = np.flatnonzero((l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1))
    if not len(hit):
        return None
    k = hit[0]
    return (1 - l1[k] - l2[k]) * v[f[k, 0]] + l1[k] * v[f[k, 1]] + l2[k] * v[f[k, 2]]


def pattern_jacobians(P: np.ndarray, C: np.ndarray, covered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where a texture's pattern lies on the cloth, by finite differences between texels: per
    texel whose right and lower neighbours are covered and on its own panel (the pattern moves
    under 3 texels' worth), J (N, 3, 2), the rest surface ``P`` (S, S, 3) moved per metre of
    pattern ``C`` (S, S, 2) along u and v, and the texel's position (N, 3)."""
    Pu, Pv = P[:-1, 1:] - P[:-1, :-1], P[1:, :-1] - P[:-1, :-1]
    Cu, Cv = C[:-1, 1:] - C[:-1, :-1], C[1:, :-1] - C[:-1, :-1]
    ok = covered[:-1, :-1] & covered[:-1, 1:] & covered[1:, :-1]
    step = max(np.median(np.linalg.norm(Pu[ok], axis=1)), np.median(np.linalg.norm(Pv[ok], axis=1)))
    ok &= (np.linalg.norm(Cu, axis=-1) < 3 * step) & (np.linalg.norm(Cv, axis=-1) < 3 * step)
    Cm = np.stack([Cu[ok], Cv[ok]], -1)
    good = np.abs(np.linalg.det(Cm)) > 1e-14
    return np.stack([Pu[ok], Pv[ok]], -1)[good] @ np.linalg.inv(Cm[good]), P[:-1, :-1][ok][good]


def closed_shell(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A garment made a closed surface: vertices welded by position, each opening (a connected
    loop of edges one face has) fanned to its centroid."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    _, first, inv = np.unique(np.round(vertices, 6), axis=0, return_index=True, return_inverse=True)
    v, f = vertices[first], inv.ravel()[faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    directed = f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    _, k, counts = np.unique(np.sort(directed, 1), axis=0, return_inverse=True, return_counts=True)
    open_ = directed[counts[k.ravel()] == 1]
    graph = coo_matrix((np.ones(len(open_)), (open_[:, 0], open_[:, 1])), shape=(len(v), len(v)))
    _, label = connected_components(graph, directed=False)
    caps, extra = [], []
    for lab in np.unique(label[open_[:, 0]]):
        edges = open_[label[open_[:, 0]] == lab]
        extra.append(v[np.unique(edges)].mean(0))
        caps.append(np.column_stack([edges[:, 1], edges[:, 0], np.full(len(edges), len(v) + len(extra) - 1)]))
    return np.concatenate([v, extra]), np.concatenate([f, *caps])
