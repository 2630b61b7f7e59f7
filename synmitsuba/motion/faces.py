"""Faces that move: expression tracks over anny's 52 ARKit face units, with speech and blinks.

An expression (``EXPRESSIONS``: neutral, smile, talk, surprise, frown, squint) is a set of unit
weights drawn from an rng at an intensity. A ``FaceTrack`` holds keys (time, expression,
intensity, seed) blended by smoothsteps, a talking amount that drives the jaw and lips with a
speech-like rhythm (syllables at 3-5 Hz in phrases with pauses), and blinks (both eyes, 100-150
ms, one every 2-10 s). ``FaceTrack.weights`` gives the (frames, 52) weights every frame is posed
with; they are also the label. ``sample_face`` couples the draw to the motion (a wave smiles, a
run squints or breathes through the mouth, idling and gesturing talk).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from synmitsuba.body.expressions import FACE_UNITS
from synmitsuba.errors import ConfigError

_BOTH = ("Left", "Right")


def _units(weights: dict) -> np.ndarray:
    """A (52,) vector from {unit or unit without its side: weight}."""
    out = np.zeros(len(FACE_UNITS))
    for name, w in weights.items():
        for unit in ([name] if name in FACE_UNITS else [name + s for s in _BOTH]):
            out[FACE_UNITS.index(unit)] = w
    return out


def _neutral(rng, k: float) -> dict:
    return {"mouthClose": 0.05 * rng.random(), "browInnerUp": 0.1 * rng.random()}


def _smile(rng, k: float) -> dict:
    s = k * rng.uniform(0.6, 1.0)
    return {"mouthSmile": s, "cheekSquint": 0.5 * s, "eyeSquint": 0.25 * s, "mouthUpperUp": 0.15 * s,
            "jawOpen": 0.12 * s * rng.random()}


def _surprise(rng, k: float) -> dict:
    return {"browInnerUp": k, "browOuterUp": 0.8 * k, "eyeWide": 0.7 * k, "jawOpen": k * rng.uniform(0.2, 0.5),
            "mouthFunnel": 0.2 * k}


def _frown(rng, k: float) -> dict:
    return {"browDown": 0.8 * k, "mouthFrown": 0.7 * k, "mouthPress": 0.3 * k, "noseSneer": 0.2 * k,
            "mouthShrugLower": 0.3 * k}


def _squint(rng, k: float) -> dict:
    return {"eyeSquint": 0.8 * k, "cheekSquint": 0.4 * k, "browDown": 0.3 * k, "noseSneer": 0.15 * k}


def _talk(rng, k: float) -> dict:
    return {"mouthSmile": 0.15 * rng.random(), "browInnerUp": 0.2 * rng.random()}


# expression -> its unit weights, drawn from rng at an intensity in (0, 1]
EXPRESSIONS: dict[str, Callable[[np.random.Generator, float], dict]] = {
    "neutral": _neutral, "smile": _smile, "talk": _talk, "surprise": _surprise, "frown": _frown, "squint": _squint}
TALK_UNITS = ("jawOpen", "mouthFunnel", "mouthPucker", "mouthStretchLeft", "mouthStretchRight", "mouthClose")


@dataclass
class FaceKey:
    """An expression a face reaches ``time`` seconds into the clip."""

    time: float
    expression: str
    intensity: float
    seed: int

    def weights(self) -> np.ndarray:
        return np.clip(_units(EXPRESSIONS[self.expression](np.random.default_rng(self.seed), self.intensity)), 0, 1)


@dataclass
class FaceTrack:
    """A face over a clip: expression keys (sorted by time), blinks (start times in seconds,
    one duration each) and the speech rhythm's seed; talking follows the "talk" keys."""

    keys: list[FaceKey]
    blinks: list[float] = field(default_factory=list)
    blink_s: float = 0.12
    blend_s: float = 0.4
    seed: int = 0

    def weights(self, times: np.ndarray) -> np.ndarray:
        """(F, 52) unit weights at ``times`` seconds, each in [0, 1]."""
        t = np.asarray(times, dtype=np.float64)[:, None]
        w = np.broadcast_to(self.keys[0].weights(), (len(t), len(FACE_UNITS))).copy()
        talking = np.full((len(t), 1), float(self.keys[0].expression == "talk") * self.keys[0].intensity)
        for key in self.keys[1:]:
            s = np.clip((t - key.time) / max(self.blend_s, 1e-6), 0.0, 1.0)
            s = s * s * (3 - 2 * s)
            w += s * (key.weights() - w)
            talking += s * (float(key.expression == "talk") * key.intensity - talking)
        w += talking * self._speech(t[:, 0])
        blink = self._blink(t[:, 0])
        for side in _BOTH:
            i = FACE_UNITS.index(f"eyeBlink{side}")
            w[:, i] = np.maximum(w[:, i], blink)
        return np.clip(w, 0.0, 1.0)

    def _speech(self, t: np.ndarray) -> np.ndarray:
        """(F, 52) jaw and lip motion of speech at full talking: syllables at 3-5 Hz, phrases of
        1-3 s with 0.2-0.6 s pauses, a lip shape per syllable."""
        rng = np.random.default_rng([self.seed, 1])
        rate = rng.uniform(3.0, 5.0)
        phase = rng.uniform(0, 2 * np.pi)
        edges = np.cumsum(np.concatenate([[-rng.uniform(0, 1)], np.ravel(np.column_stack(
            [rng.uniform(1.0, 3.0, 64), rng.uniform(0.2, 0.6, 64)]))]))
        k = np.searchsorted(edges, t, side="right") - 1
        on = (k % 2 == 0).astype(np.float64)
        syllable = np.maximum(np.sin(2 * np.pi * rate * t + phase), 0.0) ** 0.7
        n = np.floor((2 * np.pi * rate * t + phase) / (2 * np.pi)).astype(np.int64)  # syllable index
        shapes = rng.random((int(n.max() - n.min()) + 1, 4))
        shape = shapes[n - n.min()]
        out = np.zeros((len(t), len(FACE_UNITS)))
        amp = on * syllable
        out[:, FACE_UNITS.index("jawOpen")] = amp * (0.15 + 0.25 * shape[:, 0])
        out[:, FACE_UNITS.index("mouthFunnel")] = amp * 0.4 * (shape[:, 1] > 0.7)
        out[:, FACE_UNITS.index("mouthPucker")] = amp * 0.4 * (shape[:, 1] < 0.15)
        for side in _BOTH:
            out[:, FACE_UNITS.index(f"mouthStretch{side}")] = amp * 0.3 * shape[:, 2]
            out[:, FACE_UNITS.index(f"mouthLowerDown{side}")] = amp * 0.3 * shape[:, 3]
        out[:, FACE_UNITS.index("mouthClose")] = on * (1 - syllable) * 0.1
        return out

    def _blink(self, t: np.ndarray) -> np.ndarray:
        """Lid closure of the blinks: closed a third of the way through, open again after."""
        out = np.zeros(len(t))
        for start in self.blinks:
            u = (t - start) / self.blink_s
            closing, opening = np.clip(u / 0.35, 0, 1), np.clip((1 - u) / 0.65, 0, 1)
            out = np.maximum(out, np.where((u >= 0) & (u <= 1), np.minimum(closing, opening), 0.0))
        return out * out * (3 - 2 * out)

    def to_dict(self) -> dict:
        return {"keys": [[k.time, k.expression, k.intensity, k.seed] for k in self.keys], "blinks": list(self.blinks),
                "blink_s": self.blink_s, "blend_s": self.blend_s, "seed": self.seed}

    @classmethod
    def from_dict(cls, d: dict, where: str = "face") -> "FaceTrack":
        rows = d.get("keys") or []
        if not rows:
            raise ConfigError(f"{where}.keys", rows, "give at least one [time, expression, intensity, seed] key")
        for i, r in enumerate(rows):
            if not isinstance(r, (list, tuple)) or len(r) < 4:
                raise ConfigError(f"{where}.keys[{i}]", r, "give [time, expression, intensity, seed]")
            if r[1] not in EXPRESSIONS:
                raise ConfigError(f"{where}.keys[{i}]", r[1], f"use one of {', '.join(EXPRESSIONS)}")
        keys = sorted((FaceKey(float(r[0]), str(r[1]), float(r[2]), int(r[3])) for r in rows), key=lambda k: k.time)
        return cls(keys, [float(b) for b in d.get("blinks", [])], float(d.get("blink_s", 0.12)),
                   float(d.get("blend_s", 0.4)), int(d.get("seed", 0)))


# -- coupling to the motion ---------------------------------------------------------------------
def _everyday(params: dict) -> dict:
    return {"neutral": 0.3, "talk": 0.3, "smile": 0.25, "frown": 0.05, "surprise": 0.05, "squint": 0.05}


def _exerting(params: dict) -> dict:
    return {"neutral": 0.45, "squint": 0.25, "talk": 0.05, "smile": 0.1, "frown": 0.15}


def _greeting(params: dict) -> dict:
    return {"smile": 0.6, "talk": 0.3, "neutral": 0.1}


def _expressive(params: dict) -> dict:
    style = params.get("style", "raise")
    if style == "shrug":
        return {"frown": 0.3, "talk": 0.4, "neutral": 0.3}
    return {"talk": 0.5, "smile": 0.25, "surprise": 0.15, "neutral": 0.1}


def _jumping(params: dict) -> dict:
    return {"surprise": 0.3, "smile": 0.3, "neutral": 0.3, "squint": 0.1}


# motion kind -> odds of each expression: (the motion's parameters) -> {expression: weight}
FACE_ODDS: dict[str, Callable[[dict], dict]] = {
    "walk": _everyday, "side_step": _everyday, "turn": _everyday, "idle": _everyday, "squat": _exerting,
    "jog": _exerting, "run": _exerting, "jump": _jumping, "wave": _greeting, "gesture": _expressive}
CHANGE_ODDS = 0.4           # the expression changes once within a clip
BLINK_EVERY_S = (2.0, 10.0)  # seconds between blinks
BLINK_S = (0.10, 0.15)       # a blink's length


def _draw(rng, odds: dict) -> str:
    names = list(odds)
    p = np.array([odds[n] for n in names], dtype=np.float64)
    return names[int(rng.choice(len(names), p=p / p.sum()))]


def sample_face(rng: np.random.Generator, kind: str, params: dict | None = None, seconds: float = 2.0) -> FaceTrack:
    """A face track for a clip of motion ``kind`` with its parameters."""
    odds = FACE_ODDS.get(kind, _everyday)(params or {})
    keys = [FaceKey(0.0, _draw(rng, odds), round(float(rng.uniform(0.4, 1.0)), 4), int(rng.integers(2 ** 31)))]
    if rng.random() < CHANGE_ODDS:
        keys.append(FaceKey(round(float(rng.uniform(0.2, 0.8) * seconds), 4), _draw(rng, odds),
                            round(float(rng.uniform(0.4, 1.0)), 4), int(rng.integers(2 ** 31))))
    blinks, t = [], -float(rng.uniform(0, BLINK_EVERY_S[1]))  # the clip starts somewhere between blinks
    while (t := t + float(rng.uniform(*BLINK_EVERY_S))) < seconds:
        if t > -BLINK_S[1]:
            blinks.append(round(t, 4))
    return FaceTrack(keys, blinks, round(float(rng.uniform(*BLINK_S)), 4), round(float(rng.uniform(0.3, 0.6)), 4),
                     int(rng.integers(2 ** 31)))


def fixed_face(expression: str, seed: int) -> FaceTrack:
    """One expression at full intensity the whole clip, no blinks."""
    return FaceTrack([FaceKey(0.0, expression, 1.0, seed)], seed=seed)


def with_face(motion, track: FaceTrack | None):
    """The clip with ``track``'s weights at each frame (``Motion.face``); unchanged for None."""
    if track is None:
        return motion
    return replace(motion, face=track.weights(np.arange(motion.n_frames) / motion.fps))
