"""A body model in the SMPL-X (or SMPL) file layout made from anny itself: for tests, benchmarks
and trying the fit without the licensed files.

The template is anny's body at the middle phenotypes; the shape basis is the principal
components of anny bodies at random phenotypes (scaled so betas are unit variance); joints are
the anny bones ``body_model_to_anny`` names, regressed from nearby vertices; skinning weights
are anny's, summed onto those joints; there are no pose correctives. The rest pose is anny's
(a retargeted clip's anny rotations are then this model's pose parameters) or, with
``rest="tpose"``, the canonical T-pose the published models rest in.
"""
from __future__ import annotations

import os
from typing import Any

import numpy as np

from synmitsuba.body.anny_model import PHENOTYPES, _static, shaped_batch
from synmitsuba.body.lbs import bone_transforms, skin
from synmitsuba.body.skeleton import Skeleton, forward_kinematics, local_rotations
from synmitsuba.body.smplx_model import KINDS, SMPL_JOINT_NAMES, SMPL_PARENTS, SMPLX_JOINT_NAMES, SMPLX_PARENTS
from synmitsuba.motion.names import TORSO, body_model_to_anny, canonical_map
from synmitsuba.motion.retargeting import tpose_globals

GENDER_RANGE = {"neutral": (0.0, 1.0), "male": (0.0, 0.3), "female": (0.7, 1.0)}  # anny: 0 male, 1 female


def sample_phenotypes(rng: np.random.Generator, n: int, gender: str = "neutral") -> list[dict]:
    lo, hi = GENDER_RANGE[gender]
    rows = [{k: float(rng.random()) for k in PHENOTYPES} for _ in range(n)]
    for r in rows:
        r["gender"] = lo + (hi - lo) * r["gender"]
    return rows


def _joint_bones(names, bones: tuple) -> list[int]:
    """The anny bone index standing for each model joint (a joint without one, SMPL-X's jaw,
    sits at its parent's bone: the head)."""
    table = body_model_to_anny(names)
    return [bones.index(table.get(n, "head")) for n in names]


def _skinning(names, bones: tuple, parents: np.ndarray, anny_weights: np.ndarray) -> np.ndarray:
    """anny's weights summed onto model joints: a bone goes to its own joint, toes to the foot
    joint, fingers to the hand joint when the model has no fingers (SMPL), else to the nearest
    ancestor with a joint."""
    table = {b: i for i, b in enumerate(body_model_to_anny(names).get(n) for n in names) if b is not None}
    owner = np.empty(len(bones), np.int64)
    for b, name in enumerate(bones):
        side = "left" if name.endswith(".L") else "right"
        k = b
        while bones[k] not in table:
            k = parents[k]
        owner[b] = table[bones[k]]
        if name.startswith("toe"):
            owner[b] = names.index(f"{side}_foot")
        elif name.startswith(("finger", "metacarpal")) and f"{side}_hand" in names:
            owner[b] = names.index(f"{side}_hand")
    W = np.zeros((len(anny_weights), len(names)))
    np.add.at(W.T, owner, anny_weights.T)
    return W


def _regressor(verts: np.ndarray, joints: np.ndarray, near: int = 128) -> np.ndarray:
    """(J, V) rows that give each joint from its ``near`` closest template vertices in every
    sample shape (least squares, rows summing to one)."""
    from scipy.spatial import cKDTree
    S, V, _ = verts.shape
    _, idx = cKDTree(verts[0]).query(joints[0], k=near)
    reg = np.zeros((joints.shape[1], V))
    for j, cols in enumerate(idx):
        A = verts[:, cols, :].transpose(0, 2, 1).reshape(-1, near)   # (S * 3, near)
        b = joints[:, j, :].reshape(-1)
        A = np.vstack([A, 10.0 * np.ones((1, near)), 1e-3 * np.eye(near)])
        b = np.concatenate([b, [10.0], np.full(near, 1e-3 / near)])
        reg[j, cols] = np.linalg.lstsq(A, b, rcond=None)[0]
    return reg


def _tposed(verts: np.ndarray, heads: np.ndarray, st: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every sample's limbs turned into the canonical T-pose (the rotations found on the first;
    the trunk keeps its natural bend): the rest pose of the published models. Also returns
    those global rotations (J, 3, 3)."""
    sk = Skeleton(st["bones"], st["parents"], heads[0])
    G = tpose_globals(sk, {n: c for n, c in canonical_map(st["bones"]).items() if c not in TORSO})
    local = local_rotations(G, st["parents"])
    out_v, out_h = np.empty_like(verts), np.empty_like(heads)
    for i, (v, h) in enumerate(zip(verts, heads)):
        sk_i = Skeleton(st["bones"], st["parents"], h)
        out_v[i] = skin(v, st["weights"], bone_transforms(sk_i, local))
        out_h[i] = forward_kinematics(sk_i, local)[1]
    return out_v, out_h, G


def expression_basis(n: int = 10, samples: int = 512, seed: int = 0) -> np.ndarray:
    """(V, 3, n) an expression basis on anny's mesh: the principal directions of the face
    displacements anny's 52 units make in random sparse mixes (uncentred, so zero coefficients
    are the neutral face), scaled so coefficients have unit variance over those mixes."""
    from synmitsuba.body.expressions import face_units
    units = face_units()
    rng = np.random.default_rng(seed)
    W = rng.random((samples, units.offsets.shape[0])) * (rng.random((samples, units.offsets.shape[0])) < 0.15)
    D = W @ units.offsets.reshape(len(W[0]), -1)
    _, sv, vt = np.linalg.svd(D, full_matrices=False)
    local = (vt[:n] * (sv[:n, None] / np.sqrt(samples))).T.reshape(-1, 3, n)
    out = np.zeros((len(_static()["weights"]), 3, n))
    out[units.vertices] = local
    return out


def write_anny_model(folder: str, kind: str = "smplx", gender: str = "neutral", n_betas: int = 16,
                     n_samples: int = 64, seed: int = 0, rest: str = "anny") -> str:
    """Write ``<KIND>_<GENDER>.npz`` into ``folder`` and return its path. ``rest="tpose"``
    makes the T-pose the model's rest pose, as in the published files (``anny_rest`` then
    holds, per model joint, the rotation of its anny bone from anny's rest pose to it). SMPL-X
    files take SMPL-X v1.0's layout, 10 shape then 10 expression columns (``expression_basis``:
    anny's face units), whatever ``n_betas``, and hand PCA arrays (``hands_components{l,r}``: a
    random orthonormal basis where the published files hold MANO's components; ``hands_mean{l,r}``
    small random poses) in their layout."""
    names = SMPLX_JOINT_NAMES if kind == "smplx" else SMPL_JOINT_NAMES
    parents = np.array(SMPLX_PARENTS if kind == "smplx" else SMPL_PARENTS)
    rows = [{k: 0.5 for k in PHENOTYPES}] + sample_phenotypes(np.random.default_rng(seed), n_samples, gender)
    verts, heads = shaped_batch(rows)
    st = _static()
    G = np.broadcast_to(np.eye(3), (len(st["bones"]), 3, 3))
    if rest == "tpose":
        verts, heads, G = _tposed(verts, heads, st)
    diff = (verts[1:] - verts[0]).reshape(n_samples, -1)
    _, sv, vt = np.linalg.svd(diff, full_matrices=False)
    basis = (vt[:n_betas] * (sv[:n_betas, None] / np.sqrt(n_samples))).T.reshape(-1, 3, n_betas)
    joints = heads[:, _joint_bones(names, st["bones"])]
    kintree = np.stack([np.where(parents < 0, 2 ** 32 - 1, parents), np.arange(len(names))]).astype(np.int64)
    hands: dict[str, Any] = {}
    if kind == "smplx":
        basis = np.concatenate([basis[:, :, :10], expression_basis(10, seed=seed)], 2)
        rng = np.random.default_rng([seed, 45])
        for side in "lr":
            hands[f"hands_components{side}"] = np.linalg.qr(rng.normal(size=(45, 45)))[0].T
            hands[f"hands_mean{side}"] = rng.normal(0.0, 0.1, 45)
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, f"{KINDS[kind][0]}_{gender.upper()}.npz")
    np.savez(path, v_template=verts[0], f=st["faces"], shapedirs=basis, J_regressor=_regressor(verts, joints),
             weights=_skinning(names, st["bones"], st["parents"], st["weights"].astype(np.float64)),
             kintree_table=kintree, posedirs=np.zeros((verts.shape[1], 3, 9 * (len(names) - 1))),
             anny_rest=G[_joint_bones(names, st["bones"])], **hands)
    return path


def true_pose(path: str, body, clip, frames=None) -> np.ndarray:
    """The pose (F, J, 3, 3 local rotations) that lays a synthetic model written here on ``body``
    posed by ``clip``: each joint turns as its anny bone, from the model's rest (``anny_rest``)."""
    with np.load(path) as data:
        rest, parents = data["anny_rest"], data["kintree_table"][0].astype(np.int64)
    parents[0] = -1
    frames = np.arange(clip.n_frames) if frames is None else np.asarray(frames)
    names = SMPLX_JOINT_NAMES if len(parents) == len(SMPLX_JOINT_NAMES) else SMPL_JOINT_NAMES
    D = forward_kinematics(body.skeleton, clip.rotations[frames], clip.root_translation[frames])[0]
    W = D[:, _joint_bones(names, body.skeleton.names)] @ np.swapaxes(rest, -1, -2)
    return local_rotations(W, parents)
