"""HumanData export: every valid subject of every sample in a folder, as one ``.npz`` in the
layout mmhuman3d's ``HumanData`` loads (its docs/human_data.md), so HMR training code written
for mmhuman3d reads our data unchanged.

- ``image_path``: relative to a data root (the dataset folder unless told), as mmhuman3d joins
  it onto ``<data_prefix>/datasets/<dataset_name>/``.
- ``keypoints2d`` (N, 190, 3) / ``keypoints3d`` (N, 190, 4) in mmhuman3d's ``human_data``
  convention: our 23 keypoints in their named slots (``HUMAN_DATA_SLOTS``), the face's 68
  (``FACE_SLOTS``: human_data's brows, nose, eyes, lips and contour) and each hand's 20 finger
  points (``LEFT_HAND_SLOTS`` / ``RIGHT_HAND_SLOTS``; the wrist is the body's); the rest zero
  and masked out by ``keypoints2d_mask`` / ``keypoints3d_mask`` (190,).
- ``smplx`` / ``smpl``: dicts of (N, ...) arrays in the camera frame, written when a fit exists;
  ``has_smplx`` / ``has_smpl`` (N,) say which rows have a fit that passed its error threshold.
- ``meta``: per-row values (gender, camera, instance, frame, visibility classes, crop centre
  and scale); ``misc``: what holds for the whole file (flat hand mean, box source, ...).
- Our own extras ride along as non-standard keys, which ``HumanData`` accepts (the file is
  written with ``__key_strict__ = False``): ``anny`` (anny's pose), ``smplx_world`` /
  ``smpl_world`` (the fits in the world frame) and ``cam_param`` (K, R, T, lens, dist per row).
"""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.annotate.conventions import whole_body_rows
from synmitsuba.body.anny_model import KEYPOINTS
from synmitsuba.errors import ConfigError
from synmitsuba.io.exr import read_sample
from synmitsuba.io.files import atomic_path
from synmitsuba.io.listing import dataset_samples

HUMAN_DATA_SIZE = 190  # points in mmhuman3d's human_data convention
# our keypoint -> (its name in human_data, its index there). COCO's hips are not SMPL's hip
# joints: mmhuman3d keeps them apart as the "_extra" hips.
HUMAN_DATA_SLOTS: dict[str, tuple[str, int]] = {
    "nose": ("nose", 55), "left_eye": ("left_eye", 57), "right_eye": ("right_eye", 56),
    "left_ear": ("left_ear", 59), "right_ear": ("right_ear", 58),
    "left_shoulder": ("left_shoulder", 16), "right_shoulder": ("right_shoulder", 17),
    "left_elbow": ("left_elbow", 18), "right_elbow": ("right_elbow", 19),
    "left_wrist": ("left_wrist", 20), "right_wrist": ("right_wrist", 21),
    "left_hip": ("left_hip_extra", 145), "right_hip": ("right_hip_extra", 144),
    "left_knee": ("left_knee", 4), "right_knee": ("right_knee", 5),
    "left_ankle": ("left_ankle", 7), "right_ankle": ("right_ankle", 8),
    "left_big_toe": ("left_bigtoe", 60), "left_small_toe": ("left_smalltoe", 61), "left_heel": ("left_heel", 62),
    "right_big_toe": ("right_bigtoe", 63), "right_small_toe": ("right_smalltoe", 64), "right_heel": ("right_heel", 65),
}
# COCO-WholeBody's face (300W order) -> human_data: the brows, nose, eyes and lips (points 17-67)
# lie in that order from its right_eyebrow_1 (76); the jaw line (0-16) from right_contour_1 (127)
FACE_SLOTS = [127 + k for k in range(17)] + [76 + k for k in range(51)]
# a hand's 21 points (COCO-WholeBody order: wrist, thumb CMC MCP IP tip, then index, middle, ring,
# pinky MCP PIP DIP tip) -> human_data's left hand; -1: the wrist, which the body's keypoint fills.
# Joints: *_1.._3 from left_index_1 (25): index, middle, pinky, ring, thumb; tips from left_thumb (66)
_FINGER_JOINTS = {"thumb": 37, "index": 25, "middle": 28, "ring": 34, "pinky": 31}
_FINGER_TIPS = {"thumb": 66, "index": 67, "middle": 68, "ring": 69, "pinky": 70}
LEFT_HAND_SLOTS = [-1] + [slot for f in ("thumb", "index", "middle", "ring", "pinky")
                          for slot in (_FINGER_JOINTS[f], _FINGER_JOINTS[f] + 1, _FINGER_JOINTS[f] + 2, _FINGER_TIPS[f])]
RIGHT_HAND_SLOTS = [-1] + [s + (15 if s < 55 else 5) for s in LEFT_HAND_SLOTS[1:]]  # right_index_1 = 40, right_thumb = 71
# every row of ``annotate.conventions.whole_body_rows`` (ours, face, left hand, right hand)
_SLOTS = np.array([HUMAN_DATA_SLOTS[k][1] for k in KEYPOINTS] + FACE_SLOTS + LEFT_HAND_SLOTS + RIGHT_HAND_SLOTS)
BODY_MODEL_KEYS = ("betas", "global_orient", "body_pose", "transl", "left_hand_pose", "right_hand_pose", "jaw_pose",
                   "leye_pose", "reye_pose", "expression")
GENDER_CODES = {"male": "m", "female": "f", "neutral": "n"}  # as 3DPW writes them; mmhuman3d tests == "m"


def to_human_data(points: np.ndarray, confidence: np.ndarray) -> np.ndarray:
    """(N, 133, D) whole-body points (``whole_body_rows``; or our 23 alone, (N, 23, D)) and
    (N, R) confidence -> (N, 190, D + 1) in human_data's slots."""
    n, r, d = points.shape
    slots = _SLOTS[:r]
    keep = slots >= 0
    out = np.zeros((n, HUMAN_DATA_SIZE, d + 1), np.float32)
    out[:, slots[keep], :d] = points[:, keep]
    out[:, slots[keep], d] = confidence[:, keep]
    return out


def human_data_mask(rows: int = 133) -> np.ndarray:
    """(190,) 1 in the slots the first ``rows`` whole-body rows fill."""
    mask = np.zeros(HUMAN_DATA_SIZE, np.uint8)
    slots = _SLOTS[:rows]
    mask[slots[slots >= 0]] = 1
    return mask


def _rows(dataset_dir: str, data_root: str) -> tuple[list, list]:
    """(sample, subject) per valid subject with keypoints, and each one's image path."""
    rows, paths = [], []
    for stem in dataset_samples(dataset_dir, "dataset_dir"):
        image = os.path.abspath(f"{stem}.png")
        rel = os.path.relpath(image, data_root)
        if rel.split(os.sep)[0] == os.pardir:
            raise ConfigError("data_root", data_root, f"{image} lies outside it; give a folder holding the dataset")
        sample = read_sample(stem)
        for rec in sample.subjects:
            if rec["valid"] and rec["bbox_keypoints"] is not None:
                rows.append((sample, rec))
                paths.append(rel)
    return rows, paths


def _box(rec) -> list:
    box = rec["bbox_visible"] or rec["bbox_keypoints"]
    return [box[0], box[1], box[2] - box[0], box[3] - box[1], 1.0]


def _body_model(rows: list, kind: str, frame: str) -> dict | None:
    """``{param: (N, ...)}`` of the ``<kind>_<frame>`` fits (zeros where a row has none), or None."""
    key = f"{kind}_{frame}"
    first = next((rec[key] for _, rec in rows if key in rec), None)
    if first is None:
        return None
    out = {}
    for name in BODY_MODEL_KEYS:
        if name in first:
            blank = np.zeros_like(np.asarray(first[name], np.float32))
            out[name] = np.stack([np.asarray(rec[key][name], np.float32) if key in rec else blank for _, rec in rows])
    return out


def _has_fit(rows: list, kind: str) -> np.ndarray:
    return np.array([int(bool(rec.get(f"{kind}_cam", {}).get("fit", {}).get("ok", False))) for _, rec in rows], np.uint8)


def _gender(rec) -> str:
    fit = rec.get("smpl_cam") or rec.get("smplx_cam") or {}
    return GENDER_CODES.get(fit.get("gender", ""), "")


def _meta(rows: list, fitted: list) -> dict:
    """Per-row values; ``gender`` only with fits (mmhuman3d reads none for a neutral body)."""
    Ks = np.array([s.camera.K for s, _ in rows], np.float32)
    gender = {"gender": [_gender(rec) for _, rec in rows]} if fitted else {}
    return {**gender, "focal_length": Ks[:, [0, 1], [0, 1]], "principal_point": Ks[:, [0, 1], [2, 2]],
            "width": np.array([s.camera.width for s, _ in rows]), "height": np.array([s.camera.height for s, _ in rows]),
            "instance": np.array([rec["instance"] for _, rec in rows]),
            "frame": np.array([s.meta.get("frame", 0) for s, _ in rows]),
            "visibility": np.array([rec["visibility"] for _, rec in rows], np.uint8),
            "center": np.array([rec["center"] for _, rec in rows], np.float32),
            "scale": np.array([rec["scale"] for _, rec in rows], np.float32)}


def _anny(rows: list) -> dict:
    out = {}
    for frame_name, key in (("", "body_params_cam"), ("_world", "body_params_world")):
        out[f"rotations{frame_name}"] = np.array([rec[key]["rotations"] for _, rec in rows], np.float32)
        out[f"root_translation{frame_name}"] = np.array([rec[key]["root_translation"] for _, rec in rows], np.float32)
    out["root_world"] = np.array([rec["root_world"] for _, rec in rows], np.float32)
    return out


def _misc(rows: list, fitted: list) -> dict:
    """What holds for every row. Hand poses are absolute (the smplx package's
    ``flat_hand_mean=True``); boxes are the visible mask's (the keypoints' where it is empty)."""
    from synmitsuba import __version__
    sizes = {(s.camera.width, s.camera.height) for s, _ in rows}
    misc = {"kps3d_root_aligned": False, "flat_hand_mean": True, "bbox_source": "provide_by_dataset",
            "cam_param_type": "perspective", **{f"{kind}_source": "synmitsuba_fit" for kind in fitted},
            "keypoint_coords": "continuous", "keypoint_names": list(KEYPOINTS), "synmitsuba_version": __version__}
    if len(sizes) == 1:
        misc["image_shape"] = np.array([sizes.pop()[::-1]])  # (1, 2): height, width
    return misc


def export_humandata(dataset_dir: str, out_npz: str, data_root: str | None = None) -> dict:
    """Write the HumanData file of every valid subject under ``dataset_dir`` (module docstring);
    ``image_path`` is relative to ``data_root`` (default: ``dataset_dir``). Returns its counts."""
    if not os.fspath(out_npz).endswith(".npz"):
        raise ConfigError("out_npz", out_npz, "HumanData files end in .npz; name one so")
    data_root = os.path.abspath(os.fspath(data_root if data_root is not None else dataset_dir))
    rows, paths = _rows(os.fspath(dataset_dir), data_root)
    if not rows:
        raise ConfigError("dataset_dir", dataset_dir, "no valid subject in any sample; nothing to export")
    whole = [whole_body_rows(rec) for _, rec in rows]
    kps2d = np.array([p2 for p2, _, _ in whole], np.float32)
    kps3d = np.array([p3 for _, p3, _ in whole], np.float32)
    inside = np.array([c > 0 for _, _, c in whole], np.float32)
    labelled = np.array([[len(rec.get("face2d", [])) > 0] * 68 + [len(rec.get("hands2d", [])) > 0] * 42
                         for _, rec in rows], np.float32).reshape(len(rows), -1)
    in_3d = np.concatenate([np.ones((len(rows), 23), np.float32), labelled], 1)  # 3D: every labelled point
    doc: dict = {"__key_strict__": False, "__data_len__": len(rows), "__keypoints_compressed__": False,
                 "config": "synmitsuba", "image_path": np.array(paths),
                 "bbox_xywh": np.array([_box(rec) for _, rec in rows], np.float32),
                 "keypoints2d": to_human_data(kps2d, inside), "keypoints3d": to_human_data(kps3d, in_3d),
                 "keypoints2d_mask": human_data_mask(), "keypoints3d_mask": human_data_mask(),
                 "keypoints2d_convention": "human_data", "keypoints3d_convention": "human_data",
                 "anny": _anny(rows),
                 "cam_param": {"K": np.array([s.camera.K for s, _ in rows], np.float32),
                               "R": np.array([s.camera.R for s, _ in rows], np.float32),
                               "T": np.array([s.camera.t for s, _ in rows], np.float32),
                               "lens": [s.camera.lens for s, _ in rows],
                               "dist": np.array([np.pad(s.camera.dist, (0, 5 - len(s.camera.dist))) for s, _ in rows],
                                                np.float32)}}
    fitted = []
    for kind in ("smplx", "smpl"):
        cam, world = _body_model(rows, kind, "cam"), _body_model(rows, kind, "world")
        if cam is not None:
            doc.update({kind: cam, f"{kind}_world": world, f"has_{kind}": _has_fit(rows, kind)})
            fitted.append(kind)
    doc.update(meta=_meta(rows, fitted), misc=_misc(rows, fitted))
    with atomic_path(out_npz) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **doc)  # dicts become 0-d object arrays, as HumanData.dump writes them
    return {"subjects": len(rows)}
