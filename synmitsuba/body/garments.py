"""Procedural garments: shells offset from body regions (tops, bottoms, dress, shoes) and a
flared skirt surface; all bound to the body by closest-point weight transfer.

Each garment has ``grade`` (the size it is cut for, in sizes from the wearer's own: body/sizing.py;
None in recipes written before size grading, where ``size``, S..XL as 0..1, scales the ease),
``ease`` (looseness, metres),
``length`` (0..1 along its range: hem height for tops, leg length for bottoms, sleeve length
for sleeves) and ``thickness`` (metres). In the rest pose no garment vertex lies inside the body
(vertices that would are pushed out along the surface normal) and layers nest: bottoms < tops <
jackets in offset.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from synmitsuba.body.collide import neighbour_mean, pair_mean
from synmitsuba.body.sizing import GRADE_LENGTH, Fit, Girths, garment_fit, measure_girths, sample_grade
from synmitsuba.body.shoes import (ALLOWANCE, SHOE_STYLES, HeelPitch, foot_points, heel_height, heel_mesh, heel_pitch,
                                   lace_mesh, sample_shoe_texture, shaft_mesh, shoe_material, shoe_mesh)
from synmitsuba.body.textures import GarmentTextureParams
from synmitsuba.body.topology import cut, largest_piece, refine, submesh, weld
from synmitsuba.geometry import face_cross, face_normals, unique_rows, vertex_normals
from synmitsuba.schema import Choice, Nested, Number, Params, optional, spec
from synmitsuba.scene.layers import Layer

CLEARANCE = 0.002
SNUG = 0.003  # metres over its thickness the tightest graded garment stands off the body
LEG_ROOM_RAMP = 0.15  # metres under the crotch over which a bottom cut large lets out to its full room
# trouser legs (``hang_legs``): metres under the crotch over which a leg turns from the seat's shell
# into its tube; metres between the heights its tube is measured at (each over twice that up and
# down); metres off the middle between the legs the tubes stay (the inner seams hang close, not
# through each other); and the percentile of each height's points the tube clears (the thigh's
# fullest side, not a stray point)
LEG_TUBE = (0.08, 0.01, 0.004, 80.0)
# a top's slope going down (``hang_columns``): HANG[0] at an offset of HANG[2] metres, HANG[1] less per metre
# further out, never under HANG[3]; offsets nest (a jacket sits outside the shirt), so slopes do too
# and no inner garment hangs out through the one over it
HANG = (0.85, 19.0, 0.014, 0.12)
ARMPIT = 0.05  # metres under the shoulder joints the chest is measured up to
TUCK = 0.03  # metres under the waist a top worn with a skirt ends
OFFSET_SMOOTHING = 16  # rounds of averaging the body's normals over neighbours before tops stand off along them
OFFSET_BLEND = 0.04    # metres over which the averaged normals take over from the skin's (over the crotch, the waist)
# where a shell stood FOLD[0] metres off along the skin's normals would turn over (under the chest,
# the armpits, the inner elbows), spread over neighbours FOLD[1] rounds and scaled by FOLD[2]: tops
# stand off along the averaged normals there too, from the crotch's height to FOLD[3] under the shoulders'
FOLD = (0.05, 8, 3.0, 0.04)
# a top's room beside the armpits (``free_room``): probed at ROOM[0] x ROOM[1]**k metres out (k < ROOM[2],
# to ~10 cm); a shell takes up to ROOM[3] of the distance to the first probe in another part's reach,
# a room that grows at most ROOM[4] metres per metre over the skin away from its tightest point; it
# hangs out (``hang_columns``) sideways into at most ROOM[5] of the room it leaves (less for the top under: they nest)
ROOM = (0.016, 1.2, 11, 0.75, 0.5, 0.5)
ROOM_NONE = 1.0  # metres: the room where there is no limit (finite: it is interpolated)
ROOM_FREE = 0.15  # metres of room over which no top is scaled (1.5 x the loosest's offset, ~10 cm)
# the share of that scaling a cloth stage's rest shape takes over the torso (a skinned top, and the
# sleeves, take all of it): in full, a t-shirt's back, cut tighter beside the armpits, folded under its
# yoke in a walk (the arm's swing drew it; bench/RESULTS.md, sessions 105 and 109); at half it folds no
# more than unscaled there; and the rings of the body mesh next to the arm over which it rises towards the arm's
ROOM_SIMULATED = 0.5
ROOM_SHARE_RINGS = 4
# and a kind worn over a top (its order ROOM_CAP_ORDER or more: jackets, blazers, coats) never further off
# than ROOM_CAP times the room there: at half, a jacket's flank (6-7 cm off) stood past the middle of the
# gap to the arm, through its own sleeve's underside (hundreds of faces); capped so, a t-shirt (3.5 cm off,
# no faces through) moved 5 mm and folded more under its yoke in a walk (bench/RESULTS.md, session 112)
ROOM_CAP = 1.2
ROOM_CAP_ORDER = 4
# a top under the crotch (``hang_across``): metres over the crotch it starts to hang across both legs;
# metres over which it comes to (in full from the crotch down); metres between the heights it is
# measured at (each over twice that up and down); metres off the middle between the legs each half
# stays (none: the halves meet on one plane; apart, a slit showed between them; overlapping, the
# faces either side of the middle crossed); metres short of the front and back over which points
# put on the middle close in on them (``_within``); the share of its way to the front or back a
# point on the middle next to them is left (``_into_corners``)
ACROSS = (0.08, 0.08, 0.01, 0.0, 0.001, 0.03)
ACROSS_PART = 0.02  # metres either side of the crotch over which points move out from each half's centre, not both's
ACROSS_ANGLES = 90  # directions round each thigh the hull's reach is measured in
ACROSS_SIDE = 0.15  # share of the radius either side of the middle over which it follows both legs (``across_weights``)
ROOM_EDGE = 0.03  # metres: the longest edge of the body's mesh near the armpits, at most (vertices stand for faces)
# a skirt's weights: from the hip line's own down to both legs' over this drop (metres), and a point
# this share of its ring's radius to one side of the centre follows that side's leg alone
LEGS_BLEND, LEGS_SIDE = 0.08, 0.7
GROUPS = {
    "torso": ("root", "pelvis", "spine", "clavicle", "shoulder01"),
    "upperarm": ("upperarm",), "lowerarm": ("lowerarm",), "hand": ("wrist", "finger", "metacarpal"),
    "upperleg": ("upperleg",), "lowerleg": ("lowerleg",), "foot": ("foot", "toe"),
    "head": ("neck", "head", "eye"),
}


# -- body regions a garment covers: level-set fields over the rest body's vertices, in metres,
# >= 0 where the garment covers. Garments are cut along the zero level (not along triangle
# edges), so hems, cuffs and necklines follow smooth curves.
def _top(sleeve: Callable[[float], float], dress: bool = False):
    """Torso from the hem (by ``length``; a dress's bodice stops at the hips) to the neck, and
    the arms to ``sleeve(length)`` (0 shoulder .. 1 wrist)."""
    def region(g, r, v):
        y = v[:, 1]
        hem = r.waist_y - (r.waist_y - (r.crotch_y - 0.12)) * (0.6 if dress else g.length)
        arms = np.isin(r.group, ["upperarm", "lowerarm", "hand"])
        phi = np.where(arms, (sleeve(g.length) - r.arm_s) * r.arm_length, y - hem)
        phi = np.minimum(phi, _neckline(r, v))
        return np.minimum(phi, y - (r.hip_y - 0.02)) if dress else phi  # a dress's skirt is a flared surface
    return region


NECK_EASE = 0.012           # metres a neckline stands off the neck, around its base
NECK_DROP = (0.012, 0.03)   # metres under the neck's base a neckline reaches at the back, at the front
NECK_ROUND = 0.02           # metres over which the neckline turns from the front's dip to round the neck
NECK_TOP = 0.03             # metres over the neck's base a neckline reaches at most (over the trapezius)


def _neckline(r, v: np.ndarray) -> np.ndarray:
    """A crew neckline's field (>= 0 covered): a point is covered if it is farther than the
    neck's radius and ``NECK_EASE`` from the neck's axis or lower than the neckline's lowest
    reach (``NECK_DROP``, deeper at the front), and in any case not over ``NECK_TOP`` above the neck's
    base (the union rounded over ``NECK_ROUND``, or the edge has a corner where it leaves the
    dip). So the edge runs round the neck over the trapezius and dips onto the chest at the
    front, and one field for every body group leaves no step where the torso meets the
    shoulders (a level cut at the neck's height stepped there)."""
    dx, dz = v[:, 0] - r.neck_xz[0], v[:, 2] - r.neck_xz[1]
    rho = np.hypot(dx, dz)
    front = np.clip(dz / np.maximum(rho, 1e-9), 0.0, 1.0)  # cos of the angle from straight ahead (+z)
    low = r.neck_y - (NECK_DROP[0] + (NECK_DROP[1] - NECK_DROP[0]) * front)
    a, b = rho - (r.neck_radius + NECK_EASE), low - v[:, 1]
    either = 0.5 * (a + b + np.sqrt((a - b) ** 2 + NECK_ROUND ** 2))  # max(a, b), rounded where the two meet
    return np.minimum(either, r.neck_y + NECK_TOP - v[:, 1])


TANK_STRAP = 0.018    # metres: half a tank top's strap's width
TANK_SCOOP = 0.1      # metres under the neck's base its neckline reaches, at the front and the back
TANK_ARMHOLE = 0.075  # and its armholes under the shoulder joints
TANK_REACH = 0.12     # of the arm's length from the shoulder: the armholes cut the arm before this
TANK_ROUND = 0.012    # metres: how round the corners where the neckline and the armholes meet the straps


def _tank(g, r, v):
    """A tank top: a top without sleeves, a strap over each shoulder half-way from the neck to
    the joint; between the straps the neckline scoops down in a U at the front and the back
    (a half ellipse from the straps' inner edges at the neck's base), outside them the armholes
    curve down under the shoulders (quarter ellipses from their outer edges at the joints'
    height): each curve leaves its strap's edge upright, and the corner is rounded. The arms
    are cut by the armholes, not where the arm's skin begins (its vertex group: a strap ending
    there had a saw-tooth edge over the shoulder)."""
    base = _top(lambda L: TANK_REACH)(g, r, v)
    ax = np.abs(v[:, 0] - r.neck_xz[0])
    strap_x = r.neck_radius + NECK_EASE + 0.35 * (r.shoulder[0] - r.neck_radius - NECK_EASE)
    inner, outer = strap_x - TANK_STRAP, strap_x + TANK_STRAP
    strap = TANK_STRAP - np.abs(ax - strap_x)
    scoop = r.neck_y - TANK_SCOOP * np.sqrt(1.0 - np.clip(ax / inner, 0.0, 1.0) ** 2)
    out = np.clip((ax - outer) / max(r.shoulder[0] - outer, 0.02), 0.0, 1.0)
    armhole = r.shoulder[1] - TANK_ARMHOLE * np.sqrt(1.0 - (1.0 - out) ** 2)
    a, b = strap, np.where(ax < strap_x, scoop, armhole) - v[:, 1]  # the curves' step hides in the strap
    either = 0.5 * (a + b + np.sqrt((a - b) ** 2 + TANK_ROUND ** 2))  # max(a, b), rounded where they meet
    return np.minimum(base, either)


OPEN_FRONT = (0.26, 0.035)  # metres: how far under the neck's base a coat's front opening closes, and
# how far past the neck's radius it opens either side at the neck
WRAP_V = (0.17, 0.02)       # and a wrap dress's V neckline
BLAZER_V = (0.36, 0.05)     # and a blazer's lapels


def _open_front(region: Callable, v_shape: tuple[float, float] = OPEN_FRONT) -> Callable:
    """``region`` with a V opening down the front from the neck, ``v_shape`` (depth under the
    neck's base, width past the neck's radius at it): a coat's lapels parted over the top under
    it, a wrap dress's neckline."""
    depth, width = v_shape

    def opened(g, r, v):
        ax = np.abs(v[:, 0] - r.neck_xz[0])
        rise = np.clip((v[:, 1] - (r.neck_y - depth)) / depth, 0.0, 1.0)
        gap = np.maximum(ax - rise * (r.neck_radius + width), -r.normals[:, 2])  # where the body faces forward
        return np.minimum(region(g, r, v), gap)
    return opened


def _bottom(reach: Callable[[float], float]):
    """Below the waist, the legs to ``reach(length)`` (0 hip .. 1 ankle)."""
    def region(g, r, v):
        legs = np.isin(r.group, ["upperleg", "lowerleg", "foot"])
        phi = np.where(legs, (reach(g.length) - r.leg_s) * r.leg_length, np.where(r.group == "torso", 1.0, -1.0))
        return np.minimum(phi, r.waist_y - v[:, 1])
    return region


def _union(*regions: Callable) -> Callable:
    """What any of ``regions`` covers."""
    return lambda g, r, v: np.max([region(g, r, v) for region in regions], axis=0)


def _feet(g, r, v):
    """The feet and, by ``length``, the ankles."""
    return (r.group == "foot") | ((r.group == "lowerleg") & (r.leg_s >= 1.0 - 0.08 * g.length))


@dataclass(frozen=True)
class GarmentKind:
    """Everything a garment kind is. ``shape``: ``shell`` (the region offset from the body),
    ``legs`` (a shell whose legs hang as tubes: ``hang_legs``), ``flare`` (a skirt surface from
    the waist), ``shell+flare`` (a dress: bodice + skirt; ``shell+parted``, a coat's, its skirt
    open down the front) or ``hull`` (convex hull of the region, for shoes). ``order``: dressing
    order, lower goes on first and higher kinds sit outside it (shoes are separate): bottoms 1 (a top hangs over
    them), tops and dresses 2, a skirt 3 (over the top tucked into it), jackets and coats 4."""

    layer: Layer
    offset: float                 # base offset from the body surface, metres
    order: int
    shape: str
    region: Callable | None       # (params, BodyRegions, vertices) -> level set (>= 0 covered); shoes: a mask
    length: tuple[float, float]   # sampled length range
    ease: tuple[float, float] = (0.0, 0.015)
    thickness: tuple[float, float] = (0.002, 0.006)
    fabric: str = "plain"         # textures.FABRICS: the thread-scale normal map a texture's weave "auto" takes
    footwear: bool = False        # under the feet: lifts the body by its offset, outside the stack of clothes
    skirted: bool = False         # a skirt or a dress (rare in men's sampled outfits)
    tucks_tops: bool = False      # tops worn with it end tucked under the waist
    takes_jacket: bool = True     # a sampled jacket may go over it
    material: Callable | None = None  # (params, texture size) -> Material; None: garment_material
    cut: str | None = None        # a flare's cut (SKIRT_CUTS) when the garment names none; None: a_line
    prints: bool = False          # a drawn decal is printed on its chest (other kinds are drawn without one)
    panels: str | None = None     # its pattern laid on these panels (body.panels.PANEL_LAYOUTS); None: over its uv
    # a ``legs`` shape's: metres its tubes may come in towards each leg's middle a metre down (above the knee, below it)
    taper: tuple[float, float] = (0.0, 0.0)


# One entry per kind: a new garment kind is one line here (and, to be sampled, an outfit).
GARMENTS: dict[str, GarmentKind] = {
    "tshirt": GarmentKind(Layer.TOP, 0.012, 2, "shell", _top(lambda L: 0.15 + 0.25 * L), (0.2, 0.7),
                          fabric="jersey", prints=True, panels="top"),
    "longsleeve": GarmentKind(Layer.TOP, 0.012, 2, "shell", _top(lambda L: 0.85 + 0.1 * L), (0.3, 0.8),
                              fabric="jersey", prints=True, panels="top"),
    "jacket": GarmentKind(Layer.TOP, 0.03, 4, "shell", _top(lambda L: 0.9 + 0.08 * L), (0.4, 1.0),
                          (0.005, 0.03), (0.002, 0.01), fabric="twill", panels="top"),
    "tank": GarmentKind(Layer.TOP, 0.01, 2, "shell", _tank, (0.25, 0.7), fabric="jersey", prints=True, panels="top"),
    "sweater": GarmentKind(Layer.TOP, 0.018, 2, "shell", _top(lambda L: 0.92 + 0.06 * L), (0.45, 0.8),
                           (0.01, 0.03), (0.004, 0.008), fabric="jersey", panels="top"),
    # a long coat: a jacket's bodice to the hips and a skirt from them to the knees (skinned to both legs)
    "coat": GarmentKind(Layer.TOP, 0.025, 4, "shell+parted", _open_front(_top(lambda L: 0.95, dress=True)), (0.35, 0.65),
                        (0.005, 0.02), (0.004, 0.01), fabric="twill", cut="straight", panels="dress"),
    "hoodie": GarmentKind(Layer.TOP, 0.016, 2, "shell+hood", _top(lambda L: 0.95 + 0.05 * L), (0.45, 0.8),
                          (0.01, 0.03), (0.003, 0.006), fabric="jersey", prints=True, panels="top"),
    "shirt": GarmentKind(Layer.TOP, 0.012, 2, "shell+collar", _top(lambda L: 0.93 + 0.07 * L), (0.4, 0.8),
                         (0.005, 0.02), (0.002, 0.004), fabric="plain", panels="top"),
    # a blazer: a jacket's hip-length bodice, open over the top in a V down to its buttons
    "blazer": GarmentKind(Layer.TOP, 0.025, 4, "shell", _open_front(_top(lambda L: 0.95), BLAZER_V), (0.3, 0.55),
                          (0.005, 0.02), (0.003, 0.008), fabric="plain", panels="top"),
    # bottoms: the seat a shell, the legs tubes hanging round them (``hang_legs``), straight from the thigh
    # (shorts), a little tapered to the hem (trousers, chinos; jeans slimmer), or gathered to the ankle (joggers)
    "shorts": GarmentKind(Layer.BOTTOM, 0.005, 1, "legs", _bottom(lambda L: 0.1 + 0.35 * L), (0.1, 0.45),
                          fabric="twill", panels="bottom", taper=(0.05, 0.05)),
    "trousers": GarmentKind(Layer.BOTTOM, 0.005, 1, "legs", _bottom(lambda L: 0.75 + 0.27 * L), (0.85, 1.0),
                            fabric="twill", panels="bottom", taper=(0.14, 0.012)),
    "jeans": GarmentKind(Layer.BOTTOM, 0.004, 1, "legs", _bottom(lambda L: 0.75 + 0.27 * L), (0.85, 1.0),
                         (0.0, 0.012), fabric="twill", panels="bottom", taper=(0.16, 0.025)),
    "chinos": GarmentKind(Layer.BOTTOM, 0.005, 1, "legs", _bottom(lambda L: 0.75 + 0.27 * L), (0.85, 1.0),
                          fabric="twill", panels="bottom", taper=(0.14, 0.02)),
    # joggers: jersey, tapering to above the ankle (their gathered cuffs are not modelled)
    "joggers": GarmentKind(Layer.BOTTOM, 0.008, 1, "legs", _bottom(lambda L: 0.9 + 0.06 * L), (0.0, 1.0),
                           (0.005, 0.02), (0.002, 0.005), fabric="jersey", panels="bottom", taper=(0.14, 0.12)),
    "skirt": GarmentKind(Layer.BOTTOM, 0.006, 3, "flare", None, (0.2, 0.8), (0.005, 0.03), skirted=True,
                         tucks_tops=True, panels="skirt"),
    "dress": GarmentKind(Layer.DRESS, 0.012, 2, "shell+flare", _top(lambda L: 0.2 * L, dress=True), (0.3, 0.9),
                         (0.005, 0.03), skirted=True, takes_jacket=False, panels="dress"),
    # a shift: sleeveless, straight, to the knees; a wrap: a V neckline, elbow sleeves, flared
    "shift": GarmentKind(Layer.DRESS, 0.012, 2, "shell+flare", _top(lambda L: -0.1, dress=True), (0.3, 0.6),
                         (0.005, 0.02), skirted=True, takes_jacket=False, cut="straight", panels="dress"),
    "wrap": GarmentKind(Layer.DRESS, 0.012, 2, "shell+flare", _open_front(_top(lambda L: 0.3 + 0.2 * L, dress=True),
                                                                        WRAP_V), (0.35, 0.9), (0.005, 0.03),
                        skirted=True, takes_jacket=False, panels="dress"),
    # a one-piece from the neck to the ankles: a top's torso and sleeves and trousers' legs
    "jumpsuit": GarmentKind(Layer.DRESS, 0.01, 2, "legs", _union(_top(lambda L: 0.1 + 0.8 * L),
                                                                   _bottom(lambda L: 0.9 + 0.12 * L)),
                            (0.0, 1.0), (0.005, 0.02), fabric="twill", takes_jacket=False, panels="one_piece",
                            taper=(0.1, 0.015)),
    "shoes": GarmentKind(Layer.SHOES, 0.004, 0, "hull", _feet, (0.2, 0.8), fabric="none", footwear=True),
    # built round the foot (body/shoes.py); thickness is the sole's height, length the collar's (and shaft's)
    **{name: GarmentKind(Layer.SHOES, ALLOWANCE, 0, "heeled" if SHOE_STYLES[name].heel[1] else "shoe", None,
                         (0.0, 1.0), (0.0, 0.004), sole, fabric="none", footwear=True,
                         material=lambda g, size: shoe_material(SHOE_STYLES[g.kind], g.texture, size))
       for name, sole in (("sneakers", (0.02, 0.032)), ("boots", (0.02, 0.032)), ("dress_shoes", (0.012, 0.018)),
                          ("sandals", (0.01, 0.022)), ("heels", (0.006, 0.01)))},
}
KINDS = tuple(GARMENTS)
# outfits sample_subject draws from (a jacket and shoes are added by chance)
OUTFITS = (("tshirt", "trousers"), ("tshirt", "shorts"), ("longsleeve", "trousers"), ("tshirt", "skirt"),
           ("longsleeve", "skirt"), ("dress",), ("longsleeve", "shorts"))


@dataclass(frozen=True)
class SkirtCut:
    """How a skirt (or a dress's skirt) is cut. Its radius round the body's reach at each height
    grows by ``flare + ease_flare * ease`` metres from the waist to the hem, as the height
    share to the power ``curve``; on it, ``folds`` waves round the skirt (pleats or the godets
    a full skirt falls into), ``depth`` metres from crest to trough, pressed flat for
    ``stitched`` metres under the top and deepening over the next ``ramp`` (None: down to the
    hem); ``sharp``: pleats (a zigzag) rather than soft waves. ``fabric``: what the cloth stage
    simulates it as (a name in ``cloth.fabrics.FABRICS``; None: its garment kind's).
    ``vent``: metres of slit up the centre back from the hem (a straight cut's: a narrow skirt
    is walked in through its vent; closed, a stride stretched its hem 9-15 cm).
    ``share``: how often a sampled skirt has this cut."""

    flare: float
    ease_flare: float = 0.4
    curve: float = 1.3
    folds: int = 0
    depth: float = 0.0
    stitched: float = 0.1
    ramp: float | None = None
    sharp: bool = False
    fabric: str | None = None
    vent: float = 0.0
    share: float = 0.0


# One entry per cut; a garment's ``cut`` names one (None: "a_line", as every skirt was cut first).
SKIRT_CUTS: dict[str, SkirtCut] = {
    "a_line": SkirtCut(0.06, share=0.4),
    "pleated": SkirtCut(0.05, folds=12, depth=0.035, stitched=0.1, ramp=0.05, sharp=True,
                        fabric="suiting", share=0.25),  # pressed: holds its creases
    "circle": SkirtCut(0.1, 1.0, 1.0, folds=10, depth=0.1, stitched=0.04, share=0.2),
    "straight": SkirtCut(0.02, 0.2, 2.0, vent=0.18, share=0.15),
}


@dataclass
class GarmentParams(Params):
    kind: str = spec("tshirt", Choice(GARMENTS))
    size: float = spec(0.5, Number(0, 1), doc="S..XL as 0..1; recipes without a grade only")
    ease: float = spec(0.01, Number(0, 0.06), doc="looseness, metres")
    length: float = spec(0.5, Number(0, 1), doc="along the kind's range")
    thickness: float = spec(0.003, Number(0.0005, 0.04), doc="metres (footwear: the sole)")
    texture: GarmentTextureParams = spec(factory=GarmentTextureParams, check=Nested(GarmentTextureParams))
    cut: str | None = spec(None, optional(Choice(SKIRT_CUTS)), doc="skirts and dresses: a SKIRT_CUTS name; None: a_line")
    grade: int | None = spec(None, optional(Choice((-2, -1, 0, 1, 2))),
                             doc="sizes from the wearer's own it is cut for (-1 tight, 1 loose); None: ungraded (size)")


# footwear drawn with an outfit: no boots under long trousers (their shaft would cut through the legs),
# heels with skirts and dresses only (last: an outfit without a skirt draws as it did before heels)
FOOTWEAR = {"sneakers": 0.5, "dress_shoes": 0.2, "boots": 0.15, "sandals": 0.15, "heels": 0.3}


def sample_footwear(shoes: GarmentParams, outfit) -> GarmentParams:
    """A styled pair in place of a sampled ``shoes`` entry, drawn from its texture seed (so the
    subject's other draws are the ones they were before shoes had styles)."""
    rng = np.random.default_rng([shoes.texture.seed, 7])
    skirted = any(GARMENTS[k].skirted for k in outfit)
    weights = {k: 0.0 if (k == "boots" and "trousers" in outfit) or (k == "heels" and not skirted) else w
               for k, w in FOOTWEAR.items()}
    p = np.array(list(weights.values()))
    kind = list(weights)[int(rng.choice(len(p), p=p / p.sum()))]
    return sample_garment(kind, rng)


# Where a print goes on the body's uv atlas (the template's, so the same on every body): the
# chest's centre line 14-18 cm under the neck's base; u runs to the wearer's left (+x), v up.
CHEST_UV = (0.377, 0.72)
LOGO_UV = (0.045, 0.02)  # a logo sits on the left chest: 9 cm across from the centre line, 3 cm up
LOGO_SIZE = 0.08         # a drawn decal size under this is a logo (3-4 cm), over it a chest print (6-12 cm)
# Metres per unit u over per unit v on a kind's mesh, as measured before patterns went on panels
# (body.panels): the body's uv atlas (1.25-1.5 by body; the chest's 1.47), a skirt's own uv, a
# dress's bodice and flare. Only a decal reads it now: a print on the chest (tests/test_subject.py
# measures the atlas's); a sampled recipe still records its kind's.
UV_ASPECTS = {"body": 1.35, "skirt": 1.9, "dress": 2.7}


def uv_aspect(kind: GarmentKind) -> float:
    """``UV_ASPECTS``' entry for a garment kind."""
    if kind.shape == "flare":
        return UV_ASPECTS["skirt"]
    return UV_ASPECTS["dress" if kind.layer == Layer.DRESS and "flare" in kind.shape else "body"]


def lay_out(t: GarmentTextureParams, kind: GarmentKind) -> GarmentTextureParams:
    """A drawn texture ``t`` laid out on a garment of ``kind`` (no draws): square on its cloth
    (``uv_aspect``) and its decal printed on the chest of a kind that ``prints`` (centred, or a
    logo on the left chest; the drawn centre moves a print up or down), dropped on other kinds,
    where a decal drawn anywhere in the uv square came out on a hip, a thigh or a skirt's side."""
    aspect = uv_aspect(kind)
    if not kind.prints or t.decal == "none":
        return dataclasses.replace(t, uv_aspect=aspect, decal="none")
    d = t.decal_size
    if d < LOGO_SIZE and t.decal != "band":
        centre, size = [CHEST_UV[0] + LOGO_UV[0], CHEST_UV[1] + LOGO_UV[1]], 0.021 + 0.2 * (d - 0.05)
    else:
        centre = [CHEST_UV[0], CHEST_UV[1] + 0.04 * (t.decal_center[1] - 0.5)]
        size = 0.042 + 0.35 * max(d - LOGO_SIZE, 0.0)
    return dataclasses.replace(t, uv_aspect=aspect, decal_center=[round(x, 4) for x in centre],
                               decal_size=round(size, 4))


def sample_garment(kind: str, rng: np.random.Generator) -> GarmentParams:
    from synmitsuba.body.textures import sample_garment_texture
    k = GARMENTS[kind]
    style = SHOE_STYLES.get(kind)
    g = GarmentParams(kind=kind, size=round(float(rng.uniform(0, 1)), 3), ease=round(float(rng.uniform(*k.ease)), 4),
                      length=round(float(rng.uniform(*k.length)), 3),
                      thickness=round(float(rng.uniform(*k.thickness)), 4),
                      texture=sample_shoe_texture(style, rng) if style else lay_out(sample_garment_texture(rng), k))
    # drawn from the texture's seed: the subject's other draws stay as they were before grading
    return g if k.footwear else dataclasses.replace(g, grade=sample_grade(np.random.default_rng([g.texture.seed, 11])))


@dataclass
class BodyRegions:
    """Per-vertex group names and landmark heights of a shaped rest body."""

    group: np.ndarray        # (V,) group name per vertex
    normals: np.ndarray      # (V, 3) the skin's vertex normals
    outward: np.ndarray      # (V, 3) what tops and dresses stand off along (``offset_directions``)
    arm_s: np.ndarray        # (V,) 0 at the shoulder .. 1 at the wrist (arm and hand vertices)
    leg_s: np.ndarray        # (V,) 0 at the hip .. 1 at the ankle (leg and foot vertices)
    arm_length: float        # shoulder to wrist, metres
    leg_length: float        # hip to ankle, metres
    waist_y: float
    hip_y: float
    crotch_y: float
    neck_y: float
    neck_xz: tuple = (0.0, 0.0)  # the neck's axis (x, z) just above its base
    neck_radius: float = 0.06    # and its radius there (75th percentile: the outer surface)
    shoulder: tuple = (0.17, 1.4)  # the shoulder joints' |x| from the neck's axis and height, metres
    girths: Girths | None = None   # tape-measure chest and hips (body/sizing.py): what graded garments fit
    room: np.ndarray | None = None  # (V,) metres a top may stand off each vertex along ``outward`` (``free_room``)
    widest: float = 0.0  # metres: the loosest top's offset of the outfit worn (``outfit_widest``), which tops scale by
    hang: bool = False  # skinned tops: scaled to ``room`` in full
    across: bool = False  # a long top hangs across both legs under the crotch (``hang_across``)


def offset_directions(v: np.ndarray, faces: np.ndarray, normals: np.ndarray, low: float, high: float,
                      top: float, cloth: np.ndarray, rounds: int = OFFSET_SMOOTHING, blend: float = OFFSET_BLEND) -> np.ndarray:
    """The directions tops and dresses stand off along: the body's unit ``normals`` averaged
    over neighbours ``rounds`` times between the heights ``low`` and ``high`` (over the small of
    the back) and where the skin's own would fold a loose top over itself (``fold_prone``, over
    the ``cloth`` vertices, from ``low`` up to ``top``), elsewhere the skin's own, blended over
    ``blend`` metres. Offset along the skin's own normals, a loose top folds over itself where
    the body curves tighter than its offset (a sweater 39 mm off: 88 faces over the torso turned
    to the body, a dark triangle at the spine from behind, a hard crease under the chest); the
    averaged directions spread apart there. Averaged under the crotch's height too, they tilted
    a t-shirt's back hem down under the buttocks, where a walking thigh caught its simulated
    cloth and dragged it 25 cm behind; over the shoulder blades, the simulated t-shirt's cloth
    under its held yoke turned down in a shelf; round the neck, they rippled a neckline. One
    field for all tops: a jacket and the sweater under it lie on the same lines, in order."""
    mean = neighbour_mean(faces, len(normals))
    n = normals
    for _ in range(rounds):
        n = mean @ n
        n = n / np.linalg.norm(n, axis=1, keepdims=True)
    above = _ease((v[:, 1] - low) / blend)
    t = np.maximum(above * _ease((high - v[:, 1]) / blend),
                   above * _ease((top - v[:, 1]) / blend) * fold_prone(v, faces, normals, mean, cloth))
    n = normals + t[:, None] * (n - normals)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def fold_prone(v: np.ndarray, faces: np.ndarray, normals: np.ndarray, mean, cloth: np.ndarray,
               reach: float = FOLD[0], rounds: int = FOLD[1], gain: float = FOLD[2]) -> np.ndarray:
    """(V,) from 0 to 1: how near a vertex is to a face among the ``cloth`` vertices whose copy
    moved ``reach`` out along the unit vertex ``normals`` turns over (where the body curves
    tighter than that), by ``rounds`` of taking the larger of a vertex's weight and its
    neighbours' mean (``mean``, row-normalised adjacency), times ``gain``, eased."""
    turned = (face_cross(v, faces) * face_cross(v + reach * normals, faces)).sum(1) < 0
    weight = np.zeros(len(v))
    weight[faces[turned & cloth[faces].all(1)].ravel()] = 1.0
    for _ in range(rounds):
        weight = np.maximum(weight, mean @ weight)
    return _ease(gain * weight)


def _ease(t: np.ndarray) -> np.ndarray:
    """``t`` clipped to [0, 1] and eased in and out (smoothstep)."""
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def free_room(body, directions: np.ndarray, where: np.ndarray, part: np.ndarray) -> np.ndarray:
    """(V,) metres a top may stand off each vertex ``where`` (a mask) along ``directions``
    before its shell runs into another part's: ``ROOM[3]`` of the first probe out along it
    that is nearer to another ``part`` (V,) of the skin than it is to its own vertex (beside the
    armpit, the arm's underside over the torso's flank, the flank under the arm), spread
    (``spread_room``); inf where no probe is. A jacket's shells (67 mm off) met there in the rest
    pose and went through each other: faces turned to the body by the hundred, a black notch
    in the armpit with an arm raised. Hollows within one part (under the bust) are left to
    ``fold_prone`` and ``hang_columns``: spread from there, a room held a jacket in over the whole chest."""
    from pykdtree.kdtree import KDTree
    v, index = body.vertices, body.surface()
    others = {k: KDTree(np.ascontiguousarray(v[part != k], dtype=np.float64)) for k in np.unique(part)}
    ids = np.flatnonzero(where)
    room = np.full(len(v), np.inf)
    for s in ROOM[0] * ROOM[1] ** np.arange(ROOM[2]):
        p = v[ids] + s * directions[ids]
        near = np.full(len(ids), np.inf)  # the nearest vertex of another part: the skin is no nearer than an edge less
        for k, tree in others.items():
            mine = part[ids] == k
            near[mine] = tree.query(p[mine])[0]
        look = np.flatnonzero(near < s + ROOM_EDGE)
        if not len(look):
            continue
        closest, tri, bary = index.closest(p[look])
        hit = look[(np.linalg.norm(p[look] - closest, axis=1) < s) & (part[body.faces[tri, bary.argmax(1)]] != part[ids[look]])]
        room[ids[hit]] = ROOM[3] * s
        ids = np.delete(ids, hit)
    room = spread_room(room, v, body.faces)
    return np.where(room < ROOM_FREE, room, np.inf)  # where ``fit_offset`` leaves every top as it is


def spread_room(room: np.ndarray, v: np.ndarray, faces: np.ndarray, slope: float = ROOM[4]) -> np.ndarray:
    """``room`` (V,) lowered so it grows at most ``slope`` metres per metre along the mesh's
    edges: a shell eases out of a tight spot instead of stepping out of it. The least over the
    tight spots of their room plus ``slope`` times the path to them (Dijkstra from one node
    joined to each by its room over ``slope``)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra
    tight = np.flatnonzero(np.isfinite(room))
    if not len(tight):
        return room.copy()
    e = unique_rows(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1))
    n = len(v)
    a = np.concatenate([e[:, 0], np.full(len(tight), n)])
    b = np.concatenate([e[:, 1], tight])
    w = np.concatenate([np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1), room[tight] / slope])
    graph = coo_matrix((w, (a, b)), shape=(n + 1, n + 1)).tocsr()
    return slope * dijkstra(graph, directed=False, indices=n)[:n]


def fit_offset(offset: float, room: np.ndarray, widest: float) -> np.ndarray:
    """A shell's offset at each point: ``offset`` scaled by as much as the ``widest`` top's
    (the loosest worn over the same body) must be to stay within ``room`` (min(room / widest, 1),
    eased from 0.5 to 1.5 x): tops worn one over the other keep their order and their share of
    the room. Eased down to the room each alone, a jacket came within 0.3 mm of the shirt under
    it at the armpit, and the shirt showed through it with the arm raised. Exactly ``offset``
    where the room is 1.5 x ``widest`` or more."""
    t = room / widest
    fit = np.where(t <= 0.5, t, np.where(t < 1.5, t - 0.5 * (t - 0.5) ** 2, 1.0))
    return offset * fit


def dress_regions(body, r: BodyRegions, garments, skinned: bool = True) -> BodyRegions:
    """``r`` for an outfit of ``garments``: its loosest top's offset (``outfit_widest``) and,
    with a top worn, the room beside the armpits (``free_room``, over the torso and arms above
    the waist) that a top's hang moves sideways into at most (``hang_columns``) and that tops
    scale their offsets to (``fit_offset``; a cloth stage's rest shapes by ``_room_share``);
    ``skinned``, tops scale in full. Long tops hang across both legs under the crotch
    (``hang_across``; the cloth stage's sewn into one tube, ``close_middle``). ``body`` is the
    body ``r`` was measured on."""
    widest = outfit_widest(r, garments)
    if not widest:
        return dataclasses.replace(r, widest=widest)
    v = body.vertices
    probed = np.isin(r.group, ["torso", "upperarm", "lowerarm"]) & (v[:, 1] > r.waist_y)
    return dataclasses.replace(r, widest=widest, hang=skinned, across=True, room=free_room(body, r.outward, probed,
                                                                   np.isin(r.group, ["upperarm", "lowerarm", "hand"])))


def outfit_widest(r: BodyRegions, garments) -> float:
    """The offset of the loosest top or dress among ``garments`` (``GarmentParams``) as
    ``build_garment`` stands them off this body, each outside the ones before it."""
    below, widest = 0.0, 0.0
    for g in sorted(garments, key=lambda g: GARMENTS[g.kind].order):
        kind = GARMENTS[g.kind]
        if kind.footwear:
            continue
        below = garment_offset(g, below, _fit(kind, g, r))
        widest = max(widest, below) if kind.layer in (Layer.TOP, Layer.DRESS) else widest
    return widest


def _fit(kind: GarmentKind, g: GarmentParams, r: BodyRegions) -> Fit | None:
    """A graded garment's size on this body (None for an ungraded one or footwear)."""
    return garment_fit(kind.layer, g.grade, r.girths) if g.grade is not None and r.girths and not kind.footwear else None


def body_regions(body) -> BodyRegions:
    sk = body.skeleton
    bones = np.array([next((g for g, keys in GROUPS.items() if any(k in name for k in keys)), "torso")
                      for name in sk.names])
    group = bones[body.weights.argmax(1)]
    v = body.vertices
    arm_s = np.zeros(len(v))
    leg_s = np.zeros(len(v))
    arm_len, leg_len = [], []
    for side in ("L", "R"):
        sh, wr = sk.rest_positions[sk.index(f"upperarm01.{side}")], sk.rest_positions[sk.index(f"wrist.{side}")]
        axis = wr - sh
        arm = np.isin(group, ["upperarm", "lowerarm", "hand"]) & ((v[:, 0] > 0) == (side == "L"))
        arm_s[arm] = ((v[arm] - sh) @ axis) / (axis @ axis)
        hip, ank = sk.rest_positions[sk.index(f"upperleg01.{side}")], sk.rest_positions[sk.index(f"foot.{side}")]
        leg = np.isin(group, ["upperleg", "lowerleg", "foot"]) & ((v[:, 0] > 0) == (side == "L"))
        leg_s[leg] = (hip[1] - v[leg, 1]) / (hip[1] - ank[1])
        arm_len.append(np.linalg.norm(axis))
        leg_len.append(hip[1] - ank[1])
    hip_y = float(sk.rest_positions[sk.index("upperleg01.L"), 1])
    crotch_y, waist_y = hip_y - 0.07, float(sk.rest_positions[sk.index("spine03"), 1])
    armpit_y = float(sk.rest_positions[sk.index("upperarm01.L"), 1]) - ARMPIT
    neck_y = float(sk.rest_positions[sk.index("neck01"), 1]) - 0.01
    ring = v[(group == "head") & (np.abs(v[:, 1] - neck_y - 0.03) < 0.01)][:, [0, 2]]
    centre = ring.mean(0)
    normals = vertex_normals(v, body.faces)
    outward = offset_directions(v, body.faces, normals, crotch_y, waist_y + OFFSET_BLEND,
                                float(sk.rest_positions[sk.index("upperarm01.L"), 1]) - FOLD[3],
                                np.isin(group, ["torso", "upperarm", "lowerarm"]))
    return BodyRegions(group, normals, outward, arm_s, leg_s,
                       float(np.mean(arm_len)), float(np.mean(leg_len)),
                       waist_y=waist_y, hip_y=hip_y, crotch_y=crotch_y,
                       neck_y=neck_y, neck_xz=(float(centre[0]), float(centre[1])),
                       neck_radius=float(np.percentile(np.linalg.norm(ring - centre, axis=1), 75)),
                       shoulder=(float(np.mean([abs(sk.rest_positions[sk.index(f"upperarm01.{s}"), 0] - centre[0])
                                                for s in "LR"])), float(sk.rest_positions[sk.index("upperarm01.L"), 1])),
                       girths=measure_girths(v, group, crotch_y, waist_y, armpit_y))


def sample_skirt_cut(g: GarmentParams) -> GarmentParams:
    """``g`` with a cut from ``SKIRT_CUTS`` (by share) when it is a skirt or a dress, drawn from
    its texture seed (so the subject's other draws are the ones they were before skirts had cuts)."""
    if not GARMENTS[g.kind].skirted or GARMENTS[g.kind].cut:  # a kind with its own cut keeps it
        return g
    rng = np.random.default_rng([g.texture.seed, 11])
    names = [k for k, c in SKIRT_CUTS.items() if c.share > 0]
    share = np.array([SKIRT_CUTS[k].share for k in names])
    return dataclasses.replace(g, cut=names[int(rng.choice(len(names), p=share / share.sum()))])


def _plain_cloth(t: GarmentTextureParams, rng: np.random.Generator, palette, amplitude: tuple[float, float],
                 scale: float) -> GarmentTextureParams:
    """``t`` in a colour drawn from ``palette``, no pattern or print, a mottled ``noise`` bump
    (amplitude drawn from ``amplitude``, at ``scale``): denim, wool, chinos, heathered jersey."""
    base = palette[int(rng.integers(len(palette)))]
    return dataclasses.replace(t, base_lab=[float(x) for x in base], pattern="none", decal="none", bump="noise",
                               bump_amplitude=round(float(rng.uniform(*amplitude)), 3), bump_scale=scale)


DENIM = ([26, 3, -24], [34, 2, -27], [45, 0, -25], [58, -2, -20], [70, -3, -14], [20, 0, -4], [14, 0, 0])


def _denim(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """Jeans: indigo denim from dark rinse to light wash (or black), plain, a faint mottled wash."""
    return _plain_cloth(t, rng, DENIM, (0.15, 0.35), 40.0)


def _knitted(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """A sweater: its colour (and any stripes or checks) knitted, the loops over it; no print."""
    return dataclasses.replace(t, decal="none", bump="knit", bump_amplitude=round(float(rng.uniform(0.5, 0.9)), 3),
                               bump_scale=round(float(rng.uniform(25, 45)), 3))


WOOL = ([60, 8, 28], [15, 0, 0], [30, 0, -2], [22, 3, -20], [50, 0, -2], [40, -6, 18], [28, 25, 8], [72, 3, 15])


def _wool(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """A coat: plain wool in a coat's colours (camel, black, charcoal, navy, grey, olive,
    burgundy, beige), no print."""
    return _plain_cloth(t, rng, WOOL, (0.1, 0.3), 60.0)


CHINO = ([62, 3, 20], [72, 1, 10], [25, 2, -18], [42, -5, 18], [18, 0, 0], [48, 8, 24], [55, 0, -2])


def _chino(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """Chinos: plain cotton twill in khaki, stone, navy, olive, black, tan or grey."""
    return _plain_cloth(t, rng, CHINO, (0.05, 0.15), 60.0)


SHIRTING = ([95, 0, 2], [86, -2, -10], [88, 6, 3], [80, 0, -1], [28, 2, -18], [74, -4, -18], [15, 0, 0])


def _shirting(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """A shirt: shirting (white, pale blue, pale pink, light grey, navy, sky blue, black), plain,
    in fine stripes or in gingham checks of a darker shade."""
    base = [float(x) for x in SHIRTING[int(rng.integers(len(SHIRTING)))]]
    pattern = str(rng.choice(["none", "stripes", "checks"], p=[0.5, 0.25, 0.25]))
    ink = [max(base[0] - 35.0, 10.0), base[1], base[2] - 15.0 * (base[0] > 60)]
    return dataclasses.replace(t, base_lab=base, pattern=pattern, decal="none", pattern_lab=ink,
                               pattern_width=0.08 if pattern == "stripes" else 0.5,
                               pattern_scale=round(float(rng.uniform(48, 64)), 3), pattern_alpha=0.7,
                               uv_rotation_deg=90.0, bump="none")  # the stripes run down the body


HEATHER = ([58, 0, -1], [36, 0, -2], [15, 0, 0], [24, 2, -16], [40, -4, 14], [70, 0, 0], [30, 12, 2])


def _heather(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """Joggers: heathered fleece jersey (grey, charcoal, black, navy, olive, light grey, maroon),
    mottled, no print."""
    return _plain_cloth(t, rng, HEATHER, (0.2, 0.4), 90.0)


def _fleece(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """A hoodie: heathered fleece (``HEATHER``'s colours) or its own colour, plain or with a
    print on the chest, no pattern."""
    base = [float(x) for x in HEATHER[int(rng.integers(len(HEATHER)))]] if rng.random() < 0.6 else t.base_lab
    return dataclasses.replace(t, base_lab=base, pattern="none", bump="noise",
                               bump_amplitude=round(float(rng.uniform(0.2, 0.4)), 3), bump_scale=90.0)


SUITING = ([22, 1, -14], [30, 0, -2], [14, 0, 0], [50, 0, -2], [66, 3, 14], [32, 6, 12], [40, -3, 6])


def _suiting(t: GarmentTextureParams, rng: np.random.Generator) -> GarmentTextureParams:
    """A blazer: suiting (navy, charcoal, black, grey, beige, brown, olive), plain or, one in
    five, a fine pinstripe a little lighter than the cloth."""
    base = [float(x) for x in SUITING[int(rng.integers(len(SUITING)))]]
    pin = rng.random() < 0.2
    return dataclasses.replace(t, base_lab=base, pattern="stripes" if pin else "none", decal="none",
                               pattern_lab=[min(base[0] + 25.0, 95.0), base[1], base[2]], pattern_width=0.06,
                               pattern_scale=round(float(rng.uniform(24, 40)), 3), pattern_alpha=0.6,
                               uv_rotation_deg=0.0, bump="noise", bump_amplitude=0.1, bump_scale=60.0)


@dataclass(frozen=True)
class Style:
    """A garment kind a sampled garment of another kind may be made as instead (``GARMENT_STYLES``):
    ``share`` of them, when ``worn_with(outfit)``; ``texture(params, rng)`` restyles its texture."""

    kind: str
    share: float
    texture: Callable | None = None
    worn_with: Callable[[list], bool] = lambda outfit: True


# A sampled kind's other styles (the rest of its share stays the kind itself): a new style is a
# garment kind (GARMENTS) and a line here.
GARMENT_STYLES: dict[str, tuple[Style, ...]] = {
    "tshirt": (Style("tank", 0.25),),
    "longsleeve": (Style("sweater", 0.25, _knitted), Style("shirt", 0.25, _shirting), Style("hoodie", 0.2, _fleece)),
    "trousers": (Style("jeans", 0.4, _denim), Style("chinos", 0.2, _chino), Style("joggers", 0.15, _heather)),
    "jacket": (Style("coat", 0.3, _wool, worn_with=lambda outfit: "trousers" in outfit),  # its skirt over trousers only
               Style("blazer", 0.3, _suiting)),
    "dress": (Style("shift", 0.25), Style("wrap", 0.25), Style("jumpsuit", 0.15)),
}
_STYLE_OF = {st.kind: st for styles in GARMENT_STYLES.values() for st in styles}


def sample_style(g: GarmentParams, outfit, draw: bool = True) -> GarmentParams:
    """``g`` made in one of its kind's ``GARMENT_STYLES`` (by share; with ``draw``) or left as it is,
    drawn from its texture seed (so the subject's other draws are the ones they were before
    styles); a style's texture restyled (also when the outfit named the style itself)."""
    rng = np.random.default_rng([g.texture.seed, 13])
    styles = [st for st in GARMENT_STYLES.get(g.kind, ()) if st.worn_with(list(outfit))] if draw else []
    if styles:
        p = np.array([1.0 - sum(st.share for st in styles)] + [st.share for st in styles])  # shares of those worn
        pick = int(rng.choice(len(p), p=p / p.sum()))
        if pick:  # a kind with its own cut (a shift's straight skirt) drops a drawn one
            kind = styles[pick - 1].kind
            g = dataclasses.replace(g, kind=kind, cut=None if GARMENTS[kind].cut or not GARMENTS[kind].skirted else g.cut,
                                    texture=dataclasses.replace(g.texture, uv_aspect=uv_aspect(GARMENTS[kind])))
    style = _STYLE_OF.get(g.kind)
    return dataclasses.replace(g, texture=style.texture(g.texture, rng)) if style and style.texture else g


def _folds(cut: SkirtCut, ang: np.ndarray, t: float) -> np.ndarray:
    """Radial offset round a ring where the folds stand out: a zigzag for pleats, a sine for a
    full skirt's waves, ``t`` (0..1) of their full depth."""
    if not cut.folds:
        return np.zeros_like(ang)
    phase = ang * cut.folds / (2 * np.pi) % 1.0
    wave = 1 - 4 * np.abs(phase - 0.5) if cut.sharp else np.cos(2 * np.pi * phase)
    return 0.5 * cut.depth * t * wave


def _flare(body, r: BodyRegions, g: GarmentParams, offset: float, top_y: float, density: int = 1,
           parted: bool = False):
    """A skirt surface from top_y down, widening outwards by its cut (``SKIRT_CUTS``), outside
    every body vertex it passes; ``density`` times the rings down and the points round (a
    simulated skirt's folds need them), but not for sharp pleats: finer, their creases were
    softer and a walk opened them (down to 40 % of their depth; tests/test_cloth.py asks 45 %).
    ``parted``: open down the centre front under its top ring (``_parted``)."""
    cut = SKIRT_CUTS[g.cut or GARMENTS[g.kind].cut or "a_line"]
    density = 1 if cut.sharp else density
    n_seg = density * (48 if not cut.folds else 6 * cut.folds)  # six points a fold
    v = body.vertices[np.isin(r.group, ["torso", "upperleg", "lowerleg"])]  # not the hanging arms
    bottom = r.hip_y - 0.1 - (r.hip_y - 0.1 - 0.15) * g.length
    heights = np.linspace(top_y, bottom, 13 * density + 1)
    centre = v[(v[:, 1] < top_y) & (v[:, 1] > bottom)][:, [0, 2]].mean(0)
    ang = np.linspace(0, 2 * np.pi, n_seg, endpoint=False)
    d = np.stack([np.sin(ang), np.cos(ang)], 1)  # x, z
    rings = []
    prev = None
    ramp = cut.ramp or max(top_y - bottom - cut.stitched, 1e-6)  # metres over which the folds deepen
    for k, h in enumerate(heights):
        band = v[np.abs(v[:, 1] - h) < 0.03][:, [0, 2]] - centre
        reach = np.array([(band @ di).max() if len(band) else 0.05 for di in d])
        # the support of the body in each direction; smooth it around the ring
        w = 3 * density  # the same angle at every density
        reach = np.maximum(reach, np.convolve(np.pad(reach, w, mode="wrap"), np.ones(2 * w + 1) / (2 * w + 1), "valid"))
        radius = reach + offset + (cut.flare + cut.ease_flare * g.ease) * (k / (len(heights) - 1)) ** cut.curve
        if prev is not None:
            radius = np.maximum(radius, prev)  # never narrows downwards
        prev = radius
        out = radius + _folds(cut, ang, float(np.clip((top_y - h - cut.stitched) / ramp, 0, 1)))
        rings.append(np.column_stack([centre[0] + out * d[:, 0], np.full(n_seg, h), centre[1] + out * d[:, 1]]))
    verts = np.concatenate(rings)
    seam = len(verts) + np.arange(len(heights))  # each ring's first point again, at u = 1, last
    quads = []
    for k in range(len(heights) - 1):
        for j in range(n_seg):
            a, b = k * n_seg + j, (k * n_seg + j + 1 if j + 1 < n_seg else seam[k])
            c, e = a + n_seg, (b + n_seg if j + 1 < n_seg else seam[k + 1])
            quads += [[a, c, b], [b, c, e]]
    v_of = np.linspace(1, 0, len(heights))
    uv = np.column_stack([np.tile(ang / (2 * np.pi), len(heights)), np.repeat(v_of, n_seg)])
    # the seam's own copies: a face closing the ring ran its uv back across the whole square
    verts, faces, uv = (np.concatenate([verts, verts[::n_seg]]), np.array(quads),
                        np.concatenate([uv, np.column_stack([np.ones(len(heights)), v_of])]))
    if parted:
        verts = _parted(verts, len(heights), n_seg)
    return _vented(verts, faces, uv, heights, n_seg, cut.vent) if cut.vent > 0 else (verts, faces, uv)


VENT_GAP = 0.001  # metres each edge of a vent stands off the centre-back line: apart, so no weld closes it


def _parted(verts: np.ndarray, n_rings: int, n_seg: int) -> np.ndarray:
    """A ``_flare`` surface open down the centre front under its top ring, as a coat is below its
    buttons: each ring's first point (angle 0, straight ahead) and its seam copy (u = 1, appended
    after the rings) stood ``VENT_GAP`` off the line either way, so no weld closes the seam there
    (closed, a coat's straight skirt rode up a run's stride and stayed bunched at the hips)."""
    verts = verts.copy()
    rings = np.arange(1, n_rings)
    tangent = np.array([1.0, 0.0, 0.0])  # d(sin a, 0, cos a)/da at a = 0: round the ring, away from the seam copy
    verts[rings * n_seg] += VENT_GAP * tangent
    verts[n_rings * n_seg + rings] -= VENT_GAP * tangent
    return verts


def _vented(verts: np.ndarray, faces: np.ndarray, uv: np.ndarray, heights: np.ndarray, n_seg: int, vent: float):
    """A ``_flare`` surface slit up the centre back (angle pi: point n_seg / 2 of each ring) from
    the hem over the rings within ``vent`` metres of it: the faces right of the line take a
    copy of its points, each side stood ``VENT_GAP`` off the line, so the slit is an opening
    (``hem`` turns a band along both its edges, and the cloth stage does not weld it shut)."""
    back = n_seg // 2
    rings = np.flatnonzero(heights < heights[-1] + vent - 1e-9)
    rings = rings[rings > 0]
    if not len(rings) or n_seg % 2:
        return verts, faces, uv
    old = rings * n_seg + back
    new = len(verts) + np.arange(len(rings))
    tangent = np.array([-1.0, 0.0, 0.0])  # d(sin a, 0, cos a)/da at a = pi: round the ring, to the copies' side
    verts = verts.copy()
    verts[old] -= VENT_GAP * tangent
    verts = np.concatenate([verts, verts[old] + 2 * VENT_GAP * tangent])
    right = np.concatenate([2 * (k * n_seg + back) + np.arange(2) for k in range(len(heights) - 1)])
    swap = np.full(len(verts), -1)
    swap[old] = new
    sub = faces[right]
    faces = faces.copy()
    faces[right] = np.where(swap[sub] >= 0, swap[sub], sub)
    return verts, faces, np.concatenate([uv, uv[old]])


def _shoes(body, r: BodyRegions, g: GarmentParams, offset: float):
    """Each shoe is the convex hull of its foot (and ankle, by ``length``), grown by ``offset``
    and subdivided; a convex shell cannot cut into the toes. UVs by cylindrical projection."""
    import trimesh
    keep = _region(GARMENTS["shoes"])(g, r, body.vertices)
    parts = []
    for side in (1, -1):
        pts = body.vertices[keep & (np.sign(body.vertices[:, 0]) == side)]
        hull = trimesh.convex.convex_hull(pts)
        n = hull.vertex_normals
        grown = trimesh.Trimesh(hull.vertices + n * offset, hull.faces, process=False)
        v, f = trimesh.remesh.subdivide_to_size(grown.vertices, grown.faces, max_edge=0.02)
        parts.append((v, f))
    v = np.concatenate([parts[0][0], parts[1][0]])
    f = np.concatenate([parts[0][1], parts[1][1] + len(parts[0][0])])
    c = v.mean(0)
    uv = np.column_stack([(np.arctan2(v[:, 0] - c[0], v[:, 2] - c[2]) / (2 * np.pi)) % 1.0, v[:, 1] / 0.3])
    return v, f, uv


def push_out(body, points: np.ndarray, clearance: float = CLEARANCE, rounds: int = 3) -> np.ndarray:
    """Move points that are inside or closer than ``clearance`` to the body out along the normal."""
    p, surface = points.copy(), body.surface()
    for _ in range(rounds):
        d = surface.signed_distance(p)
        bad = d < clearance
        if not bad.any():
            break
        closest, tri, _ = surface.closest(p[bad])
        n = face_normals(body.vertices[body.faces[tri]])
        p[bad] = closest + n * clearance * 1.5
    return p


def _cut_shell(body, split, phi: np.ndarray, normals: np.ndarray, offset: float, room: np.ndarray | None = None,
               widest: float = 0.0, scale: float | np.ndarray = 1.0, cap: float = np.inf):
    """The body's render mesh cut along ``phi == 0`` (``topology.cut``), offset along
    ``normals`` (per body vertex): (vertices, faces, uv, the unit directions it stood off
    along, the room each has left over its offset where that scales it, ``ROOM_NONE``
    elsewhere, the body points they stood off). Only the cut's largest piece is kept: where a
    region's field dips back over zero past its edge (a tank's arms, cut by its armholes, left
    a patch of 13-29 points under each armpit on 5 of 16 subjects) the patch would ride on the
    arm skinned, and fall away simulated. ``room`` (per body vertex, ``free_room``), when
    given, scales the offset down where it is tight (``fit_offset``, as the ``widest`` top's, or
    this one's if it is wider), by the share ``scale`` of that scaling, where that is under 1 never
    to more than ``cap`` times the room (none: the offset is exact, and the room left over it none
    where it is tighter)."""
    src = split.source
    limit = np.full(len(body.vertices), ROOM_NONE) if room is None else np.minimum(room, ROOM_NONE)
    share = np.broadcast_to(np.asarray(scale, float), (len(body.vertices),))
    f, p, n, uv, limit, share = cut(split.faces, phi[src], body.vertices[src], normals[src], split.uv,
                                    limit[src, None], share[src, None])
    used, f = submesh(f, largest_piece(p, f))
    p, n, uv, limit, share = p[used], n[used], uv[used], limit[used, 0], share[used, 0]
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    widest = max(widest, offset)
    off = np.full(len(p), offset) if room is None else fit_offset(offset, limit, widest)
    if room is not None:  # a full share keeps fit_offset's arrays exactly
        shared = offset + share * (off - offset)
        off = np.where(share == 1.0, off, np.minimum(shared, cap * limit) if np.isfinite(cap) else shared)
    tight = limit < 1.5 * widest  # where fit_offset scales it
    return p + n * off[:, None], f, uv, n, np.where(tight, np.maximum(limit - off, 0.0), ROOM_NONE), p


@dataclass
class GarmentMesh:
    params: GarmentParams
    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    layer: int
    offset: float
    hem: tuple = (0, 0)  # (faces, vertices) the turned-in band appended last
    fit: Fit | None = None  # a graded garment's size on its wearer


def garment_offset(g: GarmentParams, below: float = 0.0, fit: Fit | None = None) -> float:
    """Metres the garment's shell stands off the body: its kind's, its ease and thickness, and
    its fit (a graded garment: ``fit.radial``, never tighter than ``SNUG`` over its thickness;
    an ungraded one: its ``size``); at least 4 mm outside the garment ``below`` it."""
    size = 0.7 + 0.6 * g.size
    if GARMENT_SHAPES[GARMENTS[g.kind].shape].sole:
        return GARMENTS[g.kind].offset + g.ease * size  # the upper's allowance over the foot
    if fit is not None:
        radial = fit.radial - leg_room(g, fit)
        own = max(GARMENTS[g.kind].offset + radial + g.ease + g.thickness, g.thickness + SNUG)
    else:
        own = GARMENTS[g.kind].offset + 0.004 * g.size + g.ease * size + g.thickness  # a larger size sits further out
    return max(own, below + 0.004 if below else 0.0)


def leg_room(g: GarmentParams, fit: Fit | None) -> float:
    """Metres a bottom cut large stands further out round the legs alone: its waistband is
    belted to the waist (and a top over it need not stand out)."""
    return max(fit.radial, 0.0) if fit is not None and GARMENTS[g.kind].layer == Layer.BOTTOM else 0.0


def _let_out_legs(body, r: BodyRegions, v: np.ndarray, room: float) -> np.ndarray:
    """``v`` moved ``room`` metres further out along the body's normal, from nothing at the crotch
    to all of it ``LEG_ROOM_RAMP`` under it (copies of a seam vertex share a body point: no crack)."""
    from scipy.spatial import cKDTree
    n = r.normals[cKDTree(body.vertices).query(v)[1]]
    t = np.clip((r.crotch_y - v[:, 1]) / LEG_ROOM_RAMP, 0.0, 1.0)
    return v + n * (room * t * t * (3 - 2 * t))[:, None]


def _legs_centre(body, r: BodyRegions) -> np.ndarray:
    """(x, z) of the middle between the legs: the mean of the torso's and legs' points under the hips."""
    legs = np.isin(r.group, ["torso", "upperleg", "lowerleg"]) & (body.vertices[:, 1] < r.hip_y)
    return body.vertices[legs][:, [0, 2]].mean(0)


def _legs_middle(body, r: BodyRegions) -> float:
    """The x of the middle between the legs (``_legs_centre``)."""
    return float(_legs_centre(body, r)[0])


def hang_legs(body, r: BodyRegions, v: np.ndarray, taper: tuple[float, float]) -> np.ndarray:
    """A bottom's legs as cloth hangs round them, not as a shell of them: under the crotch each
    leg's points move out from the middle of its cross-section to a tube whose radius, going down,
    comes in by at most ``taper`` times the drop (above the knee, below it) from the fullest part
    above (the thigh's, the calf's): it stands clear of the knee, the calf's hollows and the ankle.
    The seat's flesh is not the thigh's, nor the heel the ankle's: the fullness counts from
    ``LEG_TUBE[0]`` under the crotch (over which the legs turn from the shell into their tubes) to
    half that over the ankle joint. Never nearer the middle between the
    legs than ``LEG_TUBE[2]``. Each point's move depends on its position alone: seam copies of a
    point move as one."""
    ramp, step, gap, share = LEG_TUBE
    middle, out, sk = _legs_middle(body, r), v.copy(), body.skeleton
    for side, tag in ((1.0, "L"), (-1.0, "R")):
        rows = np.flatnonzero((side * (v[:, 0] - middle) > 0) & (v[:, 1] < r.crotch_y))
        if not len(rows):
            continue
        p, knee = v[rows], float(sk.rest_positions[sk.index(f"lowerleg01.{tag}"), 1])
        ankle = float(sk.rest_positions[sk.index(f"foot.{tag}"), 1]) + ramp / 2
        y = r.crotch_y - step * np.arange(int(np.ceil((r.crotch_y - p[:, 1].min()) / step)) + 1)  # going down
        windows = [np.abs(p[:, 1] - h) <= 2 * step for h in y]
        centre = np.array([p[w][:, [0, 2]].mean(0) if w.any() else (np.nan, np.nan) for w in windows])
        ok = np.isfinite(centre[:, 0])
        centre = np.stack([np.interp(y, y[ok][::-1], centre[ok, k][::-1]) for k in (0, 1)], 1)
        rel = p[:, [0, 2]] - np.stack([np.interp(p[:, 1], y[::-1], centre[::-1, k]) for k in (0, 1)], 1)
        d = np.maximum(np.linalg.norm(rel, axis=1), 1e-9)
        full = np.array([np.percentile(d[w], share) if w.any() and ankle <= h <= r.crotch_y - ramp else -np.inf
                         for w, h in zip(windows, y)])
        drop = np.cumsum(np.where(y < knee, taper[1], taper[0]) * step)  # how far the cloth may have come in by each height
        reach = np.maximum.accumulate(full + drop) - drop  # the fullest above, come in by the taper since
        radius = np.maximum(np.interp(p[:, 1], y[::-1], reach[::-1]), d)
        t = np.clip((r.crotch_y - p[:, 1]) / ramp, 0.0, 1.0)
        grow = (radius - d) * t * t * (3 - 2 * t)
        inward = -side * rel[:, 0] / d  # how much of a step out along ``rel`` goes towards the middle
        room = side * (p[:, 0] - middle) - np.minimum(gap, side * (p[:, 0] - middle))
        grow = np.where(inward > 1e-6, np.minimum(grow, room / np.maximum(inward, 1e-6)), grow)
        out[rows[:, None], [0, 2]] = p[:, [0, 2]] + rel / d[:, None] * grow[:, None]
    return out


def _hull_reach(points: np.ndarray, centre: np.ndarray, x: float, ang: np.ndarray) -> np.ndarray:
    """(len(ang) + 2,) metres from ``centre`` (x, z) along each angle (sin, cos: x, z) to the
    edge of the convex hull of ``points`` (N, 2), then the least and the greatest z of the hull
    on the line at ``x``; nan where the hull is degenerate or the centre outside it."""
    from scipy.spatial import ConvexHull, QhullError
    try:
        eq = ConvexHull(points).equations  # n . x + d <= 0 inside
    except (QhullError, ValueError):
        return np.full(len(ang) + 2, np.nan)
    inside = -(eq[:, :2] @ centre + eq[:, 2])  # each edge's distance past the centre (>= 0 inside)
    if (inside < 0).any():
        return np.full(len(ang) + 2, np.nan)
    towards = np.stack([np.sin(ang), np.cos(ang)], 1) @ eq[:, :2].T  # (A, E)
    reach = np.where(towards > 1e-9, inside / np.maximum(towards, 1e-9), np.inf).min(1)
    bound = -(eq[:, 2] + eq[:, 0] * x) / np.where(np.abs(eq[:, 1]) > 1e-9, eq[:, 1], np.nan)
    return np.concatenate([reach, [np.nanmax(np.where(eq[:, 1] < 0, bound, np.nan)),
                                   np.nanmin(np.where(eq[:, 1] > 0, bound, np.nan))]])


def _at_angles(values: np.ndarray, ang: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Each row of ``values`` (N, len(ang)), a periodic table over the angles ``ang`` (-pi..pi),
    linearly interpolated at its point's angle ``a`` (N,)."""
    x = (a - ang[0]) / (ang[1] - ang[0])
    j = np.clip(np.floor(x).astype(int), 0, len(ang) - 2)
    t = x - j
    rows = np.arange(len(a))
    return (1 - t) * values[rows, j] + t * values[rows, j + 1]


def hang_across(body, r: BodyRegions, v: np.ndarray, f: np.ndarray, base: np.ndarray,
                slope: float) -> tuple[np.ndarray, np.ndarray]:
    """A loose top under the crotch as cloth hangs there: across both legs, not round each
    thigh. Cut from the thighs, its shell was two tubes whose inner sides, offset towards each
    other, went through one another between the legs (seeds 200-229: 809 crossing faces) and
    read as a pair of shorts under the hem, a notch at the front. Each half (by the body point
    ``base`` it stood off) moves out from its thigh's centre, along its own direction, to the
    convex hull of both legs' shell points at its height, coming in going down by at most
    ``slope`` times the drop (``_hanging_hulls``, ``_across_table``), blended in from
    ``ACROSS[0]`` over the crotch to the crotch (``_onto_hull``); a point going out towards the
    middle between the legs stops on it: straight across the front and back, the thighs' inner
    sides laid on the middle where the two halves meet (``_into_corners``). Each point's move
    depends on its own position alone (seam copies move as one); the sleeves are left out.
    Returns the points and which of them were laid on the middle (the wall ``close_middle`` takes out)."""
    top = r.crotch_y + ACROSS[0]
    rows = np.flatnonzero((v[:, 1] < top) & np.isin(r.group[body.surface().tree.query(base)[1]], ["torso", "upperleg"]))
    if len(rows) < 3:
        return v, np.zeros(len(v), bool)
    middle, out = _legs_middle(body, r), v.copy()
    wall, corners = np.zeros(len(v), bool), np.zeros((len(v), 2))
    y = top - ACROSS[2] * np.arange(int(np.ceil((top - v[rows, 1].min()) / ACROSS[2])) + 1)  # going down
    windows = [np.abs(v[rows, 1] - h) <= 2 * ACROSS[2] for h in y]
    hulls = _hanging_hulls(v[rows], windows, slope * ACROSS[2])
    for side in (1.0, -1.0):  # the body's own middle line goes with the first
        mine = (base[rows, 0] >= middle) == (side > 0)
        table = _across_table(y, windows, hulls, base[rows], mine, middle + side * ACROSS[3], r.crotch_y)
        if table is None or not mine.any():
            continue
        i = rows[mine]
        heights, centre, reach, ang = table
        out[i[:, None], [0, 2]], wall[i], corners[i] = _onto_hull(v[i], heights, centre, reach, ang, top,
                                                                   middle + side * ACROSS[3], side)
    return _into_corners(out, f, wall, corners), wall


def _into_corners(v: np.ndarray, f: np.ndarray, wall: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """``v`` with each ``wall`` point (on the middle between the legs) that has neighbours off
    the middle moved all but ``ACROSS[5]`` of the way to the level (z) of the farthest of them
    out towards its nearer corner (``corners``: least, greatest z): the edges between ran across
    the corner, a notch a centimetre deep at the front and back under the crotch, a slit 3-4 cm
    deep at the back over it. Not all the way: two such points on the corner's line with a third
    made a triangle of no area, which the panels' flattening cannot solve. Seam copies move as one."""
    rep = weld(v)
    ff = rep[f]
    edges = np.concatenate([ff[:, [0, 1]], ff[:, [1, 2]], ff[:, [2, 0]]])
    a, b = edges[wall[edges[:, 0]] & ~wall[edges[:, 1]]].T
    front = v[b, 2] > corners[a].mean(1)
    level = np.full(len(v), np.nan)
    np.fmax.at(level, a[front], v[b[front], 2])
    back = np.full(len(v), np.nan)
    np.fmin.at(back, a[~front], v[b[~front], 2])
    level = np.where(np.isfinite(level), level, back)
    out = v.copy()
    moved = np.isfinite(level)
    out[moved, 2] = level[moved] + ACROSS[5] * (v[moved, 2] - level[moved])
    return out[rep]


def close_middle(v: np.ndarray, f: np.ndarray, uv: np.ndarray, wall: np.ndarray):
    """A top hung across both legs (``hang_across``) made one tube round them under the crotch:
    the ``wall`` (each thigh's inner side, laid on the middle between the legs) taken out, and the
    two halves' edges left on the middle at the front and at the back sewn to each other
    (``_sew``). With the wall, the cloth stage simulated a pair of culottes: the back's middle
    fell 17 cm between the legs as it settled and the cloth tore (seed 213's long sleeve over
    simulated shorts: an edge 0.2 m past its rest length by a walk's third frame). Edges on the
    middle whose faces do not change sides once along them (twice round a loop) are left open:
    seed 210's sweater, whose two halves touch 1.4 cm over its hem at the back, keeps a slit
    there (a vent); with the whole wall kept instead, it would simulate culottes."""
    rep = weld(v)
    w = np.zeros(len(v), bool)
    w[rep[wall]] = True
    wall = w[rep]
    keep = ~wall[f].all(1)
    if keep.all():
        return v, f, uv
    f = f[keep]
    edges = open_edges(f, rep)
    edges = edges[wall[edges].all(1)]
    for chain_a, chain_b in _middle_chains(v, f, rep, edges):
        v, f, uv = _sew(v, f, uv, rep, chain_a, chain_b)
        rep = np.concatenate([rep, len(rep) + np.arange(len(v) - len(rep))])
    used = np.unique(f)
    new = np.full(len(v), -1)
    new[used] = np.arange(len(used))
    return v[used], new[f], uv[used]


def _middle_chains(v: np.ndarray, f: np.ndarray, rep: np.ndarray, edges: np.ndarray) -> list:
    """Per path of ``edges`` (open, on the middle) whose faces lie on one side of it up to a
    point and on the other beyond it (a slit reaching the hem), or per loop of them whose faces
    lie on one side and then the other (a slit over the hem): two chains of its edges from one
    such point out, one a side (``_sew``)."""
    side = {}
    for a, b in edges:
        c = np.flatnonzero(((f == a) | (f == b)).sum(1) == 2)
        side[(rep[a], rep[b])] = (a, b, float(v[f[c[0]]].mean(0)[0]))  # the x of the face it bounds
    nxt = {ra: rb for ra, rb in side}
    ends = set(nxt) - set(nxt.values())
    out, seen = [], set()
    for start in sorted(ends) + sorted(nxt):
        if start in seen:
            continue
        path, x = [], start
        while x in nxt and x not in seen:
            seen.add(x)
            path.append(side[(x, nxt[x])])
            x = nxt[x]
        middle = float(np.median([v[p[0], 0] for p in path]))
        left = np.array([p[2] for p in path]) < middle
        pairs = [(a, b) for a, b, _ in path]
        if x != start:  # from the hem up to the point and down again
            turns = np.flatnonzero(left[1:] != left[:-1]) + 1
            if len(turns) == 1:
                k = turns[0]
                out.append(([(b, a) for a, b in pairs[:k]][::-1], pairs[k:]))
            continue
        turns = np.flatnonzero(left != np.roll(left, 1))  # round (and back to the start)
        if len(turns) == 2:  # from one turn to the other, either way
            pairs = pairs[turns[0]:] + pairs[:turns[0]]
            k = turns[1] - turns[0]
            out.append((pairs[:k], [(b, a) for a, b in pairs[k:]][::-1]))
    return out


def _sew(v: np.ndarray, f: np.ndarray, uv: np.ndarray, rep: np.ndarray, chain_a: list, chain_b: list):
    """Two chains of edges from one point out, sewn to each other: points at the same share of
    each chain's length (within ``SEW_TOLERANCE`` metres) made one at their mean, and a point of
    one without a partner put into the other's edge there (``_split_edges``), so every point of
    either lies on both; the cloth stage welds them (``_particles``)."""
    pa, pb = ([c[0][0]] + [e[1] for e in c] for c in (chain_a, chain_b))
    sa, sb = (np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(v[p], axis=0), axis=1))]) for p in (pa, pb))
    if min(sa[-1], sb[-1]) < 1e-6:
        return v, f, uv
    ta, tb, length = sa / sa[-1], sb / sb[-1], 0.5 * (sa[-1] + sb[-1])
    t, on_a, on_b, i, j = [], [], [], 0, 0  # merged points: share, index on a or -1, on b or -1
    while i < len(ta) or j < len(tb):
        both = i < len(ta) and j < len(tb) and abs(ta[i] - tb[j]) * length < SEW_TOLERANCE
        take_a = both or j >= len(tb) or (i < len(ta) and ta[i] < tb[j])
        take_b = both or not take_a
        t.append(0.5 * (ta[i] + tb[j]) if both else ta[i] if take_a else tb[j])
        on_a.append(i if take_a else -1)
        on_b.append(j if take_b else -1)
        i, j = i + take_a, j + take_b
    share = np.array(t)

    def along(s: np.ndarray, p: list) -> np.ndarray:  # the points at those shares of a chain's length
        return np.stack([np.interp(share * s[-1], s, v[p][:, k]) for k in range(3)], -1)
    pos = 0.5 * (along(sa, pa) + along(sb, pb))
    v = v.copy()
    for pts, on in ((pa, on_a), (pb, on_b)):
        for k, x in zip(on, pos):
            if k >= 0:
                v[rep == rep[pts[k]]] = x
    for pts, on in ((pa, on_a), (pb, on_b)):
        v, f, uv = _split_edges(v, f, uv, pts, np.array(on), pos)
    return v, f, uv


def _split_edges(v: np.ndarray, f: np.ndarray, uv: np.ndarray, pts: list, on: np.ndarray, pos: np.ndarray):
    """The face on each edge of a chain (points ``pts``) split in a fan at the merged points
    (``pos``) between its ends that the chain has no point of its own at (``on`` -1), their uv
    along the edge."""
    own = np.flatnonzero(on >= 0)
    new_v, new_uv, new_f, drop = [v], [uv], [], []
    n = len(v)
    for k0, k1 in zip(own[:-1], own[1:]):
        if k1 == k0 + 1:
            continue
        a, b = pts[on[k0]], pts[on[k1]]
        row = int(np.flatnonzero(((f == a) | (f == b)).sum(1) == 2)[0])
        corners = list(f[row])
        c = next(x for x in corners if x not in (a, b))
        forward = corners[(corners.index(a) + 1) % 3] == b  # the face winds a -> b -> c
        extra = pos[k0 + 1:k1]
        s = np.clip(np.linalg.norm(extra - v[a], axis=1) / max(float(np.linalg.norm(v[b] - v[a])), 1e-12), 0.0, 1.0)
        new_v.append(extra)
        new_uv.append((1 - s)[:, None] * uv[a] + s[:, None] * uv[b])
        ring = [a, *range(n, n + len(extra)), b]
        n += len(extra)
        new_f += [[p, q, c] if forward else [q, p, c] for p, q in zip(ring[:-1], ring[1:])]
        drop.append(row)
    keep = np.ones(len(f), bool)
    keep[drop] = False
    f = np.concatenate([f[keep]] + ([np.array(new_f, dtype=f.dtype)] if new_f else []))
    return np.concatenate(new_v), f, np.concatenate(new_uv)


SEW_TOLERANCE = 0.003  # metres: points of the two chains this near in arc length are made one


def _across_table(y: np.ndarray, windows: list, hulls: list, base: np.ndarray, mine: np.ndarray, line: float,
                  crotch: float):
    """``hang_across``'s measure of one half at the heights ``y``: (heights, the centre (x, z)
    its points move out from at each, and ``_hull_reach`` of the height's hull round it at
    ``ACROSS_ANGLES`` angles and on its middle ``line``, angles); None where fewer than two
    heights can be measured. The centre is the mean of the half's (``mine``) ``base`` points in
    the height's window under the crotch, where the legs part, and of both halves' over it
    (``ACROSS_PART`` either side, eased): seen from the half's centre, a point by the middle at
    the back went out sideways as much as back, and the points over the cleft crossed there."""
    ang = np.linspace(-np.pi, np.pi, ACROSS_ANGLES + 1)
    t = _ease((crotch + ACROSS_PART - y) / (2 * ACROSS_PART))
    centre = np.array([(1 - tk) * base[w][:, [0, 2]].mean(0) + tk * base[w & mine][:, [0, 2]].mean(0)
                       if (w & mine).sum() >= 3 else (np.nan, np.nan) for w, tk in zip(windows, t)])
    reach = np.array([_hull_reach(h, c, line, ang) if np.isfinite(c[0]) and h is not None
                      else np.full(len(ang) + 2, np.nan) for h, c in zip(hulls, centre)])
    ok = np.isfinite(reach).all(1) & np.isfinite(centre).all(1)
    return (y[ok], centre[ok], reach[ok], ang) if ok.sum() >= 2 else None


def _hanging_hulls(v: np.ndarray, windows: list, fall: float) -> list:
    """The corners (M, 2) of each window's hull round the (x, z) of the points ``v`` in it,
    going down: never more than ``fall`` metres inside the one above (cloth hangs from the
    belly, it does not follow it in); None where a window's hull cannot be made."""
    from scipy.spatial import ConvexHull, QhullError
    hulls, above = [], None
    for w in windows:
        pts = v[w][:, [0, 2]]
        if above is not None:
            mid = above.mean(0)
            off = above - mid
            pts = np.vstack([pts, mid + off * np.clip(1 - fall / np.maximum(np.linalg.norm(off, axis=1), 1e-9),
                                                      0, None)[:, None]])
        try:
            above = pts[ConvexHull(pts).vertices]
        except (QhullError, ValueError):
            above = None
        hulls.append(above)
    return hulls


def _onto_hull(p: np.ndarray, y: np.ndarray, centre: np.ndarray, reach: np.ndarray, ang: np.ndarray, top: float,
               line: float, side: float):
    """Points ``p`` of one half moved (``hang_across``) by its table: their (x, z), whether
    each is on the middle ``line`` (a point going out towards it stops there: the inner side of
    the thigh's tube is laid on it in order, not piled in its corners), and the least and
    greatest z of the hull there."""
    c = np.stack([np.interp(p[:, 1], y[::-1], centre[::-1, k]) for k in (0, 1)], 1)
    rel = p[:, [0, 2]] - c
    a = np.arctan2(rel[:, 0], rel[:, 1])
    k = np.clip(np.searchsorted(-y, -p[:, 1]), 1, len(y) - 1)  # y[k - 1] >= p.y >= y[k]
    t = np.clip((y[k - 1] - p[:, 1]) / (y[k - 1] - y[k]), 0.0, 1.0)
    hull = (1 - t) * _at_angles(reach[k - 1, :-2], ang, a) + t * _at_angles(reach[k, :-2], ang, a)
    corners = (1 - t)[:, None] * reach[k - 1, -2:] + t[:, None] * reach[k, -2:]
    d = np.maximum(np.linalg.norm(rel, axis=1), 1e-9)
    u = rel / d[:, None]
    inward = -side * u[:, 0]  # how much of a step out goes towards the middle
    to_line = np.where(inward > 1e-9, side * (c[:, 0] - line) / np.maximum(inward, 1e-9), np.inf)
    q = c + u * np.minimum(d + _ease((top - p[:, 1]) / ACROSS[1]) * (hull - d), to_line)[:, None]
    past = side * (q[:, 0] - line) <= 1e-9
    q[past] = np.column_stack([np.full(past.sum(), line), _within(q[past, 1], corners[past, 0], corners[past, 1])])
    return q, past, corners


def _within(z: np.ndarray, lo: np.ndarray, hi: np.ndarray, soft: float = ACROSS[4]) -> np.ndarray:
    """``z`` kept between ``lo`` and ``hi`` without two points made one: from ``soft`` metres
    short of either end, the distance left shrinks exponentially (smooth, and still in order;
    a hard clip set the points past a corner on one line, and a triangle of three of them had
    no area, which the panels' flattening cannot solve)."""
    eps = np.minimum(soft, 0.25 * (hi - lo))
    up, down = z > hi - eps, z < lo + eps
    z = np.where(up, hi - eps * np.exp(-(z - hi + eps) / eps), z)
    return np.where(down, lo + eps * np.exp(-(lo + eps - z) / eps), z)


def _legs_shape(body, r: BodyRegions, split, g: GarmentParams, cut: GarmentParams, offset: float,
                density: int = 1):
    """A bottom: the body region ``cut`` covers, offset from it, its legs hanging as tubes;
    ``density`` 2: the legs' triangles under the crotch (the cloth that hangs) halved each way
    once they hang, each new point on the curve its edge's ends' normals give (``refine``): the
    same tubes, smooth between the coarse points. Halved before they hang, each new point took
    the tube's centre and radius at its own height (measured every centimetre) and the legs
    rippled between the coarse points: their fold measure at rest was 2-3x the coarse legs'
    (24x hung on the coarse points' tubes), now 1.7x (bench/RESULTS.md, session 95)."""
    v, f, uv = _shell_shape(body, r, split, g, cut, offset)
    v = hang_legs(body, r, v, GARMENTS[g.kind].taper)
    if density > 1:
        v, f, uv = refine(v, f, uv, (v[f][:, :, 1] < r.crotch_y).any(1))
    return v, f, uv


def footwear_lift(g: GarmentParams) -> float:
    """How far a pair of shoes lifts the body: its sole (a convex hull shoe: its offset)."""
    return g.thickness if GARMENT_SHAPES[GARMENTS[g.kind].shape].sole else garment_offset(g)


def _region(kind: GarmentKind) -> Callable:
    if kind.region is None:
        raise ValueError(f"a {kind.shape} garment kind needs a region")
    return kind.region


def _room_share(body, r: BodyRegions) -> np.ndarray:
    """Per body vertex, the share of ``fit_offset``'s scaling a cloth stage's rest shape takes
    (``_cut_shell``): all of it on the arms, so a sleeve's underside comes in off the flank;
    ``ROOM_SIMULATED`` over the torso (scaled in full, the tighter side was drawn forward by the
    swinging arm and the back folded under the held yoke in a walk); raised, never lowered,
    towards the arm's over the ``ROOM_SHARE_RINGS`` rings of the body mesh next to it (stepping
    there, the shell crossed itself at the armpit's apex; over 2 rings, a sweater's held cloth,
    set on the body, turned a triangle over beside the armpit in a walk)."""
    arm = np.where(np.isin(r.group, ["upperarm", "lowerarm", "hand"]), 1.0, ROOM_SIMULATED)
    mean, share = neighbour_mean(body.faces, len(arm)), arm
    for _ in range(ROOM_SHARE_RINGS):
        share = mean @ share
    return np.maximum(arm, share)


def _shell_shape(body, r: BodyRegions, split, g: GarmentParams, cut: GarmentParams, offset: float,
                 across: bool = True):
    """The body region ``cut`` covers, offset from the body; tops and dresses along
    ``r.outward`` (``offset_directions``: bottoms keep the skin's normals, whose legs' shells
    parted higher at the crotch along the averaged ones), bridged over the hollows of the small
    of the back and the belly, and draped; a top's (``across``; not a dress's or a coat's
    bodice, whose skirt is its own) hangs across both legs under the crotch (``hang_across``), and
    the cloth stage's (``r.hang`` false) is one tube round them there (``close_middle``)."""
    kind = GARMENTS[g.kind]
    loose = kind.layer in (Layer.TOP, Layer.DRESS)
    shared = loose and not r.hang and r.room is not None  # a cloth stage's rest shape: ``_room_share``
    v, f, uv, out, spare, base = _cut_shell(body, split, _region(kind)(cut, r, body.vertices),
                                            r.outward if loose else r.normals, offset, r.room if loose else None,
                                            r.widest, scale=_room_share(body, r) if shared else 1.0,
                                            cap=ROOM_CAP if kind.order >= ROOM_CAP_ORDER else np.inf)
    rep = weld(v)
    v, base = v[rep], base[rep]  # a seam's two copies of a cut vertex, ~1e-7 m apart, made one point: no crack opens later
    if loose:
        slope = float(np.clip(HANG[0] - HANG[1] * (offset - HANG[2]), HANG[3], HANG[0]))
        torso = _over_torso(body, r, v)
        low_back = torso & (v[:, 1] > r.crotch_y) & (v[:, 1] < r.waist_y + 2 * OFFSET_BLEND)
        v = bridge(v, f, out, low_back, offset)
        v = hang_columns(v, f, torso, slope, spare=ROOM[5] * spare)
        v = smooth_openings(v, f)
        if across and r.across and kind.layer == Layer.TOP:  # a top's: a coat's skirt, a jumpsuit's legs are their own
            v, wall = hang_across(body, r, v, f, base, slope)
            if not r.hang:  # the cloth stage's: one tube round both legs, not culottes
                v, f, uv = close_middle(v, f, uv, wall)
    return v, f, uv


def _dress_shape(body, r: BodyRegions, split, g: GarmentParams, cut: GarmentParams, offset: float, density: int = 1,
                 parted: bool = False):
    """A bodice (a shell) and a skirt flaring from the hips (``density``, ``parted``: see ``_flare``),
    the skirt's uv squeezed under the bodice's in the atlas (where the legs' would be), so the two
    share no texel and each can take its own pattern."""
    v, f, uv = _shell_shape(body, r, split, g, cut, offset, across=False)
    sv, sf, suv = _flare(body, r, g, offset, r.hip_y, density, parted)
    suv = suv * [1.0, max(uv[:, 1].min() - 0.02, 0.1)]
    return np.concatenate([v, sv]), np.concatenate([f, sf + len(v)]), np.concatenate([uv, suv])


COLLAR_STAND = 0.025  # metres a shirt collar's band rises round the neck
COLLAR_FALL = 0.038   # and its fall turns down over it, out to the points
COLLAR_GAP = 0.45     # radians either side of straight ahead the collar is open (its points spread)
COLLAR_POINT = 0.035  # metres its points reach lower than the fall elsewhere, onto the chest
COLLAR_LOFT = 0.004   # metres the fall lies out from the shell under it


def _neck_edge(r: BodyRegions, v: np.ndarray, f: np.ndarray, ang: np.ndarray):
    """The radius from the neck's axis and the height of a shell's neckline at angles ``ang``
    (from straight ahead, towards +x), interpolated round its open edge near the neck."""
    ends = np.unique(open_edges(f, weld(v)))
    p = v[ends]
    dx, dz = p[:, 0] - r.neck_xz[0], p[:, 2] - r.neck_xz[1]
    rho = np.hypot(dx, dz)
    near = (rho < r.neck_radius + 0.08) & (p[:, 1] > r.neck_y - 0.08)
    a = np.arctan2(dx[near], dz[near]) % (2 * np.pi)
    order = np.argsort(a)
    a, rho, y = a[order], rho[near][order], p[near, 1][order]
    wrap = np.concatenate([a - 2 * np.pi, a, a + 2 * np.pi])
    return np.interp(ang, wrap, np.tile(rho, 3)), np.interp(ang, wrap, np.tile(y, 3))


def _collar(r: BodyRegions, v: np.ndarray, f: np.ndarray, n_seg: int = 40):
    """A shirt collar on the shell ``v, f``: a stand rising ``COLLAR_STAND`` from the shell's
    neckline, turned over at its top into a fall ``COLLAR_FALL`` long lying outside it, open
    at the front where its points spread and reach ``COLLAR_POINT`` lower, lying on the chest
    (a fall of one length all round stood off the neck like a funnel)."""
    ang = np.linspace(COLLAR_GAP, 2 * np.pi - COLLAR_GAP, n_seg)
    point = (np.clip(np.cos(ang), 0.0, 1.0) / np.cos(COLLAR_GAP)) ** 6  # 1 at the points, ~0 past 60 degrees
    r0, base = _neck_edge(r, v, f, ang)
    edge = base + COLLAR_STAND - COLLAR_FALL - COLLAR_POINT * point
    middle = 0.5 * (base + COLLAR_STAND + 0.004 + edge)
    # (radius, height) over the neckline of each ring: the base, the stand's top, the fold, down the fall to its edge
    def out(rad: float, y: np.ndarray) -> np.ndarray:  # over the chest where the points lie on it
        return r0 + rad + point * np.maximum(_shell_reach(r, v, ang, y, r0) + COLLAR_LOFT - r0 - rad, 0.0)
    rings = [(r0, base), (r0 + 0.002, base + COLLAR_STAND), (r0 + 0.008, base + COLLAR_STAND + 0.004),
             (out(0.02, middle), middle), (out(0.03, edge), edge)]
    return _strip(r, ang, rings)


def _shell_reach(r: BodyRegions, v: np.ndarray, ang: np.ndarray, y: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """How far the shell ``v`` reaches from the neck's axis at angles ``ang`` and heights ``y``
    (its farthest vertex within 2 cm of the height and 0.12 rad of the angle; ``floor`` where
    none is): where a piece lying over it must stay out of."""
    rho = np.hypot(v[:, 0] - r.neck_xz[0], v[:, 2] - r.neck_xz[1])
    turn = np.arctan2(v[:, 0] - r.neck_xz[0], v[:, 2] - r.neck_xz[1]) % (2 * np.pi)
    return np.array([rho[(np.abs(v[:, 1] - yk) < 0.02) & (np.abs((turn - a + np.pi) % (2 * np.pi) - np.pi) < 0.12)]
                     .max(initial=rk) for a, yk, rk in zip(ang, y, floor)])


def _strip(r: BodyRegions, ang: np.ndarray, rings: list):
    """A band round the neck's axis through ``rings`` of (radius, height) at angles ``ang``:
    open at its two ends, uv from the angle and the length along it."""
    n = len(ang)
    d = np.stack([np.sin(ang), np.cos(ang)], 1)  # x, z
    v = np.concatenate([np.column_stack([r.neck_xz[0] + np.broadcast_to(rad, n) * d[:, 0], np.broadcast_to(h, n),
                                         r.neck_xz[1] + np.broadcast_to(rad, n) * d[:, 1]]) for rad, h in rings])
    k, j = np.meshgrid(np.arange(len(rings) - 1), np.arange(n - 1), indexing="ij")
    a, b = (k * n + j).ravel(), (k * n + j + 1).ravel()
    faces = np.concatenate([np.stack([a, a + n, b], 1), np.stack([b, a + n, b + n], 1)])
    step = np.linalg.norm(np.diff(v.reshape(len(rings), n, 3), axis=0), axis=2).mean(1)
    uv = np.column_stack([np.tile(0.5 * ang / np.pi, len(rings)), np.repeat(np.concatenate([[0.0], np.cumsum(step)]), n)])
    return v, faces, uv


HOOD_GAP = 0.15     # radians either side of straight ahead a hood's edges leave open at the neck (they all but meet)
HOOD_DEPTH = 0.24   # metres a hood lying down reaches down the back, under the neckline at the back
HOOD_LOFT = 0.012   # metres it lies out from the garment under it


def _hood(r: BodyRegions, v: np.ndarray, f: np.ndarray, n_seg: int = 40, n_down: int = 6):
    """A hood lying down: it rises from the shell's neckline round the back of the neck, turns
    over and lies down the back (``HOOD_DEPTH`` at the middle, less towards the front), each
    point ``HOOD_LOFT`` out from the shell under it."""
    ang = np.linspace(HOOD_GAP, 2 * np.pi - HOOD_GAP, n_seg)
    r0, base = _neck_edge(r, v, f, ang)
    back = np.clip(-np.cos(ang), 0.0, 1.0)
    depth = HOOD_DEPTH * (0.08 + 0.92 * back ** 1.5)
    front = np.clip(np.cos(ang), 0.0, 1.0)
    rise = (0.5 + 0.5 * back) * (1.0 - 0.85 * front ** 2)  # the hood rolls thinner to its front edges, flat where they meet
    rings = [(r0, base), (r0 + 0.01 * rise, base + 0.03 * rise), (r0 + 0.025 * rise, base + 0.04 * rise)]
    for s in np.linspace(0.0, 1.0, n_down + 1)[1:]:
        y = base + 0.04 * rise - (depth + 0.04 * rise) * s
        rings.append((np.maximum(_shell_reach(r, v, ang, y, r0) + HOOD_LOFT, r0 + 0.025 * rise), y))
    return _strip(r, ang, rings)


NECK_PART_UV = ((0.69, 0.23), (0.97, 0.74))  # where a collar's or hood's uv goes: in the atlas's head, which no top covers


def _shell_and(neck_part: Callable) -> Callable:
    """A shape: the shell to the neckline and ``neck_part(regions, v, f)`` built on it (a
    shirt's collar, a hoodie's hood), the part's uv moved into ``NECK_PART_UV`` (its strip's
    own uv lay over the wrists' in the atlas, where long sleeves end)."""
    def shape(body, r: BodyRegions, split, g: GarmentParams, cut: GarmentParams, offset: float):
        v, f, uv = _shell_shape(body, r, split, g, cut, offset)
        pv, pf, puv = neck_part(r, v, f)
        lo, hi = np.array(NECK_PART_UV)
        puv = lo + (puv - puv.min(0)) / np.maximum(np.ptp(puv, axis=0), 1e-9) * (hi - lo)
        return np.concatenate([v, pv]), np.concatenate([f, pf + len(v)]), np.concatenate([uv, puv])
    return shape


SHOE_EDGE = 0.003  # metres: the upper's thickness, turned in along its top line


def _shoe_shape(body, r: BodyRegions, split, g: GarmentParams, cut: GarmentParams, offset: float):
    """A pair of ``body.shoes`` shoes (laces as cords, and boot shafts) round the feet, the top
    lines hemmed."""
    style = SHOE_STYLES[g.kind]
    parts = []
    for side in (1.0, -1.0):
        foot = foot_points(body, r, side)
        sv, sf, suv = shoe_mesh(foot, style, g.thickness, offset, g.length)
        parts += [(sv, sf, suv), lace_mesh(sv, sf, suv, style)]
        if style.shaft[1]:
            top = g.thickness + style.shaft[0] + (style.shaft[1] - style.shaft[0]) * g.length
            parts.append(shaft_mesh(foot, g.thickness, top, offset))
        if style.heel[1]:
            parts.append(heel_mesh(foot, heel_pitch(body.skeleton, foot, side, heel_height(style, g.length)), style))
    n = np.cumsum([0] + [len(p[0]) for p in parts])
    v, f, uv = (np.concatenate(x) for x in ([p[0] for p in parts], [p[1] + k for p, k in zip(parts, n)],
                                             [p[2] for p in parts]))
    return hem(body, v, f, uv, SHOE_EDGE)


def _rigid_feet(body, r: BodyRegions, v: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Shoes are rigid on the feet: under the ankle a vertex follows its side's foot bone alone
    (the sole stays flat), and a boot's shaft blends to its bound weights (the shin) over the
    6 cm above the ankle."""
    sk = body.skeleton
    foot = np.zeros_like(weights)
    foot[np.arange(len(v)), np.where(v[:, 0] > 0, sk.index("foot.L"), sk.index("foot.R"))] = 1.0
    t = np.clip((v[:, 1] - sk.rest_positions[sk.index("foot.L"), 1]) / 0.06, 0.0, 1.0)[:, None]
    return ((1 - t) * foot + t * weights).astype(weights.dtype)


def _flexing_feet(body, r: BodyRegions, v: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Shoes are rigid on the feet behind the ball and follow the toes in front of it, blended
    over 3 cm across the ball line: a sole bends there as the heel rises in a step (and a heel's
    pitch turns the toes back flat on its insole)."""
    out = _rigid_feet(body, r, v, weights)
    for side in (1.0, -1.0):
        pitch = heel_pitch(body.skeleton, foot_points(body, r, side), side, 0.05)  # only its ball line
        t = np.clip((pitch.ahead(v) + 0.015) / 0.03, 0.0, 1.0)
        t = t * t * (3 - 2 * t) * (np.sign(v[:, 0]) == side)
        moved = t * out[:, pitch.foot]
        out[:, pitch.toes[2]] += moved
        out[:, pitch.foot] -= moved
    return out


def heel_pitches(body, r: BodyRegions, g: GarmentParams) -> tuple[HeelPitch, ...]:
    """How a pair of heels holds the feet (left, right); nothing for flat shoes."""
    style = SHOE_STYLES.get(g.kind)
    if style is None or not style.heel[1]:
        return ()
    return tuple(heel_pitch(body.skeleton, foot_points(body, r, side), side, heel_height(style, g.length))
                 for side in (1.0, -1.0))


@dataclass(frozen=True)
class GarmentShape:
    """How a garment kind's rest mesh is made: ``build(body, regions, split, params, cut params,
    offset) -> (vertices, faces, uv)``; ``hemmed``: its open edges get a hem of the cloth's
    thickness (a closed hull has none, a shoe hems its own); ``weights(body, regions, vertices,
    bound weights) -> weights``: skinning other than the closest body point's."""

    build: Callable
    hemmed: bool = True
    weights: Callable | None = None
    sole: bool = False  # the garment's thickness is a sole the body stands on, not cloth over it
    across: bool = False  # a top's shell: under the crotch it hangs across both legs (``hang_across``)
    dense: bool = False  # ``build`` takes ``density=``: its hanging cloth is made finer to be simulated


# How many times finer each way a simulated skirt's flare is than a skinned one's: 96 points
# round (a circle skirt 120; pleats as cut) in rings 2 cm apart. At 48 round and 4 cm apart,
# folds 2-15 cm across hardly fit (bench/cloth.py's fold energy; bench/RESULTS.md). Trouser
# legs, cut from the body's mesh (edges 2.8 cm in the median, a tenth over 5 cm), are halved
# the same way under the crotch: 1.5 cm. A coat's parted skirt too (since session 98: at one
# density its walk folded 3.5x the skinned coat's, 14.5x at two; bench/RESULTS.md).
SIMULATED_DENSITY = 2

def across_weights(body, r: BodyRegions, v: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """A top's skinning weights where it hangs across both legs (``hang_across``): both legs'
    from over the crotch down (``both_legs_weights``), not the sleeves; else the bound ones.
    Bound to its closest point, each half followed one thigh and a stride opened the two halves
    where they meet in the middle."""
    if not r.across:
        return weights
    near = r.group[body.surface().tree.query(v)[1]]
    return both_legs_weights(body, r, v, weights, top=r.crotch_y + ACROSS[0], among=np.isin(near, ["torso", "upperleg"]),
                             share=ACROSS_SIDE, legs=True)


# A new garment shape is one entry here; GarmentKind.shape names one.
GARMENT_SHAPES: dict[str, GarmentShape] = {
    "shell": GarmentShape(_shell_shape, weights=across_weights, across=True),
    "legs": GarmentShape(_legs_shape, dense=True),
    "flare": GarmentShape(lambda body, r, split, g, cut, offset, density=1: _flare(body, r, g, offset, r.waist_y, density),
                          weights=lambda *a: both_legs_weights(*a), dense=True),  # hangs across both legs: skinned to both
    "shell+flare": GarmentShape(_dress_shape, weights=lambda *a: both_legs_weights(*a), dense=True),
    # a coat: a dress's shape, its skirt parted down the front
    "shell+parted": GarmentShape(functools.partial(_dress_shape, parted=True), weights=lambda *a: both_legs_weights(*a),
                                 dense=True),
    "shell+collar": GarmentShape(_shell_and(_collar), weights=across_weights, across=True),
    "shell+hood": GarmentShape(_shell_and(_hood), weights=across_weights, across=True),
    "hull": GarmentShape(lambda body, r, split, g, cut, offset: _shoes(body, r, g, offset), hemmed=False),
    "shoe": GarmentShape(_shoe_shape, hemmed=False, weights=_flexing_feet, sole=True),  # the toes bend at the ball
    "heeled": GarmentShape(_shoe_shape, hemmed=False, weights=_flexing_feet, sole=True),
}


def build_garment(body, r: BodyRegions, split, g: GarmentParams, below: float = 0.0,
                  tuck: bool = False, density: int = 1) -> GarmentMesh:
    """The rest-pose garment on ``body``; ``split`` is the body's seam-split render topology.
    ``tuck``: a top worn with a skirt (a kind that ``tucks_tops``) ends ``TUCK`` under the waist, as if tucked in (its hem
    would otherwise run inside the skirt's flare and show through it in notches). ``density``: a ``dense`` shape's
    hanging cloth that many times finer each way (``SIMULATED_DENSITY`` for the cloth stage)."""
    kind = GARMENTS[g.kind]
    fit = _fit(kind, g, r)
    offset = garment_offset(g, below, fit)
    cut_for = _cut_longer(g, g.grade or 0) if fit is not None else g  # (fit: g is graded)
    shape = cut_for
    if tuck and kind.layer == Layer.TOP:
        shape = dataclasses.replace(cut_for, length=min(cut_for.length, TUCK / (r.waist_y - (r.crotch_y - 0.12))))
    maker = GARMENT_SHAPES[kind.shape]
    v, f, uv = maker.build(body, r, split, cut_for, shape, offset, **({"density": density} if maker.dense else {}))
    room = leg_room(g, fit)
    if room and kind.shape in ("shell", "legs"):  # a skirt cut large keeps its flare: only its length grows
        v = _let_out_legs(body, r, v, room)
    n_faces, n_vertices = len(f), len(v)
    if GARMENT_SHAPES[kind.shape].hemmed:
        across = r.across and kind.layer == Layer.TOP and maker.across
        v, f, uv = hem(body, v, f, uv, g.thickness, along_normal=bool(g.cut and SKIRT_CUTS[g.cut].folds),
                       legs=(_legs_centre(body, r), r.crotch_y + ACROSS[0]) if across else None)
    v = push_out(body, v)
    return GarmentMesh(g, v, f, uv, int(kind.layer), offset, (len(f) - n_faces, len(v) - n_vertices), fit)


def _cut_longer(g: GarmentParams, grade: int) -> GarmentParams:
    """``g`` as cut ``grade`` sizes up: ``GRADE_LENGTH`` of its kind's length range longer a size."""
    return dataclasses.replace(g, length=float(np.clip(g.length + GRADE_LENGTH * grade, 0, 1))) if grade else g


def both_legs_weights(body, r: BodyRegions, v: np.ndarray, weights: np.ndarray, top: float | None = None,
                      among: np.ndarray | None = None, share: float = LEGS_SIDE, legs: bool = False) -> np.ndarray:
    """Skinning weights for a skirt (or a dress's skirt) that hangs from the hips over both legs.
    Closest-point binding gives each point one leg, so a stride tears the front and back apart
    along where the binding switches legs and drives the hem between the knees into one of them.
    Below the hips, a point takes the weights at its closest point on the body's left half and
    on its right half, mixed by how far to that side it is (half and half at the front and back
    centre, one leg alone from ``share`` of the ring's radius out), blended in from the hip
    line (or ``top``) over ``LEGS_BLEND``; only the points ``among`` (a mask) when given; with
    ``legs``, each half's closest point on its leg alone."""
    from synmitsuba.body.binding import MeshIndex
    down = np.clip((r.hip_y if top is None else top) - v[:, 1], 0.0, None) / LEGS_BLEND
    down = np.minimum(down, 1.0) * (True if among is None else among)
    rows = np.flatnonzero(down > 0)
    if not len(rows):
        return weights
    cx, cz = _legs_centre(body, r)
    p = v[rows]
    side_w = []
    for side in (1.0, -1.0):  # each half: its vertices, and the faces with all three among them
        keep = side * (body.vertices[:, 0] - cx) >= 0.0
        if legs:
            keep &= np.isin(r.group, ["upperleg", "lowerleg"])
        faces = body.faces[keep[body.faces].all(1)]
        index = np.cumsum(keep) - 1
        half = MeshIndex(body.vertices[keep], index[faces])
        _, tri, bary = half.closest(p)
        side_w.append(np.einsum("nk,nkj->nj", bary, body.weights[faces[tri]]))
    radius = np.maximum(np.hypot(p[:, 0] - cx, p[:, 2] - cz), 1e-6)
    s = np.clip(0.5 + 0.5 * (p[:, 0] - cx) / (share * radius), 0.0, 1.0)[:, None]
    mixed = s * side_w[0] + (1 - s) * side_w[1]
    out = weights.astype(np.float64).copy()
    t = down[rows, None]
    out[rows] = (1 - t) * out[rows] + t * mixed
    out /= np.maximum(out.sum(1, keepdims=True), 1e-12)
    return out.astype(weights.dtype)


def metres_per_uv(v: np.ndarray, f: np.ndarray, uv: np.ndarray) -> tuple[float, float]:
    """Metres of surface per unit u and per unit v of a mesh's texture mapping (the area-weighted
    median of each face's |dp/du| and |dp/dv|): how many thread tiles a garment's uv square holds."""
    e1, e2 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    d1, d2 = uv[f[:, 1]] - uv[f[:, 0]], uv[f[:, 2]] - uv[f[:, 0]]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    ok = np.abs(det) > 1e-12
    inv = 1.0 / np.where(ok, det, 1.0)
    dpdu = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * inv[:, None]
    dpdv = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * inv[:, None]
    area = np.linalg.norm(np.cross(e1, e2), axis=1) * ok

    def median(x):
        order = np.argsort(x)
        c = np.cumsum(area[order])
        return float(x[order][np.searchsorted(c, c[-1] / 2)]) if c[-1] > 0 else 1.0
    return median(np.linalg.norm(dpdu, axis=1)), median(np.linalg.norm(dpdv, axis=1))


def _over_torso(body, r: BodyRegions, v: np.ndarray) -> np.ndarray:
    """(N,) True for shell points whose closest body vertex is on the torso (not the arms)."""
    return r.group[body.surface().tree.query(v)[1]] == "torso"


def open_edges(f: np.ndarray, merged: np.ndarray | None = None) -> np.ndarray:
    """(E, 2) directed edges a -> b (as their face winds them) that only one face has, on the
    vertices ``merged`` (``weld``) makes one: the garment's openings."""
    directed = f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    merged = np.arange(f.max() + 1) if merged is None else merged
    m = np.sort(merged[directed], 1)
    _, inv, counts = unique_rows(m, return_inverse=True, return_counts=True)
    return directed[(counts[inv.ravel()] == 1) & (m[:, 0] != m[:, 1])]


EDGE_SMOOTHING = (3, 0.004)  # rounds of smoothing a top's openings along their curve, and metres a point may move
SLIVER = 0.001  # metres: a point the cut left this near an edge point moves with it


def smooth_openings(v: np.ndarray, f: np.ndarray, rounds: int = EDGE_SMOOTHING[0],
                    cap: float = EDGE_SMOOTHING[1]) -> np.ndarray:
    """``v`` with its openings' edges (necklines, hems, armholes) smoothed along their curves:
    a cut along a level set over the body's 1-1.5 cm triangles, offset centimetres along the
    normals, zigzags by millimetres round the neck and dips in a notch at the centre front.
    Each edge point moves in its surface's tangent plane towards the middle of its two
    neighbours on the edge (Taubin's lambda/mu steps, which take out the zigzag and keep the
    curve's size), by at most ``cap``; a point the cut left within ``SLIVER`` of an edge point
    moves with it (their sliver faces, 0.3 mm high, would turn over); a face the moves would
    turn over more than 60 degrees has its points' moves halved (up to six times). Points where
    openings meet stay put. Seam copies of a point (``weld``) move as one."""
    rep = weld(v)
    ff = rep[f]
    nxt, prv, free = _along_openings(rep[open_edges(f, rep)], len(v))
    p = v[rep]
    n = vertex_normals(p, ff)
    q = p.copy()
    for _ in range(rounds):
        for step in (0.5, -0.53):
            d = 0.5 * (q[nxt] + q[prv]) - q
            d -= np.einsum("ij,ij->i", d, n)[:, None] * n
            q[free] += step * d[free]
    move = q - p
    move *= np.minimum(1.0, cap / np.maximum(np.linalg.norm(move, axis=1), 1e-12))[:, None]
    e = ff[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    e = np.concatenate([e, e[:, ::-1]])
    e = e[free[e[:, 0]] & (nxt[e[:, 1]] == e[:, 1]) & (np.linalg.norm(p[e[:, 0]] - p[e[:, 1]], axis=1) < SLIVER)]
    move[e[:, 1]] = move[e[:, 0]]
    before = face_normals(p[ff])
    for _ in range(6):
        turned = np.einsum("ij,ij->i", face_normals((p + move)[ff]), before) < 0.5
        if not turned.any():
            break
        move[np.unique(ff[turned])] *= 0.5
    return (p + move)[rep]


def _along_openings(edges: np.ndarray, n_v: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each vertex's next and previous neighbour along the openings ``edges`` (``open_edges``;
    a vertex on none is its own), and which vertices lie inside a single opening's run (one
    edge in, one out, and so have both neighbours): (next, previous, free)."""
    nxt, prv = np.arange(n_v), np.arange(n_v)
    nxt[edges[:, 0]], prv[edges[:, 1]] = edges[:, 1], edges[:, 0]
    simple = (np.bincount(edges[:, 0], minlength=n_v) == 1) & (np.bincount(edges[:, 1], minlength=n_v) == 1)
    return nxt, prv, simple & simple[nxt] & simple[prv]


# a top hanging straight down (``hang_columns``): metres either side of a point the cloth over it
# is looked for; rounds of averaging the shell's normals over neighbours for the direction it moves out in;
# metres over which the moves are averaged (slivers of the cut, a millimetre across, turned over); metres
# round a point the points over it are looked for, again from where they moved at most so many times; and
# metres either side of the torso's middle over which points move out less sideways (none on it)
HANG_COLUMN = (0.02, 10, 0.004, 0.1, 6, 0.06)


def hang_columns(v: np.ndarray, f: np.ndarray, hanging: np.ndarray, slope: float,
                 spare: np.ndarray | None = None) -> np.ndarray:
    """Cloth that hangs (a top's or a bodice's, skinned or a simulation's rest shape): a ``hanging``
    point comes in towards the body by at most ``slope`` times its drop under any hanging point
    over it within ``HANG_COLUMN[0]`` to either side, along its horizontal outward normal
    (averaged over neighbours: a crease's own turn in), so a loose top falls from the bust and
    the shoulder blades over the underbust, the navel and the small of the back instead of
    following them like paint. Measured down the shell's edges instead, a shelf 2-4 cm deep was
    left under the bust (its edges there run sideways off it, each within the slope), and a
    simulated top kept it as its rest shape. ``spare`` caps how far a point moves sideways (x,
    towards an arm: it still moves forward or back in full). Seam copies of a point move as one."""
    rep = weld(v)
    ff = rep[f]
    p = v[rep]
    if not hanging.any():
        return p[rep]
    mean = neighbour_mean(ff, len(p))
    n = vertex_normals(p, ff)
    for _ in range(HANG_COLUMN[1]):
        n = mean @ n
    n[:, 0] *= np.clip(np.abs(p[:, 0] - _middle(p, hanging)) / HANG_COLUMN[5], 0.0, 1.0)  # straight out of the spine's groove
    n[:, 1] = 0.0
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-9)
    own = np.flatnonzero(rep == np.arange(len(p)))  # one of each seam's copies
    lift = np.where(hanging[own], _column_lift(p[own], n[own], slope, hanging[own]), 0.0)
    move = lift[:, None] * n[own]
    if spare is not None:
        move[:, 0] = np.clip(move[:, 0], -spare[own], spare[own])
    out = p.copy()
    out[own] += _within_reach(p[own], HANG_COLUMN[2]) @ move
    return out[rep]


def _column_lift(q: np.ndarray, n: np.ndarray, slope: float, over: np.ndarray) -> np.ndarray:
    """How far each of the points ``q`` must move out along ``n`` (unit, horizontal) to be at
    most ``slope`` times its drop in from each ``over`` point higher than it within
    ``HANG_COLUMN[0]`` across ``n`` (on the same side: normals within 60 degrees), looked for
    within ``HANG_COLUMN[3]`` and again from where the points moved, ``HANG_COLUMN[4]`` times
    at most: a hang carries on down from the points it moved."""
    from scipy.spatial import cKDTree
    i, j = cKDTree(q).query_pairs(HANG_COLUMN[3], output_type="ndarray").T
    b, a = np.r_[i, j], np.r_[j, i]
    keep = over[a] & (q[a, 1] > q[b, 1]) & (np.einsum("ij,ij->i", n[a], n[b]) > 0.5)
    order = np.argsort(b[keep], kind="stable")
    b, a = b[keep][order], a[keep][order]
    lift = np.zeros(len(q))
    if not len(b):
        return lift
    first = np.flatnonzero(np.r_[True, b[1:] != b[:-1]])
    for _ in range(HANG_COLUMN[4]):
        p = q + lift[:, None] * n
        d = p[a] - p[b]
        along = np.einsum("ij,ij->i", d, n[b])
        across = d[:, 0] ** 2 + d[:, 2] ** 2 - along ** 2
        need = np.maximum.reduceat(np.where(across < HANG_COLUMN[0] ** 2, along - slope * d[:, 1], 0.0), first)
        if need.max() <= 1e-5:
            break
        lift[b[first]] += np.clip(need, 0.0, None)
    return lift


def _middle(p: np.ndarray, hanging: np.ndarray) -> np.ndarray:
    """(N,) the torso's middle x at the height of each of the points ``p``: the mean x of the
    ``hanging`` points within 2 cm of it in height."""
    h = p[hanging]
    ys = np.arange(h[:, 1].min(), h[:, 1].max() + 0.02, 0.01)
    near = np.abs(h[None, :, 1] - ys[:, None]) <= 0.02
    some = near.any(1)  # a height with none (a gap in the torso's points) is interpolated over
    return np.interp(p[:, 1], ys[some], (near[some] @ h[:, 0]) / near[some].sum(1))


def _within_reach(p: np.ndarray, reach: float):
    """Row-normalised (sparse) mean over the points of ``p`` within ``reach`` of each, itself included."""
    from scipy.spatial import cKDTree
    i, j = cKDTree(p).query_pairs(reach, output_type="ndarray").T
    return pair_mean(i, j, len(p))


BRIDGE = (150, 0.5)  # rounds a loose shell fills hollows, and at most how much of its offset it moves out


def bridge(v: np.ndarray, f: np.ndarray, n: np.ndarray, moving: np.ndarray, offset: float,
           rounds: int = BRIDGE[0]) -> np.ndarray:
    """Cloth held taut across a hollow: each ``moving`` vertex goes out along ``n`` (the unit
    directions the shell stood off along: a crease's own normals turn in) while its neighbours'
    mean lies further out (never in), by at most ``BRIDGE[1]`` of the ``offset``. An offset shell
    keeps a hollow narrower than the offset as a crease: along the averaged normals, seed 100's
    sweater (39 mm off) kept the spine's groove, 2-3 cm deep, rendered as a dark line from behind."""
    rep = weld(v)
    ff = rep[f]
    p = v[rep]
    mean = neighbour_mean(ff, len(p))
    n = n[rep]
    out = np.zeros(len(p))
    cap = np.where(moving[rep], BRIDGE[1] * offset, 0.0)
    for _ in range(rounds):
        q = p + out[:, None] * n
        out = np.minimum(out + np.clip(np.einsum("ij,ij->i", mean @ q - q, n), 0.0, None), cap)
    return (p + out[:, None] * n)[rep]


def hem_sources(m: GarmentMesh) -> np.ndarray:
    """The edge vertex each vertex of ``m``'s hem band was turned in from (``hem`` appends the
    band last, its faces as ``[b, a, inner(a)]`` for every open edge (a, b), then the other
    half of each quad, ``[b, inner(a), inner(b)]``), in band order; empty for a garment without a hem."""
    n_faces, n_vertices = m.hem
    if not n_vertices:
        return np.zeros(0, np.int64)
    band = m.faces[len(m.faces) - n_faces:]
    first, second = band[:n_faces // 2], band[n_faces // 2:]
    source = np.full(n_vertices, -1, np.int64)
    base = len(m.vertices) - n_vertices
    source[second[:, 2] - base] = second[:, 0]  # inner(b) from b: an opening's end where a uv seam crosses it
    source[first[:, 2] - base] = first[:, 1]    # is some edge's b but no edge's a
    assert (source >= 0).all()  # every band vertex is some open edge's inner(a) or inner(b)
    return source


HEM_SMOOTHING = 3  # rounds of averaging a hem's turn-in direction with its neighbours' along the edge


def _smooth_along(edge: np.ndarray, ends: np.ndarray, x: np.ndarray, rounds: int) -> np.ndarray:
    """Unit vectors ``x`` at the openings' vertices ``ends`` averaged ``rounds`` times with their
    two neighbours along the openings (weights 1/4, 1/2, 1/4), where a vertex has both; ``edge``
    and ``ends`` on welded vertices (a seam's copies of a point are one, and take one value)."""
    points, first, local = np.unique(ends, return_index=True, return_inverse=True)
    nxt, prv, free = _along_openings(np.searchsorted(points, edge), len(points))
    y = x[first]
    for _ in range(rounds):
        y = np.where(free[:, None], 0.25 * y[nxt] + 0.5 * y + 0.25 * y[prv], y)
    y = y[local.ravel()]
    return y / np.maximum(np.linalg.norm(y, axis=1, keepdims=True), 1e-12)


def hem(body, v: np.ndarray, f: np.ndarray, uv: np.ndarray, depth: float, along_normal: bool = False,
        legs: tuple[np.ndarray, float] | None = None):
    """A turned-in band along every opening (hem, cuff, neckline), ``depth`` (the cloth's
    thickness) deep towards the closest body point (``along_normal``: along the cloth's own
    normal, turned to the body, so a pleated or waved hem's band follows its folds instead of
    crossing itself), so an edge seen in a close-up has thickness.
    ``legs`` (the (x, z) of the middle between them, a height): under that height, a hem
    that hangs across both legs (``hang_across``) turns in level towards that middle, blended
    in over ``ACROSS[1]`` (towards the closest body point, a band on the middle between the
    legs turned to one leg or the other from point to point, by up to 68 degrees).
    Openings are found with vertices welded within a micrometre (UV seams split the mesh, and
    the cut places a seam's two copies of a vertex up to ~1e-7 m apart, but are not openings)."""
    rep = weld(v)
    edge = open_edges(f, rep)
    if not len(edge):
        return v, f, uv
    ends = np.unique(edge)
    closest = body.surface().closest(v[ends])[0]
    gap = np.linalg.norm(v[ends] - closest, axis=1, keepdims=True)
    n = vertex_normals(v, f)[ends]
    towards = np.where(gap > 1e-4, (v[ends] - closest) / np.maximum(gap, 1e-9), n)  # on the body: the cloth's normal
    if along_normal:
        towards = n * np.where(np.einsum("ij,ij->i", n, towards) < 0, -1.0, 1.0)[:, None]
    else:  # the closest point jumps between neighbours over a hollow: averaged along the edge, no teeth
        towards = _smooth_along(rep[edge], rep[ends], towards, HEM_SMOOTHING)
    middle, top = legs if legs is not None else (np.zeros(2), -np.inf)
    low = np.flatnonzero(v[ends, 1] < top)
    if len(low):  # (elsewhere the band is as without ``legs``)
        out = (v[ends[low]] - [middle[0], 0.0, middle[1]]) * [1.0, 0.0, 1.0]
        out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-9)
        t = _ease((top - v[ends[low], 1]) / ACROSS[1])[:, None]
        blended = towards[low] + t * (out - towards[low])
        towards[low] = blended / np.maximum(np.linalg.norm(blended, axis=1, keepdims=True), 1e-9)
    inner = -np.ones(len(v), np.int64)
    inner[ends] = len(v) + np.arange(len(ends))
    a, b = edge.T
    band = np.concatenate([np.stack([b, a, inner[a]], 1), np.stack([b, inner[a], inner[b]], 1)])
    return (np.concatenate([v, v[ends] - towards * depth]), np.concatenate([f, band]),
            np.concatenate([uv, uv[ends]]))
