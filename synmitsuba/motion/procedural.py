"""Procedural motions on the humanoid skeleton: the default motion library, no data needed.

Every kind takes ``rng`` (unset parameters are sampled from plausible ranges, so the same rng
gives the same motion), ``seconds`` and ``fps``. Feet are planted: the root is moved so the
supporting foot stays put on the ground (y = 0) and the lowest foot touches it. Walks, jogs and
runs roll each foot from the heel over the ball (``foot_roll``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.body.skeleton import forward_kinematics
from synmitsuba.errors import ConfigError
from synmitsuba.motion.humanoid import FEET, HEEL_BACK, humanoid_skeleton
from synmitsuba.motion.motion import Motion
from synmitsuba.schema import Choice, Number, mapping
from synmitsuba.geometry import axis_rotation

D = np.radians
# kind -> {parameter: (low, high) sampled when not given, or a tuple of choices}
PARAMS: dict[str, dict[str, tuple]] = {
    "walk": {"speed": (1.0, 1.6), "stride": (1.0, 1.4), "amplitude": (0.7, 1.3), "style": ("normal", "relaxed", "brisk")},
    "jog": {"speed": (2.0, 3.0), "stride": (1.6, 2.2), "amplitude": (0.8, 1.2), "style": ("normal", "relaxed", "brisk")},
    "run": {"speed": (3.5, 5.0), "stride": (2.3, 3.0), "amplitude": (0.9, 1.2), "style": ("normal", "relaxed", "brisk")},
    "idle": {"amplitude": (0.5, 1.5), "style": ("calm", "restless")},
    "wave": {"amplitude": (0.7, 1.3), "handedness": ("right", "left"), "speed": (1.5, 3.0)},
    "turn": {"angle_deg": (-180.0, 180.0), "amplitude": (0.7, 1.2)},
    "side_step": {"speed": (0.4, 0.8), "stride": (0.5, 0.8), "amplitude": (0.7, 1.2), "handedness": ("right", "left")},
    "jump": {"amplitude": (0.7, 1.2), "height": (0.15, 0.4), "speed": (0.0, 1.0)},
    "squat": {"amplitude": (0.5, 1.0), "speed": (0.3, 0.7)},
    "gesture": {"amplitude": (0.6, 1.2), "style": ("raise", "point", "clap", "shrug"), "handedness": ("right", "left")},
}
KINDS = tuple(PARAMS)


def _params(kind: str, rng: np.random.Generator, given: dict) -> dict:
    spec = PARAMS[kind]
    mapping(kind, given, spec)
    out = {}
    for name, rule in spec.items():  # sample every parameter, so given ones don't shift the stream
        value = rng.choice(rule) if isinstance(rule[0], str) else rng.uniform(*rule)
        if name in given:  # a given value may lie outside the sampled range, up to twice its top
            check = Choice(rule) if isinstance(rule[0], str) else Number() if name == "angle_deg" else \
                Number(min(rule[0], 0.0) if name == "speed" else rule[0], 2 * rule[1])
            value = check(f"{kind}.{name}", given[name])
        out[name] = value.item() if hasattr(value, "item") else value
    return out


class _Pose:
    """Per-joint local rotations over F frames, composed by name."""

    def __init__(self, n: int):
        self.skel = humanoid_skeleton()
        self.R = np.broadcast_to(np.eye(3), (n, len(self.skel), 3, 3)).copy()

    def rot(self, joint: str, axis: str, angle) -> None:
        """Pre-multiply (rotate in the parent frame, after what is there)."""
        i = self.skel.index(joint)
        self.R[:, i] = axis_rotation(axis, angle) @ self.R[:, i]


def _arms_down(p: _Pose, drop=D(75), elbow=0.0) -> None:
    p.rot("l_shoulder", "z", -drop)
    p.rot("r_shoulder", "z", drop)
    p.rot("l_elbow", "y", -elbow)
    p.rot("r_elbow", "y", elbow)


def _leg(p: _Pose, side: str, hip, knee, abduct=0.0, flat=True) -> None:
    s = side[0]
    p.rot(f"{s}_hip", "x", -hip)
    p.rot(f"{s}_hip", "z", abduct if s == "l" else -abduct)
    p.rot(f"{s}_knee", "x", knee)
    if flat:  # keep the sole parallel to the ground
        p.rot(f"{s}_ankle", "x", hip - knee)


GAIT = {  # stance fraction, foot lift (m), pelvis drop (m), pelvis bob (m), trunk lean, elbow bend
    "walk": (0.60, 0.07, 0.02, 0.015, D(3), D(20)),
    "jog": (0.42, 0.14, 0.07, 0.03, D(8), D(75)),
    "run": (0.36, 0.22, 0.09, 0.04, D(12), D(90)),
}


def _foot_track(t, f: float, offset: float, beta: float, step, lift: float):
    """World foot placement along a step direction (unit 2-vector ``step`` scaled by the stride):
    planted during stance, a smooth lifted arc during swing. Returns (along, height)."""
    c = f * t + offset
    n, u = np.floor(c), c - np.floor(c)
    start = (n - offset + beta / 2) / f  # pelvis time at mid-stance of cycle n
    s = np.clip((u - beta) / (1 - beta), 0, 1)
    s = np.where(u < beta, 0.0, s * s * (3 - 2 * s))
    along = start + s / f  # in seconds of pelvis travel
    height = np.where(u < beta, 0.0, lift * np.sqrt(np.sin(np.pi * np.clip((u - beta) / (1 - beta), 0, 1))))
    return along, height


# kind -> the foot's pitch against the ground at heel strike (toe up) and at toe-off (heel up),
# and where in the stance the foot lands flat and where its heel starts to rise (fractions of
# the stance). Walking lands on the heel; running lands nearer the midfoot and pushes off longer.
ROLL = {"walk": (D(15), D(35), 0.17, 0.55), "jog": (D(8), D(30), 0.12, 0.45), "run": (D(4), D(30), 0.10, 0.40)}


def _smooth(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


@dataclass(frozen=True)
class FootRoll:
    """A foot's roll over its gait cycle (arrays over frames): ``pitch`` the foot's (radians, toe
    up > 0), ``ball`` how far its pivot is from the heel's contact point (0) to the ball joint
    (1), ``toes`` the toes' own pitch against the ground (flat on it while the heel rises)."""

    pitch: np.ndarray
    ball: np.ndarray
    toes: np.ndarray


def foot_roll(u, beta: float, roll: tuple) -> FootRoll:
    """The roll at cycle phases ``u`` in [0, 1) (stance first, a fraction ``beta`` of the cycle):
    down from the heel to flat, flat, up over the ball to toe-off, and through the swing back to
    the heel-strike pitch (the pivot moving from the ball to the heel as the foot is in the air)."""
    strike, push, flat, rise = roll
    q = u / beta
    s = (u - beta) / (1 - beta)
    stance = u < beta
    pitch = np.where(q < flat, strike * (1 - _smooth(q / flat)),
                     np.where(q < rise, 0.0, -push * ((q - rise) / (1 - rise)) ** 2))
    swing_pitch = -push + (push + strike) * _smooth(s / 0.75)
    pitch = np.where(stance, pitch, swing_pitch)
    ball = np.where(stance, (q >= flat).astype(float), 1 - _smooth((s - 0.2) / 0.6))
    toes = np.where(stance, np.where(q < flat, pitch, 0.0), swing_pitch * _smooth(s / 0.4))
    return FootRoll(pitch, ball, toes)


def _leg_ik(p: _Pose, side: str, hip, ankle, foot=None) -> None:
    """Two-bone IK: rotate hip and knee so the ankle reaches ``ankle`` (F, 3) from ``hip``; the
    foot takes the global rotation ``foot`` (F, 3, 3; flat, the identity, when None). Assumes
    the pelvis is not rotated."""
    sk = p.skel
    s = side[0]
    ih, ik, ia = sk.index(f"{s}_hip"), sk.index(f"{s}_knee"), sk.index(f"{s}_ankle")
    L1 = np.linalg.norm(sk.offsets[ik])
    L2 = np.linalg.norm(sk.offsets[ia])
    v = ankle - hip
    d = np.clip(np.linalg.norm(v, axis=1), abs(L1 - L2) + 1e-4, (L1 + L2) * 0.9999)
    u = v / np.linalg.norm(v, axis=1, keepdims=True)
    gamma = np.arcsin(np.clip(u[:, 2], -1, 1))
    phi = np.arctan2(u[:, 0], -u[:, 1])
    alpha = np.arccos(np.clip((L1 ** 2 + d ** 2 - L2 ** 2) / (2 * L1 * d), -1, 1))
    knee = np.pi - np.arccos(np.clip((L1 ** 2 + L2 ** 2 - d ** 2) / (2 * L1 * L2), -1, 1))
    p.R[:, ih] = axis_rotation("z", phi) @ axis_rotation("x", -(gamma + alpha))
    p.R[:, ik] = axis_rotation("x", knee)
    p.R[:, ia] = np.swapaxes(p.R[:, ih] @ p.R[:, ik], -1, -2)
    if foot is not None:
        p.R[:, ia] = p.R[:, ia] @ foot


def _rolled_ankle(sk, side: str, flat, roll: FootRoll) -> np.ndarray:
    """Where the ankle is when the foot, placed flat with its ankle at ``flat`` (F, 3), is turned
    by ``roll.pitch`` about its pivot (the heel's contact point or the ball joint)."""
    ankle = sk.rest_positions[sk.index(f"{side[0]}_ankle")]
    heel = ankle + [0.0, -ankle[1], -HEEL_BACK]
    pivot = heel + roll.ball[:, None] * (sk.rest_positions[sk.index(f"{side[0]}_toe")] - heel)
    turn = axis_rotation("x", -roll.pitch)
    return pivot + (flat - ankle) + np.einsum("fij,fj->fi", turn, ankle - pivot)


def _locomotion(p: _Pose, t, kind: str, a: dict, lateral: float = 0.0, roll_scale: float = 1.0) -> np.ndarray:
    """Walk, jog, run (forward, +z) or side-step (``lateral`` = +1 left / -1 right): feet follow
    planted tracks, the legs reach them by IK; ``roll_scale`` scales the feet's heel-strike and
    toe-off pitches. Returns the root translation."""
    beta, lift, drop, bob, lean, elbow = GAIT["walk" if kind == "side_step" else kind]
    style = {"normal": 1.0, "relaxed": 0.85, "brisk": 1.15}.get(a.get("style", "normal"), 1.0)
    speed, stride = a["speed"], a["stride"]
    f = speed / stride
    direction = np.array([lateral, 0.0, 0.0]) if lateral else np.array([0.0, 0.0, 1.0])
    n = len(t)
    sk = p.skel
    pelvis = np.zeros((n, 3))
    pelvis += (speed * t)[:, None] * direction
    ankles, hips, reach, rolls = {}, {}, [], {}
    for side, offset in (("left", 0.0), ("right", 0.5)):
        along, height = _foot_track(t, f, offset, beta, direction, lift * (0.6 if lateral else style))
        ankle = sk.rest_positions[sk.index(f"{side[0]}_ankle")] + (speed * along)[:, None] * direction
        ankle[:, 1] += height
        if not lateral:  # a side step keeps its feet flat
            pitches = tuple(np.multiply(ROLL[kind], (style * roll_scale, style * roll_scale, 1, 1)))
            rolls[side] = foot_roll(np.mod(f * t + offset, 1.0), beta, pitches)
            ankle = _rolled_ankle(sk, side, ankle, rolls[side])
        hip_off = sk.offsets[sk.index(f"{side[0]}_hip")]
        leg = 0.97 * (np.linalg.norm(sk.offsets[sk.index(f"{side[0]}_knee")])
                      + np.linalg.norm(sk.offsets[sk.index(f"{side[0]}_ankle")]))
        horiz = np.linalg.norm((ankle - pelvis - hip_off)[:, [0, 2]], axis=1)
        reach.append(ankle[:, 1] + np.sqrt(np.maximum(leg ** 2 - horiz ** 2, 0.0)) - hip_off[1])
        ankles[side], hips[side] = ankle, hip_off
    nominal = 0.95 - drop * style - bob * np.cos(4 * np.pi * f * t)
    y = np.minimum(nominal, np.minimum(*reach))  # low enough for both legs to reach their feet
    kernel = np.exp(-0.5 * (np.arange(-4, 5) / 2.0) ** 2)
    y_smooth = np.convolve(np.pad(y, 4, mode="edge"), kernel / kernel.sum(), mode="valid")
    pelvis[:, 1] = np.minimum(y, y_smooth)
    for side in ("left", "right"):
        roll = rolls.get(side)
        _leg_ik(p, side, pelvis + hips[side], ankles[side], None if roll is None else axis_rotation("x", -roll.pitch))
        if roll is not None:  # the toes' pitch against the ground, under the foot's
            toe = sk.index(f"{side[0]}_toe")
            p.R[:, toe] = axis_rotation("x", roll.pitch) @ axis_rotation("x", -roll.toes)
    phase = 2 * np.pi * f * t
    _arms_down(p, elbow=elbow)
    arm = a["amplitude"] * D(22) * style * (0.3 if lateral else 1.0)
    p.rot("l_shoulder", "x", arm * np.sin(phase))
    p.rot("r_shoulder", "x", -arm * np.sin(phase))
    p.rot("chest", "y", -D(5) * np.sin(phase) * a["amplitude"] * (0 if lateral else 1))
    p.rot("spine1", "x", lean * style)
    return pelvis - sk.rest_positions[0]


def _plant(p: _Pose, anchor: str = "stance", lift=None) -> np.ndarray:
    """Root translation that keeps the supporting foot fixed and the lowest foot on y = 0.
    anchor 'stance': the lower foot holds still; 'both': the feet's mean holds still."""
    _, pos = forward_kinematics(p.skel, p.R)
    idx = {side: [p.skel.index(j) for j in joints] for side, joints in FEET.items()}
    low = {}
    for side, ids in idx.items():
        k = pos[:, ids, 1].argmin(1)
        low[side] = pos[np.arange(len(pos)), np.array(ids)[k]]
    lowest_y = np.minimum(low["left"][:, 1], low["right"][:, 1])
    root = np.zeros((len(pos), 3))
    root[:, 1] = -lowest_y + (0.0 if lift is None else lift)
    stance_left = low["left"][:, 1] <= low["right"][:, 1]
    for t in range(1, len(pos)):
        if anchor == "both":
            d = 0.5 * ((low["left"][t] - low["left"][t - 1]) + (low["right"][t] - low["right"][t - 1]))
        else:
            side = "left" if stance_left[t - 1] else "right"  # the foot planted before this frame
            d = low[side][t] - low[side][t - 1]
        root[t, [0, 2]] = root[t - 1, [0, 2]] - d[[0, 2]]
    return root


def _idle(p: _Pose, t, a: dict, rng) -> None:
    amp = a["amplitude"] * (1.6 if a["style"] == "restless" else 1.0)
    f1, f2 = rng.uniform(0.15, 0.3), rng.uniform(0.25, 0.5)
    ph = rng.uniform(0, 2 * np.pi, 3)
    sway = D(2.5) * amp * np.sin(2 * np.pi * f1 * t + ph[0])
    p.rot("pelvis", "z", sway)
    p.rot("l_hip", "z", -sway)
    p.rot("r_hip", "z", -sway)
    p.rot("chest", "x", D(1.5) * np.sin(2 * np.pi * 0.25 * t))  # breathing
    p.rot("neck", "y", D(12) * amp * np.sin(2 * np.pi * f2 * t + ph[1]))
    p.rot("head", "x", D(5) * amp * np.sin(2 * np.pi * f2 * 0.7 * t + ph[2]))
    _arms_down(p, elbow=D(10))


def _wave(p: _Pose, t, a: dict, rng) -> None:
    _idle(p, t, {"amplitude": 0.6, "style": "calm"}, rng)
    s = 1 if a["handedness"] == "left" else -1
    arm = "l" if s == 1 else "r"
    ramp = np.clip(t / 0.4, 0, 1)
    ramp = ramp * ramp * (3 - 2 * ramp)
    i = p.skel.index(f"{arm}_shoulder")
    p.R[:, i] = np.eye(3)  # replace the lowered arm
    p.rot(f"{arm}_shoulder", "z", s * ramp * D(40) * a["amplitude"])
    p.rot(f"{arm}_elbow", "z", s * ramp * (D(70) + D(25) * a["amplitude"] * np.sin(2 * np.pi * a["speed"] * t)))


def _turn(p: _Pose, t, a: dict, seconds: float) -> None:
    u = np.clip(t / max(seconds, 1e-6), 0, 1)
    p.rot("pelvis", "y", D(a["angle_deg"]) * u * u * (3 - 2 * u))
    steps = 2 * np.pi * 1.6 * t
    for side, ph in (("left", steps), ("right", steps + np.pi)):
        lift = np.maximum(0, np.sin(ph)) * a["amplitude"]
        _leg(p, side, D(20) * lift, D(40) * lift)
    _arms_down(p, elbow=D(10))


def _squat(p: _Pose, t, a: dict) -> None:
    depth = a["amplitude"] * 0.5 * (1 - np.cos(2 * np.pi * a["speed"] * t))
    for side in ("left", "right"):
        _leg(p, side, D(100) * depth, D(120) * depth)
    p.rot("spine1", "x", D(35) * depth)
    _arms_down(p, drop=D(75) * (1 - depth))
    p.rot("l_shoulder", "x", -D(80) * depth)
    p.rot("r_shoulder", "x", -D(80) * depth)


def _jump(p: _Pose, t, a: dict) -> np.ndarray:
    """Crouch (0.3 s), take off (0.15 s), flight, land (0.3 s); returns the extra root height."""
    g, h = 9.81, a["height"]
    flight = 2 * np.sqrt(2 * h / g)
    t_off, t_land = 0.45, 0.45 + flight
    crouch = np.where(t < 0.3, np.sin(np.pi / 2 * t / 0.3), 0.0)
    crouch = np.where((t >= 0.3) & (t < t_off), 1 - (t - 0.3) / 0.15, crouch)
    crouch = np.where((t >= t_land) & (t < t_land + 0.3), np.sin(np.pi * (t - t_land) / 0.3), crouch)
    bend = crouch * 0.6 * a["amplitude"]
    for side in ("left", "right"):
        _leg(p, side, D(80) * bend, D(100) * bend)
    p.rot("spine1", "x", D(25) * bend)
    air = (t >= t_off) & (t < t_land)
    u = np.clip((t - 0.3) / 0.3, 0, 1) * np.clip((t_land + 0.5 - t) / 0.3, 0, 1)  # arms up around the flight
    _arms_down(p, drop=D(75) - D(120) * u * u * (3 - 2 * u))
    tau = np.clip(t - t_off, 0, flight)
    return np.where(air, np.sqrt(2 * g * h) * tau - 0.5 * g * tau ** 2, 0.0)


def _gesture(p: _Pose, t, a: dict, rng) -> None:
    _idle(p, t, {"amplitude": 0.5, "style": "calm"}, rng)
    amp = a["amplitude"]
    cycle = 0.5 * (1 - np.cos(2 * np.pi * 0.7 * t))
    for arm, s in (("l", 1), ("r", -1)):
        i = p.skel.index(f"{arm}_shoulder")
        j = p.skel.index(f"{arm}_elbow")
        mine = (arm == "l") == (a["handedness"] == "left")
        if a["style"] == "raise":
            p.rot(f"{arm}_shoulder", "z", s * D(130) * amp * cycle)
        elif a["style"] == "point" and mine:
            p.R[:, i], p.R[:, j] = np.eye(3), np.eye(3)
            p.rot(f"{arm}_shoulder", "y", -s * D(85) * np.clip(2 * cycle, 0, 1))
        elif a["style"] == "clap":
            p.R[:, i], p.R[:, j] = np.eye(3), np.eye(3)
            p.rot(f"{arm}_shoulder", "y", -s * (D(60) + D(25) * amp * cycle))
            p.rot(f"{arm}_shoulder", "z", -s * D(20))
        elif a["style"] == "shrug":
            p.rot(f"{arm}_collar", "z", s * D(15) * amp * cycle)
            p.rot(f"{arm}_elbow", "y", -s * D(60) * cycle)


def procedural_motion(kind: str, rng: np.random.Generator, seconds: float = 2.0, fps: float = 30,
                      roll: float = 1.0, **params) -> Motion:
    """A ``kind`` of motion (see ``KINDS``) on the humanoid skeleton; parameters not given are
    sampled from ``rng``. ``roll`` scales how far walks, jogs and runs pitch the feet at heel
    strike and toe-off (``ROLL``; less in heels: ``compose.subjects.heeled_roll``); it draws
    nothing from ``rng``."""
    if kind not in PARAMS:
        raise ConfigError("motion kind", kind, f"use one of {', '.join(KINDS)}")
    if not isinstance(rng, np.random.Generator):
        raise ConfigError("rng", type(rng).__name__, "pass numpy.random.default_rng(seed)")
    if not (isinstance(seconds, (int, float)) and 0 < seconds <= 600):
        raise ConfigError("seconds", seconds, "give a duration in (0, 600] seconds")
    if not (isinstance(fps, (int, float)) and 1 <= fps <= 1000):
        raise ConfigError("fps", fps, "give a frame rate in [1, 1000]")
    if not (isinstance(roll, (int, float)) and 0 <= roll <= 1.5):
        raise ConfigError("roll", roll, "give a share of the foot roll in [0, 1.5]")
    a = _params(kind, rng, params)
    n = max(2, int(round(seconds * fps)))
    t = np.arange(n) / fps
    p = _Pose(n)
    lift: np.ndarray | None = None
    anchor = "stance"
    root = None
    if kind in ("walk", "jog", "run"):
        root = _locomotion(p, t, kind, a, roll_scale=roll)
    elif kind == "side_step":
        root = _locomotion(p, t, kind, a, lateral=1.0 if a["handedness"] == "left" else -1.0)
    elif kind == "idle":
        _idle(p, t, a, rng)
        anchor = "both"
    elif kind == "wave":
        _wave(p, t, a, rng)
        anchor = "both"
    elif kind == "turn":
        _turn(p, t, a, seconds)
        anchor = "both"
    elif kind == "squat":
        _squat(p, t, a)
        anchor = "both"
    elif kind == "jump":
        lift = _jump(p, t, a)
        anchor = "both"
    elif kind == "gesture":
        _gesture(p, t, a, rng)
        anchor = "both"
    if root is None:
        root = _plant(p, anchor, lift)
    if kind == "jump" and a["speed"] > 0:  # a forward jump travels during the flight only
        air = np.asarray(lift) > 0
        root[:, 2] += np.cumsum(air) / fps * a["speed"]
    return Motion(p.skel, p.R, root, float(fps), labels=(kind,), source=f"procedural:{kind}", meta={"params": a})


def foot_sliding(motion: Motion, feet: dict | None = None, contact_height: float = 0.02) -> float:
    """Largest horizontal drift (metres) of a foot's lowest point during one ground contact."""
    feet = feet or FEET
    pos = motion.joint_positions()
    worst = 0.0
    for joints in feet.values():
        ids = [motion.skeleton.index(j) for j in joints]
        k = pos[:, ids, 1].argmin(1)
        low = pos[np.arange(len(pos)), np.array(ids)[k]]
        contact = low[:, 1] < contact_height
        drift = 0.0
        for t in range(1, len(low)):
            if contact[t] and contact[t - 1]:
                drift += float(np.linalg.norm(low[t, [0, 2]] - low[t - 1, [0, 2]]))
                worst = max(worst, drift)
            else:
                drift = 0.0
    return worst
