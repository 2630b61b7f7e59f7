"""Motion blur: sub-frames across the exposure averaged into the RGB, labels at its centre.
Checked against the analytic blur of a sinusoidal grating (a box filter scales a sinusoid by
sinc(width / period)), and on a generated sequence against the same sequence without blur."""
import json
from types import SimpleNamespace

import numpy as np
import pytest

from conftest import generate_tiny

PERIOD_PX, SHIFT_PX, FX, Z = 16.0, 8.0, 100.0, 2.0  # a frame moves the image by half a period


def _grating_scene(sm):
    """A plane 2 m in front of the cameras carrying 0.5 + 0.4 sin(2 pi x / period) along x."""
    period_m = PERIOD_PX * Z / FX
    scene = sm.Scene()
    x = np.linspace(-3.0, 3.0, 1024)
    row = 0.5 + 0.4 * np.sin(2 * np.pi * x / period_m)
    tex = np.repeat(np.repeat(row[None, :, None], 4, 0), 3, 2).astype(np.float32)
    v = np.array([[-3, -1, -Z], [3, -1, -Z], [3, 1, -Z], [-3, 1, -Z]], float)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    scene.add_mesh("grating", v, np.array([[0, 1, 2], [0, 2, 3]]), uv=uv, material=sm.Material(texture=tex))
    scene.set_environment(sm.Constant(1.0))
    return scene


def _cameras(sm, n=3):
    """Cameras moving along +x by SHIFT_PX image pixels per frame, looking down -z."""
    K = [[FX, 0, 64.0], [0, FX, 16.0], [0, 0, 1]]
    R = np.diag([1.0, -1.0, -1.0])
    step = SHIFT_PX * Z / FX
    return [sm.Camera(K=K, R=R, t=-R @ np.array([step * f, 0.0, 0.0]), width=128, height=32) for f in range(n)]


def _sinusoid(img):
    """Least-squares a + c cos + d sin at the grating's frequency over the image's columns."""
    u = np.arange(img.shape[1]) + 0.5
    A = np.stack([np.ones_like(u), np.cos(2 * np.pi * u / PERIOD_PX), np.sin(2 * np.pi * u / PERIOD_PX)], 1)
    coef = np.linalg.lstsq(A, img.mean((0, 2)), rcond=None)[0]
    return A, coef


def test_blur_of_a_moving_grating_matches_the_box_filter(sm):
    from synmitsuba.motion_blur import blurred_rgbs
    scene, cams = _grating_scene(sm), _cameras(sm)
    view = SimpleNamespace(name="cam0", cameras=cams)
    sharp = sm.render(scene, cams[1], spp=64, seed=1).passes["rgb"]
    exposure = blurred_rgbs(scene, [], [view], 1, 1.0, 8, 64, 1, {"denoise": "oidn"}, motion=True)["cam0"]
    blurred, motion = exposure.rgb, exposure.motion
    # the camera moves +x by SHIFT_PX image pixels a frame; the shutter is open the whole frame
    assert np.allclose(motion[..., 0], -SHIFT_PX, atol=1e-3) and np.allclose(motion[..., 1], 0, atol=1e-3)
    A, (a, c, d) = _sinusoid(sharp)
    attenuation = np.sinc(SHIFT_PX / PERIOD_PX)  # np.sinc(x) = sin(pi x) / (pi x): a box of width SHIFT_PX
    expected = A @ np.array([a, c * attenuation, d * attenuation])
    measured = blurred.mean((0, 2))
    assert np.sqrt(np.mean((measured - expected) ** 2)) / a < 0.01
    assert np.hypot(c, d) > 0.3  # the sharp grating is there, and the blur took 36 % of it away
    assert np.sqrt(np.mean((sharp.mean((0, 2)) - expected) ** 2)) / a > 0.05
    # the denoiser's albedo guide is blurred like the colour (under a uniform white sky the
    # plane's radiance is its albedo), so OIDN does not sharpen the motion back
    albedo = exposure.guides[0].mean((0, 2))
    assert np.sqrt(np.mean((albedo - expected) ** 2)) / a < 0.01


def test_sub_frames_share_the_samples_and_centre_on_the_frame(sm):
    from synmitsuba.motion_blur import subframe_times
    t = subframe_times(10, 0.5, 8)
    assert len(t) == 8 and np.mean(t) == pytest.approx(10) and max(t) - min(t) == pytest.approx(0.5 * 7 / 8)
    cams = _cameras(sm)
    mid = cams[0].blended(cams[1], 0.5)
    assert np.allclose(mid.center, (cams[0].center + cams[1].center) / 2) and cams[0].blended(cams[0], 0.3) is cams[0]


@pytest.fixture(scope="module")
def blurred_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("blur") / "one"
    run = generate_tiny(out, "--workers", "1", "--set", "render.shutter_deg=[180,180]")
    assert run.returncode == 0, run.stderr
    return out


def test_blur_leaves_every_label_as_without_it(tiny, blurred_run, sm):
    """Same config with and without a 180 degree shutter: the RGB differs where subjects move,
    every exact pass, label and flow is identical (defined at the exposure centre)."""
    stems = sm.list_samples(str(tiny))
    assert len(stems) == 4
    moved, errors = 0, []
    for stem in stems:
        a, b = sm.read_sample(stem), sm.read_sample(stem.replace(str(tiny), str(blurred_run)))
        assert b.meta["shutter"] == 0.5 and b.meta["subframes"] == 2  # tiny renders 2 spp: 2 sub-frames of 1
        for name in a.passes:
            if name != "rgb":
                assert np.array_equal(a.passes[name], b.passes[name]), name
        assert "motion_blur" not in a.passes and not b.passes["motion_blur"][~b.passes["mask"]].any()
        if "flow_bwd" in b.passes:  # against flow back 2 frames, taken linear: a quarter of it over a 180 degree shutter
            seen = (b.passes["flow_bwd_flag"] == 0) & (b.passes["instance"] >= 100)
            expected = -0.25 * b.passes["flow_bwd"][seen]
            big = np.linalg.norm(expected, axis=1) > 0.3
            errors.extend(np.linalg.norm(b.passes["motion_blur"][seen] - expected, axis=1)[big]
                          / np.linalg.norm(expected, axis=1)[big])
        ja = json.loads(open(f"{stem}.json").read())
        jb = json.loads(open(f"{stem.replace(str(tiny), str(blurred_run))}.json").read())
        assert ja["subjects"] == jb["subjects"] and ja["camera"] == jb["camera"]
        diff = np.abs(a.passes["rgb"] - b.passes["rgb"]).max(-1)
        moved += int((diff[a.passes["mask"]] > 0.05).sum())
    assert moved > 50
    assert len(errors) > 30 and np.median(errors) < 0.3


def test_blurred_generation_is_deterministic(blurred_run, tmp_path):
    again = tmp_path / "again"
    run = generate_tiny(again, "--workers", "1", "--set", "render.shutter_deg=[180,180]", "--set", "sequences=1")
    assert run.returncode == 0, run.stderr
    for f in sorted((again / "seq_000000").glob("*.exr")):
        assert f.read_bytes() == (blurred_run / "seq_000000" / f.name).read_bytes(), f.name


def test_sub_frame_noise_is_not_correlated_between_neighbours(sm):
    """Sub-frames rendered with consecutive seeds made ldsampler's noise correlate between
    horizontal neighbours (0.73: streaks); hashed sub-frame seeds keep pixels independent."""
    import trimesh
    from synmitsuba.motion_blur import blurred_rgbs
    scene = sm.Scene()
    wall = trimesh.creation.box((6, 4, 0.1))
    wall.apply_translation((0, 1, -2))
    scene.add_mesh("wall", wall.vertices, wall.faces, material=sm.Material(base_color=(0.6, 0.6, 0.6)))
    scene.set_environment(sm.SunSky())
    cam = sm.Camera.look_at((0, 1, 1), (0, 1, -2), width=128, height=96)
    img = blurred_rgbs(scene, [], [SimpleNamespace(name="c", cameras=[cam])], 0, 0.5, 16, 64, 1000,
                       {"sampler": "ldsampler"})["c"].rgb.mean(-1)
    noise = img - img.mean()
    assert (noise[:, 1:] * noise[:, :-1]).mean() / noise.var() < 0.1
