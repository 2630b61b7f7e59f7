"""Air resistance on cloth: each triangle feels the pressure drag of a flat plate moving through
still air, ``-1/2 rho Cd A |v_n| v_n n`` along its normal (``v_n`` the normal part of its
velocity), shared between its three particles. Cloth is light for its area: a 160 g/m² jersey
falling flat reaches about 1.5 m/s, so without air a skirt's hem swings on like a pendulum in a
vacuum (over the head in a jump: issue 34's stability clip 20). Newton's VBD takes it as an
external force, applied explicitly in each step, so a triangle never loses more than its own
normal speed to it in one step (the bound keeps the explicit force stable at any speed)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.schema import Number, check_fields, spec


@dataclass(frozen=True)
class Air:
    density: float = spec(1.2, Number(0.0), doc="kg per cubic metre (1.2 at sea level and 20 °C; 0: a vacuum)")
    drag: float = spec(1.2, Number(0.0), doc="drag coefficient of a flat plate broadside on")

    def __post_init__(self):
        check_fields(self, "cloth.air")


def drag_forces(q: np.ndarray, v: np.ndarray, faces: np.ndarray, areal_density: np.ndarray, dt: float,
                air: Air, sheltered: np.ndarray | None = None) -> np.ndarray:
    """(P, 3) forces (newtons) of ``air`` on particles at ``q`` moving at ``v`` (both (P, 3)),
    from ``faces`` (T, 3) of cloth weighing ``areal_density`` (T,) kg/m², bounded so that a
    step of ``dt`` seconds takes at most a triangle's own normal velocity. ``sheltered`` (T,)
    bool: triangles of cloth worn close over the body (a top), wound with their normal away from
    it, that feel no drag while they move inward, the body's side leading: the air between them
    and the body moves with it (the body's wake). A plate in still air, a t-shirt's back in a run
    was drawn out behind like a cape."""
    a, b, c = q[faces[:, 0]], q[faces[:, 1]], q[faces[:, 2]]
    cross = np.cross(b - a, c - a)
    twice_area = np.sqrt(np.einsum("ij,ij->i", cross, cross))
    n = cross / np.maximum(twice_area, 1e-12)[:, None]
    vel = (v[faces[:, 0]] + v[faces[:, 1]] + v[faces[:, 2]]) / 3
    vn = np.einsum("ij,ij->i", vel, n)
    k = 0.5 * air.density * air.drag  # per area, per speed squared
    rate = np.minimum(k * np.abs(vn) / areal_density, 1.0 / dt)  # 1/s: the bound at rate * dt = 1
    force = -(rate * areal_density * 0.5 * twice_area * vn)[:, None] * n  # mass x normal speed x rate
    if sheltered is not None:
        force[sheltered & (vn < 0)] = 0.0
    out = np.zeros_like(q)
    for j in range(3):  # bincount sums in index order: the same bits at any thread count
        for axis in range(3):
            out[:, axis] += np.bincount(faces[:, j], weights=force[:, axis] / 3, minlength=len(q))
    return out
