"""Exact geometry passes checked against analytic answers, on tiny real renders."""
import numpy as np
import pytest
import trimesh

from synmitsuba.engine.build import cached_build


def plane(sm, scene, point, normal, size=40.0, instance=1, layer=9):
    """A large square through ``point`` with unit ``normal``."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    a = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)
    h = size / 2
    v = np.array([point + h * (sa * a + sb * b) for sa, sb in [(-1, -1), (1, -1), (1, 1), (-1, 1)]])
    scene.add_mesh("plane", v, np.array([[0, 1, 2], [0, 2, 3]]), material=sm.Material(base_color=0.6),
                   instance=instance, layer=layer)
    return n


def test_tilted_plane_z_depth_is_analytic(sm):
    scene = sm.Scene()
    p0 = np.array([0.2, 0.8, -0.5])
    n = plane(sm, scene, p0, [0.3, 0.4, 1.0])
    cam = sm.Camera.look_at(eye=(0.5, 1.2, 3.0), target=(0, 0.9, 0), fov_y_deg=50, width=48, height=36)
    s = sm.render(scene, cam, spp=1)
    d = cam.pixel_rays()
    c = cam.center
    t = ((p0 - c) @ n) / (d @ n)
    z = t * (d @ cam.R[2])
    assert s.mask.all()
    assert np.abs(s.depth - z).max() <= 1e-4
    # position agrees with depth through the camera model
    x_cam = s.position.reshape(-1, 3) @ cam.R.T + cam.t
    assert np.abs(x_cam[:, 2] - s.depth.ravel()).max() <= 1e-4


def test_depth_is_zero_and_masked_on_background(sm):
    scene = sm.Scene()
    box = trimesh.creation.box((0.5, 0.5, 0.5))
    scene.add_mesh("box", box.vertices, box.faces, instance=3)
    cam = sm.Camera.look_at(eye=(0, 0, 3), target=(0, 0, 0), width=32, height=32)
    s = sm.render(scene, cam, spp=1)
    assert 0 < s.mask.sum() < s.mask.size
    assert (s.depth[~s.mask] == 0).all() and (s.depth[s.mask] > 2.0).all()
    assert (s.instance[~s.mask] == 0).all() and (s.normal[~s.mask] == 0).all()
    # the box face towards the camera is at z = 0.25: depth 2.75 in the middle
    assert s.depth[16, 16] == pytest.approx(2.75, abs=1e-5)


def test_sphere_normals_match_analytic(sm):
    scene = sm.Scene()
    centre, radius = np.array([0.1, 1.0, -0.2]), 0.5
    ico = trimesh.creation.icosphere(subdivisions=5, radius=radius)
    scene.add_mesh("sphere", ico.vertices + centre, ico.faces, normals=ico.vertex_normals, instance=1)
    cam = sm.Camera.look_at(eye=(0.4, 1.5, 3.0), target=centre, fov_y_deg=30, width=48, height=48)
    s = sm.render(scene, cam, spp=1)
    m = s.mask
    assert m.sum() > 400
    # analytic ray-sphere intersection for the same pixel-centre rays
    d = cam.pixel_rays()[m]
    oc = cam.center - centre
    bq = d @ oc
    disc = bq ** 2 - (oc @ oc - radius ** 2)
    inside = disc > 0.02  # away from the silhouette, where tessellation decides hit or miss
    t = -bq[inside] - np.sqrt(disc[inside])
    p = cam.center + t[:, None] * d[inside]
    n_true = (p - centre) / radius @ cam.R.T
    n = s.normal[m][inside]
    assert np.abs(np.linalg.norm(n, axis=1) - 1).max() < 1e-5
    angle = np.degrees(np.arccos(np.clip((n * n_true).sum(1), -1, 1)))
    assert angle.max() < 0.5
    assert (n[:, 2] < 0).all()  # camera-facing normals point against the optical axis (OpenCV z forward)
    assert ((n * (d[inside] @ cam.R.T)).sum(1) <= 1e-6).all()  # what FORMAT.md promises in general: n . d <= 0


def test_instance_and_layer_ids_are_exact_integers(sm):
    scene = sm.Scene()
    ids = {"a": (7, sm.Layer.BODY), "b": (42, sm.Layer.TOP), "c": (100000, sm.Layer.HAIR)}
    for k, (name, (inst, layer)) in enumerate(ids.items()):
        ball = trimesh.creation.icosphere(subdivisions=2, radius=0.3)
        scene.add_mesh(name, ball.vertices + [-0.8 + 0.8 * k, 1, 0], ball.faces, instance=inst, layer=layer)
    cam = sm.Camera.look_at(eye=(0, 1, 3), target=(0, 1, 0), width=64, height=32)
    s = sm.render(scene, cam, spp=4)
    assert s.instance.dtype == np.int32 and s.layer.dtype == np.uint8
    assert set(np.unique(s.instance)) == {0, 7, 42, 100000}
    assert set(np.unique(s.layer)) == {0, int(sm.Layer.BODY), int(sm.Layer.TOP), int(sm.Layer.HAIR)}
    for k, (inst, layer) in enumerate(ids.values()):
        (u, v), = cam.project([[-0.8 + 0.8 * k, 1, 0]])[0]
        assert s.instance[int(v), int(u)] == inst
    # ids and layers agree pixel by pixel
    lut = {7: 1, 42: 2, 100000: 6, 0: 0}
    assert all((s.layer[s.instance == i] == lay).all() for i, lay in lut.items())


def test_off_centre_K_projects_onto_rendered_pixel(sm):
    """A world point projected with K, R, t lands where both the RGB and the exact passes show it."""
    K = np.array([[300.0, 0, 23.7], [0, 180.0, 41.2], [0, 0, 1]])
    cam0 = sm.Camera.look_at(eye=(0.3, 1.4, 2.5), target=(0, 1, 0))
    cam = sm.Camera(K=K, R=cam0.R, t=cam0.t, width=64, height=56)
    target = np.array([-0.02, 1.05, 0.03])
    scene = sm.Scene()
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.02)
    scene.add_mesh("dot", ball.vertices + target, ball.faces, instance=5,
                   material=sm.Material(base_color=1.0))
    scene.set_environment(sm.Constant(0.0))
    scene.add_light(sm.PointLight(position=tuple(cam.center), intensity=50.0))
    s = sm.render(scene, cam, spp=64)
    (u, v), = cam.project([target])[0]
    assert s.instance[int(v), int(u)] == 5
    ys, xs = np.nonzero(s.mask)
    assert abs(xs.mean() + 0.5 - u) < 0.35 and abs(ys.mean() + 0.5 - v) < 0.35
    lum = s.rgb.sum(-1)
    assert lum.max() > 0.1
    yy, xx = np.mgrid[:cam.height, :cam.width] + 0.5
    cu, cv = (lum * xx).sum() / lum.sum(), (lum * yy).sum() / lum.sum()
    assert abs(cu - u) < 0.5 and abs(cv - v) < 0.5


def test_alpha_is_fractional_only_on_edges(sm):
    scene = sm.Scene()
    box = trimesh.creation.box((1.0, 1.0, 0.1))
    scene.add_mesh("box", box.vertices, box.faces, instance=1)
    cam = sm.Camera.look_at(eye=(0, 0, 3), target=(0, 0, 0), width=40, height=40)
    s = sm.render(scene, cam, spp=16)
    assert (s.alpha[s.mask] > 0).all() and (s.alpha[~s.mask] < 1).all()
    interior = s.mask & np.roll(s.mask, 1, 0) & np.roll(s.mask, -1, 0) & np.roll(s.mask, 1, 1) & np.roll(s.mask, -1, 1)
    assert (s.alpha[interior] == 1).all()
    assert 0 < ((s.alpha > 0) & (s.alpha < 1)).sum() < 4 * 40


def test_uv_pass_reports_mesh_uvs(sm):
    scene = sm.Scene()
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    uv = (v[:, :2] + 1) / 2
    tex = np.zeros((4, 4, 3), np.float32)
    tex[:2, :, 0] = 1.0  # top rows red, bottom rows blue (v up: the top of the texture is v = 1)
    tex[2:, :, 2] = 1.0
    scene.add_mesh("quad", v, np.array([[0, 1, 2], [0, 2, 3]]), uv=uv, instance=1,
                   material=sm.Material(texture=tex))
    scene.set_environment(sm.Constant(1.0))
    cam = sm.Camera.look_at(eye=(0, 0, 2), target=(0, 0, 0), fov_y_deg=40, width=32, height=32)
    s = sm.render(scene, cam, spp=4)
    m = s.mask
    x_world = s.position[m]
    assert np.abs(s.uv[m] - (x_world[:, :2] + 1) / 2).max() < 1e-5
    top, bottom = s.rgb[8, 16], s.rgb[24, 16]  # image rows grow downwards, world y up
    assert top[0] > 20 * top[2] and bottom[2] > 20 * bottom[0]


def test_curves_render_with_their_ids(sm):
    scene = sm.Scene()
    t = np.linspace(0, 1, 6)
    strands = np.array([[[x, 0.5 + 0.8 * s, 0.0] for s in t] for x in np.linspace(-0.3, 0.3, 7)])
    scene.add_curves("hair", strands, radius=0.025, material=sm.Material(kind="hair"), instance=9,
                     layer=sm.Layer.HAIR)
    cam = sm.Camera.look_at(eye=(0, 0.9, 2), target=(0, 0.9, 0), width=48, height=48)
    s = sm.render(scene, cam, spp=4)
    assert set(np.unique(s.instance)) == {0, 9}
    assert set(np.unique(s.layer)) == {0, int(sm.Layer.HAIR)}
    # seven separate strands: count runs of hits along the middle row
    row = s.mask[24].astype(int)
    assert np.count_nonzero(np.diff(row) == 1) == 7


def test_update_mesh_moves_geometry_without_rebuilding(sm):
    scene = sm.Scene()
    box = trimesh.creation.box((1.0, 1.0, 0.1))
    scene.add_mesh("box", box.vertices, box.faces, instance=1)
    cam = sm.Camera.look_at(eye=(0, 0, 3), target=(0, 0, 0), width=16, height=16)
    s1 = sm.render(scene, cam, spp=1)
    built = cached_build(scene)
    scene.update_mesh("box", box.vertices + [0, 0, -1.0])
    s2 = sm.render(scene, cam, spp=1)
    assert cached_build(scene) is built
    assert s1.depth[8, 8] == pytest.approx(2.95, abs=1e-5)
    assert s2.depth[8, 8] == pytest.approx(3.95, abs=1e-5)


def test_moved_normals_are_the_ones_given(sm):
    """A mesh moved in place with new normals shades with those normals (pushed after the
    positions, whose update makes Mitsuba recompute its own from the faces); moved without
    new normals, it gets the faces' own again."""
    scene = sm.Scene()
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    scene.add_mesh("quad", v, f, normals=np.tile([0.0, 0.0, 1.0], (4, 1)), instance=1)
    cam = sm.Camera.look_at(eye=(0, 0, 3), target=(0, 0, 0), width=16, height=16)
    sm.render(scene, cam, spp=1)
    tilted = np.tile([0.6, 0.0, 0.8], (4, 1))
    scene.update_mesh("quad", v + [0, 0, -0.5], tilted)
    s = sm.render(scene, cam, spp=1)
    world = s.normal[s.mask] @ cam.R  # camera frame -> world
    assert np.abs(world - [0.6, 0.0, 0.8]).max() < 1e-5
    assert s.depth[8, 8] == pytest.approx(3.5, abs=1e-5)
    scene.update_mesh("quad", v)
    s = sm.render(scene, cam, spp=1)
    assert np.abs(s.normal[s.mask] @ cam.R - [0.0, 0.0, 1.0]).max() < 1e-5


def test_moving_a_textured_mesh_allocates_no_copy_of_its_texture(sm):
    """An in-place update evaluates only what it holds: vertex positions, normals and control points.
    (A whole-scene ``mi.traverse`` holds a 3-channel view of each texture, which ``update()``
    evaluated and kept beside the texture: 16 MiB for this 1024-px map.)"""
    import drjit as dr

    from synmitsuba.engine.build import build
    from synmitsuba.engine.variant import current_variant
    scene = sm.Scene()
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    tex = np.random.default_rng(0).random((1024, 1024, 3)).astype(np.float32)
    scene.add_mesh("quad", v, np.array([[0, 1, 2], [0, 2, 3]]), uv=(v[:, :2] + 1) / 2, instance=1,
                   material=sm.Material(texture=tex))
    cam = sm.Camera.look_at(eye=(0, 0, 3), target=(0, 0, 0), width=16, height=16)
    sm.render(scene, cam, spp=1)
    backend = dr.JitBackend.CUDA if current_variant().startswith("cuda") else dr.JitBackend.LLVM
    dr.flush_malloc_cache()
    dr.detail.malloc_clear_statistics()
    before = dr.detail.malloc_watermark(backend)
    scene.update_mesh("quad", v + [0, 0, -0.5])
    built = build(scene)
    assert sorted(built.moving.keys()) == ["quad.vertex_normals", "quad.vertex_positions"]
    assert dr.detail.malloc_watermark(backend) - before < 1 << 20
    assert sm.render(scene, cam, spp=1).depth[8, 8] == pytest.approx(3.5, abs=1e-5)


def test_fixed_seed_is_deterministic_and_seed_changes_noise(sm):
    scene = sm.Scene()
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    scene.add_mesh("ball", ball.vertices, ball.faces, instance=1)
    scene.set_environment(sm.SunSky())
    cam = sm.Camera.look_at(eye=(0, 0.5, 2), target=(0, 0, 0), width=24, height=24)
    a, b = sm.render(scene, cam, spp=4, seed=3), sm.render(scene, cam, spp=4, seed=3)
    c = sm.render(scene, cam, spp=4, seed=4)
    for name in a.passes:
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert not np.array_equal(a.rgb, c.rgb)
    assert np.array_equal(a.depth, c.depth)


def test_per_instance_coverage_is_a_soft_mask_consistent_with_ids(sm):
    scene = sm.Scene()
    for k, inst in enumerate((3, 8)):
        box = trimesh.creation.box((0.6, 0.6, 0.1))
        scene.add_mesh(f"b{k}", box.vertices + [-0.35 + 0.7 * k, 0, 0.1 * k], box.faces, instance=inst)
    cam = sm.Camera.look_at(eye=(0, 0, 3), target=(0, 0, 0), width=40, height=30)
    s = sm.render(scene, cam, spp=4, coverage_samples=16)
    assert sorted(s.coverage) == [3, 8]
    total = s.coverage[3] + s.coverage[8]
    assert np.allclose(total, s.alpha)
    for inst, frac in s.coverage.items():
        assert (frac[s.instance == inst] > 0).all()
        inner = (s.instance == inst) & (frac == 1.0)
        assert inner.sum() > 0.6 * (s.instance == inst).sum()
    # the boxes overlap in x: where box 8 (nearer) covers a pixel fully, box 3 covers none of it
    assert (s.coverage[3][s.coverage[8] == 1.0] == 0).all()


def test_coverage_cast_at_edges_equals_coverage_cast_everywhere(sm):
    """sm.render casts coverage rays only where a pixel's 3x3 neighbourhood sees more than one
    instance; on straight and gently curved edges that is every fractional pixel, so the result
    equals casting at every pixel (the same rays per pixel), at a fraction of the rays."""
    from synmitsuba.engine.build import build
    from synmitsuba.rendering.passes import coverage, edge_pixels, exact_passes
    scene = sm.Scene()
    for k, inst in enumerate((3, 8)):
        box = trimesh.creation.box((0.6, 0.6, 0.1))
        box.apply_transform(trimesh.transformations.rotation_matrix(0.3 * (k + 1), [0, 0, 1]))
        scene.add_mesh(f"b{k}", box.vertices + [-0.35 + 0.7 * k, 0, 0.1 * k], box.faces, instance=inst)
    ball = trimesh.creation.icosphere(subdivisions=4, radius=0.3)
    scene.add_mesh("ball", ball.vertices + [0.1, -0.5, 0.3], ball.faces, instance=5)
    cam = sm.Camera.look_at(eye=(0.2, 0.1, 3), target=(0, -0.1, 0), width=80, height=64)
    built = build(scene)
    exact = exact_passes(built, cam)
    a_edges, c_edges = coverage(built, cam, 9, 4, exact=exact)
    a_all, c_all = coverage(built, cam, 9, 4)
    assert np.array_equal(a_edges, a_all)
    assert sorted(c_edges) == sorted(c_all) == [3, 5, 8]
    for i in c_all:
        assert np.array_equal(c_edges[i], c_all[i]), i
    fractional = (a_all > 0) & (a_all < 1)
    cast = edge_pixels(exact["instance"], exact["mask"], np.zeros_like(exact["mask"]))
    assert fractional.sum() > 50 and len(cast) < 0.3 * a_all.size
    s = sm.render(scene, cam, spp=1, seed=4)
    assert np.array_equal(s.alpha, a_all)
