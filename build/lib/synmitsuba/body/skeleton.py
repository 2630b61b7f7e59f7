"""Skeleton: the joint tree shared by body models and motions.

Convention (used by every body backend, every motion and the retargeter):
- metres, our world frame (right-handed, y up);
- ``rest_positions`` are joint positions in model space in the rest pose;
- every joint's frame in the rest pose is aligned with the model axes (SMPL/BVH style), so a
  local rotation ``R_i`` rotates joint ``i``'s children in its parent's (axis-aligned) frame:
  global ``G_i = G_parent(i) @ R_i``; position ``p_i = p_parent + G_parent @ offset_i``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Skeleton:
    """Joint names, parent indices (-1 for a root) and rest-pose joint positions (J, 3)."""

    names: tuple[str, ...]
    parents: np.ndarray
    rest_positions: np.ndarray

    def __post_init__(self):
        parents = np.asarray(self.parents, dtype=np.int64)
        rest = np.asarray(self.rest_positions, dtype=np.float64)
        n = len(self.names)
        if parents.shape != (n,):
            raise ValueError(f"Skeleton.parents: shape {parents.shape}, expected ({n},); give one parent per joint")
        if rest.shape != (n, 3):
            raise ValueError(f"Skeleton.rest_positions: shape {rest.shape}, expected ({n}, 3)")
        for i, p in enumerate(parents):
            if p >= i:
                raise ValueError(
                    f"Skeleton.parents[{i}] = {p}: parents must come before children (topological order)")
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "rest_positions", rest)

    def __len__(self) -> int:
        return len(self.names)

    @property
    def offsets(self) -> np.ndarray:
        """Rest offset of each joint from its parent (the root's offset is its rest position)."""
        off = self.rest_positions.copy()
        has_parent = self.parents >= 0
        off[has_parent] -= self.rest_positions[self.parents[has_parent]]
        return off

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"joint {name!r} is not in this skeleton; joints: {', '.join(self.names[:12])}...") from None


def local_rotations(global_rotations: np.ndarray, parents) -> np.ndarray:
    """Local rotations (..., J, 3, 3) from global ones: the inverse of ``forward_kinematics``'s
    ``G_i = G_parent(i) @ R_i`` (a root keeps its global rotation)."""
    G = np.asarray(global_rotations, dtype=np.float64)
    parents = np.asarray(parents)
    local = G.copy()
    has = parents >= 0
    local[..., has, :, :] = np.swapaxes(G[..., parents[has], :, :], -1, -2) @ G[..., has, :, :]
    return local


def forward_kinematics(skeleton: Skeleton, local_rotations: np.ndarray,
                       root_translation: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Global rotations (..., J, 3, 3) and joint positions (..., J, 3) from local rotations.

    ``local_rotations`` has shape (..., J, 3, 3); ``root_translation`` (..., 3) moves the roots
    (added to their rest positions).
    """
    local = np.asarray(local_rotations, dtype=np.float64)
    n = len(skeleton)
    if local.shape[-3:] != (n, 3, 3):
        raise ValueError(f"local_rotations: shape {local.shape}, expected (..., {n}, 3, 3)")
    lead = local.shape[:-3]
    glob = np.empty_like(local)
    pos = np.empty(lead + (n, 3))
    offsets = skeleton.offsets
    trans = np.zeros(lead + (3,)) if root_translation is None else np.asarray(root_translation, dtype=np.float64)
    for i, p in enumerate(skeleton.parents):
        if p < 0:
            glob[..., i, :, :] = local[..., i, :, :]
            pos[..., i, :] = offsets[i] + trans
        else:
            glob[..., i, :, :] = glob[..., p, :, :] @ local[..., i, :, :]
            pos[..., i, :] = pos[..., p, :] + np.einsum("...ij,j->...i", glob[..., p, :, :], offsets[i])
    return glob, pos
