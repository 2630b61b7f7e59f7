"""BVH import: any channel and Euler order, end sites, frame time, unit detection.

Rotations are intrinsic in the order the channels are listed (``Zrotation Xrotation
Yrotation`` -> Rz @ Rx @ Ry), degrees. Only the root's position channels move the skeleton;
position channels on other joints are read and ignored (their offsets stay fixed). End sites
become joints named ``<parent>_end`` so bone directions of the extremities are kept.
"""
from __future__ import annotations

import os
from typing import NoReturn

import numpy as np

from synmitsuba.body.skeleton import Skeleton
from synmitsuba.errors import ConfigError, SynMitsubaError
from synmitsuba.motion.motion import Motion
from synmitsuba.geometry import euler_to_matrix

# metres per file unit; "auto" picks the one giving the most human-like height (~1.7 m)
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "inch": 0.0254, "cmu": 0.0254 / 0.45}
CHANNELS = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"}


class BVHError(SynMitsubaError, ValueError):
    """A malformed BVH file; the message names the file and line."""


class _Tokens:
    def __init__(self, text: str, path: str):
        self.items = [(tok, n + 1) for n, line in enumerate(text.splitlines()) for tok in line.split()]
        self.pos, self.path = 0, path

    def fail(self, what: str) -> NoReturn:
        line = self.items[min(self.pos, len(self.items) - 1)][1] if self.items else 1
        raise BVHError(f"{self.path}, line {line}: {what}")

    def next(self, expect: str | None = None) -> str:
        if self.pos >= len(self.items):
            self.fail(f"unexpected end of file{f', expected {expect!r}' if expect else ''}")
        tok = self.items[self.pos][0]
        if expect is not None and tok.upper() != expect.upper():
            self.fail(f"expected {expect!r}, found {tok!r}")
        self.pos += 1
        return tok

    def number(self) -> float:
        tok = self.next()
        try:
            return float(tok)
        except ValueError:
            self.pos -= 1
            self.fail(f"expected a number, found {tok!r}")

    def line(self) -> int:
        return self.items[min(self.pos, len(self.items) - 1)][1]


def _joint(tk: _Tokens, name: str, parent: int, joints: list) -> None:
    tk.next("{")
    index = len(joints)
    joints.append({"name": name, "parent": parent, "offset": None, "channels": []})
    while True:
        tok = tk.next()
        key = tok.upper()
        if key == "OFFSET":
            joints[index]["offset"] = [tk.number() for _ in range(3)]
        elif key == "CHANNELS":
            n = tk.number()
            if n != int(n) or not 0 <= n <= 6:
                tk.pos -= 1
                tk.fail(f"CHANNELS count must be 0..6, found {n}")
            chans = [tk.next() for _ in range(int(n))]
            bad = [c for c in chans if c not in CHANNELS]
            if bad:
                tk.pos -= 1
                tk.fail(f"unknown channel {bad[0]!r}; expected one of {sorted(CHANNELS)}")
            joints[index]["channels"] = chans
        elif key == "JOINT":
            _joint(tk, tk.next(), index, joints)
        elif key == "END":
            tk.next("Site")
            tk.next("{")
            tk.next("OFFSET")
            off = [tk.number() for _ in range(3)]
            tk.next("}")
            joints.append({"name": f"{name}_end", "parent": index, "offset": off, "channels": []})
        elif key == "}":
            break
        else:
            tk.pos -= 1
            tk.fail(f"unexpected {tok!r} in joint {name!r}")
    if joints[index]["offset"] is None:
        tk.fail(f"joint {name!r} has no OFFSET")


def _scale(rest: np.ndarray, units: str | float) -> float:
    if not isinstance(units, str):
        return float(units)
    if units != "auto":
        if units not in UNITS:
            raise ConfigError("units", units, f"use 'auto', a number of metres per unit or one of {', '.join(UNITS)}")
        return UNITS[units]
    height = float(np.ptp(rest, axis=0).max()) or 1.0  # the largest extent: height or arm span
    return min(UNITS.values(), key=lambda s: abs(np.log(height * s / 1.7)))


def parse_bvh(text: str, path: str = "<bvh>", units: str | float = "auto", labels=()) -> Motion:
    tk = _Tokens(text, path)
    tk.next("HIERARCHY")
    tk.next("ROOT")
    joints: list = []
    _joint(tk, tk.next(), -1, joints)
    tk.next("MOTION")
    tk.next("Frames:")
    n_frames = tk.number()
    tk.next("Frame")
    tk.next("Time:")
    frame_time = tk.number()
    if n_frames != int(n_frames) or n_frames < 1:
        tk.fail(f"Frames must be a positive integer, found {n_frames}")
    if frame_time <= 0:
        tk.fail(f"Frame Time must be > 0 seconds, found {frame_time}")
    n_chan = sum(len(j["channels"]) for j in joints)
    data = np.empty((int(n_frames), n_chan))
    for f in range(int(n_frames)):
        start_line = tk.line()
        for c in range(n_chan):
            if tk.pos >= len(tk.items) or tk.items[tk.pos][1] != start_line:
                tk.fail(f"frame {f + 1} has {c} values, expected {n_chan}")
            data[f, c] = tk.number()
    if tk.pos != len(tk.items):
        tk.fail(f"more data than the {int(n_frames)} frames declared")
    bad = np.argwhere(~np.isfinite(data))
    if len(bad):
        f, c = bad[0]
        names = [f"{j['name']}.{ch}" for j in joints for ch in j["channels"]]
        raise BVHError(f"{path}: frame {f + 1}, {names[c]} is {data[f, c]}: every motion value must be a finite number")
    return _to_motion(joints, data, 1.0 / frame_time, path, units, labels)


def _to_motion(joints: list, data: np.ndarray, fps: float, path: str, units, labels) -> Motion:
    names = [j["name"] for j in joints]
    parents = np.array([j["parent"] for j in joints])
    offsets = np.array([j["offset"] for j in joints], dtype=np.float64)
    rest = offsets.copy()
    for i, p in enumerate(parents):
        if p >= 0:
            rest[i] += rest[p]
    s = _scale(rest, units)
    F, J = len(data), len(joints)
    rotations = np.broadcast_to(np.eye(3), (F, J, 3, 3)).copy()
    root = np.zeros((F, 3))
    col = 0
    for i, j in enumerate(joints):
        chans = j["channels"]
        idx = {c: col + k for k, c in enumerate(chans)}
        rot = [c for c in chans if c.endswith("rotation")]
        if rot:
            order = "".join(c[0] for c in rot)
            rotations[:, i] = euler_to_matrix(np.radians(data[:, [idx[c] for c in rot]]), order)
        if i == 0:
            for a, axis in enumerate("XYZ"):
                if f"{axis}position" in idx:
                    root[:, a] = data[:, idx[f"{axis}position"]] - offsets[0, a]
        col += len(chans)
    skel = Skeleton(tuple(names), parents, rest * s)
    source = os.path.abspath(path) if os.path.exists(path) else path
    return Motion(skel, rotations, root * s, fps, labels=tuple(labels), source=source,
                  meta={"metres_per_unit": s})


def load_bvh(path: str, units: str | float = "auto", labels=()) -> Motion:
    """Read a BVH file into a Motion (metres, y up). ``units``: 'auto', 'm', 'cm', 'mm',
    'inch', 'cmu' (CMU ASF units) or metres per unit."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ConfigError("bvh path", path, "no such file")
    with open(path, encoding="utf-8", errors="replace") as fh:
        return parse_bvh(fh.read(), path, units, labels)
