"""Accessories placed from the shaped body's joints and vertices (so they follow its shape) and
skinned with the weights of their nearest body vertex."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.body.textures import LAB, sample_lab_colour
from synmitsuba.body.topology import cut, submesh
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import align_vectors, frame, vertex_normals
from synmitsuba.schema import Choice, Number, Params, optional, spec
from synmitsuba.scene.layers import Layer

KINDS = ("glasses", "cap", "headphones", "backpack", "watch", "mask")  # sampled ones, in sampling order
BUILDERS_BY_NAME: dict = {}  # kind -> builder, filled below (BUILDERS); read when a recipe is checked


@dataclass
class AccessoryParams(Params):
    kind: str = spec("glasses", Choice(BUILDERS_BY_NAME))
    colour_lab: list | None = spec(None, optional(LAB))
    scale: float = spec(1.0, Number(0.8, 1.25))


def sample_accessories(rng: np.random.Generator) -> list[AccessoryParams]:
    chosen = [k for k in KINDS if rng.random() < 0.22]
    if "cap" in chosen and "headphones" in chosen:
        chosen.remove("headphones")
    return [AccessoryParams(k, sample_lab_colour(rng, (10, 80)), round(float(rng.uniform(0.9, 1.1)), 3)) for k in chosen]


def _place(mesh, R, t):
    return np.asarray(mesh.vertices) @ R.T + t, np.asarray(mesh.faces)


def _local(head):
    """The head frame (columns side, up, forward) and centre: local = (world - centre) @ R."""
    return frame(head["forward"], head["up"]), head["centre"]


def _glasses(p: AccessoryParams, body, head):
    """Two rims in front of the eyes (anny's eye keypoints), a bridge, end pieces and temples
    running back past the sides of the head to the ears; the frame's plane is where the rims
    clear the face by 6 mm and the bridge the nose by 4 mm: it rests on the face, not in it."""
    import trimesh
    R, c = _local(head)
    face = (body.vertices[head["mask"]] - c) @ R
    eyes, ears = (head["eyes"] - c) @ R, (head["ears"] - c) @ R
    mid, half, r = eyes.mean(0), abs(eyes[0, 0] - eyes[1, 0]) / 2, 0.022 * p.scale
    ring_path = np.zeros(len(face), bool)  # face points under the rims' tube (the lenses are open)
    for x in (-1, 1):
        ring_path |= np.abs(np.hypot(face[:, 0] - mid[0] - x * half, face[:, 1] - mid[1]) - r) < 0.005
    bridge = (np.abs(face[:, 0] - mid[0]) < 0.008) & (np.abs(face[:, 1] - mid[1] - 0.004) < 0.004)
    z = max(face[ring_path, 2].max() + 0.006, face[bridge, 2].max() + 0.004)
    back = ears[:, 2].mean() - 0.005
    parts = [trimesh.creation.box([2 * (half - r) + 0.006, 0.004, 0.004])]  # the bridge
    parts[0].apply_translation([mid[0], mid[1] + 0.004, z])
    for x in (-1, 1):
        ring = trimesh.creation.torus(r, 0.0025, major_sections=24, minor_sections=6)
        ring.apply_translation([mid[0] + x * half, mid[1], z])
        path = _temple(face, mid, x, z, back)  # along the side of the head, 4 mm off it
        points = [[mid[0] + x * (half + r), mid[1], z]] + [[mid[0] + x * w, mid[1], zk] for w, zk in path]
        parts += [ring] + [trimesh.creation.cylinder(0.002, segment=[a, b], sections=6)
                           for a, b in zip(points[:-1], points[1:])]
    return _place(trimesh.util.concatenate(parts), R, c)


def _temple(face: np.ndarray, mid: np.ndarray, x: int, front: float, back: float, steps: int = 6) -> list:
    """(half-width, z) points of one temple from the frame back to the ear: at each depth the
    head's widest point at eye height on that side, plus 4 mm, never narrower than the step
    before (a temple runs straight or outward; it does not bend into the head)."""
    side = (face[:, 0] - mid[0]) * x > 0
    level = np.abs(face[:, 1] - mid[1]) < 0.015
    out, width = [], 0.0
    for zk in np.linspace(front, back, steps):
        near = side & level & (np.abs(face[:, 2] - zk) < 0.012)
        if near.any():
            width = max(width, np.abs(face[near, 0] - mid[0]).max() + 0.004)
        out.append((width, zk))
    return out


def _cap_line(head, v: np.ndarray) -> np.ndarray:
    """Height of head-frame points ``v`` over a cap's edge: a line 3 cm above the eyes at the
    front, dropping 3 cm for every 10 cm towards the back."""
    R, c = _local(head)
    mid = ((head["eyes"] - c) @ R).mean(0)
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
    used, f = submesh(body.faces, head["mask"])
    n = vertex_normals(body.vertices, body.faces)[used] @ R
    f, dome = cut(f, _cap_line(head, v[used]), v[used] + n * 0.009)
    dome = trimesh.Trimesh(dome, f, process=False).subdivide_loop(1)  # the body's head is too coarse for a shiny crown
    dome, f = np.asarray(dome.vertices), np.asarray(dome.faces)
    bill = _bill(v[head["mask"]], ((head["eyes"] - c) @ R).mean(0)[1] + 0.03, p.scale)
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
    rad = head["radii"]
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
    return _place(trimesh.util.concatenate(parts), frame(head["forward"], head["up"]), head["centre"])


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


def _mask(p: AccessoryParams, body, head):
    """Nose and mouth down to the chin: the front of the face from a third of the way up from
    anny's nose keypoint to its eyes, down to the chin (1.9 times that eye-to-nose drop below the
    nose), cut along smooth curves, 6 mm off the skin."""
    rel = body.vertices - head["centre"]
    fwd, up, rad = head["forward"], head["up"], head["radii"]
    nose, drop = (head["nose"] - head["centre"]) @ up, (head["eyes"].mean(0) - head["nose"]) @ up
    h = rel @ up
    phi = np.minimum.reduce([nose + 0.35 * drop - h, h - (nose - 1.9 * drop), rel @ fwd - 0.3 * rad[2]])
    from synmitsuba.body.garments import push_out
    f, v, n = cut(body.faces, phi, body.vertices, vertex_normals(body.vertices, body.faces))
    # the lips' crease and the mouth's inside are concave: what lands in the head comes out
    return push_out(body, v + n / np.linalg.norm(n, axis=1, keepdims=True) * 0.006, clearance=0.003), f


# kind -> builder(params, rest body, head {centre, radii (right, up, forward), up, forward, mask (its body
# vertices), eyes and ears (2, 3): left, right keypoints; nose (3,)}) -> (V, F)
BUILDERS = BUILDERS_BY_NAME
BUILDERS.update(glasses=_glasses, cap=_cap, headphones=_headphones, backpack=_backpack, watch=_watch, mask=_mask)


def build_accessory(p: AccessoryParams, body, head) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the accessory on the rest body (see ``BUILDERS``)."""
    if p.kind not in BUILDERS:
        raise ConfigError("accessory.kind", p.kind, f"use one of {', '.join(BUILDERS)}")
    return BUILDERS[p.kind](p, body, head)


LAYER = int(Layer.ACCESSORY)
