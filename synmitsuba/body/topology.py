"""Render topology: split body vertices at UV seams, keep a map back to the original vertices."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class SplitMesh:
    source: np.ndarray   # (V', ) index of the original vertex for each render vertex
    uv: np.ndarray       # (V', 2)
    faces: np.ndarray    # (F, 3) into render vertices


def split_at_seams(faces: np.ndarray, face_uv: np.ndarray, uv: np.ndarray) -> SplitMesh:
    pairs = np.stack([faces.ravel(), face_uv.ravel()], 1)
    unique, inverse = np.unique(pairs, axis=0, return_inverse=True)
    return SplitMesh(unique[:, 0], uv[unique[:, 1]], inverse.reshape(-1, 3))


def submesh(faces: np.ndarray, keep_vertex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces whose three vertices are kept, re-indexed; returns (vertex indices, faces)."""
    f = faces[keep_vertex[faces].all(1)]
    used = np.unique(f)
    remap = -np.ones(len(keep_vertex), np.int64)
    remap[used] = np.arange(len(used))
    return used, remap[f]
