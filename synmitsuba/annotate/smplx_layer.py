"""The SMPL / SMPL-X forward pass in torch, batched over frames and differentiable in betas,
pose and translation: shape blend shapes, joint regression, pose correctives, then linear blend
skinning about the regressed joints (the published model, written from its paper)."""
from __future__ import annotations

import numpy as np

from synmitsuba.body.smplx_model import ModelFile


def rodrigues(aa):
    """Axis-angle (..., 3) -> rotation matrices (..., 3, 3), smooth through zero."""
    import torch
    angle = torch.sqrt((aa * aa).sum(-1, keepdim=True) + 1e-12)
    k = aa / angle
    zero = torch.zeros_like(k[..., 0])
    K = torch.stack([zero, -k[..., 2], k[..., 1], k[..., 2], zero, -k[..., 0], -k[..., 1], k[..., 0], zero],
                    -1).reshape(k.shape[:-1] + (3, 3))
    s, c = torch.sin(angle)[..., None], torch.cos(angle)[..., None]
    return torch.eye(3, dtype=aa.dtype) + s * K + (1 - c) * (K @ K)


class ModelLayer:
    """``layer(betas, rotations, transl, expression=None)`` -> posed vertices (F, V, 3) and joints
    (F, J, 3); ``vertices=`` poses only those (the joints still come from the whole shaped mesh,
    expression included, as SMPL-X regresses them)."""

    def __init__(self, model: ModelFile, n_betas: int | None = None, n_expression: int = 10):
        import torch
        t = lambda a: torch.as_tensor(np.ascontiguousarray(a), dtype=torch.float32)  # noqa: E731
        self.model = model
        self.n_betas = model.n_betas if n_betas is None else min(n_betas, model.n_betas)
        self.n_expression = min(n_expression, model.exprdirs.shape[2])
        self.v_template = t(model.v_template)
        self.shapedirs = t(model.shapedirs[:, :, :self.n_betas])
        self.exprdirs = t(model.exprdirs[:, :, :self.n_expression])
        self.posedirs = t(model.posedirs) if np.any(model.posedirs) else None   # (V, 3, P)
        self.J_regressor = t(model.J_regressor)
        self.weights = t(model.weights)
        self.parents = [int(p) for p in model.parents]

    def shaped(self, betas):
        """Rest vertices (V, 3) and joints (J, 3) of shape ``betas`` (B,)."""
        v = self.v_template + self.shapedirs @ betas
        return v, self.J_regressor @ v

    def __call__(self, betas, rotations, transl, vertices=None, expression=None):
        """``rotations`` (F, J, 3, 3) local (the root's is the global orientation), ``transl``
        (F, 3), ``expression`` (F, E) or None."""
        import torch
        F = rotations.shape[0]
        v, J = self.shaped(betas)
        v, J = v.expand(F, -1, -1), J.expand(F, -1, -1)
        if expression is not None and self.n_expression:
            v = v + torch.einsum("vce,fe->fvc", self.exprdirs, expression[:, :self.n_expression])
            J = torch.einsum("jv,fvc->fjc", self.J_regressor, v)
        sel = slice(None) if vertices is None else vertices
        v, weights = v[:, sel], self.weights[sel]
        if self.posedirs is not None:
            feat = (rotations[:, 1:] - torch.eye(3)).reshape(F, -1)
            v = v + torch.einsum("vcp,fp->fvc", self.posedirs[sel], feat)
        G, P = [rotations[:, 0]], [J[:, 0]]
        for i in range(1, len(self.parents)):
            p = self.parents[i]
            G.append(G[p] @ rotations[:, i])
            P.append(P[p] + (G[p] @ (J[:, i] - J[:, p])[..., None])[..., 0])
        G, P = torch.stack(G, 1), torch.stack(P, 1)                       # (F, J, 3, 3), (F, J, 3)
        b = P - (G @ J[..., None])[..., 0]
        T = torch.cat([G.reshape(F, -1, 9), b], -1)                       # (F, J, 12)
        M = weights @ T                                                   # (F, V, 12)
        x, y, z = v[..., 0:1], v[..., 1:2], v[..., 2:3]
        out = M[..., 0:9:3] * x + M[..., 1:9:3] * y + M[..., 2:9:3] * z + M[..., 9:]
        return out + transl[:, None], P + transl[:, None]
