"""Procedural ground materials: deterministic from the seed, normals from their height fields,
and no repeat over 30 m (measured on Mitsuba's albedo of a rendered top view)."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.compose import environments, grounds
from synmitsuba.rendering.passes import render_rgb

SPAN_M, PX = 30.0, 300   # top view: 30 m across, 10 cm pixels


def _top_albedo(material, period: float) -> np.ndarray:
    """Mitsuba's albedo guide of a ground of ``material`` seen from straight above (30 x 30 m)."""
    from synmitsuba.geometry import ground_grid
    scene = sm.Scene()
    v, f = ground_grid(200.0)
    scene.add_mesh("ground", v, f, uv=v[:, [0, 2]] / period, normals=np.tile([0, 1.0, 0], (len(v), 1)), material=material)
    scene.set_environment(sm.Constant(1.0))
    height = 1000.0
    fov = 2 * np.degrees(np.arctan(SPAN_M / 2 / height))
    cam = sm.Camera.look_at((0, height, 0), (0, 0, 0), up=(0, 0, -1), fov_y_deg=fov, width=PX, height=PX)
    _, (albedo, _) = render_rgb(scene, cam, spp=1, guide_spp=64)
    return albedo.mean(-1)


def _corr(b: np.ndarray, lag: int) -> float:
    pairs = [(b[:-lag], b[lag:]), (b[:, :-lag], b[:, lag:])]
    return float(np.mean([np.corrcoef(x.ravel(), y.ravel())[0, 1] for x, y in pairs]))


def _repeat_correlation(img: np.ndarray, period: float, block: int = 2) -> float:
    """How much more alike 20 cm blocks are one tile period apart than at other lags from half a
    period to two (their median): about 0 when nothing repeats, near 1 when the ground repeats
    exactly. Variation wider than a tile is alike at every lag and does not count."""
    n = img.shape[0] // block
    b = img[: n * block, : n * block].reshape(n, block, n, block).mean((1, 3))
    lag = int(round(period / (SPAN_M / PX) / block))
    others = [_corr(b, k) for k in range(max(lag // 2, 1), 2 * lag + 1) if abs(k - lag) > 1]
    return _corr(b, lag) - float(np.median(others))


@pytest.mark.parametrize("kind", sorted(grounds.GROUND_MATERIALS))
def test_ground_does_not_repeat_over_30_m(kind):
    mat, period = grounds.ground_material(kind, [0.3, 0.3, 0.3], np.random.default_rng(5), n=256)
    blended = _repeat_correlation(_top_albedo(mat, period), period)
    single = _repeat_correlation(_top_albedo(mat.a, period), period)  # one tile alone: the control
    assert single > 0.6, (kind, single)
    assert blended < 0.45, (kind, blended)


def test_ground_maps_are_deterministic_in_the_seed():
    for kind in grounds.GROUND_MATERIALS:
        a, _ = grounds.ground_material(kind, [0.4, 0.3, 0.2], np.random.default_rng(7), n=64)
        b, _ = grounds.ground_material(kind, [0.4, 0.3, 0.2], np.random.default_rng(7), n=64)
        c, _ = grounds.ground_material(kind, [0.4, 0.3, 0.2], np.random.default_rng(8), n=64)
        for f in ("texture", "roughness_map"):
            assert np.array_equal(getattr(a.a, f), getattr(b.a, f)) and np.array_equal(getattr(a.b, f), getattr(b.b, f))
        assert np.array_equal(a.weight, b.weight) and np.array_equal(a.normal_map, b.normal_map)
        assert not np.array_equal(a.a.texture, c.a.texture), kind
        assert 0 <= a.a.texture.min() and a.a.texture.max() <= 1 and 0 <= a.a.roughness_map.min() <= 1


def test_a_ground_drawn_again_is_the_one_drawn_before_and_moves_the_rng_alike():
    """Composition builds its environment on every try: the second draw from the same rng state
    is the first's material, and leaves the rng where drawing it anew (uncached) leaves it; the
    kept materials stay within ``MADE_BYTES``."""
    for kind in ("paving", "grass"):
        draws = []
        for made in (grounds.ground_material, grounds.ground_material, grounds._ground_material):
            rng = np.random.default_rng(11)
            draws.append((made(kind, [0.4, 0.3, 0.2], rng, None, 128, 1.0), rng.integers(2 ** 62)))
        (first, after), (again, after_again), (fresh, after_fresh) = draws
        assert again[0] is first[0] and after == after_again == after_fresh
        assert np.array_equal(first[0].a.texture, fresh[0].a.texture) and np.array_equal(first[0].weight, fresh[0].weight)
        other, _ = grounds.ground_material(kind, [0.4, 0.3, 0.2], np.random.default_rng(12), None, 128, 1.0)
        assert other is not first[0]
    for seed in range(4):  # 1024-px grounds, 44 MB each
        grounds.ground_material("asphalt", [0.3, 0.3, 0.3], np.random.default_rng(seed))
    assert sum(e[2] for e in grounds._MADE.values()) <= grounds.MADE_BYTES


def test_normal_map_follows_the_height_field():
    """A sine ridge h = A sin(2 pi k u / n): the encoded normal is (-h'(u), 0, 1) normalised."""
    n, period, amp, k = 128, 2.0, 0.01, 4
    u = np.arange(n)
    h = np.tile((amp * np.sin(2 * np.pi * k * u / n))[:, None], (1, n))
    enc = grounds.normal_map(h, period)
    slope = amp * 2 * np.pi * k / period * np.cos(2 * np.pi * k * u / n)
    expect = np.stack([-slope, np.zeros(n), np.ones(n)], 1) / np.sqrt(1 + slope ** 2)[:, None]
    assert np.abs(enc[:, 0] * 2 - 1 - expect).max() < 0.01


def test_every_environment_ground_is_a_registered_material():
    for name in environments.environment_names():
        env = environments.load_environment(name)
        assert env.ground.texture in grounds.GROUND_MATERIALS
        assert env.ground.period_m == grounds.GROUND_MATERIALS[env.ground.texture].period_m
