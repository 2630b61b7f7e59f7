"""Environments and lights render the radiance they are given."""
import numpy as np
import pytest
import trimesh


def background(sm, env, width=16, height=12):
    scene = sm.Scene()
    tiny = trimesh.creation.icosphere(subdivisions=1, radius=0.01)
    scene.add_mesh("speck", tiny.vertices + [0, -50, 0], tiny.faces)  # out of view
    scene.set_environment(env)
    cam = sm.Camera.look_at(eye=(0, 0, 0), target=(0, 0, -1), width=width, height=height)
    return sm.render(scene, cam, spp=4)


def test_constant_environment_is_seen_exactly(sm):
    s = background(sm, sm.Constant((0.2, 0.5, 0.9)))
    assert not s.mask.any() and (s.depth == 0).all() and (s.alpha == 0).all()
    assert np.allclose(s.rgb, [0.2, 0.5, 0.9], atol=1e-5)


def test_envmap_from_file_clamps_negative_pixels(sm, tmp_path):
    import OpenEXR
    h, w = 16, 32
    img = np.full((h, w, 3), 0.7, np.float32)
    img[:, :, 1] = -0.3  # a lossy HDRI's undershoot: must not turn into negative light
    with OpenEXR.File({"type": OpenEXR.scanlineimage}, {"RGB": img}) as f:
        f.write(str(tmp_path / "sky.exr"))
    s = background(sm, sm.EnvMap(str(tmp_path / "sky.exr"), scale=2.0))
    assert np.allclose(s.rgb[..., 0], 1.4, atol=2e-3) and np.allclose(s.rgb[..., 1], 0.0, atol=1e-6)


def test_missing_envmap_file_is_named(sm):
    with pytest.raises(sm.ConfigError) as e:
        sm.EnvMap("/nonexistent/sky.exr")  # refused when made, not first at render time
    assert "environment.file" in str(e.value) and "sky.exr" in str(e.value)


def test_sunsky_is_y_up(sm):
    """The sky is bright above the horizon (+y) and black below it, with the sun where we put it."""
    env = sm.SunSky(sun_direction=(1.0, 0.4, 0.0))
    looks = {}
    for name, target, up in [("zenith", (0, 1, 0), (0, 0, 1)), ("nadir", (0, -1, 0), (0, 0, 1)),
                             ("sun", (1, 0.4, 0), (0, 1, 0)), ("away", (-1, 0.4, 0), (0, 1, 0))]:
        scene = sm.Scene()
        scene.set_environment(env)
        scene.add_mesh("speck", np.array([[0, -50, 0], [0.01, -50, 0], [0, -50, 0.01]]), np.array([[0, 1, 2]]))
        cam = sm.Camera.look_at(eye=(0, 0, 0), target=target, up=up, fov_y_deg=30, width=8, height=8)
        looks[name] = sm.render(scene, cam, spp=4).rgb.mean()
    assert looks["nadir"] == 0.0 and looks["zenith"] > 0.005
    assert looks["sun"] > 2 * looks["away"]  # the circumsolar sky is brighter


def test_point_light_follows_inverse_square_law(sm):
    """A diffuse plane lit head-on by a point light: radiance = albedo/pi * I / d^2."""
    values = []
    for dist in (1.0, 2.0):
        scene = sm.Scene()
        v = np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], float)
        scene.add_mesh("wall", v, np.array([[0, 1, 2], [0, 2, 3]]), material=sm.Material(base_color=0.5))
        scene.add_light(sm.PointLight(position=(0, 0, dist), intensity=4.0))
        cam = sm.Camera.look_at(eye=(0, 0, dist), target=(0, 0, 0), fov_y_deg=2, width=4, height=4)
        values.append(float(sm.render(scene, cam, spp=4, max_depth=2).rgb.mean()))
    assert values[0] == pytest.approx(0.5 / np.pi * 4.0 / 1.0, rel=2e-3)
    assert values[1] == pytest.approx(0.5 / np.pi * 4.0 / 4.0, rel=2e-3)
