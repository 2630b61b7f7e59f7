"""Per-subject labels against independent computations: posing with camera-frame parameters,
visibility classes in hand-built scenes, amodal masks against a render of the subject alone,
boxes, projection by the pinhole formula, and the sample files."""
import json

import numpy as np
import pytest

from synmitsuba.compose.subjects import PlacedSubject
from synmitsuba.errors import ConfigError


@pytest.fixture(scope="module")
def walker(sm):
    human = sm.build_subject(sm.sample_subject(np.random.default_rng(4), {"outfit": ["tshirt", "shorts"],
                                                                          "hair_style": "short", "texture_size": 64}))
    clip = sm.retarget(sm.procedural_motion("walk", np.random.default_rng(0), seconds=0.5), human.skeleton)
    return PlacedSubject(human, clip, 0, 100, "subject0")


def _scene(sm, walker, frame=3):
    scene = sm.Scene()
    scene.set_environment(sm.Constant(1.0))
    walker.pose_in(scene, frame)
    return scene


def test_camera_frame_body_parameters_reproduce_camera_vertices(sm, walker):
    from scipy.spatial.transform import Rotation

    from synmitsuba.annotate import body_params_in_camera
    cam = sm.Camera.look_at(eye=(2.0, 1.5, 3.0), target=(0, 0.9, 0), width=64, height=64)
    rot, root = walker.motion.frame(3)
    rot_c, root_c = body_params_in_camera(walker.human.skeleton, rot, root, cam)
    rot_c = Rotation.from_rotvec(Rotation.from_matrix(rot_c).as_rotvec()).as_matrix()  # as stored: axis-angle
    for resolve, tol in ((False, 1e-5), (True, 1e-3)):
        # skinning is exact; the collision pass breaks ties between equally near vertices by index,
        # so a rigid move keeps its choices (a swapped neighbour moved the t-shirt 3.3 mm)
        world = walker.human.pose(rot, root, resolve=resolve)
        camera_frame = walker.human.pose(rot_c, root_c, resolve=resolve)
        for a, b in zip(world, camera_frame):
            if not a.is_curves:
                assert np.abs(a.vertices @ cam.R.T + cam.t - b.vertices).max() < (1e-5 if a.name == "body" else tol)


def test_visibility_classes_in_hand_built_scenes(sm, walker):
    from synmitsuba.annotate import keypoint_visibility
    rot, root = walker.motion.frame(3)
    kp = walker.human.keypoints(rot, root)
    body = walker.human.pose(rot, root)[0].vertices
    c = kp[:, [0, 2]].mean(0)
    front = sm.Camera.look_at(eye=(c[0], 1.0, c[1] + 4.0), target=(c[0], 0.9, c[1]), fov_y_deg=40, width=96, height=128)
    scene = _scene(sm, walker)
    vis, frac = keypoint_visibility(scene, front, kp, body, 100, {100, 200})
    face = [0, 1, 2]  # nose, eyes (COCO order)
    assert (vis[face] == 1).all() and (frac[face] > 0.5).all()
    back = sm.Camera.look_at(eye=(c[0], 1.6, c[1] - 4.0), target=(c[0], 1.6, c[1]), fov_y_deg=40, width=96, height=128)
    assert (keypoint_visibility(scene, back, kp, body, 100, {100})[0][face] == 2).all()  # behind the head
    wall = np.array([[-3, 0, 0.6], [3, 0, 0.6], [3, 0.7, 0.6], [-3, 0.7, 0.6]]) + [c[0], 0, c[1]]
    scene.add_mesh("wall", wall, np.array([[0, 1, 2], [0, 2, 3]]), instance=7)
    head = np.array([[-0.3, 1.3, 0.4], [0.3, 1.3, 0.4], [0.3, 2.0, 0.4], [-0.3, 2.0, 0.4]]) + [c[0], 0, c[1]]
    scene.add_mesh("other", head, np.array([[0, 1, 2], [0, 2, 3]]), instance=200)
    vis, _ = keypoint_visibility(scene, front, kp, body, 100, {100, 200})
    ankles = [15, 16]
    assert (vis[ankles] == 4).all() and (vis[face] == 3).all()
    up = sm.Camera.look_at(eye=(c[0], 1.0, c[1] + 4.0), target=(c[0], 3.0, c[1]), fov_y_deg=20, width=32, height=32)
    assert (keypoint_visibility(scene, up, kp, body, 100, {100, 200})[0][ankles] == 0).all()  # out of the image


def test_amodal_mask_boxes_and_projection(sm, walker):
    from synmitsuba.annotate import Annotator
    rot, root = walker.motion.frame(3)
    c = walker.human.keypoints(rot, root)[:, [0, 2]].mean(0)
    cam = sm.Camera.look_at(eye=(c[0] + 1.0, 1.0, c[1] + 4.0), target=(c[0], 0.9, c[1]), fov_y_deg=40, width=80,
                            height=96)
    scene = _scene(sm, walker)
    wall = np.array([[-3, 0, 0.6], [3, 0, 0.6], [3, 0.8, 0.6], [-3, 0.8, 0.6]]) + [c[0], 0, c[1]]
    scene.add_mesh("wall", wall, np.array([[0, 1, 2], [0, 2, 3]]), instance=7)
    sample = sm.render(scene, cam, spp=1)
    rec = Annotator([walker]).annotate(sample, scene, 3)[0]
    alone = sm.render(_scene(sm, walker), cam, spp=1)  # the subject alone, rendered on its own
    assert np.array_equal(rec["amodal_mask"], alone.instance == 100)
    visible = sample.instance == 100
    assert (visible <= rec["amodal_mask"]).all() and 0.3 < rec["visible_fraction"] < 0.9
    assert rec["visible_fraction"] == pytest.approx(visible.sum() / rec["amodal_mask"].sum())
    ys, xs = np.where(visible)
    assert rec["bbox_visible"] == [xs.min(), ys.min(), xs.max() + 1, ys.max() + 1]
    K, X = cam.K, rec["keypoints3d_cam"]
    assert np.allclose(rec["keypoints2d"][:, 0], K[0, 0] * X[:, 0] / X[:, 2] + K[0, 2])  # pinhole, by hand
    assert np.allclose(rec["keypoints2d"][:, 1], K[1, 1] * X[:, 1] / X[:, 2] + K[1, 2])
    assert rec["valid"] and rec["scale"] == pytest.approx(1.2 * max(rec["bbox_keypoints"][2] - rec["bbox_keypoints"][0],
                                                                    rec["bbox_keypoints"][3] - rec["bbox_keypoints"][1]) / 200)


def test_records_refuse_a_subject_id_an_object_shares(sm, walker):
    from synmitsuba.annotate import Annotator
    from synmitsuba.errors import ConfigError
    scene = _scene(sm, walker)
    cam = sm.Camera.look_at(eye=(0.0, 1.0, 4.0), target=(0, 0.9, 0), width=16, height=16)
    crate = np.array([[-0.3, 0, 1], [0.3, 0, 1], [0.3, 0.5, 1], [-0.3, 0.5, 1]])
    scene.add_mesh("crate", crate, np.array([[0, 1, 2], [0, 2, 3]]), instance=walker.instance)
    with pytest.raises(ConfigError, match=r"^subject0.instance = 100: the shape 'crate' has this id too"):
        Annotator([walker]).annotate(sm.render(scene, cam, spp=1), scene, 3)


def test_subject_records_survive_the_sample_files(sm, walker, tmp_path):
    from synmitsuba.annotate import Annotator
    scene = _scene(sm, walker)
    cam = sm.Camera.look_at(eye=(0.0, 1.0, 4.0), target=(0, 0.9, 0), width=40, height=48)
    sample = sm.render(scene, cam, spp=1)
    Annotator([walker]).annotate(sample, scene, 3)
    sm.write_sample(sample, tmp_path / "s")
    back = sm.read_sample(tmp_path / "s")
    a, b = sample.subjects[0], back.subjects[0]
    assert np.array_equal(a["amodal_mask"], b["amodal_mask"]) and np.array_equal(a["visibility"], b["visibility"])
    assert np.allclose(a["keypoints2d"], b["keypoints2d"], rtol=0, atol=0)
    assert np.array_equal(a["body_params_cam"]["rotations"], b["body_params_cam"]["rotations"])
    side = json.loads((tmp_path / "s.json").read_text())
    assert side["subjects"][0]["instance"] == 100 and "amodal_mask" not in side["subjects"][0]
    assert side["keypoint_names"][15:18] == ["left_ankle", "right_ankle", "left_big_toe"]
    assert len(side["keypoint_names"]) == len(side["subjects"][0]["keypoints2d"])


def test_coco_export_loads_and_scores_ap_1_with_pycocotools(sm, walker, tmp_path):
    """Two people (one partly behind the other) in two views, exported; pycocotools decodes
    the masks to the instance pass and, fed the ground truth as predictions, scores AP = 1."""
    import contextlib
    import io

    from pycocotools import mask as mask_util
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval

    from synmitsuba.annotate import Annotator
    other = PlacedSubject(walker.human, walker.motion.moved(0.0, [0.5, 0.0, -1.0]), 0, 101, "subject1")
    scene = _scene(sm, walker)
    other.pose_in(scene, 3)
    data = tmp_path / "data"
    for k, eye in enumerate([(0.3, 1.2, 4.0), (-2.5, 1.4, 3.0)]):
        cam = sm.Camera.look_at(eye=eye, target=(0.2, 0.9, -0.4), fov_y_deg=45, width=96, height=80)
        sample = sm.render(scene, cam, spp=1)
        Annotator([walker, other]).annotate(sample, scene, 3)
        sm.write_sample(sample, data / f"view{k}")
    out = tmp_path / "coco.json"
    assert sm.export_coco(str(data), str(out)) == {"images": 2, "annotations": 4}
    with contextlib.redirect_stdout(io.StringIO()):
        gt = COCO(str(out))
        for ann in gt.dataset["annotations"]:
            sample = sm.read_sample(data / f"view{ann['image_id'] - 1}")
            assert np.array_equal(mask_util.decode(gt.annToRLE(ann)).astype(bool), sample.instance == ann["instance"])
        preds = [{**a, "score": 1.0} for a in gt.dataset["annotations"]]
        for iou in ("keypoints", "segm", "bbox"):
            ev = COCOeval(gt, gt.loadRes(preds), iou)
            ev.evaluate()
            ev.accumulate()
            ev.summarize()
            assert ev.stats[0] == pytest.approx(1.0), iou
        # COCO-WholeBody's per-part evaluation, as its code does it: each part's points in place of
        # "keypoints" with its own sigmas, over the annotations where the part is valid
        doc = json.loads(out.read_text())
        for part, count in (("lefthand", 21), ("righthand", 21), ("face", 68)):
            anns = [{**a, "keypoints": a[f"{part}_kpts"], "num_keypoints": sum(v > 0 for v in a[f"{part}_kpts"][2::3])}
                    for a in doc["annotations"] if a[f"{part}_valid"]]
            assert anns, part
            part_gt = COCO()
            part_gt.dataset = {**doc, "annotations": anns}
            part_gt.createIndex()
            ev = COCOeval(part_gt, part_gt.loadRes([{**a, "score": 1.0} for a in anns]), "keypoints")
            ev.params.kpt_oks_sigmas = np.full(count, 0.025)
            ev.evaluate()
            ev.accumulate()
            ev.summarize()
            assert ev.stats[0] == pytest.approx(1.0), part
    for a in doc["annotations"]:
        rec = next(r for r in sm.read_sample(data / f"view{a['image_id'] - 1}").subjects if r["instance"] == a["instance"])
        assert len(a["keypoints"] + a["foot_kpts"] + a["face_kpts"] + a["lefthand_kpts"] + a["righthand_kpts"]) == 133 * 3
        parts = [("lefthand", rec["hands2d"][0], rec["hands_visibility"][0]),
                 ("righthand", rec["hands2d"][1], rec["hands_visibility"][1]), ("face", rec["face2d"], rec["face_visibility"])]
        for part, pts, classes in parts:
            k = np.reshape(a[f"{part}_kpts"], (len(classes), 3))
            seen = np.asarray(classes) > 0
            assert np.array_equal(k[:, 2] > 0, seen) and np.allclose(k[seen, :2], np.asarray(pts)[seen])
            x, y, w, h = a[f"{part}_box"]
            assert ((k[seen, 0] >= x) & (k[seen, 0] <= x + w) & (k[seen, 1] >= y) & (k[seen, 1] <= y + h)).all()
            assert a[f"{part}_valid"] == bool((np.asarray(classes) == 1).any())
    sm.export_coco(str(data), str(tmp_path / "index.json"), keypoint_coords="pixel_index")
    index = json.loads((tmp_path / "index.json").read_text())
    assert index["info"]["keypoint_coords"] == "pixel_index"
    for a, b in zip(json.loads(out.read_text())["annotations"], index["annotations"]):  # centres at integers
        k, kb = np.reshape(a["keypoints"], (-1, 3)), np.reshape(b["keypoints"], (-1, 3))
        shown = k[:, 2] > 0
        assert np.allclose(kb[shown, :2], k[shown, :2] - 0.5, rtol=0, atol=1e-9) and (kb[~shown] == 0).all()
        assert b["bbox"] == a["bbox"] and b["segmentation"] == a["segmentation"]
    with pytest.raises(ConfigError, match="keypoint_coords = 'centre'"):
        sm.export_coco(str(data), str(tmp_path / "x.json"), keypoint_coords="centre")
    assert sm.export_humandata(str(data), str(tmp_path / "hd.npz")) == {"subjects": 4}
    hd = np.load(tmp_path / "hd.npz", allow_pickle=True)
    cam, anny, meta = hd["cam_param"].item(), hd["anny"].item(), hd["meta"].item()
    kept = hd["keypoints2d_mask"].astype(bool)
    X, K = hd["keypoints3d"][:, kept, :3].astype(float), cam["K"].astype(float)
    proj = np.einsum("nij,nkj->nki", K, X)
    assert np.allclose(proj[..., :2] / proj[..., 2:], hd["keypoints2d"][:, kept, :2], atol=1e-3)  # K projects them
    R, T = cam["R"].astype(float), cam["T"].astype(float)
    root_cam = np.einsum("nij,nj->ni", R, anny["root_world"]) + T  # the world root trajectory, in the camera
    assert anny["rotations"].shape[1:] == (len(walker.human.skeleton), 3)
    assert np.allclose(root_cam, walker.human.skeleton.rest_positions[0] + anny["root_translation"], atol=1e-5)
    assert list(meta["instance"]) == [100, 101, 100, 101] and hd["image_path"][0] == "view0.png"
    assert hd["misc"].item()["keypoint_names"][17:20] == ["left_big_toe", "left_small_toe", "left_heel"]
    assert gt.dataset["categories"][0]["foot_keypoints"][3] == "right_big_toe"


def _labelled_view(sm, walker, offset, fov_y_deg, size):
    """The walker at frame 3 rendered and labelled from ``offset`` (x, y, z) beside it, looking
    at its middle: (sample, rotations, root)."""
    from synmitsuba.annotate import Annotator
    scene = _scene(sm, walker)
    rot, root = walker.motion.frame(3)
    c = walker.human.keypoints(rot, root)[:, [0, 2]].mean(0)
    cam = sm.Camera.look_at(eye=(c[0] + offset[0], offset[1], c[1] + offset[2]), target=(c[0], 1.0, c[1]),
                            fov_y_deg=fov_y_deg, width=size[0], height=size[1])
    s = sm.render(scene, cam, spp=1)
    Annotator([walker]).annotate(s, scene, 3)
    return s, rot, root


def test_layered_body_passes_against_the_visible_surface(sm, walker):
    """On skin pixels the body is the visible surface: body depth = depth, the surface point
    (anny face + barycentrics) rebuilt on the posed mesh = the position pass, the part = the
    nearest vertex's part; under the t-shirt the cloth lies millimetres to centimetres off the body."""
    from scipy.spatial import cKDTree

    from synmitsuba.body.segments import PART_NAMES, vertex_parts
    s, rot, root = _labelled_view(sm, walker, (0.5, 1.2, 2.5), 45, (72, 96))
    skin = (s.layer == 1) & (s.body_face > 0)
    assert skin.sum() > 200
    assert np.allclose(s.body_depth[skin], s.depth[skin], atol=2e-4)
    body = walker.human.pose(rot, root)[0].vertices
    anny = walker.human.split.source  # split vertices -> anny vertices; faces keep anny's order
    faces = walker.human.split.faces[s.body_face[skin] - 1]
    u, v = s.body_bary[skin, 0:1], s.body_bary[skin, 1:2]
    rebuilt = (1 - u - v) * body[faces[:, 0]] + u * body[faces[:, 1]] + v * body[faces[:, 2]]
    assert np.abs(rebuilt - s.position[skin]).max() < 2e-4
    assert np.array_equal(anny[faces], walker.human.body.faces[s.body_face[skin] - 1])
    parts = vertex_parts(walker.human.parts[0].weights, walker.human.skeleton.names)
    nearest = parts[cKDTree(body).query(s.position[skin])[1]] + 1
    assert (nearest == s.body_part[skin]).mean() > 0.9
    seen = {PART_NAMES[p - 1] for p in np.unique(s.body_part[skin])}
    assert "head" in seen and len(seen) >= 5, seen
    assert (np.sum(s.body_normal[skin] * s.normal[skin], -1) > 0.95).mean() > 0.9
    shirt = (s.layer == 2) & (s.body_face > 0)
    assert shirt.sum() > 100 and 0.002 < np.median(s.cloth_thickness[shirt]) < 0.15  # a loose shirt: ~6 cm
    assert (s.body_part[s.instance == 0] == 0).all() and (s.cloth_thickness[s.layer == 1] == 0).all()


def test_body_normals_are_smooth_across_the_uv_seams(sm, walker):
    """body_normal against the welded mesh's normals (copies of a vertex along uv seams merged by
    position here, area-weighted face normals summed by hand): 99 % of body pixels within 1 deg
    (was 4.9 deg here, up to 19 deg next to seams), and on skin within 1 deg of the rendered normals."""
    s, rot, root = _labelled_view(sm, walker, (1.0, 1.3, 2.2), 50, (96, 128))
    cam = s.camera
    body = walker.human.pose(rot, root)[0].vertices
    faces = walker.human.parts[0].faces.astype(np.int64)
    _, group = np.unique(np.round(walker.human.parts[0].rest, 7), axis=0, return_inverse=True)
    cross = np.cross(body[faces[:, 1]] - body[faces[:, 0]], body[faces[:, 2]] - body[faces[:, 0]])
    summed = np.zeros((group.max() + 1, 3))
    for k in range(3):
        np.add.at(summed, group.ravel()[faces[:, k]], cross)
    n = summed[group.ravel()] / np.linalg.norm(summed[group.ravel()], axis=1, keepdims=True)  # unit, then interpolated
    px = s.body_face > 0
    f, u, v = faces[s.body_face[px] - 1], s.body_bary[px, 0:1], s.body_bary[px, 1:2]
    welded = ((1 - u - v) * n[f[:, 0]] + u * n[f[:, 1]] + v * n[f[:, 2]]) @ cam.R.T
    welded /= np.linalg.norm(welded, axis=1, keepdims=True)

    def angle(a, b):
        return np.degrees(np.arccos(np.clip(np.abs(np.sum(a * b, -1)), 0, 1)))
    assert px.sum() > 1000 and np.percentile(angle(s.body_normal[px], welded), 99) < 1.0
    skin = px & (s.layer == 1)
    assert skin.sum() > 300 and np.percentile(angle(s.body_normal[skin], s.normal[skin]), 99) < 1.0


def test_bad_inputs_get_clear_answers(sm, walker, tmp_path):
    """A camera looking away (keypoints behind it), samples without subjects: answers, not crashes."""
    from synmitsuba.annotate import Annotator, layer_masks
    scene = _scene(sm, walker)
    away = sm.Camera.look_at(eye=(0.0, 1.0, 4.0), target=(0, 1.0, 8.0), width=32, height=24)
    s = sm.render(scene, away, spp=1)
    rec = Annotator([walker]).annotate(s, scene, 3)[0]
    assert (rec["visibility"] == 0).all() and not rec["valid"] and rec["bbox_keypoints"] is None
    assert rec["visible_fraction"] == 0.0 and not rec["amodal_mask"].any() and rec["layer_pixels"] == {}
    with pytest.raises(sm.ConfigError, match=r"subject0_body at another pose.*pose_in\(scene, frame\)"):
        Annotator([walker]).annotate(s, scene, 4)  # labels are cast in the scene: it must hold frame 4
    with pytest.raises(sm.ConfigError, match="subject0_body missing"):
        Annotator([walker]).annotate(s, sm.Scene(), 3)
    bare = sm.render(scene, sm.Camera.look_at(eye=(0.0, 1.0, 4.0), target=(0, 0.9, 0), width=32, height=24), spp=1)
    sm.write_sample(bare, tmp_path / "d" / "bare")  # rendered without annotation: no subjects
    assert sm.read_sample(tmp_path / "d" / "bare").subjects == []
    assert sm.export_coco(str(tmp_path / "d"), str(tmp_path / "c.json")) == {"images": 1, "annotations": 0}
    assert sm.sample_panel(bare).shape[2] == 3
    assert set(layer_masks(bare, 100)) >= {"body", "top"}


def test_every_label_survives_the_files(sm, tmp_path):
    """A composed sequence's sample written and read back: every pass (flow, body layers,
    amodal) and every record field identical."""
    cfg = {"environments": ["plaza"], "subjects": {"count": 1, "seconds": 0.3, "config": {"texture_size": 64}},
           "cameras": {"count": 1, "width": 40, "height": 32, "azimuths": 6, "shells": 1, "pitches": 1, "points": 16,
                       "score_frames": 1}}
    spec = sm.compose_scene(cfg, np.random.default_rng(1))
    _, _, sample = next(sm.render_sequence(spec, frames=[3], spp=1, flow=1))  # flow to clip frames 2 and 4
    sm.write_sample(sample, tmp_path / "x")
    back = sm.read_sample(tmp_path / "x")
    for name in ("flow_fwd", "flow_bwd", "flow_fwd_flag", "body_part", "body_face", "body_bary", "body_depth",
                 "body_normal", "cloth_thickness"):
        assert np.array_equal(back.passes[name], sample.passes[name]), name
    a, b = sample.subjects[0], back.subjects[0]
    for k in a:
        if isinstance(a[k], dict):
            assert all(np.array_equal(np.asarray(a[k][j]), np.asarray(b[k][j])) for j in a[k] if j != "phenotypes"), k
        else:
            assert np.array_equal(np.asarray(a[k], dtype=object if a[k] is None else None),
                                  np.asarray(b[k], dtype=object if b[k] is None else None)), k


def test_a_cast_from_arrays_at_any_address_runs_one_kernel(sm):
    """``cast`` answers by the distances worked out by hand (rays down -z from z = 3 meet a sheet
    at z = 0 inside it, nothing outside), and ten casts with the heap stirred between them (the
    float32 copies of the rays land at other addresses) run the kernel compiled for the first:
    drjit reads numpy's memory in place and compiled a variant for each alignment of each of the
    seven inputs (about 20 kernels compiled again in every process that casts, and a new one
    whenever the heap moved an array)."""
    import drjit as dr

    from synmitsuba.engine.raycast import cast
    scene = sm.Scene()
    scene.add_mesh("sheet", np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]), np.array([[0, 1, 2], [0, 2, 3]]),
                   instance=4)
    n = 36
    x = np.linspace(-1.5, 1.5, n)  # none on the sheet's edges
    o, d, maxt = np.column_stack([x, np.zeros(n), np.full(n, 3.0)]), np.tile([0.0, 0.0, -1.0], (n, 1)), np.full(n, 10.0)
    cast(scene, o, d, maxt)  # the scene loaded first: its own kernels are not the cast's
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    kernels, stir = [], []
    try:
        for k in range(10):
            stir += [np.empty(1 + 3 * k, np.float32)]  # kept: the next casts' arrays go elsewhere
            dr.kernel_history()  # reading clears it
            ids, t = cast(scene, o, d, maxt)
            kernels.append({k["hash"] for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT})
            inside = np.abs(x) < 1
            assert (ids[inside] == 4).all() and np.allclose(t[inside], 3.0, atol=1e-6)
            assert (ids[~inside] == 0).all() and np.isinf(t[~inside]).all()
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert all(k == kernels[0] for k in kernels), kernels


def test_rays_pass_through_everything_but_the_shapes_asked_for(sm):
    """``hits_through`` against distances worked out by hand: rays down -z from z = 5 pass a
    sheet at z = 0 and a curtain of 400 strands (one ray meets every one of them) to the target
    sheet at z = -2 (t = 7 exactly); a ``maxt`` short of it reads a miss; and rays in new
    numbers and at new addresses run the one loop kernel compiled for the first call."""
    import drjit as dr

    from synmitsuba.engine.raycast import hits_through
    quad = np.array([[0, 1, 2], [0, 2, 3]])
    scene = sm.Scene()
    for name, z, inst in (("front", 0.0, 1), ("target", -2.0, 3)):
        scene.add_mesh(name, np.array([[-1, -1, z], [1, -1, z], [1, 1, z], [-1, 1, z]]), quad, instance=inst)
    zs = np.linspace(-0.2, -1.8, 400)  # strands along x at y = 0, one every 4 mm of depth
    strands = np.stack([np.stack([np.full(400, -1.0), np.zeros(400), zs], 1),
                        np.stack([np.full(400, 1.0), np.zeros(400), zs], 1)], 1)
    scene.add_curves("curtain", strands, 0.001, instance=2)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    kernels = []
    try:
        for n in (5, 17, 40, 41):
            xy = np.column_stack([np.linspace(-0.5, 0.5, n), np.zeros(n)])  # y = 0: through every strand
            o, d = np.column_stack([xy, np.full(n, 5.0)]), np.tile([0.0, 0.0, -1.0], (n, 1))
            dr.kernel_history()  # reading clears it
            hits = hits_through(scene, o, d, ["target"])
            kernels.append({k["hash"] for k in dr.kernel_history()
                            if k.get("type") == dr.KernelType.JIT and k["operation_count"] >= 50})
            assert (hits["instance"] == 3).all() and np.allclose(hits["t"], 7.0, atol=1e-5)
            assert [hits["names"][s] for s in set(hits["shape"])] == ["target"]
            assert (hits["u"] >= 0).all() and (hits["u"] + hits["v"] <= 1).all()
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert len(kernels[0]) == 1 and all(k == kernels[0] for k in kernels), kernels
    short = hits_through(scene, o, d, ["target"], maxt=6.9)
    assert (short["instance"] == 0).all() and np.isinf(short["t"]).all() and (short["shape"] == -1).all()
    front = hits_through(scene, o, d, ["front", "target"])
    assert (front["instance"] == 1).all() and np.allclose(front["t"], 5.0, atol=1e-5)


def test_hand_points_and_expression_in_records(sm, walker, tmp_path):
    """Both hands' points are the posed hand keypoints, projected by the pinhole formula; a
    card in front of the left hand hides its points behind an object and none of the right
    hand's; the record's expression is the clip's face weights at the frame, through the files."""
    from dataclasses import replace

    from synmitsuba.annotate import Annotator
    from synmitsuba.motion.faces import fixed_face, with_face
    from synmitsuba.motion.hands import HandKey, HandTrack, with_hands
    hands = HandTrack([HandKey(0.0, "fist", 1)], [HandKey(0.0, "open", 2)])
    subject = replace(walker, motion=with_face(with_hands(walker.motion, hands), fixed_face("smile", 3)))
    rot, root = subject.motion.frame(3)
    pts = subject.human.hand_keypoints(rot, root)
    centre = pts.reshape(-1, 3).mean(0)
    eye = centre + [0.0, 0.3, 3.0]
    cam = sm.Camera.look_at(eye=tuple(eye), target=tuple(centre), fov_y_deg=40, width=96, height=96)
    scene = sm.Scene()
    scene.set_environment(sm.Constant(1.0))
    subject.pose_in(scene, 3)
    left = pts[0].mean(0)
    near = left + 0.25 * (eye - left) / np.linalg.norm(eye - left)  # a card 25 cm in front of the left hand
    card = near + np.array([[-0.08, -0.08, 0], [0.08, -0.08, 0], [0.08, 0.08, 0], [-0.08, 0.08, 0]])
    scene.add_mesh("card", card, np.array([[0, 1, 2], [0, 2, 3]]), instance=7)
    sample = sm.render(scene, cam, spp=1)
    rec = Annotator([subject]).annotate(sample, scene, 3)[0]
    assert np.allclose(rec["hands3d_world"], pts)
    K, X = cam.K, rec["hands3d_cam"]
    assert np.allclose(rec["hands2d"][..., 0], K[0, 0] * X[..., 0] / X[..., 2] + K[0, 2])
    assert np.allclose(rec["hands2d"][..., 1], K[1, 1] * X[..., 1] / X[..., 2] + K[1, 2])
    vis = rec["hands_visibility"]
    assert (vis[0] == 4).sum() >= 18 and not (vis[1] == 4).any() and (vis[1] == 1).sum() >= 8
    assert np.array_equal(rec["expression"], subject.motion.face[3]) and rec["expression"].max() > 0.3
    sm.write_sample(sample, tmp_path / "s")
    back = sm.read_sample(tmp_path / "s").subjects[0]
    assert np.array_equal(back["expression"], rec["expression"]) and np.array_equal(back["hands2d"], rec["hands2d"])
    side = json.loads((tmp_path / "s.json").read_text())
    assert side["expression_names"][24] == "jawOpen" and side["hand_keypoint_names"][1][8] == "right_forefinger4"
