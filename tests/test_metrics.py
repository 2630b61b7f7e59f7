"""synmitsuba.metrics against hand-computed values and separately written formulas."""
import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from synmitsuba import metrics
from synmitsuba.errors import ConfigError


def test_mpjpe_pve_and_pck_by_hand():
    gt = np.zeros((2, 4, 3))
    pred = gt + [3.0, 4.0, 0.0]                     # every joint 5 away
    assert metrics.mpjpe(pred, gt) == 5.0 and metrics.pve(pred, gt) == 5.0
    pred[0, 0] = 0.0                                # one of 8 exact
    assert metrics.mpjpe(pred, gt) == pytest.approx(35 / 8)
    assert metrics.pck(pred, gt, 1.0) == 1 / 8 and metrics.pck(pred, gt, 5.0) == 1.0
    vis = np.zeros((2, 4), bool)
    vis[0, :2] = True
    assert metrics.pck(pred, gt, 1.0, visible=vis) == 0.5
    with pytest.raises(ConfigError, match="same shape"):
        metrics.mpjpe(pred[:, :3], gt)


def test_pa_mpjpe_removes_a_similarity_and_matches_a_brute_force_fit():
    rng = np.random.default_rng(0)
    gt = rng.normal(size=(17, 3))
    R = Rotation.from_rotvec([0.3, -1.1, 0.5]).as_matrix()
    assert metrics.pa_mpjpe(1.7 * gt @ R.T + [1, 2, 3], gt) < 1e-12
    pred = gt + 0.1 * rng.normal(size=gt.shape)

    def err(x):  # scale, rotation vector, translation, fitted by a general optimiser
        aligned = np.exp(x[0]) * pred @ Rotation.from_rotvec(x[1:4]).as_matrix().T + x[4:]
        return ((aligned - gt) ** 2).sum()
    best = minimize(err, np.zeros(7), method="BFGS", options={"gtol": 1e-10}).x
    aligned = np.exp(best[0]) * pred @ Rotation.from_rotvec(best[1:4]).as_matrix().T + best[4:]
    assert metrics.pa_mpjpe(pred, gt) == pytest.approx(np.linalg.norm(aligned - gt, axis=1).mean(), rel=1e-5)


def test_psnr_by_hand():
    a = np.zeros((4, 4, 3))
    assert metrics.psnr(a + 0.1, a) == pytest.approx(20.0)
    assert metrics.psnr(a, a) == float("inf")
    assert metrics.psnr(a + 25.5, a, data_range=255) == pytest.approx(20.0)


def _ssim_direct(a, b, sigma=1.5, r=5, L=1.0):
    """SSIM with explicit window sums at every valid pixel (no filtering library)."""
    x = np.arange(-r, r + 1)
    g = np.exp(-x ** 2 / (2 * sigma ** 2))
    w = np.outer(g, g) / g.sum() ** 2
    c1, c2 = (0.01 * L) ** 2, (0.03 * L) ** 2
    vals = []
    for i in range(r, a.shape[0] - r):
        for j in range(r, a.shape[1] - r):
            pa, pb = a[i - r:i + r + 1, j - r:j + r + 1], b[i - r:i + r + 1, j - r:j + r + 1]
            ma, mb = (w * pa).sum(), (w * pb).sum()
            va, vb = (w * (pa - ma) ** 2).sum(), (w * (pb - mb) ** 2).sum()
            cv = (w * (pa - ma) * (pb - mb)).sum()
            vals.append((2 * ma * mb + c1) * (2 * cv + c2) / ((ma ** 2 + mb ** 2 + c1) * (va + vb + c2)))
    return np.mean(vals)


def test_ssim_against_a_direct_window_sum_and_constants():
    rng = np.random.default_rng(1)
    a = rng.random((20, 24))
    b = np.clip(a + 0.1 * rng.normal(size=a.shape), 0, 1)
    assert metrics.ssim(b, a) == pytest.approx(_ssim_direct(b, a), rel=1e-9)
    assert metrics.ssim(a, a) == pytest.approx(1.0)
    c1 = 0.01 ** 2  # constant images: only the luminance term is left
    assert metrics.ssim(np.full((16, 16), 0.2), np.full((16, 16), 0.6)) == pytest.approx((2 * 0.12 + c1) / (0.4 + c1))
    with pytest.raises(ConfigError, match="window"):
        metrics.ssim(np.zeros((8, 8)), np.zeros((8, 8)))
