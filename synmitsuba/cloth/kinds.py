"""Which garment kinds the cloth stage simulates, of what fabric, and which of their vertices
it holds to the skinned garment (a waistband, a bodice, a top's yoke, trousers' seat): those move
with the body, the rest hangs from them. A garment kind not listed here stays skinned even under
``cloth: simulated``."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from synmitsuba.body.garments import GARMENTS, SKIRT_CUTS, TUCK, BodyRegions, GarmentParams


@dataclass(frozen=True)
class ClothKind:
    fabric: str                # a name in ``fabrics.FABRICS``
    held: Callable[[np.ndarray, BodyRegions], np.ndarray]  # (rest vertices, body regions) -> (V,) bool
    sealed: bool = False       # its held band closes it round the body: nothing inside rises past it (``seal``)
    # simulated only when nothing is worn over it (a top under a jacket, or tucked into a skirt, stays
    # skinned: a free hem would pass through the skinned garment over it)
    outermost: bool = False
    # its collider holds the skinned garments worn under it as well as the body: against the body alone
    # a top's hem caught between the buttocks and was thrown 0.33 m behind (bench/RESULTS.md, session 86)
    layered: bool = False
    cuffs: float = 0.0         # metres of each sleeve's end held to the skinned sleeve (on the wrist)
    # it bends from flat, as panels sewn flat do, not from its rest shape's curvature: a top's shell is the
    # body's shape, and a back that had left the seat kept the seat's bulge, standing out behind (session 90)
    flat: bool = False
    # particles with under this share of the median particle's cloth are carried by a rigid fit of the cloth
    # round them (``simulate.slight``). A top's is far lower than a skirt's: cut from the body's own mesh, a
    # t-shirt had 180 under 0.35 in patches (armpits, underbust, the back hem's middle) that moved as rigid
    # plates and levered its back hem 0.3 m out behind in a walk; none carried, a tank's particle with no
    # cloth at all (in triangles of zero area) was flung 1.2 m as it settled (bench/RESULTS.md, session 90)
    slight: float = 0.35
    # no air drag on its body side: close over the body, the air between is carried with it (``cloth.air``)
    sheltered: bool = False
    # metres over the body (over the top under it, for a jacket) its held cloth is set at, as the free cloth
    # beside it lies (None: where the skinned garment is). A top's shell stands its offset (1.2-3 cm) off the body;
    # its free cloth falls onto the body (4-8 mm off), and the yoke stood over it in a ledge across the chest and
    # back (bench/RESULTS.md, sessions 100 and 101)
    seat: float | None = None


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


def yoke(band: float) -> Callable[[np.ndarray, BodyRegions], np.ndarray]:
    """Hold a top from ``band`` metres under the shoulder joints up, within their width (2 cm
    more): the shoulders, collar and hood; the chest, back and sleeves hang from it."""
    def held(rest: np.ndarray, regions: BodyRegions) -> np.ndarray:
        sx, sy = regions.shoulder
        return (rest[:, 1] >= sy - band) & (np.abs(rest[:, 0] - regions.neck_xz[0]) <= sx + 0.02)
    return held


SEAT = 0.006  # metres a top's held cloth is set over the body (its free cloth on the upper torso: 4-8 mm)


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
    # a coat over the top (skinned) and the trousers (simulated first), nothing over it: its bodice and sleeves
    # held as a dress's bodice is, and its skirt's top 12 cm (held at the hips alone, a run's lifted thigh threw
    # the skirt up and it stayed bunched over the seat: 0.63 m from the skinned coat, 0.43 m held this way;
    # bench/RESULTS.md, session 96), its cuffs on the wrists; the rest of its skirt, parted down the front
    # (``garments._parted``: closed, it rode up a run's stride to the hips, session 91), hangs from them
    "coat": ClothKind("coating", above("hip_y", 0.14), outermost=True, layered=True, cuffs=0.04, sheltered=True),
    # tops over trousers or shorts (or bare legs), and jackets and blazers over the top (skinned) and the
    # trousers, shorts or skirt (simulated first: ``stages``) under them, nothing over them: hanging from the shoulders,
    # the held cloth seated where the free cloth lies (``seat``: on the body, or on the top under a jacket)
    **{name: ClothKind(fabric, yoke(0.04), outermost=True, layered=True, cuffs=cuffs, flat=True, slight=0.01,
                       sheltered=True, seat=SEAT)
       for name, fabric, cuffs in (("tshirt", "jersey", 0.0), ("tank", "jersey", 0.0), ("longsleeve", "jersey", 0.03),
                                   ("shirt", "woven", 0.03), ("sweater", "knit", 0.04), ("hoodie", "knit", 0.04),
                                   ("jacket", "denim", 0.04), ("blazer", "suiting", 0.04))},
    # trousers and shorts, held from the crotch up (the seat and the crotch, where the legs' tubes would be
    # pinched between the thighs), the legs hanging from there; held further down under a skinned garment
    # that reaches lower (a coat's skirt: ``simulate.simulated_garments``); a jumpsuit the same way, its
    # torso and sleeves held with its seat
    **{name: ClothKind(fabric, above("crotch_y", 0.0), flat=True, slight=0.01, sheltered=True)
       for name, fabric in (("trousers", "twill"), ("shorts", "twill"), ("jeans", "denim"), ("chinos", "twill"),
                            ("joggers", "jersey"), ("jumpsuit", "twill"))},
}


def fabric_of(kind: ClothKind, garment: GarmentParams) -> str:
    """The fabric a garment is simulated as: its skirt cut's when the cut names one (pressed
    pleats), else its kind's."""
    return (SKIRT_CUTS[garment.cut].fabric if garment.cut else None) or kind.fabric


def simulated(worn: Iterable[str]) -> list[str]:
    """The garment kinds of ``worn`` that the cloth stage simulates: those in ``CLOTH_KINDS``
    but an ``outermost`` one with a garment worn over it."""
    worn = list(worn)
    return [w for w in worn if w in CLOTH_KINDS and not (CLOTH_KINDS[w].outermost and worn_over(w, worn))]


def stages(worn: Iterable[str]) -> list[list[str]]:
    """The simulated kinds of ``worn`` in the order the cloth stage simulates them: a ``layered``
    kind after the simulated ones under it, whose simulated cloth its collider holds (a t-shirt
    over trousers); the others first, side by side."""
    free, depth = simulated(worn), dict[str, int]()
    for w in sorted(free, key=lambda w: GARMENTS[w].order):
        under = [depth[u] for u in worn_under(w, free)] if CLOTH_KINDS[w].layered else []
        depth[w] = 1 + max(under) if under else 0
    return [[w for w in free if depth[w] == k] for k in range(max(depth.values(), default=-1) + 1)]


def worn_over(name: str, worn: Iterable[str]) -> list[str]:
    """The garment kinds of ``worn`` (not shoes) that go over garment kind ``name``: higher in
    the dressing order (``GarmentKind.order``: a jacket over a top, a skirt over the top tucked
    into it)."""
    return [w for w in worn if _dressed(w) and GARMENTS[w].order > GARMENTS[name].order]


def worn_under(name: str, worn: Iterable[str]) -> list[str]:
    """The garment kinds of ``worn`` (not shoes) that go under garment kind ``name``: lower in
    the dressing order (trousers under a top)."""
    return [w for w in worn if _dressed(w) and GARMENTS[w].order < GARMENTS[name].order]


def _dressed(kind: str) -> bool:
    return not GARMENTS[kind].footwear
