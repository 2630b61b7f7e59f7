"""Linear blend skinning with axis-aligned rest frames (see ``synmitsuba.body.skeleton``)."""
from __future__ import annotations

import numpy as np

from synmitsuba.body.skeleton import Skeleton, forward_kinematics


def bone_transforms(skeleton: Skeleton, rotations=None, root_translation=None) -> tuple[np.ndarray, np.ndarray]:
    """Per-bone (A (J, 3, 3), b (J, 3)) with posed x = A (x_rest) + b for a point rigid to the bone."""
    J = len(skeleton)
    R = np.broadcast_to(np.eye(3), (J, 3, 3)) if rotations is None else np.asarray(rotations, dtype=np.float64)
    G, P = forward_kinematics(skeleton, R, root_translation)
    b = P - np.einsum("jab,jb->ja", G, skeleton.rest_positions)
    return G, b


def skin(vertices: np.ndarray, weights, transforms: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Posed vertices (V, 3): sum_j w_vj (A_j x_v + b_j); ``weights`` (V, J), dense or a
    scipy sparse matrix."""
    A, b = transforms
    M = np.concatenate([A.reshape(len(A), 9), b], 1)          # (J, 12)
    blended = weights @ M                                      # (V, 12)
    Av = blended[:, :9].reshape(-1, 3, 3)
    return np.einsum("vab,vb->va", Av, vertices) + blended[:, 9:]
