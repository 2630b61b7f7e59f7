"""Size grading: a garment is cut for a size on a chart, and the wearer's girths pick the size
that is theirs. A garment's ``grade`` is how many sizes away from the wearer's it was cut: one
size down sits tight, one size up loose and longer. Girths are measured round the rest body as a
tape measure is (the convex hull of a horizontal slice, at the fullest level): chest between the
waist and the armpits, hips between the crotch and the waist."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from synmitsuba.scene.layers import Layer

SIZES = ("XS", "S", "M", "L", "XL", "XXL", "3XL")
GRADE_ODDS = {-1: 0.15, 0: 0.65, 1: 0.2}  # how often a sampled garment is cut a size small, true, a size large
GRADE_LENGTH = 0.1  # share of its length range a garment gains per size up (sleeves and hems, legs)


@dataclass(frozen=True)
class SizeChart:
    """Body girths (metres) the sizes are cut for: ``first`` for XS, ``step`` more each size up."""

    measure: str   # "chest" or "hip"
    first: float
    step: float = 0.08

    def girth(self, size: int) -> float:
        return self.first + self.step * size

    def size_of(self, girth: float) -> int:
        """The wearer's size: the smallest whose girth is at least theirs (below XS and above 3XL
        the chart goes on in steps)."""
        return math.ceil(round((girth - self.first) / self.step, 9))

    def name(self, size: int) -> str:
        return SIZES[size] if 0 <= size < len(SIZES) else f"{round(self.girth(size) * 100)} cm"


# tops and dresses are sized by the chest, bottoms and skirts by the hips; footwear is not graded
CHARTS = {Layer.TOP: SizeChart("chest", 0.80), Layer.DRESS: SizeChart("chest", 0.80),
          Layer.BOTTOM: SizeChart("hip", 0.86)}


@dataclass(frozen=True)
class Girths:
    """The wearer's tape-measure girths, metres."""

    chest: float
    hip: float


@dataclass(frozen=True)
class Fit:
    """How a graded garment fits its wearer: the size it was cut for (its index and name), the
    chart's girth for it and the wearer's, the chart's step, and ``radial``: metres it stands further out than a
    garment cut at the middle of the wearer's size (negative: tighter)."""

    size: int
    name: str
    girth: float
    body_girth: float
    step: float

    @property
    def ease(self) -> float:
        """Girth to spare round the body, metres (negative: the garment is stretched)."""
        return self.girth - self.body_girth

    @property
    def radial(self) -> float:
        return (self.ease - self.step / 2) / (2 * math.pi)


def perimeter(points_xz: np.ndarray) -> float:
    """Length of the convex hull round 2-D points: a tape measure pulled round them."""
    from scipy.spatial import ConvexHull
    hull = points_xz[ConvexHull(points_xz).vertices]
    return float(np.linalg.norm(hull - np.roll(hull, 1, axis=0), axis=1).sum())


def fullest(vertices: np.ndarray, keep: np.ndarray, low: float, high: float, band: float = 0.01) -> float:
    """The largest girth of the ``keep`` vertices over slices ``band`` thick from ``low`` to ``high``."""
    best = 0.0
    for y in np.arange(low, high, band):
        s = vertices[keep & (np.abs(vertices[:, 1] - y) < band)][:, [0, 2]]
        if len(s) > 8:
            best = max(best, perimeter(s))
    return best


def measure_girths(vertices: np.ndarray, group: np.ndarray, crotch_y: float, waist_y: float,
                   armpit_y: float) -> Girths:
    """Chest (the torso alone, the arms left out) and hips (torso and thighs together)."""
    return Girths(fullest(vertices, group == "torso", waist_y, armpit_y),
                  fullest(vertices, np.isin(group, ["torso", "upperleg"]), crotch_y, waist_y))


def garment_fit(layer: Layer, grade: int, girths: Girths) -> Fit | None:
    """The fit of a garment on ``layer`` cut ``grade`` sizes from the wearer's; None when the
    layer is not graded."""
    chart = CHARTS.get(layer)
    if chart is None:
        return None
    body = getattr(girths, chart.measure)
    size = chart.size_of(body) + grade
    return Fit(size, chart.name(size), round(chart.girth(size), 6), body, chart.step)


def sample_grade(rng: np.random.Generator) -> int:
    return int(list(GRADE_ODDS)[int(rng.choice(len(GRADE_ODDS), p=list(GRADE_ODDS.values())))])
