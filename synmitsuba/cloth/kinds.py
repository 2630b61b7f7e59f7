"""Which garment kinds the cloth stage simulates, of what fabric, and which of their vertices
it holds to the skinned garment (a waistband, a bodice): those move with the body, the rest
hangs from them. A garment kind not listed here stays skinned even under ``cloth: simulated``
(tops and trousers follow the body closely; see issue 34's note)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from synmitsuba.body.garments import SKIRT_CUTS, TUCK, BodyRegions, GarmentParams


@dataclass(frozen=True)
class ClothKind:
    fabric: str                # a name in ``fabrics.FABRICS``
    held: Callable[[np.ndarray, BodyRegions], np.ndarray]  # (rest vertices, body regions) -> (V,) bool
    sealed: bool = False       # its held band closes it round the body: nothing inside rises past it (``seal``)


def above(landmark: str, band: float) -> Callable[[np.ndarray, BodyRegions], np.ndarray]:
    """Hold what lies above a body landmark's height (``waist_y``, ``hip_y``, as the garment
    builder cut at) less ``band`` metres."""
    def held(rest: np.ndarray, regions: BodyRegions) -> np.ndarray:
        return rest[:, 1] >= getattr(regions, landmark) - band
    return held


def through(band: float) -> Callable[[np.ndarray, BodyRegions], np.ndarray]:
    """Hold the garment's top ``band`` metres and the first ring of vertices under them (those
    within 5 mm of the highest vertex below the band: a simulated skirt's level rings are 2-6.5
    cm apart, a short skirt's to a long one's), so the held edge is at least ``band`` down
    whatever the spacing."""
    def held(rest: np.ndarray, regions: BodyRegions) -> np.ndarray:
        y = rest[:, 1]
        inside = y >= y.max() - band
        below = y[~inside]
        return inside | (y >= below.max() - 0.005) if len(below) else inside
    return held


# One entry per simulated garment kind (a name in body.garments.GARMENTS).
CLOTH_KINDS: dict[str, ClothKind] = {
    # hangs from its waistband and yoke, held down past the end of a top tucked into it (the cloth
    # stage's collider is the body alone: a free skirt fell 2-3 cm into the tucked top's end; held
    # the top 4 cm alone, rings 2.05 cm apart left the lowest held one 1 cm above that end, and a
    # squat drew the next in under it), and sealed by it (a jump threw a circle skirt's hem up inside it)
    "skirt": ClothKind("woven", through(TUCK + 0.01), sealed=True),
    "dress": ClothKind("jersey", above("hip_y", 0.02)),   # the bodice follows the body, the skirt hangs from it
    "shift": ClothKind("woven", above("hip_y", 0.02)),
    "wrap": ClothKind("jersey", above("hip_y", 0.02)),
}


def fabric_of(kind: ClothKind, garment: GarmentParams) -> str:
    """The fabric a garment is simulated as: its skirt cut's when the cut names one (pressed
    pleats), else its kind's."""
    return (SKIRT_CUTS[garment.cut].fabric if garment.cut else None) or kind.fabric
