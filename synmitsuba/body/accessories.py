"""Accessories placed from the shaped body's joints and vertices (so they follow its shape) and
skinned with the weights of their nearest body vertex."""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from synmitsuba.body.params import check as _check
from synmitsuba.body.params import from_dict as _from_dict
from synmitsuba.body.textures import sample_lab_colour
from synmitsuba.scene.layers import Layer

KINDS = ("glasses", "cap", "headphones", "backpack", "watch", "mask")


@dataclass
class AccessoryParams:
    kind: str = "glasses"
    colour_lab: list = None
    scale: float = 1.0

    def validate(self, where: str = "accessory") -> None:
        _check(where, "kind", self.kind, choices=KINDS)
        _check(where, "scale", self.scale, 0.8, 1.25)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict, where: str = "accessory") -> "AccessoryParams":
        return _from_dict(cls, d, where)


def sample_accessories(rng: np.random.Generator) -> list[AccessoryParams]:
    chosen = [k for k in KINDS if rng.random() < 0.22]
    if "cap" in chosen and "headphones" in chosen:
        chosen.remove("headphones")
    return [AccessoryParams(k, sample_lab_colour(rng, (10, 80)), round(float(rng.uniform(0.9, 1.1)), 3)) for k in chosen]


def _frame(forward, up):
    up = up / np.linalg.norm(up)
    f = forward - up * (forward @ up)
    f /= np.linalg.norm(f)
    return np.stack([np.cross(up, f), up, f], 1)  # columns: right, up, forward


def _place(mesh, R, t):
    return np.asarray(mesh.vertices) @ R.T + t, np.asarray(mesh.faces)


def build_accessory(p: AccessoryParams, body, head) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the accessory on the rest body. ``head``: dict with centre, radii
    (right, up, forward), up, forward from the body's head vertices."""
    import trimesh
    s = p.scale
    c, rad = head["centre"], head["radii"]
    R = _frame(head["forward"], head["up"])
    sk = body.skeleton
    if p.kind == "glasses":
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
        m = trimesh.util.concatenate(parts)
        return _place(m, R, c + R @ [0, 0.2 * rad[1], rad[2] + 0.012])
    if p.kind == "cap":
        dome = trimesh.creation.icosphere(3, 1.0)
        v = dome.vertices
        keep = v[:, 2] > -0.05  # the upper half (z up in the primitive)
        dome = trimesh.Trimesh(v * [rad[0] + 0.012, rad[2] + 0.012, rad[1] * 0.8], dome.faces[keep[dome.faces].all(1)])
        brim = trimesh.creation.cylinder(radius=rad[2] * 0.9, height=0.005, sections=32)
        brim.apply_translation([0, rad[2] * 0.75, 0])
        m = trimesh.util.concatenate([dome, brim])
        m.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))  # z up -> y up
        return _place(m, R, c + R @ [0, 0.2 * rad[1], 0])
    if p.kind == "headphones":
        band = trimesh.creation.torus(rad[0] + 0.02, 0.008, major_sections=32, minor_sections=8)
        v = band.vertices
        band = trimesh.Trimesh(v, band.faces[(v[band.faces][..., 1] > -0.01).all(1)])  # the upper half arc
        band.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
        band.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1]))
        parts = [band]
        for x in (-1, 1):
            cup = trimesh.creation.cylinder(radius=0.035 * s, height=0.025, sections=24)
            cup.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
            cup.apply_translation([x * (rad[0] + 0.015), 0, 0])
            parts.append(cup)
        m = trimesh.util.concatenate(parts)
        m.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [0, 0, 1]))
        m.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1]))
        return _place(m, R, c)
    if p.kind == "backpack":
        chest = sk.rest_positions[sk.index("spine02")]
        back_z = body.vertices[np.abs(body.vertices[:, 1] - chest[1]) < 0.05][:, 2].min()
        box = trimesh.creation.box([0.28 * s, 0.38 * s, 0.12 * s])
        box = box.subdivide().subdivide()
        return np.asarray(box.vertices) + [chest[0], chest[1] - 0.03, back_z - 0.07 * s], np.asarray(box.faces)
    if p.kind == "watch":
        wrist = sk.rest_positions[sk.index("wrist.L")]
        elbow = sk.rest_positions[sk.index("lowerarm01.L")]
        axis = (wrist - elbow) / np.linalg.norm(wrist - elbow)
        near = body.vertices[np.linalg.norm(body.vertices - (wrist - 0.03 * axis), axis=1) < 0.04]
        radius = np.linalg.norm(np.cross(near - wrist, axis), axis=1).max() + 0.006 if len(near) else 0.035
        band = trimesh.creation.annulus(r_min=radius, r_max=radius + 0.004, height=0.018, sections=32)
        Rz = trimesh.geometry.align_vectors([0, 0, 1], axis)
        band.apply_transform(Rz)
        return np.asarray(band.vertices) + wrist - 0.035 * axis, np.asarray(band.faces)
    if p.kind == "mask":
        rel = body.vertices - c
        fwd, up = head["forward"], head["up"]
        sel = ((rel @ fwd) > 0.3 * rad[2]) & ((rel @ up) < -0.3 * rad[1]) & ((rel @ up) > -rad[1] * 1.05)
        from synmitsuba.body.topology import submesh, vertex_normals
        used, f = submesh(body.faces, sel)
        n = vertex_normals(body.vertices, body.faces)[used]
        return body.vertices[used] + n * 0.006, f
    raise ValueError(p.kind)


LAYER = int(Layer.ACCESSORY)
