"""How high a clip's soles are over the ground at each frame, from its skeleton alone: what
planting a retargeted clip needs (``compose.subjects.planted``) when the source is not the
procedural humanoid, whose soles are known exactly (``humanoid.sole_clearance``).

Each foot of a recognised skeleton family (``names.canonical_map``: an ankle and a toe joint)
carries sole points rigid with its bones: under the heel, under the ball (both with the ankle
bone) and the toe's tip (its end joint, or under the toe joint, with the toe bone). A point is on
the ground at its lowest height over the clip (a low percentile of both feet's, so a glitch
frame of mocap does not set it); the clearance is the least height of any point above its own.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.body.skeleton import Skeleton, forward_kinematics
from synmitsuba.motion.motion import Motion
from synmitsuba.motion.names import canonical_map

HEEL_BACK_SHARE = 0.42  # the heel's contact point behind the ankle, in ankle-to-toe lengths (the humanoid's 5.5 / 13 cm)
CONTACT_PERCENTILE = 2.0  # of a sole point's heights over the clip (both feet): its height on the ground


@dataclass(frozen=True)
class SolePoint:
    """A point rigid with bone ``bone``: ``offset`` from its joint in the rest pose's axes;
    ``kind`` pairs it with the other foot's (heel 0, ball 1, tip 2)."""

    bone: int
    offset: np.ndarray
    kind: int


def sole_points(skeleton: Skeleton) -> list[SolePoint] | None:
    """Both feet's sole points, or None when the skeleton's ankles and toes are not known."""
    canon = {c: skeleton.index(n) for n, c in canonical_map(skeleton.names).items()}
    if any(f"{s}_{j}" not in canon for s in "lr" for j in ("ankle", "toe")):
        return None
    feet = [(canon[f"{s}_ankle"], canon[f"{s}_toe"], canon.get(f"{s}_toe_end")) for s in "lr"]
    rest = skeleton.rest_positions
    ground = min(rest[j, 1] for foot in feet for j in foot if j is not None)
    points = []
    for a, t, tip in feet:
        ahead = (rest[t] - rest[a]) * [1.0, 0.0, 1.0]
        heel = rest[a] - HEEL_BACK_SHARE * ahead
        on_ground = np.array([[heel[0], ground, heel[2]], [rest[t, 0], ground, rest[t, 2]]])
        end = rest[tip] if tip is not None else np.array([rest[t, 0], ground, rest[t, 2]])
        points += [SolePoint(a, on_ground[0] - rest[a], 0), SolePoint(a, on_ground[1] - rest[a], 1),
                   SolePoint(t, end - rest[t], 2)]
    return points


def foot_clearance(motion: Motion) -> np.ndarray | None:
    """The clip's sole clearance per frame (F,), in its units (metres once imported: 0 while a
    foot is on the ground), or None when its feet are not known (``sole_points``)."""
    points = sole_points(motion.skeleton)
    if points is None:
        return None
    G, P = forward_kinematics(motion.skeleton, motion.rotations, motion.root_translation)
    heights = np.stack([P[:, p.bone, 1] + G[:, p.bone, 1] @ p.offset for p in points], axis=1)
    kinds = np.array([p.kind for p in points])
    on_ground = {k: np.percentile(heights[:, kinds == k], CONTACT_PERCENTILE) for k in set(kinds.tolist())}
    above = heights - np.array([on_ground[k] for k in kinds])
    return np.maximum(above.min(axis=1), 0.0)
