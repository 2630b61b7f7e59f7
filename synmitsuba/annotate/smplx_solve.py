"""The SMPL-X / SMPL fit's solver (``annotate.smplx_fit`` is its interface): the anny body
posed per frame as the target, the model's rest pose laid on anny's, the losses and Adam.

Losses, in cm: surface distance both ways (point to plane at the nearest vertex plus a tenth of
point to point, Geman-McClure with scale ``SIGMA_CM``, pairs whose normals disagree dropped),
the joints ``body_model_to_anny`` pairs (anny's bone heads plus the rest offset between the two
rigs, turned with the bone), a pull toward the starting pose (radians) and, in the pose step,
between neighbouring frames. Correspondences are refreshed every ``correspond_every``
iterations; the iterations pose every ``vertex_stride``-th model vertex.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.annotate.smplx_layer import ModelLayer, rodrigues
from synmitsuba.body.binding import closest_points
from synmitsuba.body.lbs import bone_transforms, skin
from synmitsuba.body.skeleton import Skeleton, forward_kinematics, local_rotations
from synmitsuba.body.smplx_model import ModelFile
from synmitsuba.geometry import axis_angle_to_matrix, matrix_to_axis_angle, vertex_normals
from synmitsuba.motion.names import TORSO, body_model_to_anny, canonical_map
from synmitsuba.motion.retargeting import aligned_globals, bone_children

BODY_JOINTS = {"smplx": 22, "smpl": 24}  # the root and the body's joints
# joints the pose step refines: the body's, and SMPL-X's jaw (22) and fingers (25-54); the eyes
# (23, 24) keep anny's gaze
POSE_JOINTS = {"smplx": list(range(23)) + list(range(25, 55)), "smpl": list(range(24))}
SIGMA_CM = 2.0                           # robust loss scale
FINGERS = ("thumb", "index", "middle", "ring", "pinky")


@dataclass
class FitSettings:
    """Iterations and loss weights (units: cm for distances, radians for the prior)."""

    joint_iterations: int = 80
    shape_iterations: int = 150
    pose_iterations: int = 30
    chunk: int = 16
    correspond_every: int = 10
    vertex_stride: int = 2     # the iterations pose every n-th model vertex; errors use them all
    joint_weight: float = 0.5
    prior_weight: float = 2.0          # pose step: pull toward the clip's rotations
    shape_prior_weight: float = 0.01   # shape step: the start is only a guess at the rest pose
    smooth_weight: float = 2.0
    betas_weight: float = 1e-3
    expression_weight: float = 1e-3   # pose step: a pull of the expression toward neutral


# -- targets ---------------------------------------------------------------------------------
@dataclass
class _Targets:
    """The anny body posed at each frame: what the model is fitted to."""

    vertices: np.ndarray        # (F, Va, 3)
    normals: np.ndarray         # (F, Va, 3)
    faces: np.ndarray
    joints: np.ndarray          # (F, Ja, 3) anny bone heads
    globals: np.ndarray         # (F, Ja, 3, 3) anny bone rotations from the rest pose


def _anny_targets(body, rotations, roots, faces=None) -> _Targets:
    """The anny body posed per frame, its face moved first by the ARKit weights ``faces``
    (F, 52) when the clip has a face track."""
    from synmitsuba.body.expressions import face_units
    sk = body.skeleton
    verts, normals, heads, glob = [], [], [], []
    for f, (R, t) in enumerate(zip(rotations, roots)):
        rest = face_units().moved(body.vertices, None if faces is None else faces[f])
        v = skin(rest, body.weights, bone_transforms(sk, R, t))
        G, P = forward_kinematics(sk, R, t)
        verts.append(v)
        normals.append(vertex_normals(v, body.faces))
        heads.append(P)
        glob.append(G)
    return _Targets(np.array(verts), np.array(normals), body.faces, np.array(heads), np.array(glob))


def _pairs(model: ModelFile, body) -> dict[int, int]:
    """{model joint: anny bone}."""
    names = body.skeleton.names
    return {model.joint_names.index(m): names.index(a) for m, a in body_model_to_anny(model.joint_names).items()
            if a in names}


# -- the rest pose that turns the model's bones onto anny's ---------------------------------------
def _rest_alignment(model: ModelFile, body, pairs: dict[int, int]) -> np.ndarray:
    """Local rotations (J, 3, 3) turning the model's mean-shape limb bones onto anny's rest bones
    (A-pose arms onto a T-pose model); the torso stays, as both stand upright facing +z (its
    short bones' directions say more about the two rigs than about the pose)."""
    J = model.J_regressor @ model.v_template
    sk = Skeleton(model.joint_names, model.parents, J)
    canon = canonical_map(model.joint_names, "smplx")
    children = {i: j for i, j in bone_children(sk, canon).items() if canon[model.joint_names[i]] not in TORSO}
    for i, name in enumerate(model.joint_names):  # finger joint k -> k + 1
        if name.split("_")[-1][:-1] in FINGERS and name[-1] in "12":
            children[i] = model.joint_names.index(name[:-1] + str(int(name[-1]) + 1))
    rest = body.skeleton.rest_positions
    bones = {i: (j, rest[pairs[j]] - rest[pairs[i]]) for i, j in children.items()
             if i != 0 and i in pairs and j in pairs}
    return local_rotations(aligned_globals(sk, bones), model.parents)


# -- optimisation ------------------------------------------------------------------------------
def _gm(r):
    """Geman-McClure on residuals in cm."""
    r2 = r * r
    return SIGMA_CM ** 2 * r2 / (SIGMA_CM ** 2 + r2)


class _Problem:
    """Frames of targets and the model's correspondences to them, refreshed now and then."""

    def __init__(self, layer: ModelLayer, targets: _Targets, joint_idx, joint_targets, s: FitSettings):
        import torch
        self.layer, self.t, self.s = layer, targets, s
        self.joint_idx = list(joint_idx)
        self.joint_targets = torch.as_tensor(joint_targets, dtype=torch.float32)
        self.A = torch.as_tensor(targets.vertices, dtype=torch.float32)
        self.NA = torch.as_tensor(targets.normals, dtype=torch.float32)
        self.faces = layer.model.faces
        self.subset = np.arange(0, len(layer.model.v_template), s.vertex_stride)
        self.subset_t = torch.as_tensor(self.subset)
        self.surface = True  # False: joints only (the shape step's first stage)
        from scipy.spatial import cKDTree
        self.trees = [cKDTree(v) for v in targets.vertices]

    def correspond(self, full: np.ndarray) -> None:
        """Nearest anny vertex for each model vertex and nearest model vertex for each anny
        vertex, per frame; pairs whose normals disagree get no weight."""
        import torch
        from scipy.spatial import cKDTree
        to_a, to_m, w_a, w_m, nm = [], [], [], [], []
        for f, v in enumerate(full):
            n = vertex_normals(v, self.faces)[self.subset]
            v = v[self.subset]
            ia = self.trees[f].query(v, workers=-1)[1]
            im = cKDTree(v).query(self.t.vertices[f], workers=-1)[1]
            to_a.append(ia)
            to_m.append(im)
            nm.append(n[im])
            w_a.append((n * self.t.normals[f][ia]).sum(1) > 0.3)
            w_m.append((n[im] * self.t.normals[f]).sum(1) > 0.3)
        self.to_a, self.to_m = torch.as_tensor(np.array(to_a)), torch.as_tensor(np.array(to_m))
        self.w_a = torch.as_tensor(np.array(w_a), dtype=torch.float32)
        self.w_m = torch.as_tensor(np.array(w_m), dtype=torch.float32)
        self.NM = torch.as_tensor(np.array(nm), dtype=torch.float32)

    def loss(self, verts, joints):
        import torch
        jerr = 100 * (joints[:, self.joint_idx] - self.joint_targets)
        joint_term = self.s.joint_weight * (jerr ** 2).sum(-1).mean()
        if not self.surface:
            return joint_term
        f = torch.arange(verts.shape[0])[:, None]
        p, n = self.A[f, self.to_a], self.NA[f, self.to_a]
        d = 100 * (verts - p)
        s2a = (self.w_a * (_gm((d * n).sum(-1)) + 0.1 * _gm(d.norm(dim=-1)))).mean()
        q = 100 * (self.A - torch.gather(verts, 1, self.to_m[..., None].expand(-1, -1, 3)))
        a2s = (self.w_m * (_gm((q * self.NM).sum(-1)) + 0.1 * _gm(q.norm(dim=-1)))).mean()
        return s2a + a2s + joint_term


def _run(problem: _Problem, betas, pose0, transl0, free: list[int], iterations: int, fit_betas: bool,
         warm=None, smooth: bool = False, prior: float = 0.0, expression: bool = False, expr0=None):
    """Adam on (betas), corrections to ``pose0`` at joints ``free`` and to ``transl0`` and, with
    ``expression``, the expression coefficients (from ``expr0`` (F, E), else zeros or the warm
    start); returns numpy (betas, pose (F, J, 3), transl (F, 3), expression (F, E), last
    corrections)."""
    import torch
    s = problem.s
    F = pose0.shape[0]
    base = torch.as_tensor(pose0, dtype=torch.float32)
    t0 = torch.as_tensor(transl0, dtype=torch.float32)
    dpose = torch.zeros((F, len(free), 3)) if warm is None else torch.as_tensor(warm[0]).repeat(F, 1, 1)
    dt = torch.zeros((F, 3)) if warm is None else torch.as_tensor(warm[1]).repeat(F, 1)
    E = problem.layer.n_expression if expression else 0
    ex = torch.zeros((F, E)) if warm is None or E == 0 else torch.as_tensor(warm[2]).repeat(F, 1)
    if E and expr0 is not None:
        ex = torch.as_tensor(expr0, dtype=torch.float32).clone()
    b = torch.as_tensor(betas, dtype=torch.float32)
    dpose.requires_grad_(), dt.requires_grad_(), ex.requires_grad_()
    groups = [{"params": [dpose], "lr": 0.02}, {"params": [dt], "lr": 0.005}]
    if E:
        groups.append({"params": [ex], "lr": 0.3})
    if fit_betas:
        b.requires_grad_()
        groups.append({"params": [b], "lr": 0.05})
    opt = torch.optim.Adam(groups)
    sched = torch.optim.lr_scheduler.MultiStepLR(opt, [int(0.6 * iterations), int(0.85 * iterations)], 0.3)
    free_t = torch.as_tensor(free)
    for it in range(iterations):
        pose = base.clone()
        pose[:, free_t] = base[:, free_t] + dpose
        expr = ex if E else None
        if problem.surface and it % s.correspond_every == 0:
            with torch.no_grad():
                problem.correspond(problem.layer(b, rodrigues(pose), t0 + dt, expression=expr)[0].numpy())
        verts, joints = problem.layer(b, rodrigues(pose), t0 + dt, problem.subset_t, expression=expr)
        loss = problem.loss(verts, joints) + prior * (dpose[:, 1:] ** 2).sum(-1).mean()
        if E:
            loss = loss + s.expression_weight * (ex ** 2).sum(-1).mean()
        if fit_betas:
            loss = loss + s.betas_weight * (b ** 2).sum()
        if smooth and F > 1:
            loss = loss + s.smooth_weight * ((dpose[1:] - dpose[:-1]) ** 2).sum(-1).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
    with torch.no_grad():
        pose = base.clone()
        pose[:, free_t] = base[:, free_t] + dpose
    return (b.detach().numpy().astype(np.float64), pose.numpy().astype(np.float64),
            (t0 + dt).detach().numpy().astype(np.float64), ex.detach().numpy().astype(np.float64),
            (dpose[-1].detach().clone(), dt[-1].detach().clone(), ex[-1].detach().clone()))


# -- the two steps -------------------------------------------------------------------------------
@dataclass
class Shape:
    model: ModelFile
    layer: ModelLayer
    betas: np.ndarray
    pose: np.ndarray            # (J, 3) the rest pose that lays the model on anny's rest body
    transl: np.ndarray          # (3,)
    error_mm: float
    offsets: np.ndarray         # (J, 3) model joint - anny bone head, rest pose


def fit_shape(model: ModelFile, body, n_betas: int = 10, settings: FitSettings | None = None) -> Shape:
    """Step 1: betas, rest pose and translation that lay the model on anny's rest body."""
    import torch
    s = settings or FitSettings()
    layer = ModelLayer(model, n_betas)
    pairs = _pairs(model, body)
    rest = body.skeleton.rest_positions
    targets = _anny_targets(body, [np.broadcast_to(np.eye(3), (len(rest), 3, 3))], [np.zeros(3)])
    idx = [j for j in pairs if j < BODY_JOINTS[model.kind]]
    pose0 = matrix_to_axis_angle(_rest_alignment(model, body, pairs))[None]
    J0 = model.J_regressor[0] @ model.v_template
    transl0 = (rest[pairs[0]] - J0)[None]
    problem = _Problem(layer, targets, idx, rest[[pairs[j] for j in idx]][None], s)
    free = list(range(BODY_JOINTS[model.kind]))
    problem.surface = False  # joints first: they fix the torso's bend, which the surface alone lets slide
    betas, pose, transl, _, _ = _run(problem, np.zeros(layer.n_betas), pose0, transl0, free, s.joint_iterations,
                                     True, prior=s.shape_prior_weight)
    problem.surface = True
    betas, pose, transl, _, _ = _run(problem, betas, pose, transl, free, s.shape_iterations, True,
                                     prior=s.shape_prior_weight)
    with torch.no_grad():
        verts, joints = layer(torch.as_tensor(betas, dtype=torch.float32), rodrigues(torch.as_tensor(pose, dtype=torch.float32)),
                              torch.as_tensor(transl, dtype=torch.float32))
    err = _surface_mm(verts.numpy().astype(np.float64), targets)
    joints = joints[0].numpy().astype(np.float64)
    offsets = np.zeros_like(joints)
    for j, a in pairs.items():
        offsets[j] = joints[j] - rest[a]
    return Shape(model, layer, betas, pose[0], transl[0], float(err[0].mean()), offsets)


def _surface_mm(model_verts: np.ndarray, targets: _Targets) -> np.ndarray:
    """(F, V) exact distances (mm) from the model's vertices to the anny surface."""
    return np.array([1000 * np.linalg.norm(closest_points(a, targets.faces, v, k=1)[0] - v, axis=1)
                     for a, v in zip(targets.vertices, model_verts)])


def _initial_pose(shape: Shape, pairs: dict[int, int], targets: _Targets, rest: np.ndarray):
    """Per frame, the model's local rotations (F, J, 3) and translation (F, 3) that turn each
    paired joint as its anny bone turns from the rest pose, starting from the fitted rest pose;
    and the joint targets: anny bone heads plus the rest offset turned with the bone."""
    m = shape.model
    W0 = forward_kinematics(Skeleton(m.joint_names, m.parents, np.zeros((len(m.parents), 3))),
                            axis_angle_to_matrix(shape.pose))[0]
    F = len(targets.globals)
    W = np.empty((F, len(m.parents), 3, 3))
    for j, p in enumerate(m.parents):
        W[:, j] = targets.globals[:, pairs[j]] @ W0[j] if j in pairs else W[:, p] @ (W0[p].T @ W0[j])
    J0 = m.J_regressor[0] @ (m.v_template + m.shapedirs[:, :, :len(shape.betas)] @ shape.betas)
    root = pairs[0]
    pelvis = targets.joints[:, root] + np.einsum("fab,b->fa", targets.globals[:, root], J0 + shape.transl - rest[root])
    jt = {j: targets.joints[:, a] + np.einsum("fab,b->fa", targets.globals[:, a], shape.offsets[j]) for j, a in pairs.items()}
    return matrix_to_axis_angle(local_rotations(W, m.parents)), pelvis - J0, jt, J0


@dataclass
class FrameFit:
    """Step 2's result over frames: parameters and per-frame errors."""

    pose: np.ndarray             # (N, J, 3) axis-angle, local
    transl: np.ndarray           # (N, 3)
    pelvis: np.ndarray           # (3,) the shaped model's rest pelvis joint
    surface_mean_mm: np.ndarray  # (N,)
    surface_max_mm: np.ndarray   # (N,)
    joint_mm: np.ndarray         # (N,)
    expression: np.ndarray       # (N, E) (E = 0 without an expression basis)
    hand_mm: np.ndarray          # (N,) mean surface distance of the model's hand vertices
    face_mm: np.ndarray          # (N,) ... of its face vertices


def part_vertices(model: ModelFile) -> dict[str, np.ndarray]:
    """The model's ``hand`` vertices (mostly skinned to a wrist or finger joint) and ``face``
    vertices (mostly skinned to the head, jaw or eyes, in front of the head joint in the rest
    pose, where the face looks: +z)."""
    owner = model.weights.argmax(1)
    names = model.joint_names
    hand = [j for j, n in enumerate(names) if n.endswith("wrist") or n.split("_")[-1][:-1] in FINGERS]
    head = [j for j, n in enumerate(names) if n in ("head", "jaw", "left_eye_smplx", "right_eye_smplx")]
    J = model.J_regressor @ model.v_template
    front = model.v_template[:, 2] > J[names.index("head"), 2] if "head" in names else np.zeros(len(owner), bool)
    return {"hand": np.flatnonzero(np.isin(owner, hand)), "face": np.flatnonzero(np.isin(owner, head) & front)}


def _solve_expression(layer: ModelLayer, betas, pose, transl, expr, targets: _Targets, trees: list,
                      face: np.ndarray, rounds: int = 4, ridge: float = 0.05) -> np.ndarray:
    """The expression (F, E) refined in closed form at the fitted pose. The face vertices move
    linearly in the coefficients (their columns found by differences, all frames in one batch),
    so point-to-plane distances to the nearest target points (``trees``, found again each
    round) are least squares in them, beside a small rigid motion of the face that takes up
    what the head's pose leaves (else the expression would bend the face to follow it);
    ``ridge`` pulls the coefficients toward neutral. Adam's few pose-step iterations leave the
    expression about half-way; this lands it."""
    import torch
    F, E = expr.shape
    t = lambda a: torch.as_tensor(np.ascontiguousarray(a), dtype=torch.float32)  # noqa: E731
    probe = (expr[:, None, :] + np.vstack([np.zeros(E), np.eye(E)])[None]).reshape(-1, E)
    with torch.no_grad():
        v = layer(t(betas), rodrigues(t(np.repeat(pose, E + 1, 0))), t(np.repeat(transl, E + 1, 0)),
                  torch.as_tensor(face), expression=t(probe))[0].numpy().astype(np.float64).reshape(F, E + 1, -1, 3)
    out = expr.copy()
    for f in range(F):
        v0, cols = v[f, 0], v[f, 1:] - v[f, 0]                               # (Vf, 3), (E, Vf, 3)
        arm = v0 - v0.mean(0)
        x = np.zeros(E + 6)                                                  # expression steps, then rotation, shift
        for _ in range(rounds):
            cur = v0 + np.einsum("e,evc->vc", x[:E], cols) + np.cross(x[E:E + 3], arm) + x[E + 3:]
            dist, idx = trees[f].query(cur)
            n, p = targets.normals[f][idx], targets.vertices[f][idx]
            A = np.concatenate([np.einsum("vc,evc->ve", n, cols), np.cross(arm, n), n], 1)
            r = np.einsum("vc,vc->v", n, p - v0)
            w = (dist < 0.015) / (1 + (np.einsum("vc,vc->v", n, p - cur) / 0.003) ** 2)  # far pairs, outliers: less
            reg = np.zeros(E + 6)
            reg[:E] = ridge * (A[:, :E] ** 2 * w[:, None]).sum() / E
            x = np.linalg.solve((A * w[:, None]).T @ A + np.diag(reg) + 1e-9 * np.eye(E + 6),
                                (A * w[:, None]).T @ r - reg * np.concatenate([expr[f], np.zeros(6)]))
        out[f] = expr[f] + x[:E]
    return out


def fit_frames(shape: Shape, body, clip, frames: np.ndarray, s: FitSettings) -> FrameFit:
    """Step 2 over ``frames`` of ``clip``, in chunks warm-started from the chunk before: the
    body, jaw and finger joints refined from the clip's, the expression (SMPL-X files with an
    expression basis) from neutral, against the body with the clip's face track on it."""
    import torch
    m = shape.model
    pairs = _pairs(m, body)
    rest = body.skeleton.rest_positions
    free = POSE_JOINTS[m.kind]
    idx = [j for j in pairs if j < BODY_JOINTS[m.kind]]
    expression = m.kind == "smplx" and shape.layer.n_expression > 0
    parts = part_vertices(m)
    poses, transls, exprs, surf, jerr, warm = [], [], [], [], [], None
    for start in range(0, len(frames), s.chunk):
        chunk = frames[start:start + s.chunk]
        faces = None if clip.face is None else clip.face[chunk]
        targets = _anny_targets(body, clip.rotations[chunk], clip.root_translation[chunk], faces)
        pose0, transl0, jt, J0 = _initial_pose(shape, pairs, targets, rest)
        problem = _Problem(shape.layer, targets, idx, np.stack([jt[j] for j in idx], 1), s)
        expr0 = None
        if expression and faces is not None:  # the face first, at the clip's pose: else the head turns to fit it
            expr0 = _solve_expression(shape.layer, shape.betas, pose0, transl0, np.zeros((len(chunk), shape.layer.n_expression)),
                                      targets, problem.trees, parts["face"])
        _, pose, transl, expr, warm = _run(problem, shape.betas, pose0, transl0, free, s.pose_iterations, False, warm,
                                           True, s.prior_weight, expression, expr0)
        if expr0 is not None:
            expr = _solve_expression(shape.layer, shape.betas, pose, transl, expr, targets, problem.trees, parts["face"])
        with torch.no_grad():
            verts, joints = shape.layer(torch.as_tensor(shape.betas, dtype=torch.float32),
                                        rodrigues(torch.as_tensor(pose, dtype=torch.float32)),
                                        torch.as_tensor(transl, dtype=torch.float32),
                                        expression=torch.as_tensor(expr, dtype=torch.float32) if expression else None)
        surf.append(_surface_mm(verts.numpy().astype(np.float64), targets))
        joints = joints.numpy().astype(np.float64)
        jerr.append(1000 * np.mean([np.linalg.norm(joints[:, j] - jt[j], axis=-1) for j in idx], 0))
        poses.append(pose)
        transls.append(transl)
        exprs.append(expr)
    mm = np.concatenate(surf)
    return FrameFit(np.concatenate(poses), np.concatenate(transls), J0, mm.mean(1), mm.max(1), np.concatenate(jerr),
                    np.concatenate(exprs), mm[:, parts["hand"]].mean(1), mm[:, parts["face"]].mean(1))
