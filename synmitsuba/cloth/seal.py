"""``WaistSeal``: a skirt's waistband closes it round the body (over the top tucked into it), so
nothing inside the skirt rises past the band. The cloth stage collides with the body alone, and
the band is held a top's thickness off it: in a jump's flight a circle skirt's hem folded up
inside itself, through that gap, to between the body and the tucked top (up to 24 mm under
it). After each frame, a free particle inside the band's bottom ring and above it is set just
under it, in the waist's frame (a rigid fit of the body's waist to its rest pose)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.geometry import rigid_fit

SEAL_GAP = 0.005  # metres under the band's bottom ring a particle is set


@dataclass(frozen=True)
class WaistSeal:
    """For one garment: its free particles' rows among all particles (``free``), the band's
    bottom ring in the rest pose (its height ``bottom``; its points' angles about its xz
    ``centre``, sorted and wrapped round, and their radii) and the body's rest ``waist``
    vertices (their indices ``anchors``) that the waist's frame is fitted to."""

    free: np.ndarray
    bottom: float
    centre: np.ndarray
    angles: np.ndarray
    radii: np.ndarray
    anchors: np.ndarray
    waist: np.ndarray

    def apply(self, body: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``q`` (all particles) with this garment's free ones that have risen inside the band
        set ``SEAL_GAP`` under its bottom ring; the others untouched (bit for bit)."""
        rot, shift = rigid_fit(self.waist, body[self.anchors])
        p = np.einsum("ij,jk->ik", q[self.free] - shift, rot)  # in the rest pose's frame
        rel = p[:, [0, 2]] - self.centre
        up = p[:, 1] > self.bottom - SEAL_GAP
        inside = np.hypot(*rel.T) < np.interp(np.arctan2(rel[:, 1], rel[:, 0]), self.angles, self.radii)
        hit = np.flatnonzero(up & inside)
        if not len(hit):
            return q
        p[hit, 1] = self.bottom - SEAL_GAP
        q = q.copy()
        q[self.free[hit]] = np.einsum("ij,kj->ik", p[hit], rot) + shift
        return q


def waist_seal(rest: np.ndarray, held: np.ndarray, rows: np.ndarray, body_rest: np.ndarray,
               torso: np.ndarray) -> WaistSeal:
    """The seal of a garment held by a band at its top: ``rest`` its particles' rest positions,
    ``held`` which are held, ``rows`` where they are among all particles; ``body_rest`` the body's
    rest vertices, ``torso`` (V,) which are the torso's (the waist's frame is fitted to those from
    the band's bottom up to 3 cm over its top)."""
    bottom, top = float(rest[held, 1].min()), float(rest[held, 1].max())
    ring = rest[held & (rest[:, 1] < bottom + 0.005)][:, [0, 2]]
    centre = ring.mean(0)
    a, r = np.arctan2(*(ring - centre).T[::-1]), np.hypot(*(ring - centre).T)
    order = np.argsort(a)
    a, r = a[order], r[order]  # wrapped round: np.interp is linear across the seam at +-pi
    angles, radii = np.r_[a[-1] - 2 * np.pi, a, a[0] + 2 * np.pi], np.r_[r[-1], r, r[0]]
    anchors = np.flatnonzero(torso & (body_rest[:, 1] >= bottom) & (body_rest[:, 1] <= top + 0.03))
    return WaistSeal(rows[~held], bottom, centre, angles, radii, anchors, body_rest[anchors])
