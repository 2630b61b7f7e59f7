"""The cloth stage's Warp kernels compiled ahead of the first simulation (``synmitsuba warm``):
Warp compiles a module the first time one of its kernels runs and keeps it in its disk cache
(``WARP_CACHE_PATH``), so a machine image, a cluster's setup step or ``make test`` pays for it
once, before its workers start, instead of each worker's first garment waiting for it."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from synmitsuba.cloth.fabrics import FABRICS
from synmitsuba.cloth.simulate import ClothPiece, ClothSettings, Collider, drape

# a closed box, 2 cm a side, centred 5 cm over the ground: the collider
_BOX = np.array([[x, y, z] for x in (-0.01, 0.01) for y in (0.04, 0.06) for z in (-0.01, 0.01)])
_BOX_FACES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                       [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
# two triangles of cloth just over it
_SHEET = np.array([[-0.02, 0.065, -0.02], [0.02, 0.065, -0.02], [-0.02, 0.065, 0.02], [0.02, 0.065, 0.02]])
_SHEET_FACES = np.array([[0, 2, 1], [1, 2, 3]])


def compile_kernels(settings: ClothSettings | None = None) -> np.ndarray:
    """Drape two triangles over a box for one frame, and keep them out of it, under ``settings``
    (default: the stage's): every Warp module the cloth stage runs is then compiled, or loaded
    from the disk cache. Returns the sheet as draped (4, 3)."""
    from synmitsuba.cloth.outside import keep_outside
    s = settings or ClothSettings()
    piece = ClothPiece(_SHEET_FACES, np.zeros(len(_SHEET), bool), FABRICS["woven"])
    collider = Collider(_BOX_FACES, lambda f: (_BOX, _SHEET), 30.0, 1)
    q = drape([piece], collider, replace(s, settle_s=0.0, substeps=1, max_substeps=1), names=["warm-up sheet"])[0]
    return keep_outside(_BOX, _BOX_FACES, q, s.particle_radius / 2, device=s.device)
