"""Sampler choice, OIDN denoising and kernel reuse in animation, checked against references."""
import numpy as np
import pytest
import trimesh

from synmitsuba.engine.settings import choose_sampler


def test_auto_sampler_keeps_the_requested_sample_count(sm):
    import mitsuba as mi
    for spp in range(1, 41):
        name = choose_sampler("auto", spp)
        assert mi.load_dict({"type": name, "sample_count": spp}).sample_count() == spp, (spp, name)
    assert choose_sampler("auto", 16) == "ldsampler" and choose_sampler("auto", 64) == "ldsampler"
    assert choose_sampler("auto", 16, "envmap") == "multijitter"  # under an HDRI (bench/samplers.py)
    with pytest.raises(sm.ConfigError, match="spp = 8: the ldsampler sampler cannot take 8"):
        choose_sampler("ldsampler", 8)


def _scene(sm):
    scene = sm.Scene()
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    tex = np.zeros((8, 8, 3), np.float32)
    tex[::2] = [0.8, 0.2, 0.1]
    tex[1::2] = [0.1, 0.3, 0.8]
    uv = np.column_stack([np.arctan2(ball.vertices[:, 0], ball.vertices[:, 2]) / (2 * np.pi) + 0.5,
                          ball.vertices[:, 1] + 0.5])
    scene.add_mesh("ball", ball.vertices + [0, 0.5, 0], ball.faces, uv=uv, normals=ball.vertex_normals, instance=1,
                   material=sm.Material(texture=tex, kind="principled", roughness=0.5))
    ground = np.array([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], float)
    scene.add_mesh("ground", ground, np.array([[0, 2, 1], [0, 3, 2]]), material=sm.Material(base_color=0.5))
    scene.set_environment(sm.SunSky(sun_direction=(0.5, 0.8, 0.3)))
    return scene, sm.Camera.look_at(eye=(0, 1.2, 2.5), target=(0, 0.45, 0), fov_y_deg=45, width=64, height=48)


@pytest.fixture(scope="module")
def denoise_case(sm):
    scene, cam = _scene(sm)
    ref = np.mean([sm.render(scene, cam, spp=1024, seed=100 + k).rgb for k in range(2)], 0)
    return scene, cam, ref, sm.render(scene, cam, spp=4, seed=1)


@pytest.mark.parametrize("denoise", ["oidn", "oidn-balanced", "oidn-fast"])
def test_denoising_brings_a_noisy_render_closer_to_the_reference_and_keeps_labels(sm, denoise_case, denoise):
    pytest.importorskip("pyoidn")
    scene, cam, ref, noisy = denoise_case
    clean = sm.render(scene, cam, spp=4, seed=1, denoise=denoise)

    def mse(img):
        return float(np.mean((np.clip(img, 0, 1) - np.clip(ref, 0, 1)) ** 2))
    assert mse(clean.rgb) < 0.5 * mse(noisy.rgb)
    assert np.array_equal(clean.rgb_noisy, noisy.rgb)  # the raw colour is kept, bit for bit
    for name, arr in noisy.passes.items():
        if name != "rgb":
            assert np.array_equal(clean.passes[name], arr), name  # labels do not depend on denoising
    assert clean.meta["denoise"] == denoise and clean.meta["sampler"] == "ldsampler"


def test_oidn_qualities_differ_and_the_best_is_closest(sm, denoise_case):
    """The three qualities run three networks: their outputs differ, and OIDN's ``high`` is the
    closest to the reference on this scene (the order bench/render_quality.py measures)."""
    pytest.importorskip("pyoidn")
    scene, cam, ref, _ = denoise_case
    out = {d: sm.render(scene, cam, spp=4, seed=1, denoise=d).rgb for d in ("oidn", "oidn-fast")}
    assert not np.array_equal(out["oidn"], out["oidn-fast"])
    err = {d: float(np.mean((np.clip(img, 0, 1) - np.clip(ref, 0, 1)) ** 2)) for d, img in out.items()}
    assert err["oidn"] < err["oidn-fast"], err


def test_guides_are_the_albedo_and_normal_of_what_each_pixel_sees(sm):
    """The denoising guides against a direct computation: a camera looking down on a ground of
    one colour with a sphere of another on it. Wherever a pixel sees only the ground, albedo is
    its colour and the normal +y; only the sphere, its colour and its normal, the mean of the
    sphere's normal (analytic, at the exact position pass's pixel-centre hit); across the
    outline, a mix of the two colours (averaged over the pixel: partial shares), more of the
    ball's on its side of the edge."""
    import mitsuba as mi

    from synmitsuba.engine.build import build
    from synmitsuba.rendering import sensor as sensor_mod
    from synmitsuba.rendering.denoise import guides
    ground_c, ball_c, r, centre = np.array([0.2, 0.5, 0.3]), np.array([0.7, 0.2, 0.1]), 0.5, np.array([0, 0.5, 0])
    scene = sm.Scene()
    quad = np.array([[-9, 0, -9], [9, 0, -9], [9, 0, 9], [-9, 0, 9]], float)
    scene.add_mesh("ground", quad, np.array([[0, 2, 1], [0, 3, 2]]), material=sm.Material(base_color=tuple(ground_c)))
    ball = trimesh.creation.icosphere(subdivisions=6, radius=r)
    scene.add_mesh("ball", ball.vertices + centre, ball.faces, normals=ball.vertex_normals, instance=1,
                   material=sm.Material(base_color=tuple(ball_c)))
    scene.set_environment(sm.Constant(1.0))
    cam = sm.Camera.look_at(eye=(0, 3.0, 1.0), target=(0, 0.3, 0), fov_y_deg=35, width=48, height=40)
    sensor_mod.register(mi.variant())
    albedo, normal = guides(build(scene).mi_scene, sensor_mod.sensor_dict(cam, 64), seed=3, spp=64)
    exact = sm.render(scene, cam, spp=1)
    assert np.all(exact.passes["alpha"] == 1)  # the ground covers every pixel
    on_ball = np.squeeze(exact.passes["instance"]) == 1
    assert on_ball.sum() > 100 and (~on_ball).sum() > 100
    # pixels whose 3x3 neighbourhood is all ground or all ball: the whole pixel sees one surface
    from scipy.ndimage import binary_erosion
    inner_ball, inner_ground = binary_erosion(on_ball), binary_erosion(~on_ball)
    np.testing.assert_allclose(albedo[inner_ground], np.broadcast_to(ground_c, albedo[inner_ground].shape), atol=1e-3)
    np.testing.assert_allclose(normal[inner_ground], np.broadcast_to([0, 1, 0], normal[inner_ground].shape), atol=1e-3)
    np.testing.assert_allclose(albedo[inner_ball], np.broadcast_to(ball_c, albedo[inner_ball].shape), atol=1e-3)
    # the sphere's normal at the pixel: the analytic normal where the pixel's rays meet it
    pts = exact.passes["position"][inner_ball]
    analytic = (pts - centre) / r
    cos = np.sum(normal[inner_ball] * analytic, -1) / np.linalg.norm(normal[inner_ball], axis=-1)
    assert np.percentile(cos, 5) > 0.995, np.percentile(cos, [0, 5, 50])
    # across the outline: the mix of the two colours, the ball's share between 0 and 1 and
    # larger on the ball's side of the edge
    edge = ~(inner_ball | inner_ground)
    share = (albedo[edge][:, 0] - ground_c[0]) / (ball_c[0] - ground_c[0])
    assert np.all((share > -0.02) & (share < 1.02))
    np.testing.assert_allclose(albedo[edge], ground_c + share[:, None] * (ball_c - ground_c), atol=0.01)
    assert share[on_ball[edge]].mean() > share[~on_ball[edge]].mean() + 0.3
    assert np.sum((share > 0.1) & (share < 0.9)) >= 30  # averaged over the pixel, not its centre alone


ANIMATION_KERNELS = """
import gc, json
import numpy as np
import drjit as dr
import synmitsuba as sm
from synmitsuba.engine.build import STATS
sm.set_variant()
human = sm.build_subject(sm.sample_subject(np.random.default_rng(2), {"hair_style": "short", "texture_size": 64}))
clip = sm.retarget(sm.procedural_motion("walk", np.random.default_rng(0), seconds=0.5), human.skeleton)
scene = sm.Scene()
scene.set_environment(sm.Constant(1.0))
cam = sm.Camera.look_at(eye=(0, 1.0, 4.0), target=(0, 0.9, 0), fov_y_deg=40, width=32, height=48)
dr.set_flag(dr.JitFlag.KernelHistory, True)
frames, loads = [], []
for f in range(8):
    gc.collect()
    human.add_to(scene, *clip.frame(f), instance=1)
    sm.render(scene, cam, spp=2, seed=f)
    frames.append([k["hash"] for k in dr.kernel_history()  # reading clears it
                   if k.get("type") == dr.KernelType.JIT and k["operation_count"] >= 100])
    loads.append(STATS["loads"])
print(json.dumps({"loads": loads, "frames": frames}))
"""


def test_animation_compiles_no_render_kernel_after_the_second_frame():
    """A walking subject with hair: frames move meshes and curves in place, so after the first
    frame nothing is reloaded and the render kernels (path tracer, exact passes, coverage) are
    the same from frame to frame: a value baked into them per frame (a seed, a vertex) would
    give every frame new hashes. Frames 2-7 run one set of kernels. (They once came in two or
    three variants 6 operations apart: drjit read the hair's control points as one packet or
    as four floats depending on where numpy had put them; they now sit at 64-byte aligned
    addresses, ``engine.build.aligned_floats``.) In a process of its own, where only this
    scene's Mitsuba objects are alive (drjit traces virtual calls over every live instance).
    Tiny bookkeeping kernels (~20 operations) are not counted: they compile in microseconds,
    the render kernels in seconds."""
    import json
    import subprocess
    import sys
    run = subprocess.run([sys.executable, "-c", ANIMATION_KERNELS], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert len(set(report["loads"])) == 1, report["loads"]  # one load, at the first frame
    frames = report["frames"][2:]
    per_frame = max(len(f) for f in frames)
    assert per_frame >= 4  # path tracer, exact passes, coverage, ...
    assert all(set(f) == set(frames[0]) for f in frames), [[h[:8] for h in f] for f in frames]


def test_another_camera_compiles_no_render_kernel(sm):
    """Cameras are values, not literals, in every kernel: a sequence's second view (or the next
    sequence's cameras) reuses the path tracer, exact passes and coverage compiled for the first."""
    import gc

    import drjit as dr
    scene, _ = _scene(sm)
    cams = [sm.Camera.look_at(eye=eye, target=(0, 0.3, 0), fov_y_deg=40, width=40, height=30)
            for eye in ((0.3, 1.2, 3.0), (-2.0, 0.8, 2.2), (1.0, 2.5, -2.0))]
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        gc.collect()  # only this scene's objects are live (see the animation test below)
        sm.render(scene, cams[0], spp=4, seed=0)
        dr.kernel_history()  # reading clears it
        for cam in cams[1:]:
            sm.render(scene, cam, spp=4, seed=0)
        history = [k for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    big = [k for k in history if k["operation_count"] >= 100]
    assert len(big) >= 6  # path tracer, exact passes and coverage for each of the two cameras
    assert all(k["cache_hit"] for k in big), [(k["hash"][:8], k["operation_count"]) for k in big if not k["cache_hit"]]
