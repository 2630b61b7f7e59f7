"""Stick figures: a mesh of spheres and cylinders for joint positions (previews, debugging)."""
from __future__ import annotations

from typing import Any

import numpy as np


def stick_figure(positions: np.ndarray, parents, radius: float = 0.025) -> tuple[np.ndarray, np.ndarray]:
    """One mesh (vertices, faces) with a sphere per joint and a cylinder per bone."""
    import trimesh
    parts = []
    for i, p in enumerate(parents):
        ball = trimesh.creation.icosphere(subdivisions=1, radius=radius * 1.3)
        ball.apply_translation(positions[i])
        parts.append(ball)
        if p >= 0 and np.linalg.norm(positions[i] - positions[p]) > 1e-6:
            parts.append(trimesh.creation.cylinder(radius=radius, segment=[positions[p], positions[i]], sections=10))
    mesh: Any = trimesh.util.concatenate(parts)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)
