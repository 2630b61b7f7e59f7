"""Keypoint conventions our 23 keypoints (``anny_model.KEYPOINTS``: COCO-17, then COCO-WholeBody's
6 foot points) convert to, for training code written against another layout. A convention
lists, per output point, the keypoints it is the mean of (none: not labelled, masked out).
A derived point's visibility class is that of its sources when they agree, else 0 if any is
outside the image, else the highest occlusion class among them.

Joint conventions (``JOINT_CONVENTIONS``: ``smpl24``) take the subject's skeleton joints
(``joints3d_*``, anny's bone heads) that correspond to SMPL's 24, as retargeting and the SMPL
fits pair them; joints carry no occlusion class: 1 inside the image, 0 outside."""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from synmitsuba.body.anny_model import KEYPOINTS

_K = {name: i for i, name in enumerate(KEYPOINTS)}


@dataclass(frozen=True)
class Convention:
    names: tuple[str, ...]
    sources: tuple[tuple[int, ...], ...]  # per output point: source row indices averaged (() = unlabelled)
    rows: str = "body"  # what the sources index: "body" (our 23 keypoints) or "whole" (``whole_body_rows``)

    @property
    def mask(self) -> np.ndarray:
        """(K,) 1 where the point is labelled."""
        return np.array([1 if s else 0 for s in self.sources], np.uint8)


def _named(pairs) -> Convention:
    return Convention(tuple(n for n, _ in pairs), tuple(tuple(_K[s] for s in src) for _, src in pairs))


_BODY25 = [("nose", ["nose"]), ("neck", ["left_shoulder", "right_shoulder"]), ("right_shoulder", ["right_shoulder"]),
           ("right_elbow", ["right_elbow"]), ("right_wrist", ["right_wrist"]), ("left_shoulder", ["left_shoulder"]),
           ("left_elbow", ["left_elbow"]), ("left_wrist", ["left_wrist"]), ("mid_hip", ["left_hip", "right_hip"]),
           ("right_hip", ["right_hip"]), ("right_knee", ["right_knee"]), ("right_ankle", ["right_ankle"]),
           ("left_hip", ["left_hip"]), ("left_knee", ["left_knee"]), ("left_ankle", ["left_ankle"]),
           ("right_eye", ["right_eye"]), ("left_eye", ["left_eye"]), ("right_ear", ["right_ear"]),
           ("left_ear", ["left_ear"]), ("left_big_toe", ["left_big_toe"]), ("left_small_toe", ["left_small_toe"]),
           ("left_heel", ["left_heel"]), ("right_big_toe", ["right_big_toe"]), ("right_small_toe", ["right_small_toe"]),
           ("right_heel", ["right_heel"])]
_WHOLEBODY_REST = ([f"face_{i}" for i in range(68)] + [f"left_hand_{i}" for i in range(21)]
                   + [f"right_hand_{i}" for i in range(21)])

CONVENTIONS: dict[str, Convention] = {
    "ours": _named([(n, [n]) for n in KEYPOINTS]),
    "coco17": _named([(n, [n]) for n in KEYPOINTS[:17]]),
    "coco_wholebody": Convention(KEYPOINTS + tuple(_WHOLEBODY_REST),
                                 tuple((i,) for i in range(len(KEYPOINTS) + len(_WHOLEBODY_REST))), rows="whole"),
    "openpose25": _named(_BODY25),
}


JOINT_CONVENTIONS = ("smpl24",)


def whole_body_rows(rec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A record's 133 COCO-WholeBody rows: 2D (133, 2), camera-frame 3D (133, 3) and classes
    (133,): our 23 keypoints, the face's 68, the left then the right hand's 21. A record written
    before the face or the hands were labelled has those rows at 0 with class 0."""
    parts = [(rec["keypoints2d"], rec["keypoints3d_cam"], rec["visibility"], 23)]
    face, hands = rec.get("face2d", []), rec.get("hands2d", [])
    parts.append((face, rec.get("face3d_cam"), rec.get("face_visibility"), 68) if len(face) else (None, None, None, 68))
    for side in (0, 1):
        parts.append((hands[side], rec["hands3d_cam"][side], rec["hands_visibility"][side], 21) if len(hands)
                     else (None, None, None, 21))
    p2, p3, cls = [], [], []
    for a, b, c, n in parts:
        p2.append(np.zeros((n, 2)) if a is None else np.asarray(a, np.float64))
        p3.append(np.zeros((n, 3)) if b is None else np.asarray(b, np.float64))
        cls.append(np.zeros(n, np.uint8) if c is None else np.asarray(c, np.uint8))
    return np.concatenate(p2), np.concatenate(p3), np.concatenate(cls)


@functools.cache
def smpl24_bones() -> tuple[int, ...]:
    """anny bone index of each SMPL joint (``smplx_model.SMPL_JOINT_NAMES`` order)."""
    from synmitsuba.body.anny_model import _static
    from synmitsuba.body.smplx_model import SMPL_JOINT_NAMES
    from synmitsuba.motion.names import body_model_to_anny
    bones, pairs = list(_static()["bones"]), body_model_to_anny(SMPL_JOINT_NAMES)
    return tuple(bones.index(pairs[n]) for n in SMPL_JOINT_NAMES)


def joint_names(convention: str) -> tuple[str, ...]:
    from synmitsuba.body.smplx_model import SMPL_JOINT_NAMES
    return tuple(SMPL_JOINT_NAMES)


def convert_keypoints(points: np.ndarray, classes: np.ndarray, convention: str) -> tuple[np.ndarray, np.ndarray]:
    """Our keypoints (..., 23, D) and visibility classes (..., 23) (or, for a convention over
    ``rows="whole"``, the 133 of ``whole_body_rows``) in ``convention``: (..., K, D) and (..., K);
    unlabelled points are 0 with class 0 (see ``Convention.mask``)."""
    conv = CONVENTIONS[convention]
    points, classes = np.asarray(points), np.asarray(classes)
    out = np.zeros(points.shape[:-2] + (len(conv.names), points.shape[-1]), points.dtype)
    vis = np.zeros(classes.shape[:-1] + (len(conv.names),), classes.dtype)
    for k, src in enumerate(conv.sources):
        if not src:
            continue
        out[..., k, :] = points[..., list(src), :].mean(-2)
        c = classes[..., list(src)]
        vis[..., k] = np.where((c == c[..., :1]).all(-1), c[..., 0], np.where((c == 0).any(-1), 0, c.max(-1)))
    return out, vis
