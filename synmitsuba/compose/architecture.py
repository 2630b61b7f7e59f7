"""Procedural architecture and props: facades with windows and doors, street furniture, indoor
furniture with bevelled edges, trees with branches and leaves, bushes; and layouts that fill a
street, a room or a park of 30 m and more with them from a seed.

Every builder takes (w, h, d, rng) and returns [(trimesh, role)] in the object's frame (ground
at y = 0, centred on x and z); a role is ``main`` (the object's colour) or one of ``ROLES``.
A layout is ``(size_m, rng) -> Place``: the area people stand in, ``EnvObject`` dicts, boxes no
camera may enter (outside a room, over its ceiling) and ceiling lights.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

# role -> (linear RGB, roughness, metallic)
ROLES: dict[str, tuple] = {
    "dark": ((0.05, 0.05, 0.05), 0.6, 0.0), "trunk": ((0.12, 0.07, 0.04), 0.9, 0.0),
    "leaf": ((0.05, 0.18, 0.04), 0.7, 0.0), "leaf2": ((0.09, 0.2, 0.03), 0.7, 0.0),
    "glass": ((0.03, 0.04, 0.05), 0.02, 0.0), "frame": ((0.7, 0.7, 0.68), 0.4, 0.0),
    "metal": ((0.08, 0.08, 0.09), 0.35, 1.0), "light": ((0.9, 0.85, 0.7), 0.2, 0.0),
    "wood": ((0.3, 0.17, 0.08), 0.5, 0.0), "fabric": ((0.25, 0.25, 0.28), 0.95, 0.0),
    "door": ((0.2, 0.1, 0.05), 0.5, 0.0), "stone": ((0.45, 0.44, 0.42), 0.8, 0.0),
}


def _tm():
    import trimesh
    return trimesh


def _chamfer_points(w, h, d, b) -> np.ndarray:
    """The 24 corners of three boxes, each inset by ``b`` on two axes: a chamfered box's hull."""
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], np.float64)
    return np.concatenate([signs * np.array(ex) / 2 for ex in
                           ((w, h - 2 * b, d - 2 * b), (w - 2 * b, h, d - 2 * b), (w - 2 * b, h - 2 * b, d))])


@functools.lru_cache(maxsize=1)
def _chamfer_faces() -> np.ndarray:
    """Outward faces over ``_chamfer_points``' order: one convex hull of a generic chamfered box.
    Every chamfered box (all sides over twice the bevel) has the same 24 corners on the same
    faces, so the hull is taken once (qhull cost 2.7 ms a box; city_street has 1,038)."""
    pts = _chamfer_points(1.0, 1.3, 1.7, 0.1)
    hull = _tm().convex.convex_hull(pts)
    index = np.array([int(np.argmin(np.linalg.norm(pts - v, axis=1))) for v in hull.vertices])
    if len(set(index.tolist())) != len(pts):
        raise RuntimeError("the chamfered box's template hull lost a corner")
    return index[hull.faces]


def chamfer_box(w, h, d, bevel=0.01, x=0.0, y0=0.0, z=0.0):
    """A box with chamfered edges (the hull of three inset boxes): edges catch light as real
    furniture and kerbs do, where a sharp box reads as a render."""
    b = min(bevel, w / 3, h / 3, d / 3)
    if not b > 0:
        raise ValueError(f"chamfer_box({w}, {h}, {d}, bevel={bevel}): sides and bevel must be over 0")
    return _tm().Trimesh(_chamfer_points(w, h, d, b) + (x, y0 + h / 2, z), _chamfer_faces(), process=False)


def _cyl(r, h, x=0.0, y0=0.0, z=0.0, sections=16):
    tm = _tm()
    m = tm.creation.cylinder(radius=r, height=h, sections=sections)
    return m.apply_transform(tm.transformations.rotation_matrix(np.pi / 2, (1, 0, 0))).apply_translation((x, y0 + h / 2, z))


def _segment(a, b, r, sections=8):
    """A cylinder from point a to point b."""
    tm = _tm()
    return tm.creation.cylinder(radius=r, segment=np.array([a, b], np.float64), sections=sections)


# -- buildings --------------------------------------------------------------------------------
def building(w, h, d, rng):
    """A facade block: the wall (main) with rows of recessed windows (dark glass, light frames,
    sills) on its front (+z) face, a door in the ground floor, a cornice on top."""
    parts = [(chamfer_box(w, h, d, 0.02), "main")]
    storey = 3.0
    floors = max(int(h // storey), 1)
    cols = max(int(w // 2.4), 1)
    pitch = w / cols
    door_col = int(rng.integers(cols))
    front = d / 2
    for f in range(floors):
        for c in range(cols):
            x = -w / 2 + pitch * (c + 0.5)
            if f == 0 and c == door_col:
                parts += [(chamfer_box(1.1, 2.3, 0.06, 0.005, x=x, z=front - 0.02), "door"),
                          (chamfer_box(1.3, 0.12, 0.1, 0.01, x=x, y0=2.3, z=front), "frame")]
                continue
            ww, wh = min(1.3, pitch * 0.55), 1.6
            y = f * storey + 0.9
            parts += [(chamfer_box(ww + 0.12, wh + 0.12, 0.05, 0.005, x=x, y0=y - 0.06, z=front + 0.005), "frame"),
                      (chamfer_box(ww, wh, 0.02, 0.002, x=x, y0=y, z=front + 0.03), "glass"),
                      (chamfer_box(0.03, wh, 0.03, 0.003, x=x, y0=y, z=front + 0.045), "frame"),
                      (chamfer_box(ww + 0.2, 0.06, 0.14, 0.01, x=x, y0=y - 0.08, z=front + 0.05), "stone")]
    parts.append((chamfer_box(w + 0.2, 0.25, d + 0.2, 0.03, y0=h - 0.25), "stone"))
    return parts


def lamp(w, h, d, rng):
    """A street lamp: pole, base, arm and a lit head."""
    return [(_cyl(0.12, 0.4), "metal"), (_cyl(0.05, h), "metal"),
            (_segment((0, h - 0.1, 0), (0.6, h + 0.05, 0), 0.035), "metal"),
            (chamfer_box(0.5, 0.12, 0.22, 0.03, x=0.75, y0=h - 0.05), "metal"),
            (chamfer_box(0.42, 0.02, 0.16, 0.005, x=0.75, y0=h - 0.06), "light")]


def bollard(w, h, d, rng):
    return [(_cyl(w / 2, h - 0.05), "main"), (_cyl(w / 2 + 0.01, 0.05, y0=h - 0.05), "metal")]


def kerb(w, h, d, rng):
    """A raised pavement strip with a chamfered kerb edge."""
    return [(chamfer_box(w, h, d, 0.03), "main")]


def bench(w, h, d, rng):
    """A bench: three slats with chamfered edges on two metal frames."""
    t, gap = 0.035, 0.01
    slats = [(chamfer_box(w, t, d / 3 - gap, 0.006, y0=h - t, z=(k - 1) * d / 3), "main") for k in range(3)]
    return slats + [(chamfer_box(0.05, h - t, d * 0.9, 0.008, x=s * (w / 2 - 0.12)), "metal") for s in (-1, 1)]


def steps(w, h, d, rng, n=3):
    """A flight of ``n`` steps rising towards -z."""
    return [(chamfer_box(w, h * (k + 1) / n, d * (n - k) / n, 0.01, z=-d / 2 + d * (n - k) / (2 * n)), "main")
            for k in range(n)]


def pillar(w, h, d, rng):
    """A round column on a square plinth under a square capital."""
    return [(_cyl(w / 2, h, sections=32), "main"), (chamfer_box(1.3 * w, 0.12, 1.3 * d, 0.015), "stone"),
            (chamfer_box(1.3 * w, 0.1, 1.3 * d, 0.015, y0=h - 0.1), "stone")]


# -- furniture --------------------------------------------------------------------------------
def table(w, h, d, rng):
    t = 0.04
    legs = [(chamfer_box(0.06, h - t, 0.06, 0.008, x=sx * (w / 2 - 0.08), z=sz * (d / 2 - 0.08)), "wood")
            for sx in (-1, 1) for sz in (-1, 1)]
    return [(chamfer_box(w, t, d, 0.01, y0=h - t), "main"), *legs]


def chair(w, h, d, rng):
    seat = 0.45
    legs = [(chamfer_box(0.04, seat, 0.04, 0.005, x=sx * (w / 2 - 0.04), z=sz * (d / 2 - 0.04)), "wood")
            for sx in (-1, 1) for sz in (-1, 1)]
    return [(chamfer_box(w, 0.04, d, 0.008, y0=seat - 0.04), "main"),
            (chamfer_box(w, h - seat, 0.04, 0.008, y0=seat, z=-d / 2 + 0.02), "main"), *legs]


def sofa(w, h, d, rng):
    seat = 0.42
    return [(chamfer_box(w, seat - 0.1, d, 0.04, y0=0.1), "main"),
            (chamfer_box(w, h - seat + 0.1, 0.2, 0.05, y0=seat - 0.1, z=-d / 2 + 0.1), "main"),
            (chamfer_box(0.18, 0.25, d, 0.05, x=-w / 2 + 0.09, y0=seat - 0.1), "main"),
            (chamfer_box(0.18, 0.25, d, 0.05, x=w / 2 - 0.09, y0=seat - 0.1), "main"),
            *[(chamfer_box((w - 0.4) / 2 - 0.02, 0.14, d - 0.25, 0.05, x=s * (w - 0.4) / 4, y0=seat - 0.1, z=0.1), "fabric")
              for s in (-1, 1)],
            *[(_cyl(0.025, 0.1, x=sx * (w / 2 - 0.1), z=sz * (d / 2 - 0.1)), "dark") for sx in (-1, 1) for sz in (-1, 1)]]


def shelf(w, h, d, rng):
    """A bookshelf: sides, boards and rows of books of drawn sizes and roles."""
    t = 0.02
    parts = [(chamfer_box(t, h, d, 0.004, x=s * (w / 2 - t / 2)), "main") for s in (-1, 1)]
    boards = max(int(h // 0.38), 2)
    for k in range(boards + 1):
        y = k * (h - t) / boards
        parts.append((chamfer_box(w - 2 * t, t, d, 0.004, y0=y), "main"))
        if k < boards:
            x = -w / 2 + t
            while x < w / 2 - t - 0.05:
                bw, bh = rng.uniform(0.02, 0.05), rng.uniform(0.18, 0.3)
                role = str(rng.choice(["fabric", "door", "frame", "dark"]))
                parts.append((chamfer_box(bw, bh, d * 0.8, 0.002, x=x + bw / 2, y0=y + t), role))
                x += bw + 0.002
    return parts


# -- plants -----------------------------------------------------------------------------------
def _leaves(centres: np.ndarray, size: float, rng) -> object:
    """Leaf-shaped quads (a diamond of two triangles) at random orientations, one mesh."""
    tm = _tm()
    n = len(centres)
    a, b = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(a, b)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    s = size * rng.uniform(0.6, 1.3, (n, 1))
    v = np.stack([centres - a * s, centres - b * s * 0.45, centres + a * s, centres + b * s * 0.45], 1).reshape(-1, 3)
    f = (np.arange(n)[:, None] * 4 + np.array([[0, 1, 2], [0, 2, 3]]).reshape(1, -1)).reshape(-1, 3)
    return tm.Trimesh(v, f, process=False)


def tree(w, h, d, rng):
    """A trunk that forks into branches (tapered cylinders) ending in clusters of leaves."""
    trunk_h = 0.4 * h
    parts = [(_segment((0, 0, 0), (0, trunk_h, 0), 0.05 * w, 10), "trunk")]
    tips = []
    for k in range(int(rng.integers(5, 8))):
        az, up = rng.uniform(0, 2 * np.pi), rng.uniform(0.35, 0.8)
        start = np.array([0.0, trunk_h * rng.uniform(0.7, 1.0), 0.0])
        length = rng.uniform(0.35, 0.55) * h
        end = start + length * np.array([np.cos(az) * (1 - up) * 1.2, up, np.sin(az) * (1 - up) * 1.2])
        end[[0, 2]] *= (w / 2) / max(np.hypot(end[0], end[2]), w / 2)
        parts.append((_segment(start, end, 0.025 * w, 6), "trunk"))
        for j in range(3):
            twig = end + rng.normal(0, 0.25 * w, 3) * [1, 0.5, 1]
            parts.append((_segment(start + (end - start) * rng.uniform(0.5, 0.9), twig, 0.008 * w, 5), "trunk"))
            tips.append(twig)
    tips = np.asarray(tips)
    centres = np.repeat(tips, 400, 0) + rng.normal(0, 0.2 * w, (len(tips) * 400, 3)) * [1, 0.7, 1]
    half = len(centres) // 2
    parts += [(_leaves(centres[:half], 0.11, rng), "leaf"), (_leaves(centres[half:], 0.11, rng), "leaf2")]
    return parts


def bush(w, h, d, rng):
    c = rng.normal(0, 1, (2400, 3))
    c = c / np.maximum(np.linalg.norm(c, axis=1, keepdims=True), 1) * [w / 2, h / 2, d / 2] + [0, h / 2, 0]
    stems = [(_segment((0, 0, 0), (x, h * 0.6, z), 0.01, 5), "trunk") for x, z in rng.normal(0, w / 5, (5, 2))]
    return [*stems, (_leaves(c[:1200], 0.08, rng), "leaf"), (_leaves(c[1200:], 0.08, rng), "leaf2")]


def planter(w, h, d, rng):
    """A planter box with a bush growing out of it."""
    box_h = 0.45 * h
    plants = [(m.apply_translation((0.0, box_h - 0.05, 0.0)), r) for m, r in bush(0.9 * w, h - box_h + 0.05, 0.9 * d, rng)]
    return [(chamfer_box(w, box_h, d, 0.02), "main"), *plants]


BUILDERS: dict[str, tuple[Callable, tuple]] = {   # kind -> (builder, default w, h, d)
    "box": (lambda w, h, d, rng: [(chamfer_box(w, h, d, 0.01), "main")], (0.6, 0.6, 0.6)),
    "wall": (lambda w, h, d, rng: [(chamfer_box(w, h, d, 0.01), "main")], (4.0, 2.5, 0.2)),
    "pillar": (pillar, (0.5, 3.0, 0.5)), "bench": (bench, (1.6, 0.45, 0.45)), "planter": (planter, (0.8, 0.9, 0.8)),
    "tree": (tree, (1.6, 3.5, 1.6)), "steps": (steps, (2.0, 0.45, 1.2)),
    "building": (building, (12.0, 9.0, 8.0)), "lamp": (lamp, (0.3, 4.5, 0.3)), "bollard": (bollard, (0.16, 0.9, 0.16)),
    "kerb": (kerb, (10.0, 0.15, 2.5)), "table": (table, (1.4, 0.75, 0.8)), "chair": (chair, (0.45, 0.9, 0.48)),
    "sofa": (sofa, (2.0, 0.85, 0.9)), "shelf": (shelf, (1.0, 1.9, 0.32)), "tree2": (tree, (3.0, 6.0, 3.0)),
    "bush": (bush, (1.2, 0.9, 1.2)),
}


# -- layouts ----------------------------------------------------------------------------------
@dataclass
class Place:
    """What a layout draws: ``area`` (x_min, z_min, x_max, z_max), ``objects`` (EnvObject dicts),
    ``keep_out`` (boxes (x0, y0, z0, x1, y1, z1) no camera enters), ``lights`` (dicts of
    ``AreaLight`` fields: position, target, size, radiance)."""

    area: list
    objects: list
    keep_out: list = field(default_factory=list)
    lights: list = field(default_factory=list)


def _obj(kind, x, z, yaw=0.0, size=None, color=(0.5, 0.5, 0.5), roughness=0.7, **extra) -> dict:
    d = {"kind": kind, "position": [float(x), float(z)], "yaw_deg": float(yaw), "color": [float(c) for c in color],
         "roughness": float(roughness), **extra}
    if size is not None:
        d["size"] = [float(s) for s in size]
    return d


FACADES = [(0.55, 0.35, 0.25), (0.62, 0.58, 0.5), (0.4, 0.38, 0.36), (0.7, 0.66, 0.58), (0.35, 0.22, 0.16)]


def street(size: float, rng) -> Place:
    """A street ``size`` long: facades of drawn widths and heights on both sides behind raised
    pavements, lamps, bollards and benches along the kerbs. People walk the carriageway."""
    half, road, walk = size / 2, 4.0, 3.0
    objs = []
    for side in (-1, 1):
        objs.append(_obj("kerb", side * (road + walk / 2), 0, 0, (walk, 0.15, size + 20), (0.5, 0.49, 0.46),
                         texture="concrete"))
        z = -half - 10
        while z < half + 10:
            w = float(rng.uniform(8, 16))
            h = float(3.0 * rng.integers(2, 6) + 0.6)
            objs.append(_obj("building", side * (road + walk + 4.0), z + w / 2, -90 * side, (w, h, 8.0),
                             FACADES[int(rng.integers(len(FACADES)))], 0.85,
                             texture=str(rng.choice(["paving", "concrete"]))))
            z += w + float(rng.uniform(0, 0.5))
        for k, zz in enumerate(np.arange(-half, half, 8.0) + rng.uniform(0, 4)):
            objs.append(_obj("lamp", side * (road + 0.5), zz, 90 + 90 * side))
            objs.append(_obj("bollard", side * (road + 0.3), zz + 3.0, 0, None, (0.15, 0.15, 0.16), 0.4))
            if k % 2:
                objs.append(_obj("bench", side * (road + walk - 0.6), zz + 1.5, 90 * side, None, (0.35, 0.2, 0.1)))
    for end in (-1, 1):   # the street ends in a facade across it, not in an empty plain
        w = 2 * (road + walk + 8.0)
        objs.append(_obj("building", 0, end * (half + 18.0), 90 + 90 * end, (w, 12.6, 8.0),
                         FACADES[int(rng.integers(len(FACADES)))], 0.85, texture="paving"))
    return Place([-road + 0.5, -half, road - 0.5, half], objs)


def room(size: float, rng) -> Place:
    """A room ``size`` across: walls with a door and windows (wall pieces around the openings),
    a sofa, a table with chairs, shelves, along the walls; the middle left free."""
    half, t, h = size / 2, 0.2, 2.8
    wall = tuple(float(c) for c in rng.choice([(0.75, 0.72, 0.66), (0.6, 0.62, 0.6), (0.7, 0.6, 0.5)]))
    objs = []
    for yaw, (cx, cz) in ((0, (0, -half)), (90, (-half, 0)), (180, (0, half)), (-90, (half, 0))):
        ox, oz = np.cos(np.radians(yaw)), -np.sin(np.radians(yaw))   # along the wall
        openings = [(float(rng.uniform(-half + 1.5, half - 1.5)), 1.0, 0.0, 2.1)] if yaw == 180 else \
            [(float(x), 1.4, 0.9, 1.4) for x in np.linspace(-half / 2, half / 2, 2)]
        edges = [-half - t] + [v for o in sorted(openings) for v in (o[0] - o[1] / 2, o[0] + o[1] / 2)] + [half + t]
        for a, b in zip(edges[::2], edges[1::2]):
            objs.append(_obj("wall", cx + ox * (a + b) / 2, cz + oz * (a + b) / 2, yaw, (b - a, h, t), wall, 0.9,
                             texture="plaster"))
        for x, ow, sill, oh in openings:
            if sill > 0:
                objs.append(_obj("wall", cx + ox * x, cz + oz * x, yaw, (ow, sill, t), wall, 0.9, texture="plaster"))
            top = sill + oh
            objs.append(_obj("wall", cx + ox * x, cz + oz * x, yaw, (ow, h - top, t), wall, 0.9, lift=top,
                             texture="plaster"))
    objs += [_obj("sofa", 0, -half + 0.7, 0, None, (0.3, 0.32, 0.36), 0.95),
             _obj("table", -half + 1.4, half - 1.6, 0, None, (0.35, 0.2, 0.1), 0.5, texture="wood"),
             *[_obj("chair", -half + 1.4 + dx, half - 1.6 + dz, yaw, None, (0.35, 0.2, 0.1), 0.5)
               for dx, dz, yaw in ((0, -0.65, 0), (0, 0.65, 180))],
             *[_obj("shelf", half - 0.3, z, -90, None, (0.5, 0.42, 0.32), 0.6, texture="wood") for z in (-1.2, 0.0)],
             _obj("box", 0, 0, 0, (size + 2 * t, 0.15, size + 2 * t), wall, 0.9, lift=h, obstacle=False)]  # ceiling
    inner, far, wall_in = half - 1.6, 1e4, half - 0.3
    keep_out = [[wall_in, -far, -far, far, far, far], [-far, -far, -far, -wall_in, far, far],
                [-far, -far, wall_in, far, far, far], [-far, -far, -far, far, far, -wall_in],
                [-far, h - 0.2, -far, far, far, far]]
    lights = [{"position": [0.0, h - 0.01, z], "target": [0.0, 0.0, z], "size": [1.2, 0.6], "radiance": 12.0}
              for z in (-half / 3, half / 3)]
    return Place([-inner, -inner, inner, inner], objs, keep_out, lights)


def park(size: float, rng) -> Place:
    """A park ``size`` across: trees and bushes scattered around a lawn, benches facing it."""
    half, objs = size / 2, list[dict]()
    while len(objs) < int(size * 0.7):
        x, z = rng.uniform(-half, half, 2)
        if max(abs(x), abs(z)) < 7.0:
            continue
        big = rng.random() < 0.55
        s = rng.uniform(0.8, 1.3)
        objs.append(_obj("tree2" if big else "bush", x, z, rng.uniform(-180, 180),
                         (3.0 * s, 6.5 * s, 3.0 * s) if big else (1.3 * s, 0.9 * s, 1.3 * s), (0.3, 0.3, 0.3)))
    for k in range(4):
        a = np.pi / 2 * k + 0.4
        yaw = (-np.degrees(a) - 90 + 180) % 360 - 180
        objs.append(_obj("bench", 6.0 * np.cos(a), 6.0 * np.sin(a), yaw, None, (0.35, 0.2, 0.1)))
    return Place([-5.0, -5.0, 5.0, 5.0], objs)


LAYOUTS: dict[str, Callable] = {"street": street, "room": room, "park": park}
