"""Accessories placed from the shaped body's joints and vertices (so they follow its shape) and
skinned with the weights of their nearest body vertex."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from synmitsuba.body.garments import hem, open_edges, push_out
from synmitsuba.body.textures import LAB, sample_lab_colour
from synmitsuba.body.topology import cut, submesh
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import align_vectors, frame, vertex_normals
from synmitsuba.schema import Choice, Number, Params, optional, spec
from synmitsuba.scene.layers import Layer

BUILDERS_BY_NAME: dict = {}  # kind -> builder, filled below (BUILDERS); read when a recipe is checked


@dataclass(frozen=True)
class GlassesFrame:
    """A glasses frame: each lens's half width and half height (m, at scale 1), its rim's
    ``squareness`` (the superellipse exponent: 2 an ellipse, 4 a rounded rectangle), the rim
    tube's radius, whether it is metal (drawn in metal colours, rendered metallic) and its share
    among people wearing glasses (0: never drawn)."""

    half_width: float
    half_height: float
    squareness: float
    rim: float
    metal: bool = False
    share: float = 0.0


# Lenses are wider than tall and most rims are thin: the first frame ("round", kept for recipes
# without one) was a 44 mm circle in a 5 mm tube, loud enough to hide the iris from a detector.
GLASSES_FRAMES: dict[str, GlassesFrame] = {
    "round": GlassesFrame(0.022, 0.022, 2.0, 0.0025),
    "wire_oval": GlassesFrame(0.024, 0.017, 2.4, 0.0009, metal=True, share=0.3),
    "wire_round": GlassesFrame(0.020, 0.019, 2.0, 0.0009, metal=True, share=0.15),
    "acetate_rectangle": GlassesFrame(0.025, 0.017, 4.0, 0.0014, share=0.35),
    "acetate_soft": GlassesFrame(0.024, 0.019, 3.0, 0.0014, share=0.2),
}
# (L*, a*, b*) of frames: metal ones silver, gunmetal, black, gold, rose gold; plastic (acetate)
# ones mostly dark: black, two tortoiseshell browns, navy, burgundy, grey
METAL_LAB = ((78.0, 0.0, 1.0), (38.0, 0.0, -2.0), (16.0, 0.0, 0.0), (72.0, 4.0, 38.0), (70.0, 14.0, 16.0))
ACETATE_LAB = ((12.0, 0.0, 0.0), (12.0, 0.0, 0.0), (28.0, 10.0, 18.0), (38.0, 14.0, 28.0), (22.0, 3.0, -20.0),
               (25.0, 25.0, 8.0), (55.0, 0.0, 0.0))


@dataclass
class AccessoryParams(Params):
    kind: str = spec("glasses", Choice(BUILDERS_BY_NAME))
    colour_lab: list | None = spec(None, optional(LAB))
    scale: float = spec(1.0, Number(0.8, 1.25))
    frame: str | None = spec(None, optional(Choice(GLASSES_FRAMES)))  # glasses only; None: "round"


def sample_glasses_frames(rng: np.random.Generator, accessories: list[AccessoryParams]) -> None:
    """Give each pair of glasses a frame from ``GLASSES_FRAMES`` (by share) and a frame's colour
    (``METAL_LAB`` or ``ACETATE_LAB``, jittered). Called after every other draw of a subject, so the people without glasses, and
    everything else about those with them, stay as they were drawn before frames existed."""
    names = [k for k, f in GLASSES_FRAMES.items() if f.share > 0]
    share = np.array([GLASSES_FRAMES[k].share for k in names])
    for a in accessories:
        if a.kind == "glasses":
            a.frame = names[int(rng.choice(len(names), p=share / share.sum()))]
            palette = METAL_LAB if GLASSES_FRAMES[a.frame].metal else ACETATE_LAB
            lab = np.array(palette[int(rng.integers(len(palette)))]) + rng.normal(0, 2, 3)
            a.colour_lab = [round(float(x), 3) for x in np.clip(lab, [0, -128, -128], [100, 128, 128])]


def sample_accessories(rng: np.random.Generator) -> list[AccessoryParams]:
    """Each kind in ``ACCESSORIES`` worn or not, independently at its ``rate`` (one draw each, in order)."""
    chosen = [k for k, a in ACCESSORIES.items() if rng.random() < a.rate]
    if "cap" in chosen and "headphones" in chosen:
        chosen.remove("headphones")
    return [AccessoryParams(k, sample_lab_colour(rng, (10, 80)), round(float(rng.uniform(0.9, 1.1)), 3)) for k in chosen]


def _place(mesh, R, t):
    return np.asarray(mesh.vertices) @ R.T + t, np.asarray(mesh.faces)


@dataclass
class HeadFrame:
    """The rest head that accessories are fitted to: a frame (``centre``, ``up``, ``forward``),
    the skull's half extents ``radii``, the head vertices' ``mask``, anny's eye, nose and ear
    keypoints, and ``chin``: the head-frame height of the chin's underside (``under_chin``)."""

    centre: np.ndarray
    up: np.ndarray
    forward: np.ndarray
    radii: np.ndarray
    mask: np.ndarray
    eyes: np.ndarray   # (2, 3) left, right
    nose: np.ndarray   # (3,)
    ears: np.ndarray   # (2, 3) left, right
    chin: float = 0.0
    pupils: np.ndarray | None = None  # (2, 3) the eyeballs' front poles, which glasses centre on (else ``eyes``)


def _local(head: HeadFrame):
    """The head frame (columns side, up, forward) and centre: local = (world - centre) @ R."""
    return frame(head.forward, head.up), head.centre


def _glasses(p: AccessoryParams, body, head):
    """Two rims of the recipe's ``GLASSES_FRAMES`` shape in front of the eyes (the pupils, or
    anny's eye keypoints), a bridge, end pieces and temples running back from the rims' upper outer corners
    past the sides of the head to the ears; the frame's plane is where the rims clear the face by 3.5 mm and the bridge the nose
    by 4 mm: it rests on the face, not in it."""
    import trimesh
    fr = GLASSES_FRAMES[p.frame or "round"]
    R, c = _local(head)
    face = (body.vertices[head.mask] - c) @ R
    eyes = ((head.eyes if head.pupils is None else head.pupils) - c) @ R
    ears = (head.ears - c) @ R
    mid, half = eyes.mean(0), abs(eyes[0, 0] - eyes[1, 0]) / 2
    a = min(fr.half_width * p.scale, half - fr.rim - 0.004)  # a narrow face keeps a bridge
    b, t = fr.half_height * a / fr.half_width, fr.rim  # a narrowed lens keeps its proportions
    curve = _superellipse(a, b, fr.squareness)
    near = np.zeros(len(face), bool)  # face points under the rims' tube (the lenses are open)
    for x in (-1, 1):
        d = np.linalg.norm(face[:, None, :2] - (curve + [mid[0] + x * half, mid[1]])[None], axis=2).min(1)
        near |= d < t + 0.0025
    bridge = (np.abs(face[:, 0] - mid[0]) < 0.008) & (np.abs(face[:, 1] - mid[1] - 0.004) < 0.004)
    z = max(face[near, 2].max() + t + 0.0035, face[bridge, 2].max() + 0.004)
    back, y = ears[:, 2].mean() - 0.005, mid[1] + 0.5 * b  # temples at the rims' upper corners
    parts = [trimesh.creation.box([2 * (half - a) + 2 * t, 1.6 * t, 1.6 * t])]  # the bridge
    parts[0].apply_translation([mid[0], mid[1] + 0.3 * b, z])
    for x in (-1, 1):
        parts.append(_rim(curve + [mid[0] + x * half, mid[1]], z, t))
        edge = np.abs(curve[:, 0])[curve[:, 1] >= 0.5 * b].max()  # the rim's outer edge at the temple's height
        path = _temple(face, mid[0], y, x, z, back, half + edge)  # along the side of the head, 4 mm off it
        points = [[mid[0] + x * (half + edge), y, z]] + [[mid[0] + x * w, y, zk] for w, zk in path]
        parts += [trimesh.creation.cylinder(max(0.8 * t, 0.0012), segment=[p0, p1], sections=6)
                  for p0, p1 in zip(points[:-1], points[1:])]
    return _place(trimesh.util.concatenate(parts), R, c)


def _superellipse(a: float, b: float, n: float, k: int = 64) -> np.ndarray:
    """(k, 2) points, counter-clockwise, of |x/a|^n + |y/b|^n = 1."""
    s = np.linspace(0, 2 * np.pi, k, endpoint=False)
    c, si = np.cos(s), np.sin(s)
    return np.stack([a * np.sign(c) * np.abs(c) ** (2 / n), b * np.sign(si) * np.abs(si) ** (2 / n)], 1)


def _rim(curve: np.ndarray, z: float, radius: float, around: int = 8):
    """A closed tube of ``radius`` along a closed counter-clockwise ``curve`` in the plane at ``z``."""
    import trimesh
    tangent = np.roll(curve, -1, 0) - np.roll(curve, 1, 0)
    out = np.stack([tangent[:, 1], -tangent[:, 0]], 1) / np.linalg.norm(tangent, axis=1, keepdims=True)
    phi = np.linspace(0, 2 * np.pi, around, endpoint=False)
    ring = curve[:, None] + radius * np.cos(phi)[None, :, None] * out[:, None]
    v = np.concatenate([ring, z + radius * np.broadcast_to(np.sin(phi), ring.shape[:2])[..., None]], 2)
    k = len(curve)
    i, j = np.meshgrid(np.arange(k), np.arange(around), indexing="ij")
    a, b = i * around + j, i * around + (j + 1) % around
    c, d = (i + 1) % k * around + j, (i + 1) % k * around + (j + 1) % around
    f = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    return trimesh.Trimesh(v.reshape(-1, 3), f, process=False)


def _temple(face: np.ndarray, mid_x: float, y: float, x: int, front: float, back: float, start: float,
            steps: int = 6) -> list:
    """(half-width, z) points of one temple from the frame (half-width ``start``) back to the ear:
    at each depth the head's widest point at the temple's height ``y`` on that side, plus 4 mm,
    never narrower than the step before (a temple runs straight or outward; it does not bend
    into the head)."""
    side = (face[:, 0] - mid_x) * x > 0
    level = np.abs(face[:, 1] - y) < 0.015
    out, width = [], start
    for zk in np.linspace(front, back, steps):
        near = side & level & (np.abs(face[:, 2] - zk) < 0.012)
        if near.any():
            width = max(width, np.abs(face[near, 0] - mid_x).max() + 0.004)
        out.append((width, zk))
    return out


def _cap_line(head, v: np.ndarray) -> np.ndarray:
    """Height of head-frame points ``v`` over a cap's edge: a line 3 cm above the eyes at the
    front, dropping 3 cm for every 10 cm towards the back."""
    R, c = _local(head)
    mid = ((head.eyes - c) @ R).mean(0)
    return v[:, 1] - (mid[1] + 0.03 - 0.3 * (mid[2] - v[:, 2]))


def under_cap(head, points: np.ndarray) -> np.ndarray:
    """Which points lie above a cap's edge (hair rooted there is hidden under a cap)."""
    R, c = _local(head)
    return _cap_line(head, (np.asarray(points) - c) @ R) > 0


CAP_BILL = (0.07, 55.0, 0.012, 0.15)  # length (m, at scale 1), half-span (deg), side droop (m), downward pitch


def _cap(p: AccessoryParams, body, head):
    """A crown that follows the skull 9 mm off the scalp, cut along the cap's edge line (the
    triangles split on it, so the edge is a smooth curve; loop-subdivided once), and a bill: a
    D-shaped peak over the brow, ``CAP_BILL`` long, spanning the front half-span either side,
    curved down at its sides and pitched down, 4 mm thick with a closed rim."""
    import trimesh
    R, c = _local(head)
    v = (body.vertices - c) @ R
    used, f = submesh(body.faces, head.mask)
    n = vertex_normals(body.vertices, body.faces)[used] @ R
    f, dome = cut(f, _cap_line(head, v[used]), v[used] + n * 0.009)
    fine = trimesh.Trimesh(dome, f, process=False).subdivide_loop(1)  # the body's head is too coarse for a shiny crown
    dome, f = np.asarray(fine.vertices), np.asarray(fine.faces)
    bill = _bill(v[head.mask], ((head.eyes - c) @ R).mean(0)[1] + 0.03, p.scale)
    return np.concatenate([dome, bill[0]]) @ R.T + c, np.concatenate([f, bill[1] + len(dome)])


def _bill(head_v: np.ndarray, front_y: float, scale: float, n: int = 31):
    """The cap's bill in the head frame: (vertices, faces) of its top, bottom and outer rim."""
    length, span, droop, pitch = CAP_BILL
    ring = head_v[np.abs(head_v[:, 1] - front_y) < 0.012]
    phi = np.radians(np.linspace(-span, span, n))
    ang = np.arctan2(ring[:, 0], ring[:, 2])
    # inner edge 5 mm off the head's outline at the crown's edge (under the crown, 9 mm off: no gap shows)
    r_in = np.array([np.hypot(ring[:, 0], ring[:, 2])[np.abs(ang - a) < np.radians(6)].max() for a in phi]) + 0.005
    reach = length * scale * np.cos(phi * 90.0 / span) ** 0.5 + 0.004  # straight ahead: a D no wider than the head
    side = (np.sin(phi) / np.sin(np.radians(span))) ** 2
    inner = np.column_stack([r_in * np.sin(phi), np.full(n, front_y + 0.003), r_in * np.cos(phi)])
    outer = inner + np.column_stack([np.zeros(n), -0.003 - droop * side - pitch * reach, reach])
    rows = [inner, outer, outer - [0, 0.004, 0], inner - [0, 0.004, 0]]  # top inner, top outer, bottom outer, bottom inner
    verts = np.concatenate(rows)
    faces = []
    for k in range(3):  # top, rim, bottom: quads between consecutive rows
        a = k * n + np.arange(n - 1)
        b = a + n
        faces += [np.column_stack([a, b, a + 1]), np.column_stack([a + 1, b, b + 1])]
    return verts, np.concatenate(faces)


def _headphones(p: AccessoryParams, body, head):
    """A band arching over the crown from ear to ear (in the head's side-up plane) and a cup
    over each ear."""
    import trimesh
    rad = head.radii
    band = trimesh.creation.torus(rad[0] + 0.02, 0.008, major_sections=32, minor_sections=8)  # in the xy plane
    v = band.vertices
    band = trimesh.Trimesh(v, band.faces[(v[band.faces][..., 1] > -0.01).all(1)])  # the upper half arc
    # the crown is 1.1 radii above the head's centre (placed at 45 % of the skull's height)
    band.apply_scale([1.0, (1.1 * rad[1] + 0.02) / (rad[0] + 0.02), 1.0])
    parts = [band]
    for x in (-1, 1):
        cup = trimesh.creation.cylinder(radius=0.035 * p.scale, height=0.025, sections=24)
        cup.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
        cup.apply_translation([x * (rad[0] + 0.015), 0, 0])
        parts.append(cup)
    return _place(trimesh.util.concatenate(parts), frame(head.forward, head.up), head.centre)


def _backpack(p: AccessoryParams, body, head):
    """A box on the back at chest height."""
    import trimesh
    s, sk = p.scale, body.skeleton
    chest = sk.rest_positions[sk.index("spine02")]
    back_z = body.vertices[np.abs(body.vertices[:, 1] - chest[1]) < 0.05][:, 2].min()
    box = trimesh.creation.box([0.28 * s, 0.38 * s, 0.12 * s]).subdivide().subdivide()
    return np.asarray(box.vertices) + [chest[0], chest[1] - 0.03, back_z - 0.07 * s], np.asarray(box.faces)


def _watch(p: AccessoryParams, body, head):
    """A band around the left wrist, sized to the forearm."""
    import trimesh
    sk = body.skeleton
    wrist, elbow = sk.rest_positions[sk.index("wrist.L")], sk.rest_positions[sk.index("lowerarm01.L")]
    axis = (wrist - elbow) / np.linalg.norm(wrist - elbow)
    near = body.vertices[np.linalg.norm(body.vertices - (wrist - 0.03 * axis), axis=1) < 0.04]
    radius = np.linalg.norm(np.cross(near - wrist, axis), axis=1).max() + 0.006 if len(near) else 0.035
    band = trimesh.creation.annulus(r_min=radius, r_max=radius + 0.004, height=0.018, sections=32)
    return np.asarray(band.vertices) @ align_vectors([0, 0, 1], axis).T + wrist - 0.035 * axis, np.asarray(band.faces)


MASK_SIDE = 0.18  # the mask's sides: a plane this share of the head's depth in front of its centre
MASK_PLEATS = (0.013, 0.0012)  # a surgical mask's pleats: period (m, down the face) and depth (m)


def _mask(p: AccessoryParams, body, head):
    """A face mask from the nose bridge to under the chin, stretched taut over nose, cheeks and
    chin (it bridges the lips and the hollows beside the nose instead of following them), pleated,
    with a hemmed edge of the cloth's thickness and an elastic loop round each ear."""
    R, c = _local(head)
    v = (body.vertices - c) @ R
    shell, f = _mask_shell(body, head, v)
    shell, f = _pleat(shell, f)
    shell, f, _ = hem(body, shell @ R.T + c, f, np.zeros((len(shell), 2)), 0.0015)
    loops = [_tube(_ear_loop(body, head, (shell - c) @ R, x), 0.0012) for x in (-1, 1)]
    parts = [(shell, f)] + [(q @ R.T + c, g) for q, g in loops]
    start = np.cumsum([0] + [len(q) for q, _ in parts[:-1]])
    return np.concatenate([q for q, _ in parts]), np.concatenate([g + k for (_, g), k in zip(parts, start)])


def mask_uv(head, vertices: np.ndarray) -> tuple[np.ndarray, tuple[float, float]]:
    """Cloth coordinates of a mask's vertices (world, rest pose): u along the face round the
    head's vertical axis (arc at the mask's median distance from it), v up, each scaled to
    [0, 1] over the mask; and the metres each spans, so that a weave's tiles come out at
    thread size. The ear loops run round the head too, so their u grows along them."""
    R, c = _local(head)
    v = (np.asarray(vertices) - c) @ R
    arc = np.arctan2(v[:, 0], v[:, 2]) * np.median(np.hypot(v[:, 0], v[:, 2]))
    lo, span = np.array([arc.min(), v[:, 1].min()]), np.array([np.ptp(arc), np.ptp(v[:, 1])])
    return (np.stack([arc, v[:, 1]], 1) - lo) / np.maximum(span, 1e-9), (float(span[0]), float(span[1]))


def _mask_outline(head, v: np.ndarray) -> np.ndarray:
    """> 0 inside the mask, for head-frame points ``v`` (columns side, up, forward): under a top
    edge that rises over the nose bridge (half-way from anny's nose keypoint to its eyes) from
    0.15 of that drop at the cheeks, above a line 6 mm under the chin (``head.chin``), in
    front of a plane at 0.18 of the head's depth before its centre (2-3 cm short of the ears)."""
    R, c = _local(head)
    nose, eyes = (head.nose - c) @ R, ((head.eyes - c) @ R).mean(0)
    drop, x = eyes[1] - nose[1], v[:, 0] - nose[0]
    top = nose[1] + drop * (0.15 + 0.35 * np.exp(-(x / 0.015) ** 2))
    return np.minimum.reduce([top - v[:, 1], v[:, 1] - (head.chin - 0.006), v[:, 2] - MASK_SIDE * head.radii[2]])


def under_chin(vertices: np.ndarray, head) -> float:
    """Head-frame height of the underside of the chin: going down the face's midline from anny's nose
    keypoint, the first level at which the face's front is over 25 mm behind the nose keypoint
    (the throat); 2.7 eye-to-nose drops under the nose if none is within 12 cm."""
    R, c = _local(head)
    v = (vertices - c) @ R
    nose, eyes = (head.nose - c) @ R, ((head.eyes - c) @ R).mean(0)
    mid = v[(np.abs(v[:, 0] - nose[0]) < 0.01) & (v[:, 1] < nose[1]) & (v[:, 1] > nose[1] - 0.12)]
    for y in np.arange(nose[1] - 0.03, nose[1] - 0.12, -0.002):
        if mid[np.abs(mid[:, 1] - y) < 0.004, 2].max(initial=-np.inf) < nose[2] - 0.025:
            return float(y + 0.002)
    return float(nose[1] - 2.7 * (eyes[1] - nose[1]))


def mask_covers(head, points: np.ndarray) -> np.ndarray:
    """Which points (beard roots) lie under the mask's outline or within 1 cm of it."""
    R, c = _local(head)
    return _mask_outline(head, (np.asarray(points) - c) @ R) > -0.01


MASK_GRID = 0.003  # the shell's grid step (m) along the face (at 10 cm from the head's axis) and down it (then 1/3)


def _mask_shell(body, head, v: np.ndarray, off: float = 0.005, rounds: int = 4):
    """The mask as cloth spans a face, in the head frame: on a grid over (angle round the head's
    vertical axis, height), the body's outermost distance from that axis (so the mouth's inside
    and the nostrils do not count), ``off`` further out, raised down every column and along every
    row to its upper concave envelope (straight lines over the hollows beside and under the nose,
    over the lips and from the chin to the neck), averaged ``rounds`` times over a 3 x 3 window
    (the tent over the nose gets a rounded ridge), cut along ``_mask_outline`` and pushed out to
    3 mm off the skin where that leaves it closer. (vertices, faces)."""
    from scipy.ndimage import uniform_filter
    R, c = _local(head)
    arc, r = np.arctan2(v[:, 0], v[:, 2]) * 0.1, np.hypot(v[:, 0], v[:, 2])  # arc: along the face at 10 cm
    span = _mask_outline(head, v) > -0.012
    lo, hi = np.array([arc[span].min(), v[span, 1].min()]), np.array([arc[span].max(), v[span, 1].max()])
    ga, gh = (np.arange(lo[k], hi[k] + MASK_GRID, MASK_GRID) for k in range(2))
    near = span | ((v[:, 1] > lo[1] - 0.01) & (v[:, 1] < hi[1] + 0.01) & (v[:, 2] > 0))
    i, j = np.round((arc[near] - lo[0]) / MASK_GRID).astype(int), np.round((v[near, 1] - lo[1]) / MASK_GRID).astype(int)
    grid = np.full((len(ga) + 2, len(gh) + 2), -np.inf)
    for di in (0, 1, 2):  # each vertex counts in its cell and the 8 round it
        for dj in (0, 1, 2):
            np.maximum.at(grid, (np.clip(i + di, 0, len(ga) + 1), np.clip(j + dj, 0, len(gh) + 1)), r[near])
    grid = _fill(grid[1:-1, 1:-1]) + off
    grid = np.maximum(grid, np.apply_along_axis(lambda col: _concave(gh, col), 1, grid))  # down each column
    grid = np.maximum(grid, np.apply_along_axis(lambda row: _concave(ga, row), 0, grid))  # along each row
    for _ in range(rounds):
        grid = uniform_filter(grid, 3, mode="nearest")
    fine = np.arange(gh[0], gh[-1], MASK_GRID / 3)  # 1 mm rows: the pleats run across them
    grid = np.stack([np.interp(fine, gh, row) for row in grid])
    gh = fine
    A, H = np.meshgrid(ga, gh, indexing="ij")
    s = np.stack([grid * np.sin(A / 0.1), H, grid * np.cos(A / 0.1)], -1).reshape(-1, 3)
    q = np.arange(len(ga) * len(gh)).reshape(len(ga), len(gh))
    a, b, d, e = q[:-1, :-1].ravel(), q[1:, :-1].ravel(), q[:-1, 1:].ravel(), q[1:, 1:].ravel()
    f, s = cut(np.concatenate([np.stack([a, d, b], 1), np.stack([b, d, e], 1)]), _mask_outline(head, s), s)
    return (push_out(body, s @ R.T + c, clearance=0.003) - c) @ R, f


def _fill(grid: np.ndarray) -> np.ndarray:
    """Empty cells (-inf) of a grid take the mean of their filled neighbours, repeatedly."""
    grid = grid.copy()
    while np.isinf(grid).any() and not np.isinf(grid).all():
        pad = np.pad(grid, 1, constant_values=-np.inf)
        around = np.stack([pad[a:a + grid.shape[0], b:b + grid.shape[1]] for a in range(3) for b in range(3)])
        ok = np.isfinite(around)
        mean = np.where(ok, around, 0).sum(0) / np.maximum(ok.sum(0), 1)
        grid = np.where(np.isinf(grid) & ok.any(0), mean, grid)
    return grid


def _concave(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The upper concave envelope of y(x) (x ascending) at x: the line cloth stretched over it takes."""
    hull: list = []  # upper hull by the monotone chain
    for j in range(len(x)):
        while len(hull) >= 2 and ((x[hull[-1]] - x[hull[-2]]) * (y[j] - y[hull[-2]])
                                  - (y[hull[-1]] - y[hull[-2]]) * (x[j] - x[hull[-2]])) >= 0:
            hull.pop()
        hull.append(j)
    return np.interp(x, x[hull], y[hull])


def _pleat(s: np.ndarray, f: np.ndarray):
    """Pleated: each ``MASK_PLEATS`` band down the face stands out along the normal towards its
    lower edge and falls back over the last quarter (a fold that overlaps the band under it),
    fading out within 1.5 cm of the edge."""
    from scipy.spatial import cKDTree
    edge = np.unique(open_edges(f))
    period, depth = MASK_PLEATS
    u = ((s[:, 1].max() - s[:, 1]) / period) % 1.0
    profile = np.where(u < 0.75, u / 0.75, (1.0 - u) / 0.25)
    fade = np.clip(cKDTree(s[edge]).query(s)[0] / 0.015, 0.0, 1.0) ** 2
    return s + vertex_normals(s, f) * (depth * profile * fade)[:, None], f


def _ear_loop(body, head, shell: np.ndarray, x: int, points: int = 36) -> np.ndarray:
    """One elastic loop (head frame) from the mask's top side corner over the ear, round behind it
    and under the lobe back to the bottom corner: an ellipse round the pinna (anny's ear keypoint
    sits at its front) joined to the corners, laid 2.5 mm off the head's surface."""
    R, c = _local(head)
    rim = shell[(shell[:, 0] * x > 0.03) & (shell[:, 2] < MASK_SIDE * head.radii[2] + 0.004)]  # its side edge
    top, bottom = rim[rim[:, 1].argmax()], rim[rim[:, 1].argmin()]
    k = head.radii[1] / 0.08
    ear = (head.ears[0 if x > 0 else 1] - c) @ R
    centre = ear + np.array([0, -0.004, -0.010]) * k
    t = np.linspace(-0.15 * np.pi, 1.1 * np.pi, points)  # from over the ear's front, over, behind and under it
    reach = np.where(np.cos(t) > 0, 0.034, 0.040) * k
    ring = centre + np.column_stack([np.zeros(points), reach * np.cos(t), -0.026 * k * np.sin(t)])
    path = np.concatenate([np.linspace(top, ring[0], 8, endpoint=False), ring,
                           np.linspace(ring[-1], bottom, 9)[1:]])
    path[1:-1, 0] = x * (_surface_width(body, head, path[1:-1]) + 0.0025)  # the ends stay on the shell
    path[1:-1, 0] = np.convolve(path[:, 0], np.ones(3) / 3, "valid")
    return (push_out(body, path @ R.T + c, clearance=0.0025) - c) @ R


def _surface_width(body, head, path: np.ndarray, reach: float = 0.15, step: float = 0.003) -> np.ndarray:
    """How far out to the side of the head frame's midplane the body's outermost surface is at
    each path point's height and depth, to 0.5 mm: marching in from ``reach`` by ``step``, then by
    0.5 mm over the last step (cavities inside the head, such as the mouth's, do not count)."""
    R, c = _local(head)
    side = np.where(path[:, 0] < 0, -1.0, 1.0)

    def first_inside(widths):  # (N, K) widths, decreasing -> the first inside (0 where none is)
        q = np.repeat(path, widths.shape[1], 0)
        q[:, 0] = (widths * side[:, None]).ravel()
        inside = body.surface().signed_distance(q @ R.T + c).reshape(widths.shape) < 0
        return np.where(inside.any(1), widths[np.arange(len(path)), np.argmax(inside, axis=1)], 0.0)
    coarse = first_inside(np.tile(np.arange(reach, 0.0, -step), (len(path), 1)))
    return first_inside(np.minimum(coarse[:, None] + step, reach) - np.arange(0.0, step + 1e-9, 0.0005)[None])


def _tube(points: np.ndarray, radius: float, sections: int = 6, across=(1.0, 0.0, 0.0)):
    """An open-ended tube of ``radius`` along a polyline that never runs along ``across``:
    (vertices, faces)."""
    tangent = np.gradient(points, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    a = np.cross(tangent, across)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(tangent, a)
    ang = 2 * np.pi * np.arange(sections) / sections
    v = (points[:, None] + radius * (np.cos(ang)[None, :, None] * a[:, None] + np.sin(ang)[None, :, None] * b[:, None]))
    i = np.arange(len(points) - 1)[:, None] * sections
    j = np.arange(sections)[None, :]
    p, q = i + j, i + (j + 1) % sections
    f = np.concatenate([np.stack([p, q, p + sections], -1), np.stack([q, q + sections, p + sections], -1)], 1)
    return v.reshape(-1, 3), f.reshape(-1, 3)


# kind -> builder(params, rest body, head {centre, radii (right, up, forward), up, forward, mask (its body
# vertices), eyes and ears (2, 3): left, right keypoints; nose (3,); chin: ``under_chin``}) -> (V, F)
def _uncapped(head: HeadFrame, hair) -> np.ndarray:
    """No strand grows through a cap's crown."""
    return ~under_cap(head, hair.points[:, 0])


def _unmasked(head: HeadFrame, hair) -> np.ndarray:
    """No beard strand (scalp regions are 0-4) grows through a face mask."""
    return ~((hair.region >= 5) & mask_covers(head, hair.points[:, 0]))


@dataclass(frozen=True)
class AccessoryKind:
    """Everything an accessory kind is: ``build(params, body, head) -> (vertices, faces)`` on the
    rest body; its ``metallic``; ``fabric_uv(head, vertices) -> (uv, (metres per u, per v))`` for
    matte cloth with a plain weave at thread size; ``keeps_hair(head, strands)``: the strands
    it leaves (None: all)."""

    build: Callable
    # the share of people sampled wearing it (one in ~3 adults in the street wears glasses, one in ~30
    # a face mask): every kind at 0.22 put masks and headphones on a fifth of people
    rate: float = 0.0
    metallic: float = 0.0
    fabric_uv: Callable | None = None
    keeps_hair: Callable | None = None
    metallic_of: Callable | None = None  # params -> metallic, where it depends on them (None: ``metallic``)


# One entry per kind, in sampling order: a new accessory is one builder and one line here (a rate 0 is never drawn).
ACCESSORIES: dict[str, AccessoryKind] = {
    "glasses": AccessoryKind(_glasses, rate=0.3, metallic_of=lambda p: 0.9 * GLASSES_FRAMES[p.frame or "round"].metal),
    "cap": AccessoryKind(_cap, rate=0.12, keeps_hair=_uncapped),
    "headphones": AccessoryKind(_headphones, rate=0.06), "backpack": AccessoryKind(_backpack, rate=0.2),
    "watch": AccessoryKind(_watch, rate=0.3, metallic=0.8),
    "mask": AccessoryKind(_mask, rate=0.03, fabric_uv=mask_uv, keeps_hair=_unmasked),
}
BUILDERS = BUILDERS_BY_NAME
BUILDERS.update({kind: a.build for kind, a in ACCESSORIES.items()})


def build_accessory(p: AccessoryParams, body, head) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the accessory on the rest body (see ``BUILDERS``)."""
    if p.kind not in BUILDERS:
        raise ConfigError("accessory.kind", p.kind, f"use one of {', '.join(BUILDERS)}")
    return BUILDERS[p.kind](p, body, head)


LAYER = int(Layer.ACCESSORY)
