"""Ground-projected HDRI backdrops: our panorama directions against Mitsuba's own envmap, the
projected ground against the photo, shadows, the dome, the sun as a key light."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.compose import backdrop, environments
from synmitsuba.compose.environments import EnvmapLighting, SCENES_DIR
from synmitsuba.scene import panorama

CITY = "hdri/city.exr"
H_M, R_M = 1.7, 20.0


def _mitsuba_radiance(env: sm.EnvMap, directions: np.ndarray) -> np.ndarray:
    """Mitsuba's envmap emitter evaluated along world directions (the library as reference)."""
    import drjit as dr
    import mitsuba as mi
    from synmitsuba.engine.build import environment_dict
    from synmitsuba.engine.variant import require_variant
    require_variant()
    emitter = mi.load_dict(environment_dict(sm.EnvMap(source=env.pixels(), scale=env.scale,
                                                      rotation_deg=env.rotation_deg)))
    si = dr.zeros(mi.SurfaceInteraction3f, len(directions))
    si.wi = mi.Vector3f(*(-directions).T.astype(np.float32))
    out = np.array(emitter.eval(si), np.float64)
    return out.T if out.shape[0] == 3 and out.shape[-1] != 3 else out


def test_panorama_directions_match_mitsuba_envmap():
    import os
    env = sm.EnvMap(source=os.path.join(SCENES_DIR, CITY), rotation_deg=37.0)
    d = np.random.default_rng(0).normal(size=(4000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ours = panorama.lookup(env.pixels(), d, 37.0)
    ref = _mitsuba_radiance(env, d)
    rel = np.abs(ours - ref) / (ref + 1e-2)
    assert np.median(rel) < 0.01, np.median(rel)
    # a pixel centre's direction reads that pixel exactly
    px = env.pixels()
    dirs = panorama.pixel_directions(*px.shape[:2], 37.0)
    assert np.allclose(panorama.lookup(px, dirs[100:110, 200:210], 37.0), px[100:110, 200:210], atol=1e-5)


def _backdrop_scene(rotation=25.0, with_box=False):
    lighting = EnvmapLighting(CITY, 1.0, rotation)
    scene = sm.Scene()
    sun = backdrop.add_backdrop(scene, lighting, H_M, R_M)
    if with_box:
        import trimesh
        box = trimesh.creation.box(extents=(1.0, 1.0, 1.0)).apply_translation((0, 1.5, 0))
        scene.add_mesh("box", box.vertices, box.faces, material=sm.Material(base_color=0.5), instance=2)
    return scene, lighting, sun


def test_projected_ground_shows_the_photo_and_catches_shadows():
    """Seen from off the projection point, an unshadowed ground pixel has the photo's colour in
    the direction from the projection point to that ground point (the position pass); under a
    box the ground is darker than the photo, and the box's shadow falls away from the sun."""
    scene, lighting, sun = _backdrop_scene(with_box=True)
    assert sun is not None and sun.direction[1] > 0.3
    cam = sm.Camera.look_at((2.5, 1.2, 3.0), (0, 0, -1.0), fov_y_deg=70, width=96, height=72)
    s = sm.render(scene, cam, spp=256, seed=1)
    from scipy.ndimage import binary_dilation
    box = binary_dilation(s.passes["instance"] == 2, iterations=2)   # pixels the box's edge shares
    ground = (s.passes["layer"] == int(sm.Layer.GROUND)) & ~box
    p = s.passes["position"][ground]
    # the photo over each pixel: 16 sub-pixel rays met with the plane y = 0, looked up from
    # the projection point, averaged (a box filter, as the render's)
    photo = 0.0
    for off in [((i + 0.5) / 4, (j + 0.5) / 4) for i in range(4) for j in range(4)]:
        d = cam.pixel_rays(np.array(off))[ground]
        q = cam.center + (-cam.center[1] / d[:, 1])[:, None] * d - [0.0, H_M, 0.0]
        photo = photo + _mitsuba_radiance(lighting.emitter(), q / np.linalg.norm(q, axis=1, keepdims=True)) / 16
    rgb = s.passes["rgb"][ground].astype(np.float64)
    # shadow of the box: ground points whose ray to the sun meets the box
    t = (1.5 - p[:, 1]) / sun.direction[1]
    at = p + t[:, None] * sun.direction
    shadowed = (np.abs(at[:, 0]) < 0.6) & (np.abs(at[:, 2]) < 0.6)
    r = np.hypot(p[:, 0], p[:, 2])
    lit = ~shadowed & (r > 1.5)
    ratio = rgb.sum(1) / photo.sum(1)
    assert lit.sum() > 500 and shadowed.sum() > 20
    assert abs(np.median(ratio[lit]) - 1.0) < 0.05, np.median(ratio[lit])
    assert np.percentile(np.abs(ratio[lit] - 1), 90) < 0.1, np.percentile(np.abs(ratio[lit] - 1), 90)
    assert np.median(ratio[shadowed]) < 0.75, np.median(ratio[shadowed])


def _photo_over(cam, lighting, mask, point) -> np.ndarray:
    """The panorama over each masked pixel (16 sub-pixel rays, box filter) as seen from the
    projection ``point``: the ray's ground point looked at from there (Mitsuba's envmap)."""
    photo = 0.0
    for off in [((i + 0.5) / 4, (j + 0.5) / 4) for i in range(4) for j in range(4)]:
        d = cam.pixel_rays(np.array(off))[mask]
        q = cam.center + (-cam.center[1] / d[:, 1])[:, None] * d - point
        photo = photo + _mitsuba_radiance(lighting.emitter(), q / np.linalg.norm(q, axis=1, keepdims=True)) / 16
    return photo


def test_backdrop_projected_from_the_camera_shows_the_photo_as_shot():
    """Moved above a camera off its first centre, the projection shows each ground pixel as the
    photo does along that pixel's own ray (no smear), and the dome moves with it; from the old
    centre the same pixels showed something else."""
    scene, lighting, _ = _backdrop_scene()
    cam = sm.Camera.look_at((7.0, H_M, 5.0), (2.0, 0.0, -3.0), fov_y_deg=60, width=64, height=48)
    before = sm.render(scene, cam, spp=64, seed=1)
    assert backdrop.centre_backdrop(scene, cam.center)
    assert not backdrop.centre_backdrop(scene, cam.center)                  # already there
    assert np.allclose(scene.environment.dome.centre, [7.0, H_M, 5.0])
    after = sm.render(scene, cam, spp=64, seed=1)
    ground = (after.passes["layer"] == int(sm.Layer.GROUND)) & (before.passes["layer"] == int(sm.Layer.GROUND))
    assert ground.sum() > 1000
    seen = _photo_over(cam, lighting, ground, cam.center)   # = the panorama along the pixel's ray
    ratio = after.passes["rgb"][ground].sum(1) / seen.sum(1)
    assert abs(np.median(ratio) - 1) < 0.05 and np.percentile(np.abs(ratio - 1), 90) < 0.1, np.median(ratio)
    old = before.passes["rgb"][ground].sum(1) / seen.sum(1)
    assert np.percentile(np.abs(old - 1), 90) > 0.3, np.percentile(np.abs(old - 1), 90)
    # the same views in any order give the same bits: the disc is built from the point
    backdrop.centre_backdrop(scene, (0.0, 0.0, 0.0))
    backdrop.centre_backdrop(scene, cam.center)
    assert np.array_equal(sm.render(scene, cam, spp=4, seed=2).rgb, sm.render(scene, cam, spp=4, seed=2).rgb)
    fresh, _, _ = _backdrop_scene()
    backdrop.centre_backdrop(fresh, cam.center)
    assert np.array_equal(fresh.meshes["ground"].vertices, scene.meshes["ground"].vertices)


def test_dome_background_is_the_photo_seen_from_its_centre():
    """Above the horizon a pixel shows the panorama where its ray meets the dome (a sphere of
    R_M about the ground point below the projection point), seen from the projection point."""
    scene, lighting, _ = _backdrop_scene(rotation=140.0)
    cam = sm.Camera.look_at((4.0, 1.5, 2.0), (-3.0, 3.0, -6.0), fov_y_deg=60, width=64, height=48)
    s = sm.render(scene, cam, spp=64, seed=2)
    sky = s.passes["alpha"] == 0
    rays = cam.pixel_rays()[sky]
    o = cam.center
    b = rays @ o
    t = -b + np.sqrt(b * b - (o @ o - R_M ** 2))       # far root of |o + t d| = R (dome about the origin)
    q = o + t[:, None] * rays - [0.0, H_M, 0.0]
    expect = _mitsuba_radiance(lighting.emitter(), q / np.linalg.norm(q, axis=1, keepdims=True))
    got = s.passes["rgb"][sky].astype(np.float64)
    assert sky.sum() > 1000
    assert np.median(np.abs(got - expect) / (expect + 0.05)) < 0.03
    # every pixel, not only most, is the (sun-less) panorama at the dome: Mitsuba's envmap and our
    # bilinear lookup differ by up to 9 % at the panorama's edges, and a traced background
    # corrected by difference kept that, drawing each edge a second time where infinity puts it
    exact = scene.environment.scale * panorama.lookup(scene.environment.pixels(), q / np.linalg.norm(q, axis=1, keepdims=True), 140.0)
    err = np.abs(got - exact) / (exact + 0.05)
    assert np.percentile(err, 99) < 1e-4, np.percentile(err, 99)
    at_infinity = _mitsuba_radiance(lighting.emitter(), rays)
    assert np.median(np.abs(at_infinity - expect) / (expect + 0.05)) > 0.05   # the dome changed what is seen


def test_dome_background_blurs_with_the_exposure_cameras():
    """Under motion blur the dome is the mean over the exposure's cameras of what each sees
    there, at most ``TAPS`` of them spread over the exposure."""
    from synmitsuba.rendering.dome import TAPS, on_dome
    scene, _, _ = _backdrop_scene(rotation=140.0)
    env = scene.environment
    cams = [sm.Camera.look_at((4.0, 1.5, 2.0), (-3.0 + 0.4 * k, 3.0, -6.0), fov_y_deg=60, width=64, height=48)
            for k in range(2 * TAPS)]
    out = on_dome(np.zeros((48, 64, 3), np.float32), env, cams[0], np.zeros((48, 64)), cams)
    expect = 0.0
    picked = [cams[k] for k in np.unique(np.linspace(0, len(cams) - 1, TAPS).round().astype(int))]
    for cam in picked:
        rays = cam.pixel_rays().reshape(-1, 3)
        o = cam.center
        b = rays @ o
        q = o + (-b + np.sqrt(b * b - (o @ o - R_M ** 2)))[:, None] * rays - [0.0, H_M, 0.0]
        d = q / np.linalg.norm(q, axis=1, keepdims=True)
        expect = expect + env.scale * panorama.lookup(env.pixels(), d, env.rotation_deg) / TAPS
    err = np.abs(out.reshape(-1, 3) - expect) / (expect + 0.05)
    assert np.percentile(err, 99) < 1e-4, np.percentile(err, 99)
    sharp = on_dome(np.zeros((48, 64, 3), np.float32), env, cams[0], np.zeros((48, 64)))
    assert np.abs(sharp - out).mean() > 0.1 * np.abs(out).mean()     # the blur changed it


def test_find_sun_on_a_synthetic_sky():
    h, w = 256, 512
    sky = np.full((h, w, 3), 0.5, np.float32)
    dirs = panorama.pixel_directions(h, w)
    toward = np.array([0.3, 0.8, -0.5]) / np.linalg.norm([0.3, 0.8, -0.5])
    disc = dirs @ toward > np.cos(np.radians(2.0))
    sky[disc] = [400.0, 380.0, 350.0]
    found = backdrop.find_sun(sky, rotation_deg=30.0)
    expect_dir = panorama.rot_y(30.0) @ toward
    assert np.degrees(np.arccos(np.clip(found.direction @ expect_dir, -1, 1))) < 0.5
    omega = panorama.solid_angles(h, w)[..., None] * disc[..., None]
    assert np.allclose(found.irradiance, ((np.array([400.0, 380.0, 350.0]) - 0.5) * omega).sum((0, 1)), rtol=1e-3)
    assert np.allclose(found.pixels, 0.5, atol=1e-4)
    assert backdrop.find_sun(np.full((h, w, 3), 0.5, np.float32)) is None


def test_every_blender_hdri_has_a_backdrop_and_cameras_stay_on_its_ground():
    import glob
    import os
    hdris = {os.path.basename(p) for p in glob.glob(os.path.join(SCENES_DIR, "hdri", "*.exr"))}
    backdrops = [environments.load_environment(n) for n in environments.environment_names() if n.startswith("hdri_")]
    assert {os.path.basename(e.lighting.file) for e in backdrops} == hdris and len(hdris) == 8
    env = environments.load_environment("hdri_forest")
    cfg = {"environments": ["hdri_forest"], "subjects": {"count": 2, "seconds": 0.5},
           "cameras": {"count": 3, "width": 64, "height": 48}}
    spec = sm.compose_scene(cfg, np.random.default_rng(4), seed=4)
    eyes = np.array([c.center for v in spec.views for c in v.cameras])
    assert len(spec.views) == 3
    assert np.abs(eyes[:, [0, 2]]).max() <= environments.DOME_KEEP * env.backdrop.radius_m + 1e-9
    # every subject stands on the photo's open floor as seen from each view's projection point:
    # the forest's path (panorama azimuths 30-100 degrees open for 10 m, 100-185 for 6), elsewhere fences
    rot = spec.lighting.rotation_deg
    for v in spec.views:
        p = backdrop.view_projection_point(v.cameras)
        assert abs(p[1] - 1.7) <= env.backdrop.camera_rise_m == 1.2      # near the shooting height
        for s in spec.subjects:
            x0, z0, x1, z1 = s.footprint
            for x in (x0, x1):
                for z in (z0, z1):
                    # the corner's azimuth across the panorama, worked out here from its convention
                    d = np.array([x - p[0], 0.0, z - p[2]])
                    c, sn = np.cos(np.radians(rot)), np.sin(np.radians(rot))
                    local = np.array([c * d[0] - sn * d[2], 0.0, sn * d[0] + c * d[2]])   # turned back by rot
                    az = np.degrees(np.arctan2(local[0], -local[2])) % 360
                    dist = np.hypot(d[0], d[2])
                    assert dist <= 2.0 or (30 <= az <= 100 and dist <= 10) or (100 <= az <= 185 and dist <= 6), \
                        (v.name, az, dist)


def test_floor_reach_and_panorama_azimuths():
    b = environments.Backdrop.from_dict({"radius_m": 20, "floor_m": 2.0, "floor_sectors": [[300, 40, 9], [90, 120, 5]]},
                                        "backdrop")
    assert np.allclose(b.floor_reach([0, 20, 41, 100, 299, 330, 200]), [9, 9, 2, 5, 2, 9, 2])
    assert environments.Backdrop.from_dict({"radius_m": 20}, "backdrop").open_floor_m == 18.0
    # a pixel's own direction falls at its column's angle
    dirs = panorama.pixel_directions(8, 16, 37.0)
    assert np.allclose(panorama.azimuth_deg(dirs[2:6], 37.0), np.tile(360 * (np.arange(16) + 0.5) / 16, (4, 1)))


def test_backdrop_needs_an_hdri():
    with pytest.raises(sm.ConfigError, match="backdrop"):
        environments.Environment.from_dict({"name": "x", "backdrop": {"height_m": 1.7}}, "environment")
