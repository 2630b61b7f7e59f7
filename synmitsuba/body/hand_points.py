"""Hand keypoints: COCO-WholeBody's 21 points a hand on anny's hand.

Order and names as COCO-WholeBody (and MediaPipe Hands) give them: the wrist, then the thumb
(CMC, MCP, IP, tip) and each finger (MCP, PIP, DIP, tip) from index to pinky. Joints are anny's
bone heads (wrist, finger1-1 .. finger5-3); a tip is the skin vertex of the end bone that lies
furthest along that bone in the rest pose, so it moves with the skin.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

HAND_FINGERS = ("thumb", "forefinger", "middle_finger", "ring_finger", "pinky_finger")
HAND_KEYPOINTS = ("hand_root",) + tuple(f"{f}{k}" for f in HAND_FINGERS for k in (1, 2, 3, 4))


def hand_keypoint_names(side: str) -> tuple[str, ...]:
    """COCO-WholeBody's names of one hand's 21 points, ``side`` "left" or "right"."""
    return tuple(f"{side}_{n}" for n in HAND_KEYPOINTS)


@dataclass(frozen=True)
class HandPoints:
    """Where each hand's 21 points come from: bone heads (2, 16) for the wrist and the
    three joints of each finger, in ``HAND_KEYPOINTS`` order without the tips, and tip
    vertices (2, 5)."""

    joints: np.ndarray
    tips: np.ndarray

    def posed(self, transforms: tuple[np.ndarray, np.ndarray], rest_heads: np.ndarray, vertices: np.ndarray,
              weights) -> np.ndarray:
        """(2, 21, 3) world points, left hand first, for bone ``transforms`` (A, b)."""
        from synmitsuba.body.lbs import skin
        A, b = transforms
        heads = np.einsum("jab,jb->ja", A, rest_heads) + b
        tips = skin(vertices[self.tips.ravel()], weights[self.tips.ravel()], transforms).reshape(2, 5, 3)
        out = np.empty((2, 21, 3))
        out[:, 0] = heads[self.joints[:, 0]]
        for f in range(5):
            out[:, 1 + 4 * f:4 + 4 * f] = heads[self.joints[:, 1 + 3 * f:4 + 3 * f]]
            out[:, 4 + 4 * f] = tips[:, f]
        return out


def hand_points(skeleton, vertices: np.ndarray, weights: np.ndarray) -> HandPoints:
    """Bones and tip vertices of both hands (left first) on a rest body."""
    joints, tips = np.zeros((2, 16), np.int64), np.zeros((2, 5), np.int64)
    owner = np.asarray(weights.argmax(1)).ravel()
    P = skeleton.rest_positions
    for h, s in enumerate("LR"):
        joints[h, 0] = skeleton.index(f"wrist.{s}")
        for f in range(5):
            chain = [skeleton.index(f"finger{f + 1}-{k}.{s}") for k in (1, 2, 3)]
            joints[h, 1 + 3 * f:4 + 3 * f] = chain
            end = np.flatnonzero(owner == chain[2])
            along = P[chain[2]] - P[chain[1]]
            tips[h, f] = end[np.argmax((vertices[end] - P[chain[2]]) @ along)]
    return HandPoints(joints, tips)


def dorsal_axis(skeleton, s: str) -> np.ndarray:
    """Unit direction out of the back of hand ``s`` ("L" or "R") in the rest pose: normal to the
    plane of the middle finger and the knuckles, on the side away from the thumb."""
    P = skeleton.rest_positions

    def at(name):
        return P[skeleton.index(f"{name}.{s}")]
    dorsal = np.cross(at("finger3-3") - at("finger3-1"), at("finger5-1") - at("finger2-1"))
    dorsal /= np.linalg.norm(dorsal)
    return -dorsal if (at("finger1-2") - at("finger3-1")) @ dorsal > 0 else dorsal  # the thumb sits on the palm's side

