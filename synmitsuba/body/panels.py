"""Where a garment's printed or woven pattern lies: per texel of its uv atlas, coordinates in
metres on the flat panels a tailor cuts, so checks stay square and stripes level all round.

Shell garments take the body's uv atlas, which unrolls the skin as one pelt cut down the back:
a pattern drawn in it turned to diamonds on the back and fanned round the shoulders. Instead
the garment's rest mesh is cut into panels (``PANEL_LAYOUTS``, named by its kind):
- a top's front and back (side seams where the torso's depth is halved), a sleeve past each
  armhole (a plane fitted where the body's arm skin meets its torso; its seam underneath),
  and a collar or hood above the neck's base (its seam in front);
- trousers' two legs (seams at the centre front and back, the inseam inside each);
- a jumpsuit's top above the waist, trouser legs below it;
- a skirt, and a dress's or coat's skirt below the hips, in one piece round, its seam at the back.
Each panel is laid flat with its grain up (``flatten``: two Poisson solves that fit unit
gradients along and across the grain), cut open along its seam where it goes round, and
shifted so v is height (stripes meet at the side seams) and u is 0 on the torso's centre lines.
Each texel takes the panel its own rest position falls in (seams run smooth across faces).
Coordinates are in metres, so a pattern's ``pattern_scale`` is its repeats per metre of cloth
on every such garment (over a garment's uv square it was 0.4 m of a skirt, 2 m of a top).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

ARMHOLE_NEAR = 0.015  # metres: arm skin this close to torso skin is where a sleeve is set in


@dataclass(frozen=True)
class _Limb:
    """A sleeve's, trouser leg's or collar's frame: its bones' ``joints`` (K, 3; shoulder, elbow,
    wrist), ``ref`` (a unit vector) the direction round them where the angle is 0, and for a
    sleeve the armhole plane (``seam_at``, ``seam_normal`` pointing down the arm)."""

    joints: np.ndarray
    ref: np.ndarray
    seam_at: np.ndarray | None = None
    seam_normal: np.ndarray | None = None

    @property
    def start(self) -> np.ndarray:
        return self.joints[0]

    @property
    def axis(self) -> np.ndarray:
        """Unit vector from its first joint to its last."""
        return _unit(self.joints[-1] - self.joints[0])

    def past_seam(self, p: np.ndarray) -> np.ndarray:
        return (p - self.seam_at) @ self.seam_normal > 0

    def angle(self, p: np.ndarray) -> np.ndarray:
        """Radians round the nearest bone from ``ref``, in (-pi, pi]: the seam is at +-pi (round
        each bone, not one straight line: a bent elbow's sleeve goes round the elbow)."""
        a, b = self.joints[:-1], self.joints[1:]
        d = b - a
        t = np.clip(np.einsum("pkd,kd->pk", p[:, None] - a[None], d) / np.einsum("kd,kd->k", d, d), 0.0, 1.0)
        near = a[None] + t[..., None] * d[None]
        k = np.argmin(np.linalg.norm(p[:, None] - near, axis=2), axis=1)
        axis = d[k] / np.linalg.norm(d[k], axis=1, keepdims=True)
        perp = p - near[np.arange(len(p)), k]
        ref = self.ref - (axis @ self.ref)[:, None] * axis
        side = np.cross(axis, ref)
        return np.arctan2(np.einsum("pd,pd->p", perp, side), np.einsum("pd,pd->p", perp, ref))


@dataclass(frozen=True)
class PanelFrame:
    """What a rest body gives every garment's panels: where the torso's sides are (``heights``,
    ``depth``: the middle of its depth there, z), the sleeves and legs (L then R), the neck (its
    seam in front) and a skirt (round the hips, its seam at the back), the neck's axis (x, z)
    and base height, the waist's and hips' heights and the body's middle x."""

    heights: np.ndarray
    depth: np.ndarray
    sleeves: tuple[_Limb, _Limb]
    legs: tuple[_Limb, _Limb]
    neck: _Limb
    skirt: _Limb
    neck_xz: np.ndarray
    neck_y: float
    waist_y: float
    hip_y: float
    mid_x: float

    @classmethod
    def of(cls, vertices: np.ndarray, regions, skeleton) -> "PanelFrame":
        """The frame of the rest body ``vertices`` (its ``BodyRegions`` and skeleton)."""
        from scipy.spatial import cKDTree
        torso = vertices[regions.group == "torso"]
        heights, depth = [], []
        for h in np.arange(torso[:, 1].min(), torso[:, 1].max() + 0.02, 0.02):
            band = torso[np.abs(torso[:, 1] - h) < 0.015, 2]
            if len(band):  # a band may fall between the torso's rings of vertices
                heights.append(h)
                depth.append((band.min() + band.max()) / 2)
        rest = skeleton.rest_positions
        near_torso = cKDTree(torso)
        sleeves, legs = [], []
        for side, sign in (("L", 1.0), ("R", -1.0)):
            arm_joints = rest[[skeleton.index(f"{j}.{side}") for j in ("upperarm01", "lowerarm01", "wrist")]]
            axis = _unit(arm_joints[-1] - arm_joints[0])
            arm = vertices[(regions.group == "upperarm") & (np.sign(vertices[:, 0] - torso[:, 0].mean()) == sign)]
            rim = arm[near_torso.query(arm)[0] < ARMHOLE_NEAR]
            at = rim.mean(0)
            normal = np.linalg.svd(rim - at)[2][-1]
            sleeves.append(_Limb(arm_joints, np.array([0.0, 1.0, 0.0]), at, normal if normal @ axis > 0 else -normal))
            leg_joints = rest[[skeleton.index(f"{j}.{side}") for j in ("upperleg01", "lowerleg01", "foot")]]
            legs.append(_Limb(leg_joints, np.array([sign, 0.0, 0.0])))
        nx, nz = regions.neck_xz
        neck = _Limb(np.array([[nx, regions.neck_y, nz], [nx, regions.neck_y + 0.3, nz]]), np.array([0.0, 0.0, -1.0]))
        mid_x, hips = float(torso[:, 0].mean()), float(np.interp(regions.hip_y, heights, depth))
        skirt = _Limb(np.array([[mid_x, regions.hip_y, hips], [mid_x, 0.0, hips]]), np.array([0.0, 0.0, 1.0]))
        return cls(np.array(heights), np.array(depth), (sleeves[0], sleeves[1]), (legs[0], legs[1]), neck, skirt,
                   np.asarray(regions.neck_xz), float(regions.neck_y), float(regions.waist_y), float(regions.hip_y),
                   mid_x)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


TORSO_FRONT, TORSO_BACK, NECK, SLEEVE_L, SLEEVE_R, LEG_L, LEG_R, FLARE = range(8)


def top_panels(p: np.ndarray, frame: PanelFrame) -> np.ndarray:
    """A top's panel per point: front or back of the torso (split at its sides, where the
    section's centre lies), a collar or hood above the neck's base near its axis, a sleeve past
    each armhole."""
    cz = np.interp(p[:, 1], frame.heights, frame.depth)
    out = np.where(p[:, 2] >= cz, TORSO_FRONT, TORSO_BACK)
    neck = (p[:, 1] > frame.neck_y) & (np.linalg.norm(p[:, [0, 2]] - frame.neck_xz, axis=1) < 0.16)
    out[neck] = NECK
    for sleeve, sign, label in zip(frame.sleeves, (1.0, -1.0), (SLEEVE_L, SLEEVE_R)):
        out[~neck & (np.sign(p[:, 0] - frame.mid_x) == sign) & sleeve.past_seam(p)] = label
    return out


def bottom_panels(p: np.ndarray, frame: PanelFrame) -> np.ndarray:
    """Trousers: a panel per leg, the two meeting at the centre front and back."""
    return np.where(p[:, 0] >= frame.mid_x, LEG_L, LEG_R)


def one_piece_panels(p: np.ndarray, frame: PanelFrame) -> np.ndarray:
    """A jumpsuit: a top above the waist seam, trouser legs below it."""
    return np.where(p[:, 1] >= frame.waist_y, top_panels(p, frame), bottom_panels(p, frame))


def skirt_panels(p: np.ndarray, frame: PanelFrame) -> np.ndarray:
    """A skirt: one piece round the body, its seam at the back."""
    return np.full(len(p), FLARE)


def dress_panels(p: np.ndarray, frame: PanelFrame) -> np.ndarray:
    """A dress or a coat: a top's panels over a skirt from the hips (where its flare starts)."""
    return np.where(p[:, 1] >= frame.hip_y, top_panels(p, frame), FLARE)


# garment kinds' layouts are named in body.garments.GarmentKind.panels
PANEL_LAYOUTS: dict[str, Callable[[np.ndarray, PanelFrame], np.ndarray]] = {
    "top": top_panels, "bottom": bottom_panels, "one_piece": one_piece_panels, "skirt": skirt_panels,
    "dress": dress_panels,
}


def flatten(v: np.ndarray, f: np.ndarray, grain: np.ndarray) -> np.ndarray:
    """(V, 2) metres on a flat panel of the connected triangle mesh (v, f) laid with its grain
    along ``grain`` ((3,), or (F, 3) per triangle): the (u, v) whose gradients on each triangle best match, in least
    squares weighted by area, unit vectors across the grain and along it (the grain projected
    into the triangle; the normal across it): where the cloth is a cylinder or a cone, an
    isometry; elsewhere the misfit spreads thin. Two Poisson solves; a point pinned at 0."""
    from scipy.sparse import coo_matrix, diags
    from scipy.sparse.linalg import spsolve
    p0, p1, p2 = (v[f[:, k]] for k in range(3))
    normal = np.cross(p1 - p0, p2 - p0)
    area2 = np.maximum(np.linalg.norm(normal, axis=1), 1e-15)
    n = normal / area2[:, None]
    # gradient of a linear function on a triangle: sum_i phi_i (n x e_i) / (2 area), e_i opposite vertex i
    rows, cols, vals = [], [], []
    for k, e in enumerate((p2 - p1, p0 - p2, p1 - p0)):
        g = np.cross(n, e) / area2[:, None]
        for d in range(3):
            rows.append(3 * np.arange(len(f)) + d)
            cols.append(f[:, k])
            vals.append(g[:, d])
    G = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * len(f), len(v))).tocsr()
    grain = np.broadcast_to(grain, normal.shape)
    up = grain - np.einsum("fd,fd->f", n, grain)[:, None] * n  # the grain in each triangle's plane
    lying = np.linalg.norm(up, axis=1)  # 1 where the cloth hangs along the grain, 0 where it lies across it
    up /= np.maximum(lying, 1e-12)[:, None]
    across = np.cross(up, n)
    W = diags(np.repeat(area2 * lying ** 2, 3))  # where the grain is ill-defined (a shoulder's top) the rest decides
    L = (G.T @ W @ G).tocsc()[1:, 1:]  # vertex 0 pinned at 0
    out = np.zeros((len(v), 2))
    for k, target in enumerate((across, up)):
        out[1:, k] = spsolve(L, (G.T @ W @ target.ravel())[1:])
    return out


SEAM_RINGS = 1  # each panel is flattened this many rings of faces past its own, so a seam can run between vertices


@dataclass(frozen=True)
class PanelCorners:
    """Per panel (a key of ``corners``), (F, 3, 2) metres on it of each face corner, NaN for
    faces it does not reach; ``label`` (F,) the panel of each face's centre."""

    label: np.ndarray
    corners: dict


def panel_corners(layout: str, vertices: np.ndarray, faces: np.ndarray, uv: np.ndarray, frame: PanelFrame) -> PanelCorners:
    """Each panel of a garment laid flat: its faces (sorted into panels by their centres,
    ``PANEL_LAYOUTS``) and ``SEAM_RINGS`` rings past them, welded across the atlas's seams,
    flattened (``flatten``) piece by connected piece with the grain up (up a sleeve), and
    shifted so v is height (a sleeve's: up from its shoulder) and u is 0 on a torso panel's
    centre line: stripes meet at the side seams as a tailor matches them. A collar or hood
    (its own strip in ``uv``) takes its grain along its strip's v."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from synmitsuba.body.topology import weld
    label = PANEL_LAYOUTS[layout](vertices[faces].mean(1), frame)
    one = weld(vertices, 1e-5)[faces]
    incidence = coo_matrix((np.ones(one.size), (np.repeat(np.arange(len(faces)), 3), one.ravel())),
                           shape=(len(faces), len(vertices))).tocsr()
    out = {}
    for panel in np.unique(label):
        reach = label == panel
        for _ in range(SEAM_RINGS):  # faces sharing a vertex with the panel
            reach = (incidence @ (incidence.T @ reach.astype(float))) > 0
        idx = np.flatnonzero(reach)
        keep, local = np.unique(one[idx], return_inverse=True)
        local = local.reshape(-1, 3)
        tube = _tube(int(panel), frame)
        if tube is not None:  # a sleeve, leg or collar goes round: cut it open along its seam
            local, keep = _cut_open(local, keep, tube.angle(vertices[keep]))
        n = len(keep)
        edges = np.concatenate([local[:, [0, 1]], local[:, [1, 2]]])
        parts = connected_components(coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n)),
                                     directed=False)[1][local[:, 0]]
        flat = np.full((len(faces), 3, 2), np.nan)
        for part in np.unique(parts):
            sel = np.flatnonzero(parts == part)
            used, tri = np.unique(local[sel], return_inverse=True)
            tri = tri.reshape(-1, 3)
            v = vertices[keep[used]]
            grain = _uv_grain(vertices, faces[idx[sel]], uv) if panel == NECK else _grain(int(panel), frame)
            flat[idx[sel]] = _placed(flatten(v, tri, grain), v, int(panel), frame)[tri]
        out[int(panel)] = flat
    return PanelCorners(label, out)


def _tube(panel: int, frame: PanelFrame) -> _Limb | None:
    """The frame a panel goes round (its seam at +-pi), None for a torso's front or back."""
    return {SLEEVE_L: frame.sleeves[0], SLEEVE_R: frame.sleeves[1], LEG_L: frame.legs[0], LEG_R: frame.legs[1],
            NECK: frame.neck, FLARE: frame.skirt}.get(panel)


def _cut_open(f: np.ndarray, keep: np.ndarray, angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces ``f`` over vertices ``keep`` cut along the seam at angle +-pi: a face across it takes
    copies of its vertices on the negative side (``keep`` grows by those copies)."""
    a = angle[f]
    across = (a.max(1) - a.min(1)) > np.pi
    moved = across[:, None] & (a < 0)
    if not moved.any():
        return f, keep
    copies = np.unique(f[moved])
    slot = np.full(len(keep), -1)
    slot[copies] = len(keep) + np.arange(len(copies))
    f = f.copy()
    f[moved] = slot[f[moved]]
    return f, np.concatenate([keep, keep[copies]])


def _sleeve(panel: int, frame: PanelFrame) -> _Limb | None:
    """The sleeve a panel is, or None."""
    return frame.sleeves[panel - SLEEVE_L] if panel in (SLEEVE_L, SLEEVE_R) else None


def _grain(panel: int, frame: PanelFrame) -> np.ndarray:
    """The way a panel's grain runs on the body: up, and up a sleeve towards its shoulder."""
    sleeve = _sleeve(panel, frame)
    return -sleeve.axis if sleeve is not None else np.array([0.0, 1.0, 0.0])


def _uv_grain(vertices: np.ndarray, f: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(F, 3) the way ``uv``'s v runs on each face (unit where it is defined)."""
    e1, e2 = vertices[f[:, 1]] - vertices[f[:, 0]], vertices[f[:, 2]] - vertices[f[:, 0]]
    d1, d2 = uv[f[:, 1]] - uv[f[:, 0]], uv[f[:, 2]] - uv[f[:, 0]]
    dpdv = e2 * d1[:, 0:1] - e1 * d2[:, 0:1]  # (dp/dv) times the uv triangle's signed area
    dpdv *= np.sign(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])[:, None]
    return dpdv / np.maximum(np.linalg.norm(dpdv, axis=1, keepdims=True), 1e-15)


def _placed(uv: np.ndarray, v: np.ndarray, panel: int, frame: PanelFrame) -> np.ndarray:
    """A flattened piece shifted so v is height (a sleeve's: up from its shoulder) and u is 0
    on a torso panel's centre line."""
    sleeve = _sleeve(panel, frame)
    height = -(v - sleeve.start) @ sleeve.axis if sleeve is not None else v[:, 1]
    uv[:, 1] += np.median(height - uv[:, 1])
    if panel in (TORSO_FRONT, TORSO_BACK):
        centre = np.abs(v[:, 0] - frame.mid_x) < 0.01
        uv[:, 0] -= np.median(uv[centre, 0]) if centre.any() else np.median(uv[:, 0])
    return uv


def pattern_coords(layout: str, vertices: np.ndarray, faces: np.ndarray, uv: np.ndarray, frame: PanelFrame,
                   size: int) -> np.ndarray:
    """(size, size, 2) float32 panel coordinates in metres of each texel of a garment's uv (row
    0 at v = 1): each texel on the panel its own rest position falls in (so a
    seam runs smooth across faces, not along their edges), where that panel reaches its face,
    else on its face's panel. A texel no face covers takes its nearest covered texel's (so
    filtering at an island's edge draws no seam)."""
    from scipy.ndimage import distance_transform_edt
    from synmitsuba.body.textures import rasterise_uv
    panels = panel_corners(layout, vertices, faces, uv, frame)
    rows, cols, f, w = rasterise_uv(uv, faces, size)
    own = PANEL_LAYOUTS[layout](np.einsum("nk,nkd->nd", w, vertices[faces[f]]), frame)
    at = np.full((len(f), 2), np.nan)
    for panel, corners in panels.corners.items():  # NaN where the panel does not reach the face
        on = own == panel
        at[on] = np.einsum("nk,nkd->nd", w[on], corners[f[on]])
    missing = ~np.isfinite(at).all(1)
    for panel, corners in panels.corners.items():
        on = missing & (panels.label[f] == panel)
        at[on] = np.einsum("nk,nkd->nd", w[on], corners[f[on]])
    out = np.zeros((size, size, 2))
    covered = np.zeros((size, size), bool)
    out[rows, cols] = at
    covered[rows, cols] = True
    if covered.any() and not covered.all():
        r, c = distance_transform_edt(~covered, return_distances=False, return_indices=True)
        out = out[r, c]
    return out.astype(np.float32)
