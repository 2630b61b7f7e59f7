"""HumanData export against mmhuman3d's documented layout (docs/human_data.md and the key table of
its ``HumanData`` class). mmhuman3d itself does not install on this Python (it pins mmcv 1.x and
pickle5), so the file is loaded here the way ``HumanData.load`` loads it and checked key by key
against a table written from those docs; the values against the samples themselves."""
import shutil
import subprocess
import sys

import numpy as np
import pytest

# docs/human_data.md: key -> (type after HumanData.load, shape with -1 = any, sliced along rows)
LAYOUT = {
    "image_path": (list, None, True), "bbox_xywh": (np.ndarray, (-1, 5), True), "config": (str, None, False),
    "keypoints2d": (np.ndarray, (-1, 190, 3), True), "keypoints3d": (np.ndarray, (-1, 190, 4), True),
    "keypoints2d_mask": (np.ndarray, (190,), False), "keypoints3d_mask": (np.ndarray, (190,), False),
    "keypoints2d_convention": (str, None, False), "keypoints3d_convention": (str, None, False),
    "smplx": (dict, None, True), "smpl": (dict, None, True), "meta": (dict, None, False), "misc": (dict, None, False),
}
SMPLX = {"body_pose": (21, 3), "global_orient": (3,), "betas": (10,), "transl": (3,), "left_hand_pose": (15, 3),
         "right_hand_pose": (15, 3), "expression": (10,), "leye_pose": (3,), "reye_pose": (3,), "jaw_pose": (3,)}
# human_data indices of COCO-17 (mmhuman3d maps COCO's hips to left_hip_extra / right_hip_extra),
# then COCO-WholeBody's feet (left big toe, small toe, heel, then right), from its HUMAN_DATA list
HUMAN_DATA_INDEX = [55, 57, 56, 59, 58, 16, 17, 18, 19, 20, 21, 145, 144, 4, 5, 7, 8, 60, 61, 62, 63, 64, 65]
# the face's 68 (300W order): right_contour_1 .. left_contour_1 are 127-143, right_eyebrow_1 .. lip_bottom
# (brows, nose bridge and base, eyes, outer and inner lips, in 300W's order) 76-126
FACE_INDEX = list(range(127, 144)) + list(range(76, 127))
# each hand's points after the wrist (thumb CMC MCP IP tip, index, middle, ring, pinky MCP PIP DIP tip):
# left_thumb_1 = 37, left_index_1 = 25, left_middle_1 = 28, left_ring_1 = 34, left_pinky_1 = 31, tips 66-70
LEFT_HAND_INDEX = [37, 38, 39, 66, 25, 26, 27, 67, 28, 29, 30, 68, 34, 35, 36, 69, 31, 32, 33, 70]
RIGHT_HAND_INDEX = [52, 53, 54, 71, 40, 41, 42, 72, 43, 44, 45, 73, 49, 50, 51, 74, 46, 47, 48, 75]


def load_like_human_data(path):
    """What ``HumanData.load`` does: 0-d arrays back to their values, supported keys to their
    type (image_path to a list), the three ``__attributes__`` taken out."""
    out, attrs = {}, {}
    with np.load(path, allow_pickle=True) as npz:
        for key, value in dict(npz).items():
            if value.shape == ():
                value = value.item()
            elif key in LAYOUT and type(value) is not LAYOUT[key][0]:
                value = LAYOUT[key][0](value)
            (attrs if key.startswith("__") else out)[key] = value
    return out, attrs


def _fake_fit(rng, ok=True):
    """A fit record as ``fit-smplx`` writes it (values random: the export only moves them)."""
    p = {k: rng.normal(size=s).tolist() for k, s in SMPLX.items()}
    return {"model": "smplx", "gender": "female", **p, "fit": {"ok": ok, "surface_mean_mm": 1.0}}


@pytest.fixture(scope="module")
def fitted(tiny, tmp_path_factory):
    """The tiny dataset under ``root/datasets/tiny`` with SMPL-X fits written into sequence 0's
    labels (frame 2's flagged as failed); sequence 1 has none."""
    root = tmp_path_factory.mktemp("hd")
    data = root / "datasets" / "tiny"
    shutil.copytree(tiny, data)
    from synmitsuba.io.exr import update_subjects
    rng = np.random.default_rng(0)
    for stem in ("f0000_cam0", "f0002_cam0"):
        def add_fit(records, ok=stem == "f0000_cam0"):
            for sub in records:
                sub["smplx_cam"], sub["smplx_world"] = _fake_fit(rng, ok), _fake_fit(rng)
        update_subjects(str(data / "seq_000000" / stem), add_fit)
    return root, data


def test_humandata_layout_key_by_key(fitted, sm):
    root, data = fitted
    out = root / "preprocessed_datasets" / "tiny.npz"
    assert sm.export_humandata(str(data), str(out)) == {"subjects": 4}
    hd, attrs = load_like_human_data(out)
    n = attrs["__data_len__"]
    assert n == 4 and attrs["__key_strict__"] is False and attrs["__keypoints_compressed__"] is False
    for key, (kind, shape, rows) in LAYOUT.items():
        if key == "smpl":
            assert key not in hd  # no SMPL fit: no key (mmhuman3d then sets has_smpl = 0)
            continue
        value = hd[key]
        assert type(value) is kind, key
        if shape is not None:
            assert value.ndim == len(shape) and all(s in (-1, v) for s, v in zip(shape, value.shape)), (key, value.shape)
        if rows and kind is not dict:
            assert len(value) == n, key
    assert hd["config"] == "synmitsuba" and hd["keypoints2d_convention"] == hd["keypoints3d_convention"] == "human_data"
    for name, shape in SMPLX.items():  # each sub-array sliced along rows, as HumanData slices dict values
        assert hd["smplx"][name].shape == (n, *shape), name
    for key in ("gender", "focal_length", "principal_point", "height", "width"):
        assert len(hd["meta"][key]) == n, key
    assert hd["misc"]["flat_hand_mean"] is True and hd["misc"]["kps3d_root_aligned"] is False
    assert list(hd["has_smplx"]) == [1, 0, 0, 0]  # sequence 0 frame 0 fitted, frame 2 flagged, sequence 1 none
    mask = np.zeros(190, np.uint8)
    mask[HUMAN_DATA_INDEX + FACE_INDEX + LEFT_HAND_INDEX + RIGHT_HAND_INDEX] = 1
    assert np.array_equal(hd["keypoints2d_mask"], mask) and np.array_equal(hd["keypoints3d_mask"], mask)
    assert not hd["keypoints2d"][:, mask == 0].any() and not hd["keypoints3d"][:, mask == 0].any()


def test_humandata_values_match_the_samples(fitted, sm):
    root, data = fitted
    out = root / "elsewhere.npz"
    sm.export_humandata(str(data), str(out), data_root=str(root / "datasets"))
    hd, _ = load_like_human_data(out)
    fits = 0
    for i, rel in enumerate(hd["image_path"]):
        assert rel.startswith("tiny/seq_") and (root / "datasets" / rel).is_file()  # relative to the data root
        sample = sm.read_sample(str(root / "datasets" / rel)[:-4])
        rec = next(r for r in sample.subjects if r["instance"] == hd["meta"]["instance"][i])
        kp2, kp3 = hd["keypoints2d"][i, HUMAN_DATA_INDEX], hd["keypoints3d"][i, HUMAN_DATA_INDEX]
        assert np.allclose(kp2[:, :2], rec["keypoints2d"], atol=1e-3)
        assert np.array_equal(kp2[:, 2], (rec["visibility"] > 0).astype(np.float32))
        assert np.allclose(kp3[:, :3], rec["keypoints3d_cam"], atol=1e-5) and (kp3[:, 3] == 1).all()
        parts = [(FACE_INDEX, rec["face2d"], rec["face3d_cam"], rec["face_visibility"])]
        parts += [(index, rec["hands2d"][h], rec["hands3d_cam"][h][1:], rec["hands_visibility"][h])
                  for h, index in enumerate((LEFT_HAND_INDEX, RIGHT_HAND_INDEX))]
        for index, p2, p3, classes in parts:
            p2, classes = np.asarray(p2)[-len(index):], np.asarray(classes)[-len(index):]
            assert np.allclose(hd["keypoints2d"][i, index, :2], p2, atol=1e-3)
            assert np.array_equal(hd["keypoints2d"][i, index, 2], (classes > 0).astype(np.float32))
            assert np.allclose(hd["keypoints3d"][i, index, :3], p3, atol=1e-5) and (hd["keypoints3d"][i, index, 3] == 1).all()
        x0, y0, x1, y1 = rec["bbox_visible"]
        assert np.allclose(hd["bbox_xywh"][i], [x0, y0, x1 - x0, y1 - y0, 1], atol=1e-3)
        K = sample.camera.K
        assert np.allclose(hd["meta"]["focal_length"][i], [K[0, 0], K[1, 1]], rtol=1e-6)
        assert np.allclose(hd["meta"]["principal_point"][i], [K[0, 2], K[1, 2]], rtol=1e-6)
        if "smplx_cam" in rec:
            fits += 1
            for name in SMPLX:
                assert np.allclose(hd["smplx"][name][i], rec["smplx_cam"][name], atol=1e-6), name
                assert np.allclose(hd["smplx_world"][name][i], rec["smplx_world"][name], atol=1e-6), name
            assert hd["meta"]["gender"][i] == "f"
        else:
            assert not any(hd["smplx"][name][i].any() for name in SMPLX) and hd["meta"]["gender"][i] == ""
    assert fits == 2


def test_humandata_refuses_bad_paths(fitted, tmp_path, sm):
    from synmitsuba.errors import ConfigError
    root, data = fitted
    with pytest.raises(ConfigError, match="data_root"):
        sm.export_humandata(str(data), str(tmp_path / "x.npz"), data_root=str(tmp_path))
    with pytest.raises(ConfigError, match="out_npz"):
        sm.export_humandata(str(data), str(tmp_path / "x.json"))
    assert not list(tmp_path.iterdir())


def test_export_command_writes_coco_and_humandata(fitted, tmp_path):
    _, data = fitted
    for fmt, name in (("coco", "c.json"), ("humandata", "h.npz")):
        run = subprocess.run([sys.executable, "-m", "synmitsuba", "export", fmt, str(data), str(tmp_path / name)],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        assert (tmp_path / name).is_file() and "4" in run.stdout
    run = subprocess.run([sys.executable, "-m", "synmitsuba", "export", "humandata", str(tmp_path / "none"),
                          str(tmp_path / "n.npz")], capture_output=True, text=True)
    assert run.returncode == 2 and "DATASET" in run.stderr and "Traceback" not in run.stderr
