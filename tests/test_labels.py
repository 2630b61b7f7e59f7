"""Label passes checked against analytic answers: uv on shapes without texture coordinates,
and soft coverage (alpha) for sample counts that are and are not perfect squares."""
import numpy as np
import pytest

from synmitsuba.engine.rays import strata

W, H, F = 256, 24, 100.0


def _edge_scene(sm, horizontal: bool, edge_px: float):
    """A plane at z = 1 in front of an axis-aligned OpenCV camera at the origin, covering the
    image below row ``edge_px`` (horizontal) or right of column ``edge_px``."""
    K = np.array([[F, 0, W / 2], [0, F, H / 2], [0, 0, 1.0]])
    cam = sm.Camera(K=K, width=W, height=H)
    if horizontal:
        y0 = (edge_px - H / 2) / F  # v = F y + cy
        quad = [[-10, y0, 1], [10, y0, 1], [10, 10, 1], [-10, 10, 1]]
    else:
        x0 = (edge_px - W / 2) / F
        quad = [[x0, -10, 1], [10, -10, 1], [10, 10, 1], [x0, 10, 1]]
    scene = sm.Scene()
    scene.add_mesh("plane", np.array(quad, float), np.array([[0, 1, 2], [0, 2, 3]]), instance=1)
    scene.set_environment(sm.Constant(1.0))
    return scene, cam


def test_strata_tile_the_pixel_for_every_count():
    for n in range(1, 65):
        rows, cols = strata(n)
        assert rows * cols == n and rows <= cols
    assert strata(16) == (4, 4) and strata(12) == (3, 4) and strata(7) == (1, 7)


@pytest.mark.parametrize("n", [1, 2, 3, 5, 8, 12, 16])
def test_alpha_on_an_edge_matches_analytic_coverage(sm, n):
    """True coverage of the edge row is 0.4 (edge at row 10.6): the mean alpha over that row
    must be 0.4 for any sample count (n = 2 gave 0.000 and n = 8 gave 0.328 before)."""
    for horizontal in (True, False):
        edge = 10.6 if horizontal else 100.6
        scene, cam = _edge_scene(sm, horizontal, edge)
        s = sm.render(scene, cam, spp=1, coverage_samples=n, seed=3)
        line = s.alpha[10] if horizontal else s.alpha[:, 100]
        before = s.alpha[:10] if horizontal else s.alpha[:, :100]
        after = s.alpha[11:] if horizontal else s.alpha[:, 101:]
        assert (before == 0).all() and (after == 1).all()
        sd = np.sqrt(0.4 * 0.6 / (n * line.size))  # worst case: independent samples
        assert abs(line.mean() - 0.4) < max(4 * sd, 0.01), (n, horizontal, line.mean())
        assert np.allclose(line * n, np.round(line * n))  # k / n exactly


def test_uv_is_zero_and_flagged_on_shapes_without_uv(sm):
    scene = sm.Scene()
    tri = np.array([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], float)
    scene.add_mesh("tri", tri, np.array([[0, 1, 2]]), instance=1)
    quad = np.array([[1.2, -1, 0], [2.2, -1, 0], [2.2, 1, 0], [1.2, 1, 0]], float)
    scene.add_mesh("quad", quad, np.array([[0, 1, 2], [0, 2, 3]]), uv=[[0.25, 0.25], [0.75, 0.25], [0.75, 0.75],
                                                                   [0.25, 0.75]], instance=2)
    scene.set_environment(sm.Constant(1.0))
    cam = sm.Camera.look_at(eye=(0.6, 0, 4), target=(0.6, 0, 0), fov_y_deg=50, width=48, height=32)
    s = sm.render(scene, cam, spp=1)
    on_tri, on_quad = s.instance == 1, s.instance == 2
    assert on_tri.sum() > 50 and on_quad.sum() > 50
    assert (s.uv[on_tri] == 0).all() and not s.uv_valid[on_tri].any()
    assert s.uv_valid[on_quad].all() and (s.uv[on_quad] >= 0.25 - 1e-6).all() and (s.uv[on_quad] <= 0.75 + 1e-6).all()
    assert not s.uv_valid[~s.mask].any()


def test_every_accessory_hit_has_no_uv(sm):
    """Accessories are built without texture coordinates: their pixels carry uv 0, flagged."""
    rng = np.random.default_rng(0)
    recipe = sm.sample_subject(rng, {"accessories": ["glasses", "cap"], "texture_size": 64})
    human = sm.build_subject(recipe)
    scene = sm.Scene()
    scene.set_environment(sm.Constant(1.0))
    human.add_to(scene, instance=1)
    top = human.body.vertices[:, 1].max()
    cam = sm.Camera.look_at(eye=(0, top - 0.1, 0.9), target=(0, top - 0.12, 0), fov_y_deg=30, width=48, height=48)
    s = sm.render(scene, cam, spp=1)
    acc = s.layer == int(sm.Layer.ACCESSORY)
    body = s.layer == int(sm.Layer.BODY)
    assert acc.sum() > 20 and body.sum() > 20
    assert (s.uv[acc] == 0).all() and not s.uv_valid[acc].any() and s.uv_valid[body].all()
