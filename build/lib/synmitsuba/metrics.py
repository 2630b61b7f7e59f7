"""Evaluation metrics for pose-and-shape estimation and rendering, on numpy arrays.

Joints and vertices are (..., N, 3) in metres (results in metres; multiply by 1000 for mm).
Images are (H, W) or (H, W, C) floats; ``data_range`` is the span of valid values (1.0 for
images in [0, 1]).
"""
from __future__ import annotations

import numpy as np

from synmitsuba.errors import ConfigError


def _pair(pred, gt, what: str) -> tuple[np.ndarray, np.ndarray]:
    p, g = np.asarray(pred, np.float64), np.asarray(gt, np.float64)
    if p.shape != g.shape or p.ndim < 2 or p.shape[-1] != 3:
        raise ConfigError(what, f"{p.shape} vs {g.shape}", "give predictions and ground truth of the same shape (..., N, 3)")
    return p, g


def mpjpe(pred, gt) -> float:
    """Mean per-joint position error: mean Euclidean distance over joints (and frames)."""
    p, g = _pair(pred, gt, "mpjpe")
    return float(np.linalg.norm(p - g, axis=-1).mean())


def pve(pred, gt) -> float:
    """Per-vertex error: ``mpjpe`` over mesh vertices (same topology)."""
    p, g = _pair(pred, gt, "pve")
    return float(np.linalg.norm(p - g, axis=-1).mean())


def procrustes(pred, gt) -> np.ndarray:
    """``pred`` (N, 3) aligned to ``gt`` by the similarity transform (scale, rotation,
    translation) that minimises the squared error (Umeyama, 1991; reflections excluded)."""
    p, g = _pair(pred, gt, "procrustes")
    mp, mg = p.mean(0), g.mean(0)
    P, G = p - mp, g - mg
    U, S, Vt = np.linalg.svd(P.T @ G)
    D = np.eye(3)
    D[2, 2] = np.sign(np.linalg.det(U @ Vt))
    R = (U @ D @ Vt).T
    scale = np.trace(np.diag(S) @ D) / (P ** 2).sum()
    return scale * P @ R.T + mg


def pa_mpjpe(pred, gt) -> float:
    """MPJPE after Procrustes alignment of each frame's joints (..., N, 3)."""
    p, g = _pair(pred, gt, "pa_mpjpe")
    flat_p, flat_g = p.reshape(-1, *p.shape[-2:]), g.reshape(-1, *g.shape[-2:])
    return float(np.mean([np.linalg.norm(procrustes(a, b) - b, axis=-1).mean() for a, b in zip(flat_p, flat_g)]))


def pck(pred, gt, threshold: float, visible=None) -> float:
    """Share of keypoints (2D or 3D, (..., N, D)) within ``threshold`` of the ground truth,
    over the ``visible`` ones when a mask (..., N) is given."""
    p, g = np.asarray(pred, np.float64), np.asarray(gt, np.float64)
    if p.shape != g.shape:
        raise ConfigError("pck", f"{p.shape} vs {g.shape}", "give predictions and ground truth of the same shape")
    hit = np.linalg.norm(p - g, axis=-1) <= threshold
    if visible is not None:
        v = np.broadcast_to(np.asarray(visible, bool), hit.shape)
        if not v.any():
            raise ConfigError("pck.visible", "none", "at least one keypoint must be visible")
        return float(hit[v].mean())
    return float(hit.mean())


def psnr(img, ref, data_range: float = 1.0) -> float:
    """Peak signal-to-noise ratio in dB (inf for identical images)."""
    a, b = np.asarray(img, np.float64), np.asarray(ref, np.float64)
    if a.shape != b.shape:
        raise ConfigError("psnr", f"{a.shape} vs {b.shape}", "give two images of the same shape")
    mse = np.mean((a - b) ** 2)
    return float("inf") if mse == 0 else float(10 * np.log10(data_range ** 2 / mse))


def ssim(img, ref, data_range: float = 1.0, sigma: float = 1.5) -> float:
    """Structural similarity (Wang et al. 2004): Gaussian window (sigma 1.5, truncated at
    3.5 sigma), K1 = 0.01, K2 = 0.03, averaged over valid pixels and channels."""
    from scipy.ndimage import gaussian_filter
    a, b = np.asarray(img, np.float64), np.asarray(ref, np.float64)
    if a.shape != b.shape or a.ndim not in (2, 3):
        raise ConfigError("ssim", f"{a.shape} vs {b.shape}", "give two (H, W) or (H, W, C) images of the same shape")
    if a.ndim == 2:
        a, b = a[..., None], b[..., None]
    c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
    r = int(3.5 * sigma + 0.5)
    if min(a.shape[:2]) <= 2 * r:
        raise ConfigError("ssim", a.shape, f"images must be larger than the {2 * r + 1}-pixel window")

    def blur(x):
        return np.stack([gaussian_filter(x[..., c], sigma, truncate=3.5, mode="reflect") for c in range(x.shape[-1])], -1)
    mu_a, mu_b = blur(a), blur(b)
    var_a, var_b, cov = blur(a * a) - mu_a ** 2, blur(b * b) - mu_b ** 2, blur(a * b) - mu_a * mu_b
    s = ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) / ((mu_a ** 2 + mu_b ** 2 + c1) * (var_a + var_b + c2))
    return float(s[r:-r, r:-r].mean())
