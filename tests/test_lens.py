"""Lens distortion and depth of field against independent references: OpenCV's projectPoints
(and its fisheye twin) for the projection, the rendered exact passes against that projection,
a defocused point light against the thin-lens circle of confusion, and labels unchanged by
the aperture."""
import numpy as np
import pytest

from synmitsuba.errors import ConfigError

BROWN = [-0.25, 0.08, 0.002, -0.003, -0.01]
FISHEYE = [0.05, -0.02, 0.004, -0.001]


def _camera(sm, lens="brown_conrady", dist=None, **kw):
    K = np.array([[210.0, 0.0, 83.0], [0.0, 205.0, 58.5], [0.0, 0.0, 1.0]])
    cam = sm.Camera.look_at(eye=(0.4, 1.2, 3.0), target=(0.0, 0.9, 0.0), width=160, height=120, K=K)
    return sm.Camera(K=cam.K, R=cam.R, t=cam.t, width=160, height=120, lens=lens, dist=dist, **kw)


def _points_in_view(cam, n=200, seed=0):
    rng = np.random.default_rng(seed)
    p = np.stack([rng.uniform(-0.5, 0.5, n), rng.uniform(-0.35, 0.35, n), np.ones(n)], 1) * rng.uniform(1, 6, (n, 1))
    return (p - cam.t) @ cam.R  # camera frame -> world


@pytest.mark.parametrize("lens, dist", [("brown_conrady", BROWN), ("fisheye", FISHEYE)])
def test_projection_matches_opencv(sm, lens, dist):
    import cv2
    cam = _camera(sm, lens, dist)
    X = _points_in_view(cam)
    uv, _ = cam.project(X)
    rvec = cv2.Rodrigues(cam.R)[0]
    if lens == "fisheye":
        ref = cv2.fisheye.projectPoints(X[:, None], rvec, cam.t, cam.K, np.array(dist))[0][:, 0]
    else:
        ref = cv2.projectPoints(X, rvec, cam.t, cam.K, np.array(dist))[0][:, 0]
    assert np.abs(uv - ref).max() < 1e-3
    assert np.abs(uv - cam.resized(160, 120).project(X)[0]).max() == 0  # resized keeps the lens
    plain = sm.Camera(K=cam.K, R=cam.R, t=cam.t, width=160, height=120)
    assert np.abs(uv - plain.project(X)[0]).max() > 2  # the distortion is not negligible here


@pytest.mark.parametrize("lens, dist", [("brown_conrady", BROWN), ("fisheye", FISHEYE)])
def test_pixel_rays_invert_the_projection(sm, lens, dist):
    cam = _camera(sm, lens, dist)
    d = cam.pixel_rays().reshape(-1, 3)
    uv, z = cam.project(cam.center + 2.5 * d)
    u, v = np.meshgrid(np.arange(160) + 0.5, np.arange(120) + 0.5)
    assert (z > 0).all() and np.abs(uv - np.stack([u.ravel(), v.ravel()], 1)).max() < 1e-6


def _wall_scene(sm):
    """A textured wall and a box in front of it, lit evenly."""
    import trimesh
    scene = sm.Scene()
    wall = trimesh.creation.box((6.0, 4.0, 0.1))
    wall.apply_translation((0.0, 1.0, -1.5))
    box = trimesh.creation.box((0.6, 0.8, 0.6))
    box.apply_translation((0.2, 0.9, 0.3))
    scene.add_mesh("wall", wall.vertices, wall.faces, material=sm.Material(base_color=(0.6, 0.5, 0.4)))
    scene.add_mesh("box", box.vertices, box.faces, material=sm.Material(base_color=(0.2, 0.3, 0.7)))
    scene.set_environment(sm.Constant(1.0))
    return scene


def test_distorted_exact_passes_land_where_the_projection_puts_them(sm):
    """Each hit pixel's position pass, projected through the distortion (numpy, forward), falls
    on that pixel's centre: the drjit rays undistort as the projection distorts; the RGB sees
    the same geometry (its mask matches alpha)."""
    cam = _camera(sm, "brown_conrady", BROWN)
    sample = sm.render(_wall_scene(sm), cam, spp=4)
    P, hit = sample.passes["position"].reshape(-1, 3), sample.passes["mask"].reshape(-1)
    uv, _ = cam.project(P[hit])
    u, v = np.meshgrid(np.arange(160) + 0.5, np.arange(120) + 0.5)
    centres = np.stack([u.ravel(), v.ravel()], 1)[hit]
    assert hit.mean() > 0.9 and np.abs(uv - centres).max() < 0.01
    plain = sm.render(_wall_scene(sm), sm.Camera(K=cam.K, R=cam.R, t=cam.t, width=160, height=120), spp=4)
    moved = np.abs(plain.passes["position"] - sample.passes["position"]).max(-1) > 0.02
    assert moved.mean() > 0.3  # away from the centre every pixel sees another point


@pytest.mark.filterwarnings("ignore:the camera sees no geometry")  # the emitter alone: lights are not geometry
def test_depth_of_field_blurs_a_point_by_the_circle_of_confusion(sm):
    """A 4 mm emitter 2 m away, focus at 1 m, aperture radius a: its image is a disc of radius
    f a |1/z - 1/s| pixels (thin lens); its per-axis spread is sqrt(rho^2 / 4 + the emitter's
    and the pixel's own). Exact passes and labels are those of the pinhole."""
    z, s, a, f = 2.0, 1.0, 0.02, 400.0
    scene = sm.Scene()
    scene.set_environment(sm.Constant(0.0))
    scene.add_light(sm.AreaLight(position=(0.0, 1.0, -z), target=(0.0, 1.0, 0.0), size=(0.004, 0.004), radiance=1e3))
    K = [[f, 0, 40.0], [0, f, 40.0], [0, 0, 1]]
    R = np.diag([1.0, -1.0, -1.0])  # looking down -z, y up in the world
    t = -R @ np.array([0.0, 1.0, 0.0])
    pin = sm.Camera(K=K, R=R, t=t, width=80, height=80)
    lens = sm.Camera(K=K, R=R, t=t, width=80, height=80, aperture_radius=a, focus_distance=s)
    spreads = []
    for cam in (pin, lens):
        img = sm.render(scene, cam, spp=256, seed=1).passes["rgb"].sum(-1)
        w = img / img.sum()
        x = np.arange(80) + 0.5
        mx = (w.sum(0) * x).sum()
        spreads.append(np.sqrt((w.sum(0) * (x - mx) ** 2).sum()))
    rho = f * a * abs(1 / z - 1 / s)
    assert spreads[1] == pytest.approx(np.sqrt(rho ** 2 / 4 + spreads[0] ** 2), rel=0.03)
    assert spreads[0] < 1.0 < rho
    a_pin, a_lens = (sm.render(_wall_scene(sm), c, spp=2, seed=3) for c in (
        _camera(sm), _camera(sm, aperture_radius=0.05, focus_distance=2.0)))
    for name in ("depth", "normal", "position", "instance", "alpha"):
        assert np.array_equal(a_pin.passes[name], a_lens.passes[name]), name
    assert not np.array_equal(a_pin.passes["rgb"], a_lens.passes["rgb"])


def test_camera_lens_round_trips_and_bad_values_name_the_field(sm):
    cam = _camera(sm, "fisheye", FISHEYE, aperture_radius=0.01, focus_distance=3.0)
    back = sm.Camera.from_dict(cam.to_dict())
    assert back.lens == "fisheye" and list(back.dist) == FISHEYE and back.aperture_radius == 0.01
    assert back.focus_distance == 3.0
    with pytest.raises(ConfigError, match="camera.dist"):
        _camera(sm, "fisheye", BROWN)
    with pytest.raises(ConfigError, match="camera.lens"):
        _camera(sm, "tilt_shift")
    with pytest.raises(ConfigError, match="camera.focus_distance"):
        _camera(sm, focus_distance=0.0)


def test_a_lens_that_folds_back_is_refused_and_points_past_its_fold_stay_outside(sm):
    """r (1 + k1 r^2) with k1 = -0.4 stops growing at r^2 = 1 / 1.2: corners past it would have
    no ray, so such a camera is refused; points past the fold project far outside, where OpenCV
    folds them back into the image."""
    import cv2
    with pytest.raises(ConfigError, match="camera.dist.*folds back"):
        sm.Camera(
            K=[[60.0, 0, 80], [0, 60, 60], [0, 0, 1]], width=160, height=120, dist=[-0.4, 0, 0, 0, 0])
    cam = sm.Camera(K=[[200.0, 0, 80], [0, 200, 60], [0, 0, 1]], width=160, height=120, dist=[-0.4, 0, 0, 0, 0])
    X = np.array([[1.4, 0.0, 1.0], [0.3, 0.1, 1.0]])  # r^2 = 1.96 past the fold (0.83), and one inside
    uv, _ = cam.project(X)
    ref = cv2.projectPoints(X, np.zeros(3), np.zeros(3), cam.K, cam.dist)[0][:, 0]
    assert 0 <= ref[0, 0] < 160 and uv[0, 0] > 1e4  # OpenCV folds it into the image; we keep it out
    assert np.abs(uv[1] - ref[1]).max() < 1e-6


def test_generated_views_sample_lenses_and_their_keypoints_follow_opencv(tmp_path, sm):
    """``compose.cameras.distortion`` / ``aperture_radius`` draw a lens per view: every sample
    stores it, keypoints are projected through it (cv2.projectPoints agrees), the focus sits on
    the subjects."""
    import cv2
    from conftest import generate_tiny
    run = generate_tiny(tmp_path, "--set", "sequences=1", "--set", "compose.cameras.distortion=[-0.3,-0.1]",
                        "--set", "compose.cameras.tangential=0.005", "--set", "compose.cameras.aperture_radius=[0.01,0.02]")
    assert run.returncode == 0, run.stderr
    stems = sm.list_samples(str(tmp_path))
    assert stems
    for stem in stems:
        s = sm.read_sample(stem)
        cam = s.camera
        assert -0.3 <= cam.dist[0] < 0 and 0.01 <= cam.aperture_radius <= 0.02 and np.abs(cam.dist[2:4]).max() > 0
        for rec in s.subjects:
            ref = cv2.projectPoints(rec["keypoints3d_world"], cv2.Rodrigues(cam.R)[0], cam.t, cam.K, cam.dist)[0][:, 0]
            assert np.abs(ref - rec["keypoints2d"]).max() < 1e-3
            depth = (cam.R @ rec["keypoints3d_world"].T).T[:, 2] + cam.t[2]
            assert depth.min() - 0.5 < cam.focus_distance < depth.max() + 0.5


def test_a_scene_file_camera_carries_its_lens_and_bad_coefficients_name_the_key(tmp_path):
    """Scene files take lens keys per camera and shutter / photo in render; a wrong coefficient
    count is one error naming cameras[i].dist; ``synmitsuba render`` passes render's effects on."""
    import textwrap
    from types import SimpleNamespace

    from synmitsuba.cli.render import scene_config
    from synmitsuba.compose.scenefile import check_scene_file, scene_cameras
    text = textwrap.dedent("""
        render: {spp: 8, width: 64, height: 48, shutter_deg: 90, subframes: 4, photo: {enabled: true, iso: [400, 400]}}
        environment: {type: constant, radiance: 1.0}
        cameras:
          - {name: a, look_at: {eye: [0, 1, 4], target: [0, 1, 0], fov_y_deg: 40}, dist: [-0.1, 0.01, 0, 0, 0],
             aperture_radius: 0.01, focus_distance: 4.0}
          - {name: b, look_at: {eye: [0, 1, 4], target: [0, 1, 0], fov_y_deg: 40}, lens: fisheye, dist: [0.1, 0, 0, 0, 0]}
    """)
    (tmp_path / "s.yaml").write_text(text)
    with pytest.raises(ConfigError, match=r"cameras\[1\]\.dist"):
        scene_cameras(check_scene_file(str(tmp_path / "s.yaml")))
    (tmp_path / "s.yaml").write_text(text.replace("lens: fisheye, dist: [0.1, 0, 0, 0, 0]", "lens: fisheye"))
    doc = check_scene_file(str(tmp_path / "s.yaml"))
    (_, a), (_, b) = scene_cameras(doc)
    assert list(a.dist) == [-0.1, 0.01, 0, 0, 0] and a.aperture_radius == 0.01 and a.focus_distance == 4.0
    assert b.lens == "fisheye" and not b.distorted
    args = SimpleNamespace(spp=None, denoise=None, seed=None, frames=1, stride=1, no_labels=False, scene=str(tmp_path / "s.yaml"))
    r = scene_config(args, doc).render
    assert r.shutter_deg == [90.0, 90.0] and r.subframes == 4 and r.photo.enabled and r.photo.iso == [400.0, 400.0]
