"""Render topology: split body vertices at UV seams, keep a map back to the original vertices."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.geometry import unique_rows, vertex_normals


@dataclass
class SplitMesh:
    source: np.ndarray   # (V', ) index of the original vertex for each render vertex
    uv: np.ndarray       # (V', 2)
    faces: np.ndarray    # (F, 3) into render vertices


def split_at_seams(faces: np.ndarray, face_uv: np.ndarray, uv: np.ndarray) -> SplitMesh:
    pairs = np.stack([faces.ravel(), face_uv.ravel()], 1)
    unique, inverse = unique_rows(pairs, return_inverse=True)
    return SplitMesh(unique[:, 0], uv[unique[:, 1]], inverse.reshape(-1, 3))


def submesh(faces: np.ndarray, keep_vertex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces whose three vertices are kept, re-indexed; returns (vertex indices, faces)."""
    f = faces[keep_vertex[faces].all(1)]
    used = np.unique(f)
    remap = -np.ones(len(keep_vertex), np.int64)
    remap[used] = np.arange(len(used))
    return used, remap[f]


def largest_piece(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(V,) True for the vertices of the mesh's largest connected piece (by vertex count), its
    pieces joined where vertices meet (``weld``: a uv seam does not split a piece)."""
    rep = weld(vertices)
    f = rep[faces]
    piece = _lowest_joined(np.concatenate([f[:, [0, 1]], f[:, [1, 2]]]), len(vertices))[rep]
    size = np.bincount(piece[np.unique(faces)], minlength=len(vertices))
    return piece == np.argmax(size)


def clip_faces(faces: np.ndarray, phi: np.ndarray, snap: float = 0.02):
    """Cut a triangle mesh along the level set ``phi == 0`` and keep ``phi >= 0``: triangles
    crossing it are split on their edges (marching triangles), so the boundary follows the
    smooth curve instead of the triangles' edges. Returns ``(faces, pairs, t)``: faces index the
    original vertices, then one new vertex per cut edge, ``(1 - t) * v[pairs[:, 0]] + t *
    v[pairs[:, 1]]``. ``t`` is kept within [snap, 1 - snap] so no sliver is left."""
    faces = np.asarray(faces)
    V = len(phi)
    inside = phi[faces] >= 0
    count = inside.sum(1)
    out = [faces[count == 3]]
    cut = faces[(count == 1) | (count == 2)]
    ins = inside[(count == 1) | (count == 2)]
    # rotate each cut face so that its odd vertex (alone on its side) comes first
    odd = np.where(ins.sum(1) == 1, np.argmax(ins, 1), np.argmin(ins, 1))
    rot = np.stack([cut[np.arange(len(cut)), (odd + k) % 3] for k in range(3)], 1)
    a, b, c = rot.T
    edges = np.concatenate([np.stack([a, b], 1), np.stack([c, a], 1)])
    key = np.sort(edges, 1)
    pairs, index = unique_rows(key, return_inverse=True)
    index = index.ravel()
    p_ab, p_ca = V + index[:len(a)], V + index[len(a):]
    one = ins.sum(1) == 1  # the odd vertex is the one kept
    out.append(np.stack([a, p_ab, p_ca], 1)[one])
    two = ~one
    out += [np.stack([p_ab, b, c], 1)[two], np.stack([p_ab, c, p_ca], 1)[two]]
    fa, fb = phi[pairs[:, 0]], phi[pairs[:, 1]]
    t = np.clip(fa / (fa - fb), snap, 1 - snap)
    return np.concatenate(out), pairs, t


def cut(faces: np.ndarray, phi: np.ndarray, *attributes: np.ndarray):
    """``clip_faces`` with per-vertex ``attributes`` (positions, normals, uv, ...) interpolated
    onto the cut and every array compacted to the vertices kept: (faces, attribute, ...)."""
    f, pairs, t = clip_faces(faces, phi)
    used = np.unique(f)
    remap = -np.ones(len(phi) + len(pairs), np.int64)
    remap[used] = np.arange(len(used))
    out = [np.concatenate([a, (1 - t)[:, None] * a[pairs[:, 0]] + t[:, None] * a[pairs[:, 1]]])[used]
           for a in attributes]
    return (remap[f], *out)


def weld(vertices: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """A representative index per vertex: vertices within ``tol`` (chains of them) share one,
    the lowest of the group; unlike rounding, no grid splits two close points."""
    from scipy.spatial import cKDTree
    return _lowest_joined(cKDTree(vertices).query_pairs(tol, output_type="ndarray"), len(vertices))


def refine(vertices: np.ndarray, faces: np.ndarray, uv: np.ndarray, mark: np.ndarray,
           curved: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Halve every edge of the ``mark``ed faces (red-green refinement): a marked face becomes
    four; a face with two or three of its edges halved becomes four too (repeated until none is
    left), one with a single halved edge two, so no edge is halved on one side alone. Edges are
    matched by position (``weld``): a seam's two copies of an edge are halved together, each
    side keeping its own uv. ``curved``: a new point lies on the curve through its edge's ends
    that meets their vertex normals square (a PN triangle's edge: on a circle, its arc, not its
    chord; a chord's midpoint is a dimple of the edge's sagitta, a bump at every new point);
    else at the edge's middle. Returns (vertices, faces, uv), the old vertices first."""
    rep = weld(vertices)
    corners = [faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]
    red, halved = _red(np.asarray(mark, bool), [np.sort(rep[c], axis=1) for c in corners])
    pairs, mid = np.unique(np.sort(np.concatenate([c[halved[:, k]] for k, c in enumerate(corners)]), axis=1),
                           axis=0, return_inverse=True)
    middle = vertices[pairs].mean(1)
    if curved:
        normal = vertex_normals(vertices, rep[faces])[rep]  # a seam's copies of a point share theirs
        a, b = vertices[pairs[:, 0]], vertices[pairs[:, 1]]
        na, nb = normal[pairs[:, 0]], normal[pairs[:, 1]]
        middle -= (np.einsum("ij,ij->i", b - a, na)[:, None] * na + np.einsum("ij,ij->i", a - b, nb)[:, None] * nb) / 8
    news, start = np.full(faces.shape, -1), 0  # each face's new point on each of its edges, in ``pairs``' order
    for k in range(3):
        count = int(halved[:, k].sum())
        news[halved[:, k], k] = len(vertices) + mid.ravel()[start:start + count]
        start += count
    return (np.concatenate([vertices, middle]), _split_faces(faces, news, red, halved),
            np.concatenate([uv, uv[pairs].mean(1)]))


def _red(mark: np.ndarray, keys: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The faces to split in four (``mark`` and those with two or more halved edges, until none
    is left) and which of each face's three edges is halved; ``keys``: each corner pair's edge
    as its welded ends, sorted."""
    uniq, inverse = np.unique(np.concatenate(keys), axis=0, return_inverse=True)
    inverse = inverse.reshape(3, -1).T  # (F, 3): each face's edges among ``uniq``
    red, halved = mark.copy(), np.zeros(len(uniq), bool)
    while True:
        halved[inverse[red].ravel()] = True
        more = ~red & (halved[inverse].sum(1) >= 2)
        if not more.any():
            return red, halved[inverse]
        red |= more


def _split_faces(faces: np.ndarray, news: np.ndarray, red: np.ndarray, halved: np.ndarray) -> np.ndarray:
    """``faces`` with each ``red`` one in four (its corners and ``news``, its edges' new points)
    and each with one halved edge in two, winding kept."""
    a, b, c = faces.T
    ab, bc, ca = news.T
    four = np.stack([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1), np.stack([ca, bc, c], 1),
                     np.stack([ab, bc, ca], 1)], 1)[red].reshape(-1, 3)
    one = ~red & halved.any(1)
    k = np.argmax(halved[one], axis=1)  # the halved edge: rotate it to the front, then split it
    f1, m1 = faces[one], news[one, k]
    rot = np.stack([f1[np.arange(len(k)), (k + j) % 3] for j in range(3)], 1)
    two = np.concatenate([np.stack([rot[:, 0], m1, rot[:, 2]], 1), np.stack([m1, rot[:, 1], rot[:, 2]], 1)])
    return np.concatenate([faces[~red & ~one], four, two])


def collapse_short_edges(vertices: np.ndarray, faces: np.ndarray, tol: float) -> np.ndarray:
    """A representative index per vertex, as ``weld`` gives: the ends of every edge of ``faces``
    shorter than ``tol`` (chains of them) share one, the lowest. Only edges join: two sheets
    that lie close but apart stay apart."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    short = edges[np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1) < tol]
    return _lowest_joined(short, len(vertices))


def _lowest_joined(pairs: np.ndarray, n: int) -> np.ndarray:
    """For each of ``n`` vertices the lowest index of those that ``pairs`` (K, 2) join to it."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    first = np.full(labels.max() + 1, n)
    np.minimum.at(first, labels, np.arange(n))
    return first[labels]


def closed_tube(rings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A closed surface through ``rings`` (K, M, 3), each a closed loop, fans capping both
    ends, faces wound outward."""
    k, m = rings.shape[:2]
    v = np.concatenate([rings.reshape(-1, 3), rings[[0, -1]].mean(1)])
    i, j = np.meshgrid(np.arange(k - 1), np.arange(m), indexing="ij")
    a, b = (i * m + j).ravel(), (i * m + (j + 1) % m).ravel()
    f = np.concatenate([np.stack([a, a + m, b], 1), np.stack([b, a + m, b + m], 1)])
    ring = np.arange(m)
    caps = [np.stack([np.full(m, k * m), ring, (ring + 1) % m], 1),
            np.stack([np.full(m, k * m + 1), (k - 1) * m + (ring + 1) % m, (k - 1) * m + ring], 1)]
    f = np.concatenate([f, *caps])
    if signed_volume(v, f) < 0:
        f = f[:, ::-1]
    return v, f


def signed_volume(v: np.ndarray, f: np.ndarray) -> float:
    """The volume a closed surface encloses, negative when its faces wind inward."""
    return float(np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6)


def merge_meshes(meshes: list) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) pairs as one mesh."""
    out_v, out_f, n = [], [], 0
    for v, f in meshes:
        out_v.append(v)
        out_f.append(f + n)
        n += len(v)
    return np.concatenate(out_v), np.concatenate(out_f)
