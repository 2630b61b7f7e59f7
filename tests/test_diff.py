"""Differentiable textures: the drjit texture against the dataset's numpy one, every parameter
type's gradient against central finite differences, fitting, a torch loss through dr.wrap."""
import numpy as np
import pytest

from synmitsuba.body.textures import GarmentTextureParams, render_garment_texture
from synmitsuba.errors import ConfigError

QUAD = (np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], float), np.array([[0, 2, 1], [0, 3, 2]]),
        np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float))
TRUTH = GarmentTextureParams(pattern="stripes", decal="circle", base_lab=[60, 20, 10], pattern_lab=[30, -10, 20],
                             pattern_scale=4, uv_rotation_deg=20, uv_offset=[0.13, 0.4], decal_center=[0.4, 0.6],
                             decal_size=0.2)


def quad_scene(sm, texture_size=64):
    """A textured cloth quad beside a plain one (for the bitmap texture), under a constant sky."""
    v, f, uv = QUAD
    scene = sm.Scene()
    scene.add_mesh("cloth", v, f, uv=uv, material=sm.Material(texture=render_garment_texture(TRUTH, texture_size)[0]))
    scene.add_mesh("patch", v * 0.3 + [0, 0.01, 0], f, uv=uv,
                   material=sm.Material(texture=np.random.default_rng(0).random((8, 8, 3)).astype(np.float32)))
    scene.set_environment(sm.Constant(0.8))
    return scene


def top_camera(sm, size=32, eye=(0, 2.2, 0.01)):
    return sm.Camera.look_at(eye=eye, target=(0, 0, 0), fov_y_deg=50, width=size, height=size)


@pytest.mark.parametrize("pattern,decal", [("stripes", "circle"), ("checks", "star"), ("plaid", "band"),
                                           ("dots", "number"), ("gradient", "none"), ("camouflage", "circle")])
def test_procedural_texture_is_the_dataset_texture_with_antialiased_edges(sm, pattern, decal):
    """Against numpy's hard-edged texture supersampled 8x (the area average of each texel): where
    all 64 subsamples agree (away from edges) the drjit texture equals it (bar the odd texel
    whose subsamples just miss an edge), and at edges it
    stays close to the area average (a one-texel ramp, not a step)."""
    from synmitsuba.diff.texture import ProceduralTexture
    p = GarmentTextureParams(**{**TRUTH.to_dict(), "pattern": pattern, "decal": decal, "pattern_scale": 6.3,
                                "uv_scale": 1.3, "uv_aspect": 1.35})  # as a sampled garment's
    proc = ProceduralTexture(p, 64)
    got = np.array(proc.evaluate(proc.initial()))
    assert got.shape == (64, 64, 3)
    if pattern == "gradient":  # continuous: the same values at texel centres, bar its wrap seam
        assert (np.abs(got - render_garment_texture(p, 64)[0]).max(-1) < 2e-4).mean() > 0.97
        return
    fine = render_garment_texture(p, 64 * 8)[0].reshape(64, 8, 64, 8, 3)
    area = fine.mean((1, 3))
    uniform = (np.ptp(fine, axis=(1, 3)) < 1e-6).all(-1)
    assert uniform.mean() > 0.4
    same = (np.abs(got - area).max(-1) < 2e-4)[uniform]
    assert same.mean() > 0.995  # a texel whose 64 subsamples just miss an edge may see the ramp
    assert np.abs(got - area)[~uniform].mean() < 0.06


def warped(n: int) -> np.ndarray:
    """(n, n, 2) smooth pattern coordinates at the texel centres (row 0 at v = 1): a bent,
    sheared grid, as a garment's panels give (``body.panels``)."""
    v, u = (np.mgrid[:n, :n] + 0.5) / n
    v = 1 - v
    return np.stack([1.3 * u + 0.08 * np.sin(2 * np.pi * v), v + 0.1 * u * u], -1).astype(np.float32)


@pytest.mark.parametrize("pattern", ["stripes", "checks", "dots"])
def test_procedural_texture_over_panel_coordinates_is_the_dataset_texture(sm, pattern):
    """Over given pattern coordinates (a garment's panels) the drjit texture is numpy's drawn
    over the same coordinates, supersampled 8x, as on the uv square (test above), and the
    decal stays in uv; a coordinates map of the wrong shape is refused."""
    from synmitsuba.diff.texture import ProceduralTexture
    p = GarmentTextureParams(**{**TRUTH.to_dict(), "pattern": pattern, "decal": "star", "pattern_scale": 6.3,
                                "uv_scale": 1.3})
    proc = ProceduralTexture(p, 64, warped(64))
    got = np.array(proc.evaluate(proc.initial()))
    fine = render_garment_texture(p, 64 * 8, warped(64 * 8))[0].reshape(64, 8, 64, 8, 3)
    area = fine.mean((1, 3))
    uniform = (np.ptp(fine, axis=(1, 3)) < 1e-6).all(-1)
    assert uniform.mean() > 0.4
    # the ramp is a texel wide along the coordinates' steepest way: a texel beside an edge sees it more often
    assert (np.abs(got - area).max(-1) < 2e-4)[uniform].mean() > 0.985
    assert np.abs(got - area)[~uniform].mean() < 0.06
    assert np.abs(got - np.array(ProceduralTexture(p, 64).evaluate(proc.initial()))).max() > 0.1  # the coordinates count
    with pytest.raises(ConfigError, match="coords"):
        ProceduralTexture(p, 64, warped(32))


def test_a_bound_garment_is_drawn_over_its_panels(sm):
    """``bind_procedural`` on a built t-shirt redraws its material's texture: over the
    material's panel coordinates, not the uv square: the bitmap's values within 2e-4 in four
    texels in five (the rest lie on the checks' edges, ramped in one and box-filtered in the
    other); over the uv square, in under three in five."""
    from synmitsuba.diff import DiffScene
    from synmitsuba.diff.texture import ProceduralTexture
    recipe = sm.sample_subject(np.random.default_rng(7), {"outfit": ["tshirt"], "shoes": False, "jacket": False,
                                                          "hair_style": "bald", "accessories": [], "texture_size": 256})
    shirt = next(g for g in recipe.garments if g.kind == "tshirt")
    shirt.texture.pattern, shirt.texture.decal, shirt.texture.pattern_scale = "checks", "none", 9.0
    human = sm.build_subject(recipe)
    scene = sm.Scene()
    human.add_to(scene, *human.standing(), instance=1, prefix="subject1")
    ds = DiffScene(scene)
    ds.bind_procedural("subject1_tshirt", shirt.texture)
    proc = ds._textures["subject1_tshirt"][1]
    got = np.array(proc.evaluate(proc.initial()))
    bitmap = next(p for p in human.parts if p.name == "tshirt").material.texture
    assert (np.abs(got - bitmap).max(-1) < 2e-4).mean() > 0.8
    flat = np.array(ProceduralTexture(shirt.texture, 256).evaluate(proc.initial()))
    assert (np.abs(flat - bitmap).max(-1) < 2e-4).mean() < 0.6


SEEDS = (11, 13, 17, 19)


def _fd_check(sm, ds, cam, target, name, h, direction=None, spp=1024, seeds=SEEDS):
    """(AD directional derivative, central difference) of an image MSE for variable ``name``."""
    import drjit as dr
    import mitsuba as mi
    ref = mi.TensorXf(target)

    def loss(seed):
        return dr.mean(dr.square(ds.render(cam, spp=spp, seed=seed) - ref), axis=None)

    x0 = ds.variables[name]
    x = np.array(x0, dtype=np.float64)
    direction = np.ones_like(x) / np.sqrt(x.size) if direction is None else direction
    var = dr.detach(x0)
    dr.enable_grad(var)
    ds.variables[name] = var
    ad = 0.0
    for seed in seeds:  # the gradient pass traces its own paths (noise): average a few
        dr.backward(loss(seed))
        ad += float((np.array(dr.grad(var), dtype=np.float64) * direction).sum())
        dr.clear_grad(var)
    ad /= len(seeds)
    values = []
    for sign in (1, -1):
        moved = x + sign * h * direction
        ds.set(name, moved if ds.specs[name].kind == "texture" else moved.ravel().tolist())
        values.append(sum(float(loss(seed).array[0]) for seed in seeds) / len(seeds))
    ds.variables[name] = x0
    return ad, (values[0] - values[1]) / (2 * h)


def test_gradients_match_central_differences_for_every_parameter_type(sm):
    """Colours, blend weights, pattern scale and phase, decal placement and size, a bitmap
    texture, the environment's radiance: AD (prb) within 5 % of central differences of the
    same image loss (averaged over 4 seeds), at 32 x 32 and 1024 spp."""
    scene = quad_scene(sm)
    ds = sm.DiffScene(scene)
    ds.bind_procedural("cloth", TRUTH)
    ds.bind_texture("patch")
    cam = top_camera(sm)
    target = np.array(ds.render(cam, spp=64, seed=5))
    start = {"cloth.base_rgb": [0.3, 0.3, 0.3], "cloth.pattern_rgb": [0.1, 0.4, 0.2], "cloth.pattern_scale": 4.4,
             "cloth.phase": [0.13, 0.43], "cloth.decal_center": [0.42, 0.58], "cloth.decal_size": 0.22,
             "cloth.pattern_alpha": 0.7, "cloth.decal_alpha": 0.8, "environment.radiance": [0.5, 0.6, 1.1]}
    for k, v in start.items():
        ds.set(k, v)
    ds.set("patch.texture", np.array(ds.variables["patch.texture"]) * 0.5)
    steps = {"cloth.pattern_scale": 0.01, "cloth.phase": 0.002, "cloth.decal_center": 0.002, "cloth.decal_size": 0.002}
    rng = np.random.default_rng(1)
    errors = {}
    for name in [*start, "patch.texture"]:
        direction = None
        if name == "patch.texture":
            direction = rng.normal(size=np.array(ds.variables[name]).shape)
            direction /= np.linalg.norm(direction)
        ad, fd = _fd_check(sm, ds, cam, target, name, steps.get(name, 0.01), direction)
        assert abs(fd) > 1e-5, name  # the loss does depend on it
        errors[name] = abs(ad - fd) / abs(fd)
    assert max(errors.values()) <= 0.05, errors


def sun_scene(sm, elevation=30.0, azimuth=60.0):
    """A box on a grey ground under Mitsuba's sun and sky (angles in degrees, as diff.sun)."""
    import trimesh
    scene = sm.Scene()
    ground = trimesh.creation.box([4, 0.02, 4])
    ground.apply_translation([0, -0.01, 0])
    scene.add_mesh("ground", ground.vertices, ground.faces, material=sm.Material(base_color=(0.5, 0.5, 0.5)))
    box = trimesh.creation.box([1.0, 0.8, 1.0])
    box.apply_translation([0, 0.4, 0])
    scene.add_mesh("box", box.vertices, box.faces, material=sm.Material(base_color=(0.7, 0.3, 0.2)))
    el, az = np.radians(elevation), np.radians(azimuth)
    scene.set_environment(sm.SunSky(sun_direction=(np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az))))
    return scene


def test_soft_sun_lights_as_mitsubas_sun_and_its_lobe_holds_the_irradiance(sm):
    """The soft sun's lobe integrates to the irradiance measured from Mitsuba's sun disk; a
    white plane facing straight up under it alone has radiance E sin(el) (coth k - 1/k) / pi (the
    mean cosine of a von Mises-Fisher lobe); the box scene renders as under the sunsky."""
    import mitsuba as mi
    from synmitsuba.diff.sun import texel_directions
    ds = sm.DiffScene(sun_scene(sm), soft_sun_deg=4.0)
    sun = ds.sun
    assert sun.irradiance.min() > 0.5  # Mitsuba's default sun: about (1.5, 1.2, 0.9)
    ds.set("environment.sky_scale", 0.0)
    data = np.array(sun.evaluate(*(mi.Float(ds.get(k)) for k in
                                   ("environment.sun_elevation", "environment.sun_azimuth",
                                    "environment.sun_scale", "environment.sky_scale"))))
    H, W = sun.height, sun.width
    theta = np.pi * np.arange(H) / (H - 1)  # rows from the zenith, as Mitsuba stores them
    solid = np.sin(theta)[:, None] * (np.pi / (H - 1)) * (2 * np.pi / W)
    np.testing.assert_allclose((data[:, 1:-1] * solid[..., None]).sum((0, 1)), sun.irradiance, rtol=1e-3)
    assert texel_directions(4, 8).shape == (4, 10, 3)
    # a white plane facing up, lit by the sun's lobe alone
    plane = sm.Scene()
    v, f, _ = QUAD
    plane.add_mesh("plane", v * 50, f, material=sm.Material(base_color=(1.0, 1.0, 1.0)))
    plane.set_environment(sun_scene(sm).environment)
    flat = sm.DiffScene(plane, soft_sun_deg=4.0, max_depth=2)
    flat.set("environment.sky_scale", 0.0)
    img = np.array(flat.render(top_camera(sm, 16, eye=(0, 1, 0.001)), spp=256, seed=1))
    k = flat.sun.kappa
    expected = flat.sun.irradiance * np.sin(np.radians(30)) * (1 / np.tanh(k) - 1 / k) / np.pi
    np.testing.assert_allclose(img.mean((0, 1)), expected, rtol=0.005)
    # the box scene: the soft sun and Mitsuba's sunsky give the same mean image
    cam = sm.Camera.look_at(eye=(1.8, 1.6, 2.4), target=(0, 0.4, 0), fov_y_deg=40, width=32, height=32)
    soft = np.array(sm.DiffScene(sun_scene(sm), soft_sun_deg=4.0).render(cam, spp=256, seed=1))
    sharp = np.array(sm.DiffScene(sun_scene(sm)).render(cam, spp=256, seed=1))
    np.testing.assert_allclose(soft.mean((0, 1)), sharp.mean((0, 1)), rtol=0.01)


@pytest.mark.slow  # 100 s on 2 cores; make test keeps the lobe's physics and the sun fit
def test_sun_direction_and_scales_get_gradients_that_match_central_differences(sm):
    """Elevation, azimuth, sun and sky scale of the soft sun: AD (prb) within 5 % of central
    differences of the same image loss (8 seeds at 1024 spp: moving the sun also moves the
    envmap's sampling density, so each side of a difference draws other paths)."""
    ds = sm.DiffScene(sun_scene(sm), soft_sun_deg=4.0)
    cam = sm.Camera.look_at(eye=(1.8, 1.6, 2.4), target=(0, 0.4, 0), fov_y_deg=40, width=32, height=32)
    ds.set("environment.sun_elevation", 40.0)
    ds.set("environment.sun_azimuth", 20.0)
    target = np.array(ds.render(cam, spp=256, seed=5))
    for k, v in (("sun_elevation", 28.0), ("sun_azimuth", 60.0), ("sun_scale", 1.3), ("sky_scale", 0.5)):
        ds.set(f"environment.{k}", v)
    errors = {}
    for name, h in (("sun_elevation", 2.0), ("sun_azimuth", 2.0), ("sun_scale", 0.1), ("sky_scale", 0.1)):
        ad, fd = _fd_check(sm, ds, cam, target, f"environment.{name}", h, seeds=SEEDS + (23, 29, 31, 37))
        assert abs(fd) > 1e-5, name
        errors[name] = abs(ad - fd) / abs(fd)
    assert max(errors.values()) <= 0.05, errors


def test_fit_recovers_the_sun_direction_from_its_shadow_and_shading(sm):
    """One view of the box scene lit from (35, 45) deg; the fit starts 7 and 12 deg away."""
    ds = sm.DiffScene(sun_scene(sm, 35.0, 45.0), soft_sun_deg=4.0)
    cam = sm.Camera.look_at(eye=(1.8, 1.6, 2.4), target=(0, 0.4, 0), fov_y_deg=40, width=32, height=32)
    target = np.array(ds.render(cam, spp=256, seed=3))
    start = {"environment.sun_elevation": 28.0, "environment.sun_azimuth": 57.0}
    result = sm.fit_texture(ds, [cam], [target], start, steps=50, spp=32, lr=0.5)
    assert np.mean(result.losses[-5:]) < 0.5 * result.losses[0]  # down to the renders' noise
    assert result.values["environment.sun_elevation"] == pytest.approx(35.0, abs=1.0)
    assert result.values["environment.sun_azimuth"] == pytest.approx(45.0, abs=2.0)


def test_fit_texture_recovers_known_pattern_parameters_from_two_views(sm):
    scene = quad_scene(sm)
    ds = sm.DiffScene(scene)
    ds.bind_procedural("cloth", TRUTH)
    truth = {k: ds.get(k) for k in ("cloth.base_rgb", "cloth.pattern_rgb", "cloth.phase", "cloth.pattern_scale")}
    cams = [top_camera(sm, 48), top_camera(sm, 48, eye=(0.8, 2.0, 0.6))]
    targets = [np.array(ds.render(c, spp=64, seed=100 + i)) for i, c in enumerate(cams)]
    # a start a user would make by eye: light cloth, dark stripes, roughly where they are
    start = {"cloth.base_rgb": [0.6, 0.35, 0.3], "cloth.pattern_rgb": [0.15, 0.15, 0.1], "cloth.phase": [0.13, 0.42],
             "cloth.pattern_scale": 4.1}
    result = sm.fit_texture(ds, cams, targets, start, steps=60, spp=8, lr={"cloth.base_rgb": 0.03,
                                                                          "cloth.pattern_rgb": 0.03})
    assert len(result.losses) == 60 and result.seconds_per_step > 0
    assert np.mean(result.losses[-5:]) < 0.1 * result.losses[0]
    assert result.initial["cloth.pattern_scale"] == pytest.approx(4.1)
    for k in ("cloth.base_rgb", "cloth.pattern_rgb"):
        np.testing.assert_allclose(result.values[k], truth[k], atol=0.02, err_msg=k)
    assert result.values["cloth.pattern_scale"] == pytest.approx(truth["cloth.pattern_scale"], abs=0.02)
    assert result.values["cloth.phase"][1] == pytest.approx(truth["cloth.phase"][1], abs=0.005)


def test_a_torch_loss_through_dr_wrap_gives_the_drjit_gradient(sm):
    import drjit as dr
    import mitsuba as mi
    torch = pytest.importorskip("torch")

    @dr.wrap(source="drjit", target="torch")
    def torch_mse(img, ref):
        return torch.mean((img - ref) ** 2)

    ds = sm.DiffScene(quad_scene(sm))
    ds.bind_procedural("cloth", TRUTH)
    cam = top_camera(sm, 16)
    ref = mi.TensorXf(np.full((16, 16, 3), 0.2, np.float32))
    grads = []
    for loss in (torch_mse, lambda a, b: dr.mean(dr.square(a - b), axis=None)):
        var = dr.detach(ds.variables["cloth.base_rgb"])
        dr.enable_grad(var)
        ds.variables["cloth.base_rgb"] = var
        dr.backward(loss(ds.render(cam, spp=4, seed=3), ref))
        grads.append(np.array(dr.grad(var)).ravel())
    assert np.abs(grads[0]).min() > 0
    np.testing.assert_allclose(grads[0], grads[1], rtol=1e-4)


def test_bad_inputs_name_the_field(sm):
    ds = sm.DiffScene(quad_scene(sm))
    with pytest.raises(ConfigError, match="bind_procedural"):
        ds.set("cloth.base_rgb", [0.1, 0.2, 0.3])
    with pytest.raises(ConfigError, match="scene's meshes"):
        ds.bind_procedural("shirt", TRUTH)
    cam = top_camera(sm, 16)
    with pytest.raises(ConfigError, match=r"targets\[0\]"):
        sm.fit_texture(ds, [cam], [np.zeros((8, 8, 3))], ["environment.radiance"], steps=1)
    with pytest.raises(ConfigError, match="one target image per camera"):
        sm.fit_texture(ds, [cam, cam], [np.zeros((16, 16, 3))], ["environment.radiance"], steps=1)
    with pytest.raises(ConfigError, match="integrator"):
        sm.DiffScene(quad_scene(sm), integrator="path")
    with pytest.raises(ConfigError, match="soft_sun_deg.*SunSky.*Constant"):
        sm.DiffScene(quad_scene(sm), soft_sun_deg=2.0)
    with pytest.raises(ConfigError, match=r"soft_sun_deg.*\[0.25, 20\]"):
        sm.DiffScene(sun_scene(sm), soft_sun_deg=0.0)


def test_cli_fit_texture_round_trip_recovers_a_garment_colour(sm, tmp_path):
    """make-targets renders a subject; fitting from a recipe whose t-shirt has another colour
    brings the colour back (CIELAB distance) and writes the fit, the recipe and a comparison."""
    import json

    from synmitsuba.body.recipe import SubjectRecipe
    from synmitsuba.body.textures import lab_to_linear_rgb
    from synmitsuba.cli import main
    recipe = sm.sample_subject(np.random.default_rng(7), {"outfit": ["tshirt", "trousers"], "jacket": False,
                                                          "hair_style": "bald", "accessories": [], "texture_size": 64})
    shirt = next(g for g in recipe.garments if g.kind == "tshirt")
    shirt.texture.pattern, shirt.texture.decal, shirt.texture.bump = "none", "none", "none"
    shirt.texture.base_lab = [55.0, 25.0, -30.0]  # well inside the gamut: 30 steps reach it from grey
    truth = list(shirt.texture.base_lab)
    (tmp_path / "truth.json").write_text(recipe.to_json())
    targets = tmp_path / "targets"
    assert main(["fit-texture", str(targets), "--subject", str(tmp_path / "truth.json"), "--make-targets", "2",
                 "--size", "32", "--target-spp", "16"]) == 0
    shirt.texture.base_lab = [50.0, 0.0, 0.0]
    (tmp_path / "guess.json").write_text(recipe.to_json())
    out = tmp_path / "fit"
    assert main(["fit-texture", str(targets), "--subject", str(tmp_path / "guess.json"), "--out", str(out),
                 "--garment", "tshirt", "--params", "base_rgb", "--steps", "30", "--spp", "4", "--lr", "0.03",
                 "--quiet"]) == 0
    fit = json.loads((out / "fit.json").read_text())
    assert fit["losses"][-1] < fit["losses"][0]  # (the floor is the targets' and the fit's noise)
    fitted = SubjectRecipe.from_json((out / "recipe.json").read_text())
    got = next(g for g in fitted.garments if g.kind == "tshirt").texture.base_lab
    np.testing.assert_allclose(lab_to_linear_rgb(got), lab_to_linear_rgb(truth), atol=0.03)
    assert (out / "compare.png").is_file()
    assert main(["fit-texture", str(targets), "--subject", str(tmp_path / "guess.json"), "--out", str(out),
                 "--params", "colour"]) == 2  # one line naming --params
