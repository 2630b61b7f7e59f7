"""Retargeting as the SynBody paper states it.

Model-space rotations come from forward kinematics, R^_i(t) = R^_p(i)(t) R_i(t). Both
skeletons are brought to a common T-pose (frame 0): R^_i(0) for the target, R^_src(0) for the
source, found by turning each bone onto the canonical humanoid's T-pose direction. Each target
bone then takes its source bone's rotation relative to the T-pose,
    R^_i(t) = R^_src(t) R^_src(0)^-1 R^_i(0),
which equals the paper's R^_i(0) R^_src(t) R^_src(0)^-1 whenever R^_i(0) is the identity (a
target whose rest pose is the T-pose, as in our Skeleton convention), and otherwise is the order
that keeps bone directions equal between source and target. Root translation is scaled by the
ratio of pelvis heights, T(t) = H_pelvis / H_pelvis_src * T_src(t). A SMPL-X source (AMASS)
also hands its 30 finger joints to anny's finger bones (``names.finger_pairs``), rest to rest;
``meta["fingers"]`` says whether it moved any, so drawn hand behaviours leave them alone. Every
source's toe joint (at the ball) turns all five of anny's toes (``names.toe_followers``).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from synmitsuba.body.skeleton import Skeleton
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import align_vectors
from synmitsuba.motion.humanoid import humanoid_skeleton
from synmitsuba.motion.motion import Motion
from synmitsuba.motion.names import BONE_CHILD, canonical_map, finger_pairs, toe_followers


def _descendant(sk: Skeleton, i: int, j: int) -> bool:
    while j >= 0:
        if j == i:
            return True
        j = sk.parents[j]
    return False


def aligned_globals(sk: Skeleton, bones: dict[int, tuple[int, np.ndarray]]) -> np.ndarray:
    """Global rotations (J, 3, 3) that turn each listed bone, ``{joint: (descendant joint,
    direction)}``, onto its direction by the smallest rotation from its parent's; every other
    joint keeps its parent's."""
    G = np.empty((len(sk), 3, 3))
    for i in range(len(sk)):
        parent = G[sk.parents[i]] if sk.parents[i] >= 0 else np.eye(3)
        G[i] = parent
        if i in bones:
            j, direction = bones[i]
            d_rest = parent @ (sk.rest_positions[j] - sk.rest_positions[i])
            if np.linalg.norm(d_rest) > 1e-9:
                G[i] = align_vectors(d_rest, direction) @ parent
    return G


def bone_children(sk: Skeleton, canon: dict[str, str]) -> dict[int, int]:
    """{joint: the descendant its bone points to} through the canonical names (``BONE_CHILD``)."""
    inv = {c: n for n, c in canon.items()}
    out = {}
    for i, name in enumerate(sk.names):
        child = BONE_CHILD.get(canon.get(name, ""))
        if child in inv and _descendant(sk, i, sk.index(inv[child])):
            out[i] = sk.index(inv[child])
    return out


def tpose_globals(sk: Skeleton, canon: dict[str, str]) -> np.ndarray:
    """Global rotations (J, 3, 3) that put ``sk`` into the canonical humanoid's T-pose.

    The feet (each ankle and everything below it) keep their rest orientation: every rest pose
    we read stands flat-footed, while bone directions differ by skeleton (anny's ankle-to-toe
    slopes 19 degrees, the humanoid's 26.6), and aligning them would hold a target's feet
    toe-down by the difference at every frame."""
    ref = humanoid_skeleton()
    bones = {i: (j, ref.rest_positions[ref.index(BONE_CHILD[canon[sk.names[i]]])] -
                 ref.rest_positions[ref.index(canon[sk.names[i]])]) for i, j in bone_children(sk, canon).items()}
    G = aligned_globals(sk, bones)
    G[_feet(sk, canon)] = np.eye(3)
    return G


def _feet(sk: Skeleton, canon: dict[str, str]) -> list[int]:
    """Each ankle joint and all its descendants."""
    ankles = [i for i, n in enumerate(sk.names) if canon.get(n, "").endswith("_ankle")]
    return [j for j in range(len(sk)) if any(_descendant(sk, a, j) for a in ankles)]


def pelvis_height(sk: Skeleton, root: int = 0) -> float:
    """Height of the root joint above the lowest joint of the rest pose."""
    return float(sk.rest_positions[root, 1] - sk.rest_positions[:, 1].min())


def _pairs(src: Skeleton, tgt: Skeleton, name_map: dict | None) -> dict[int, int]:
    """{target joint index: source joint index}."""
    if name_map is not None:
        bad = [k for k in name_map if k not in src.names] + [v for v in name_map.values() if v not in tgt.names]
        if bad:
            raise ConfigError("name_map", bad[0], "names must be source joints -> target joints")
        return {tgt.index(t): src.index(s) for s, t in name_map.items()}
    if src.names == tgt.names:
        return {i: i for i in range(len(tgt))}
    cs, ct = canonical_map(src.names), canonical_map(tgt.names)
    inv_s = {c: n for n, c in cs.items()}
    pairs = {tgt.index(n): src.index(inv_s[c]) for n, c in ct.items() if c in inv_s}
    if len(pairs) < 6:
        raise ConfigError("name_map", None, "could not match the skeletons' joint names (found "
                          f"{len(pairs)} pairs); pass name_map={{source joint: target joint}}")
    pairs.update({tgt.index(t): src.index(s) for t, s in finger_pairs(src.names, tgt.names).items()})
    pairs.update({tgt.index(t): pairs[tgt.index(m)] for t, m in toe_followers(tgt.names).items()
                  if tgt.index(m) in pairs})
    return pairs


def _moves_fingers(motion: Motion, target: Skeleton) -> bool:
    """Whether the source turns any finger joint it hands over to the target's fingers."""
    joints = [motion.skeleton.index(s) for s in finger_pairs(motion.skeleton.names, target.names).values()]
    return bool(joints) and not np.allclose(motion.rotations[:, joints], np.eye(3), atol=1e-9)


def retarget(motion: Motion, target: Skeleton, name_map: dict | None = None) -> Motion:
    """The motion on ``target``: mapped bones follow the source bones' model-space rotations
    relative to the common T-pose; unmapped ones keep their T-pose; the root translation is
    scaled by the pelvis height ratio."""
    src = motion.skeleton
    pairs = _pairs(src, target, name_map)
    same = src.names == target.names and np.allclose(src.rest_positions, target.rest_positions)
    if same:
        S0 = T0 = np.broadcast_to(np.eye(3), (len(target), 3, 3))
    else:
        S0 = tpose_globals(src, canonical_map(src.names))
        T0 = tpose_globals(target, canonical_map(target.names))
    Gs = motion.global_rotations()
    F = motion.n_frames
    G = np.empty((F, len(target), 3, 3))
    R = np.empty_like(G)
    for i in range(len(target)):
        p = target.parents[i]
        if i in pairs:
            s = pairs[i]
            G[:, i] = Gs[:, s] @ (S0[s].T @ T0[i])
        else:
            G[:, i] = (G[:, p] if p >= 0 else np.eye(3)) @ ((T0[p].T if p >= 0 else np.eye(3)) @ T0[i])
        R[:, i] = G[:, i] if p < 0 else np.swapaxes(G[:, p], -1, -2) @ G[:, i]
    s_root = pairs.get(0, 0)
    ratio = pelvis_height(target) / max(pelvis_height(src, s_root), 1e-9)
    if same:
        ratio = 1.0
    world_root = src.rest_positions[s_root] + motion.root_translation if s_root == 0 else \
        motion.joint_positions()[:, s_root]
    root = ratio * world_root - target.rest_positions[0]
    return replace(motion, skeleton=target, rotations=R, root_translation=root,
                   meta={**motion.meta, "retargeted_from": list(src.names[:3]), "pelvis_ratio": ratio,
                         "fingers": _moves_fingers(motion, target)})
