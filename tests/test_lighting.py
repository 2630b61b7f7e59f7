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


def test_direct_light_estimates_match_closed_forms(sm):
    """Each emitter's light at a point (the mean irradiance on five faces of a cube, floor
    face left out): a sky of radiance L gives pi L, a lamp straight above gives E / 5."""
    from synmitsuba.engine.build import _light, direct_light, environment_dict
    at = (0.0, 1.0, 0.0)
    assert direct_light(environment_dict(sm.Constant(0.4)), at) == pytest.approx(np.pi * 0.4, rel=5e-3)  # a 32 x 32 grid
    assert direct_light(_light(sm.DirectionalLight(direction=(0, -1, 0), irradiance=3.0)), at) == pytest.approx(0.6)
    assert direct_light(_light(sm.PointLight(position=(0, 3, 0), intensity=10.0)), at) == pytest.approx(10 / 4 / 5)


def sky_and_sun(sm, spp: int):
    """A grey ground under a sky and a sun lamp 60 degrees up, seen from above."""
    scene = sm.Scene()
    v = np.array([[-50, 0, -50], [50, 0, -50], [50, 0, 50], [-50, 0, 50]], float)
    scene.add_mesh("ground", v, np.array([[0, 2, 1], [0, 3, 2]]), material=sm.Material(base_color=0.5))
    scene.set_environment(sm.Constant(0.3))
    sun = np.array([0.0, np.sin(np.radians(60)), np.cos(np.radians(60))])
    scene.add_light(sm.DirectionalLight(direction=tuple(-sun), irradiance=4.0))
    cam = sm.Camera.look_at(eye=(0, 2, 0.01), target=(0, 0, 0), fov_y_deg=30, width=32, height=32)
    return scene, sm.render(scene, cam, spp=spp, seed=3, max_depth=2).rgb, 0.5 * (4.0 * sun[1] / np.pi + 0.3)


def test_emitters_are_sampled_by_their_light(sm, monkeypatch):
    """With a sky and a sun lamp the sun gets three light samples in four (its light 2.1 against
    the sky's 0.94 / 4): the ground is still exactly as bright as albedo (E cos / pi + L) says,
    and its pixels are less noisy than with Mitsuba's uniform choice between the two."""
    import synmitsuba.engine.build as build
    scene, rgb, expected = sky_and_sun(sm, 64)
    assert rgb.mean() == pytest.approx(expected, rel=5e-3)
    params = build.cached_build(scene).params
    assert (params["environment.sampling_weight"], params["light_0.sampling_weight"]) == (1.0, 3.0)
    weighted = sky_and_sun(sm, 4)[1].std()
    monkeypatch.setattr(build, "_weigh_emitters", lambda *args, **kw: None)  # Mitsuba's default
    uniform = sky_and_sun(sm, 4)[1].std()
    assert weighted < 0.85 * uniform


def test_emitter_quarters():
    """Shares of the light samples in whole quarters, each emitter at least one."""
    from synmitsuba.engine.build import quarters
    assert quarters([1.0, 1.0]) == [2, 2]
    assert quarters([0.2, 1.0]) == [1, 3] and quarters([1.0, 0.0]) == [3, 1]
    assert quarters([5.0, 1.0, 1.0]) == [2, 1, 1] and quarters([9.0, 0.1, 0.1, 0.1]) == [1, 1, 1, 1]
    assert quarters([2.0]) == [4]


def test_8bit_maps_are_data_and_8bit_textures_are_srgb(sm):
    """A uint8 albedo is sRGB-decoded (128 -> 0.2158, the sRGB curve); a uint8 normal, bump or
    roughness map is only scaled (128 -> 128 / 255): decoding the flat normal (128, 128, 255)
    would have tilted it."""
    grey = np.full((4, 4, 3), 128, np.uint8)
    flat = np.dstack([grey[..., :2], np.full((4, 4), 255, np.uint8)])
    m = sm.Material(kind="principled", texture=grey, normal_map=flat, roughness_map=grey[..., 0])
    srgb = ((128 / 255 + 0.055) / 1.055) ** 2.4
    assert np.allclose(m.texture, srgb, atol=1e-4)
    assert np.allclose(m.normal_map[..., :2], 128 / 255) and np.allclose(m.normal_map[..., 2], 1.0)
    assert np.allclose(m.roughness_map, 128 / 255)
    assert np.allclose(sm.Material(bump=grey[..., 0]).bump, 128 / 255)


def test_normal_map_repeat_is_checked(sm):
    """Two positive finite repeats (u, v), kept as floats; anything else names the field."""
    from synmitsuba.errors import ConfigError
    assert sm.Material(normal_map_repeat=[3, 2]).normal_map_repeat == (3.0, 2.0)
    for bad in ((0, 1), (1, -2), (1,), (1, float("nan"))):
        with pytest.raises(ConfigError, match="material.normal_map_repeat"):
            sm.Material(normal_map_repeat=bad)
