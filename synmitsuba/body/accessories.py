"""Accessories placed from the shaped body's joints and vertices (so they follow its shape) and
skinned with the weights of their nearest body vertex."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.body.textures import LAB, sample_lab_colour
from synmitsuba.body.topology import submesh
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


def _glasses(p: AccessoryParams, body, head):
    """Two rims, a bridge and two temples reaching back along the head."""
    import trimesh
    s, c, rad = p.scale, head["centre"], head["radii"]
    parts = []
    for x in (-1, 1):
        ring = trimesh.creation.torus(0.022 * s, 0.0025, major_sections=24, minor_sections=6)
        ring.apply_translation([x * 0.032 * s, 0, 0])
        parts.append(ring)
    parts.append(trimesh.creation.box([0.03 * s, 0.004, 0.004]))
    for x in (-1, 1):
        arm = trimesh.creation.box([0.004, 0.004, rad[2] * 1.05])
        arm.apply_translation([x * (rad[0] + 0.004), 0, -rad[2] * 0.5])
        parts.append(arm)
    R = frame(head["forward"], head["up"])
    return _place(trimesh.util.concatenate(parts), R, c + R @ [0, 0.2 * rad[1], rad[2] + 0.012])


def _cap(p: AccessoryParams, body, head):
    """A dome over the skull and a brim at the front."""
    import trimesh
    c, rad = head["centre"], head["radii"]
    dome = trimesh.creation.icosphere(3, 1.0)
    v = dome.vertices
    keep = v[:, 2] > -0.05  # the upper half (z up in the primitive)
    dome = trimesh.Trimesh(v * [rad[0] + 0.012, rad[2] + 0.012, rad[1] * 0.8], dome.faces[keep[dome.faces].all(1)])
    brim = trimesh.creation.cylinder(radius=rad[2] * 0.9, height=0.005, sections=32)
    brim.apply_translation([0, rad[2] * 0.75, 0])
    m = trimesh.util.concatenate([dome, brim])
    m.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))  # z up -> y up
    R = frame(head["forward"], head["up"])
    return _place(m, R, c + R @ [0, 0.2 * rad[1], 0])


def _headphones(p: AccessoryParams, body, head):
    """A band arching over the head and a cup over each ear."""
    import trimesh
    rad = head["radii"]
    band = trimesh.creation.torus(rad[0] + 0.02, 0.008, major_sections=32, minor_sections=8)
    v = band.vertices
    band = trimesh.Trimesh(v, band.faces[(v[band.faces][..., 1] > -0.01).all(1)])  # the upper half arc
    band.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    band.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1]))
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
    """The face below the nose, lifted off the skin."""
    rel = body.vertices - head["centre"]
    fwd, up, rad = head["forward"], head["up"], head["radii"]
    sel = ((rel @ fwd) > 0.3 * rad[2]) & ((rel @ up) < -0.3 * rad[1]) & ((rel @ up) > -rad[1] * 1.05)
    used, f = submesh(body.faces, sel)
    n = vertex_normals(body.vertices, body.faces)[used]
    return body.vertices[used] + n * 0.006, f


# kind -> builder(params, rest body, head {centre, radii (right, up, forward), up, forward}) -> (V, F)
BUILDERS = BUILDERS_BY_NAME
BUILDERS.update(glasses=_glasses, cap=_cap, headphones=_headphones, backpack=_backpack, watch=_watch, mask=_mask)


def build_accessory(p: AccessoryParams, body, head) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the accessory on the rest body (see ``BUILDERS``)."""
    if p.kind not in BUILDERS:
        raise ConfigError("accessory.kind", p.kind, f"use one of {', '.join(BUILDERS)}")
    return BUILDERS[p.kind](p, body, head)


LAYER = int(Layer.ACCESSORY)
