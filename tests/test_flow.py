"""Exact optical flow against analytic answers: a translating plane, a moving camera, a
rotating box (its position pass rotated and projected by hand), occlusion and out-of-view
flags."""
import numpy as np
import pytest
import trimesh

from synmitsuba.errors import ConfigError

from synmitsuba.annotate.flow import BACKGROUND, HIDDEN, OUTSIDE, SEEN, Geometry, exact_flow

PLANE = np.array([[-3.0, -3, 0], [3, -3, 0], [3, 3, 0], [-3, 3, 0]])
QUAD = np.array([[0, 1, 2], [0, 2, 3]])


def _plane_scene(sm):
    scene = sm.Scene()
    scene.add_mesh("plane", PLANE, QUAD, instance=1)
    return scene


def test_translating_plane_and_moving_camera(sm):
    scene = _plane_scene(sm)
    cam = sm.Camera.look_at(eye=(0, 0, 5.0), target=(0, 0, 0), fov_y_deg=40, width=32, height=24)
    now, then = Geometry({"plane": PLANE}), Geometry({"plane": PLANE + [0.1, 0.05, 0]})
    flow, flags = exact_flow(scene, cam, cam, now, then)
    fx, fy = cam.K[0, 0], cam.K[1, 1]
    assert (flags[:, :-1] == SEEN).all() and (flags[:, -1] == OUTSIDE).all()  # 0.66 px right: the last column leaves
    assert np.allclose(flow[..., 0], fx * 0.1 / 5, atol=1e-3) and np.allclose(flow[..., 1], -fy * 0.05 / 5, atol=1e-3)
    moved = sm.Camera.look_at(eye=(0.2, 0, 5.0), target=(0.2, 0, 0), fov_y_deg=40, width=32, height=24)
    flow, flags = exact_flow(scene, cam, moved, now, now)
    assert np.allclose(flow[..., 0], -fx * 0.2 / 5, atol=1e-3) and np.allclose(flow[..., 1], 0, atol=1e-3)
    assert np.array_equal(scene.meshes["plane"].vertices, PLANE)  # the scene is back at its own frame


def test_rotating_box_matches_its_position_pass_rotated(sm):
    from synmitsuba.geometry import axis_rotation
    box = trimesh.creation.box(extents=(1.0, 1.2, 0.8))
    scene = sm.Scene()
    scene.add_mesh("box", box.vertices, box.faces, instance=2)
    cam = sm.Camera.look_at(eye=(1.5, 1.2, 3.5), target=(0, 0, 0), fov_y_deg=35, width=40, height=32)
    R = axis_rotation("y", np.radians(40.0))
    flow, flags = exact_flow(scene, cam, cam, Geometry({"box": box.vertices}), Geometry({"box": box.vertices @ R.T}))
    s = sm.render(scene, cam, spp=1)
    hit = s.mask
    uv, _ = cam.project(s.position[hit] @ R.T)
    px = np.stack(np.meshgrid(np.arange(40) + 0.5, np.arange(32) + 0.5), -1)[hit]
    assert np.abs(flow[hit] - (uv - px)).max() < 2e-3
    assert (flags[~hit] == BACKGROUND).all() and (flow[~hit] == 0).all()
    assert (flags[hit] == HIDDEN).any() and (flags[hit] == SEEN).mean() > 0.7  # faces turning away get hidden


def test_occluder_and_out_of_view_flags(sm):
    scene = _plane_scene(sm)
    cube = trimesh.creation.box(extents=(0.6, 0.6, 0.6))
    v0 = cube.vertices + [-1.0, 0, 1.0]
    scene.add_mesh("cube", v0, cube.faces, instance=3)
    cam = sm.Camera.look_at(eye=(0, 0, 5.0), target=(0, 0, 0), fov_y_deg=40, width=48, height=36)
    then = Geometry({"plane": PLANE, "cube": v0 + [1.0, 0, 0]})
    flow, flags = exact_flow(scene, cam, cam, Geometry({"plane": PLANE, "cube": v0}), then)
    scene_then = _plane_scene(sm)
    scene_then.add_mesh("cube", v0 + [1.0, 0, 0], cube.faces, instance=3)
    inst_then = sm.render(scene_then, cam, spp=1).instance
    now_inst = sm.render(scene, cam, spp=1).instance
    hidden = (flags == HIDDEN) & (now_inst == 1)
    assert hidden.sum() > 20
    ys, xs = np.nonzero(hidden)
    to = np.floor(np.stack([xs + 0.5, ys + 0.5], -1) + flow[ys, xs]).astype(int)
    assert (inst_then[to[:, 1], to[:, 0]] == 3).all()  # hidden plane points land on the cube at g
    gone = Geometry({"plane": PLANE + [20.0, 0, 0], "cube": v0})
    _, flags = exact_flow(scene, cam, cam, Geometry({"plane": PLANE, "cube": v0}), gone)
    assert (flags[now_inst == 1] == OUTSIDE).all()


def test_render_sequence_writes_flow_with_hair(sm, tmp_path):
    import numpy as np

    from synmitsuba.compose.subjects import PlacedSubject
    human = sm.build_subject(sm.sample_subject(np.random.default_rng(2), {"hair_style": "long", "accessories": [], "texture_size": 64}))
    clip = sm.retarget(sm.procedural_motion("wave", np.random.default_rng(0), seconds=0.3), human.skeleton)
    from synmitsuba.annotate.flow import subjects_geometry
    p = PlacedSubject(human, clip, 0, 100, "s0")
    scene = sm.Scene()
    p.pose_in(scene, 4)
    head = human.keypoints(*clip.frame(4))[0]
    cam = sm.Camera.look_at(eye=head + [0, 0.1, 1.2], target=head, fov_y_deg=40, width=48, height=48)
    flow, flags = exact_flow(scene, cam, cam, subjects_geometry([p], 4), subjects_geometry([p], 5))
    s = sm.render(scene, cam, spp=1)
    hair = s.layer == 6
    assert hair.sum() > 50 and (flags[hair] != BACKGROUND).all()
    from scipy.spatial import cKDTree
    P4, P5 = [[x for x in human.pose(*clip.frame(f)) if x.name == "hair"][0].points for f in (4, 5)]
    t = np.linspace(0, 1, 21)[None, None, :, None]  # each strand's axis, finely sampled, at frames 4 and 5
    axis4, axis5 = [(P[:, :-1, None] * (1 - t) + P[:, 1:, None] * t).reshape(-1, 3) for P in (P4, P5)]
    hit = s.position[hair]
    _, near = cKDTree(axis4).query(hit, k=16)  # the segments of the 16 nearest samples: the hit projected onto
    strand, seg = np.unravel_index(near // 21, P4[:, :-1].shape[:2])  # each, the nearest of them kept
    a, b = P4[strand, seg], P4[strand, seg + 1]
    u = np.clip(((hit[:, None] - a) * (b - a)).sum(2) / ((b - a) ** 2).sum(2), 0, 1)[..., None]
    best = np.argmin(np.linalg.norm(hit[:, None] - ((1 - u) * a + u * b), axis=2), 1)[:, None]
    strand, seg, u = [np.take_along_axis(x, best, 1)[:, 0] for x in (strand, seg, u[..., 0])]
    a, b, u = P4[strand, seg], P4[strand, seg + 1], u[:, None]
    moved = (1 - u) * P5[strand, seg] + u * P5[strand, seg + 1] + hit - ((1 - u) * a + u * b)  # by hand
    r = [x for x in human.pose(*clip.frame(4)) if x.name == "hair"][0].radius
    r = (1 - u[:, 0]) * r[strand, seg] + u[:, 0] * r[strand, seg + 1]
    sure = np.abs(np.linalg.norm(hit - ((1 - u) * a + u * b), axis=1) - r) < 0.05 * r  # on this strand, not a crossing one
    assert sure.mean() > 0.9
    (A4, b4), (A5, b5) = [(T[0][human.head_bone], T[1][human.head_bone]) for T in
                          (human._transforms(*clip.frame(4)), human._transforms(*clip.frame(5)))]
    with_head = (axis4 - b4) @ A4 @ A5.T + b5  # long hair on the back does not move rigidly with the head
    assert np.linalg.norm(axis5 - with_head, axis=1).max() > 0.005
    uv, _ = cam.project(moved)
    px = np.stack(np.meshgrid(np.arange(48) + 0.5, np.arange(48) + 0.5), -1)[hair]
    assert np.abs(flow[hair] - (uv - px))[sure].max() < 1e-2
    assert np.array_equal(scene.curves["s0_hair"].points,
                          next(x for x in human.pose(*clip.frame(4)) if x.name == "hair").points)
    with pytest.raises(ConfigError, match=r"frame = 9: the clip has frames 0\.\.8: there is no flow"):
        subjects_geometry([p], clip.n_frames)


def test_composed_ground_is_exact_near_the_scene_and_still_where_nothing_moves(sm):
    """The plaza's ground (40 km across) against the plane y = 0 intersected in float64: the
    position pass within 0.1 mm and uv within 1e-4 tiles up to 10 m; the flow of still ground
    and objects under a still camera, with one shape moving, within 0.01 px (it was 0.17 px,
    and the position 6.3 mm off, on one triangle pair)."""
    from synmitsuba.compose.environments import add_environment, load_environment, sample_lighting
    env, rng = load_environment("plaza"), np.random.default_rng(0)
    scene = sm.Scene()
    add_environment(scene, env, sample_lighting(env, rng), rng)
    scene.add_mesh("mover", PLANE * 0.2 + [0, 1, 2], QUAD, instance=100)
    cam = sm.Camera.look_at(eye=(0.3, 1.6, 6.0), target=(0.1, 0.0, 0.0), fov_y_deg=60, width=96, height=72)
    s = sm.render(scene, cam, spp=1)
    d = cam.pixel_rays()
    t = -cam.center[1] / d[..., 1]  # float64 ray-plane intersection
    exact = cam.center + np.where(t > 0, t, np.nan)[..., None] * d
    near = (s.instance == 1) & (t < 10)
    assert near.sum() > 2000
    assert np.abs(s.passes["position"][near] - exact[near]).max() < 1e-4
    assert np.abs(s.passes["uv"][near] - exact[near][:, [0, 2]] / env.ground.period_m).max() < 1e-4
    now, then = Geometry({"mover": scene.meshes["mover"].vertices}), Geometry({"mover": PLANE * 0.2 + [0.1, 1, 2]})
    flow, flags = exact_flow(scene, cam, cam, now, then)
    still = (s.instance > 0) & (s.instance < 100) & (flags == SEEN)
    assert still.sum() > 3000 and np.abs(flow[still]).max() < 0.01
    assert np.abs(flow[s.instance == 100, 0] - cam.K[0, 0] * 0.1 / 4.0).max() < 0.2  # the mover's flow, roughly
