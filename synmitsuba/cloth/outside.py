"""``keep_outside``: cloth vertices inside a posed body, or closer to it than a margin, set that
margin outside it, at the closest point of the whole body mesh, inside or outside told by the
mesh's winding number (Warp's mesh query, on the CPU: deterministic).

The cloth stage's per-frame push-out (``simulate.out_of_body``) looks only at the triangles round
the nearest few body vertices, which is fast and right where cloth lies over one part of the body;
where a raised thigh runs into a skirt's front, or at an armpit's crease, the nearest vertices are
the torso's and a vertex 1-2 cm inside the thigh read as outside. The held vertices (a bodice
from the skinned shell) and the hem band (set in from its edge) are not simulated and were not
pushed out at all. This pass runs once per output frame over every vertex of the garment."""
from __future__ import annotations

from typing import Any

import numpy as np


def keep_outside(body: np.ndarray, faces: np.ndarray, points: np.ndarray, margin: float,
                 reach: float = 0.1, passes: int = 2, device: str = "cpu") -> np.ndarray:
    """``points`` (N, 3) with those inside the closed mesh (``body``, ``faces``) or under
    ``margin`` over it set ``margin`` outside it along the line from their closest point; the
    others returned unchanged (bit for bit). A second pass takes out what the first moved into
    another part of the body (between two thighs). Where the closest surface is itself inside
    the body (a raised thigh run into the belly) a point can stay inside: that is the body's own
    overlap, not the cloth's. Points farther than ``reach`` from the surface are left alone."""
    import warp as wp

    from synmitsuba.cloth.outside_kernel import push
    q = np.array(points, dtype=np.float64)
    with wp.ScopedDevice(device):
        mesh = wp.Mesh(points=wp.array(np.asarray(body, np.float32), dtype=wp.vec3),
                       indices=wp.array(np.asarray(faces, np.int32).ravel(), dtype=wp.int32),
                       support_winding_number=True)
        for _ in range(passes):
            src: Any = wp.array(q.astype(np.float32), dtype=wp.vec3)
            out = wp.empty(len(q), dtype=wp.vec3)
            moved = wp.empty(len(q), dtype=wp.int32)
            wp.launch(push, dim=len(q), inputs=[mesh.id, src, float(margin), float(reach)], outputs=[out, moved])
            m = moved.numpy().astype(bool)
            if not m.any():
                break
            q[m] = out.numpy()[m]
    return q
