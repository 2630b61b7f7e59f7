"""Photo development (rendering.photo) against independent references: white balance against
colour-science's Planckian locus and sRGB, metering and noise against their analytic
statistics, JPEG against the input; on a generation, every label and the clean radiance as
without it."""
import numpy as np
import pytest

from conftest import colour_science, generate_tiny


@pytest.mark.parametrize("kelvin", [2000.0, 3200.0, 5000.0, 6504.0, 9000.0])
def test_white_balance_gains_match_colour_science(kelvin):
    from synmitsuba.rendering.photo import white_balance_gains
    colour = colour_science()

    def white(T):
        xy = colour.temperature.CCT_to_xy_Kang2002(T)
        return colour.XYZ_to_sRGB(colour.xy_to_XYZ(xy), apply_cctf_encoding=False)
    ref = white(6504.0) / white(kelvin)
    assert np.allclose(white_balance_gains(kelvin), ref / ref[1], rtol=2e-3)


def test_a_warm_balance_turns_daylight_blue():
    from synmitsuba.rendering.photo import white_balance_gains
    g = white_balance_gains(3200.0)
    assert g[2] > 1.5 and g[0] < 0.8


def test_metering_puts_a_uniform_image_on_middle_grey():
    from synmitsuba.rendering.photo import LUMA, metered_scale
    img = np.full((8, 8, 3), 3.0)
    for bias in (-1.0, 0.0, 1.5):
        lum = (img * metered_scale(img, bias)) @ LUMA
        assert np.allclose(lum, 0.18 * 2 ** bias, rtol=1e-4)


def test_sensor_noise_has_the_photon_and_read_variance():
    from synmitsuba.rendering.photo import Photo, sensor_noise
    photo = Photo(iso=800.0, full_well_e=20000.0, read_noise_e=3.0)
    well = 20000.0 * 100 / 800
    v = 0.25
    out = sensor_noise(np.full((256, 256, 3), v), photo, np.random.default_rng(0))
    assert out.mean() == pytest.approx(v, rel=2e-3)
    assert out.var() == pytest.approx((v * well + 3.0 ** 2) / well ** 2, rel=0.03)


def test_jpeg_quality_orders_the_error():
    from synmitsuba.rendering.photo import jpeg
    rng = np.random.default_rng(1)
    u = np.linspace(0, 1, 64)
    img = np.clip(0.3 + 0.3 * np.sin(8 * u)[None, :, None] * np.cos(6 * u)[:, None, None]
                  + 0.02 * rng.normal(size=(64, 64, 3)), 0, 1)
    err = {q: np.sqrt(np.mean((jpeg(img, q) - img) ** 2)) for q in (10, 95)}
    assert 0 < err[95] < err[10]


def test_developed_generation_keeps_labels_and_the_clean_render(tiny, tmp_path, sm):
    run = generate_tiny(tmp_path, "--workers", "1", "--set", "sequences=1", "--set", "render.photo.enabled=true",
                        "--set", "render.photo.jpeg_quality=[50,90]")
    assert run.returncode == 0, run.stderr
    stems = sm.list_samples(str(tmp_path))
    assert len(stems) == 2
    for stem in stems:
        a, b = sm.read_sample(stem.replace(str(tmp_path), str(tiny))), sm.read_sample(stem)
        assert np.array_equal(a.passes["rgb"], b.passes["rgb_clean"])  # the radiance, as without development
        for name in a.passes:
            if name != "rgb":
                assert np.array_equal(a.passes[name], b.passes[name]), name
        p = b.meta["photo"]
        assert -1 <= p["exposure_bias_ev"] <= 1 and 100 <= p["iso"] <= 1600 and 50 <= p["jpeg_quality"] <= 90
        assert b.passes["rgb"].min() >= 0 and b.passes["rgb"].max() <= 1
        assert not np.array_equal(b.passes["rgb"], b.passes["rgb_clean"])
