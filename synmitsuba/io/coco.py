"""COCO export: person keypoints and instance segmentation of every written sample in a folder.

``export_coco(dataset_dir, out_json)`` writes one image per sample (its PNG, relative to the
JSON's folder) and one annotation per valid subject: the 17 COCO keypoints as (x, y, v) with
v = 2 visible, 1 in the image but occluded (by itself, a subject or an object), 0 outside
(x = y = 0); the 6 foot points in ``foot_kpts`` (COCO-WholeBody order); the visible mask as
uncompressed RLE (column-major runs, starting with background); its area and tight box
[x, y, w, h]; the amodal box in ``bbox_amodal``. ``pycocotools`` reads and evaluates the file.
COCO-WholeBody's fields come with it: ``lefthand_kpts`` / ``righthand_kpts`` (21 x 3, its order),
``face_kpts`` (68 x 3, 300W's order), ``lefthand_box`` / ``righthand_box`` / ``face_box`` (the
part's points in the image, padded by ``PART_PAD`` of the larger side, [x, y, w, h]; zeros when
none) and ``*_valid`` (some point of that part visible). A sample written before a part's labels
existed gets it unlabelled (v = 0, not valid), so WholeBody loaders still read the file.

Keypoint coordinates: ``"continuous"`` (default, as in every sample: pixel (0, 0) spans
[0, 1) x [0, 1), so a pixel's centre is at +0.5) or ``"pixel_index"`` (0.5 less: the centre of
pixel (i, j) is (i, j), the convention detectron2 and mmpose assume when they add 0.5 to COCO
keypoints). Boxes and masks are pixel edges either way; the file's ``info`` names the choice.
"""
from __future__ import annotations

import json
import os

import numpy as np

from synmitsuba.body.anny_model import KEYPOINTS
from synmitsuba.body.face_points import FACE_POINTS
from synmitsuba.annotate.keypoints import coco_flags
from synmitsuba.io.listing import dataset_samples
from synmitsuba.io.exr import read_sample
from synmitsuba.errors import ConfigError
from synmitsuba.io.files import atomic_path

COCO_KEYPOINTS = list(KEYPOINTS[:17])
FOOT_KEYPOINTS = list(KEYPOINTS[17:])  # COCO-WholeBody's foot order: left big toe, small toe, heel, then right
COCO_SKELETON = [[16, 14], [14, 12], [17, 15], [15, 13], [12, 13], [6, 12], [7, 13], [6, 7], [6, 8], [7, 9], [8, 10],
                 [9, 11], [2, 3], [1, 2], [1, 3], [2, 4], [3, 5], [4, 6], [5, 7]]


def rle(mask: np.ndarray) -> dict:
    """COCO uncompressed RLE of a boolean (H, W) mask."""
    flat = np.asarray(mask, bool).ravel(order="F")
    change = np.flatnonzero(np.diff(flat.astype(np.int8))) + 1
    edges = np.concatenate([[0], change, [flat.size]])
    counts = np.diff(edges).tolist()
    if flat.size and flat[0]:
        counts = [0] + counts
    return {"size": [int(mask.shape[0]), int(mask.shape[1])], "counts": [int(c) for c in counts]}


KEYPOINT_COORDS = {"continuous": 0.0, "pixel_index": -0.5}  # added to keypoint x and y


def _keypoints(rec: dict, first: int, count: int, shift: float = 0.0) -> list:
    out = []
    flags = coco_flags(rec["visibility"][first:first + count])
    for (x, y), flag in zip(np.asarray(rec["keypoints2d"])[first:first + count], flags):
        out += [float(x) + shift, float(y) + shift, int(flag)] if flag else [0.0, 0.0, 0]
    return out


PART_PAD = 0.1  # a hand's or the face's box: its points' box grown by this share of its larger side on every side


def _part(name: str, pts: np.ndarray, classes: np.ndarray, shift: float, width: int, height: int) -> dict:
    """COCO-WholeBody's ``<name>_kpts``, ``<name>_box`` and ``<name>_valid`` from a part's points
    (K, 2) and visibility classes (K,)."""
    flags = coco_flags(classes)
    kpts: list = []
    for (x, y), flag in zip(pts, flags):
        kpts += [float(x) + shift, float(y) + shift, int(flag)] if flag else [0.0, 0.0, 0]
    inside = pts[classes > 0]
    box = [0.0, 0.0, 0.0, 0.0]
    if len(inside):
        lo, hi = inside.min(0), inside.max(0)
        pad = PART_PAD * float((hi - lo).max())
        lo, hi = np.maximum(lo - pad, 0), np.minimum(hi + pad, [width, height])
        box = [float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1])]
    return {f"{name}_kpts": kpts, f"{name}_box": box, f"{name}_valid": bool((classes == 1).any())}


def _unlabelled(name: str, count: int) -> dict:
    """A part a sample written before its labels lacks: v = 0 everywhere, not valid."""
    return {f"{name}_kpts": [0.0, 0.0, 0] * count, f"{name}_box": [0.0, 0.0, 0.0, 0.0], f"{name}_valid": False}


def _hand(rec: dict, side: int, shift: float, width: int, height: int) -> dict:
    """One hand's COCO-WholeBody fields from a record's ``hands2d`` / ``hands_visibility``."""
    name = ("lefthand", "righthand")[side]
    if len(rec.get("hands2d", [])) == 0:
        return _unlabelled(name, 21)
    return _part(name, np.asarray(rec["hands2d"])[side], np.asarray(rec["hands_visibility"])[side], shift, width, height)


def _face(rec: dict, shift: float, width: int, height: int) -> dict:
    """The face's COCO-WholeBody fields from a record's ``face2d`` / ``face_visibility``."""
    if len(rec.get("face2d", [])) == 0:
        return _unlabelled("face", FACE_POINTS)
    return _part("face", np.asarray(rec["face2d"]), np.asarray(rec["face_visibility"]), shift, width, height)


def _xywh(box: list | None) -> list | None:
    """A ``[x_min, y_min, x_max, y_max]`` box as COCO writes boxes, ``[x, y, w, h]``."""
    return None if box is None else [box[0], box[1], box[2] - box[0], box[3] - box[1]]


def _annotation(rec: dict, sample, image_id: int, ann_id: int, shift: float) -> dict | None:
    visible = sample.instance == rec["instance"]
    if not rec["valid"] or not visible.any():
        return None
    box = rec["bbox_visible"]
    kps = _keypoints(rec, 0, 17, shift)
    return {"id": ann_id, "image_id": image_id, "category_id": 1, "iscrowd": 0, "segmentation": rle(visible),
            "area": float(visible.sum()), "bbox": _xywh(box),
            "keypoints": kps, "num_keypoints": int(sum(1 for v in kps[2::3] if v > 0)),
            "foot_kpts": _keypoints(rec, 17, 6, shift), "bbox_amodal": _xywh(rec["bbox_amodal"]), "instance": rec["instance"],
            "visible_fraction": rec["visible_fraction"],
            **_face(rec, shift, sample.camera.width, sample.camera.height),
            **_hand(rec, 0, shift, sample.camera.width, sample.camera.height),
            **_hand(rec, 1, shift, sample.camera.width, sample.camera.height)}


def export_coco(dataset_dir: str, out_json: str, keypoint_coords: str = "continuous") -> dict:
    """Write the COCO file for every sample under ``dataset_dir``; returns its counts.
    ``keypoint_coords``: ``"continuous"`` or ``"pixel_index"`` (the module docstring)."""
    if keypoint_coords not in KEYPOINT_COORDS:
        raise ConfigError("keypoint_coords", keypoint_coords, f"give one of {', '.join(KEYPOINT_COORDS)}")
    shift = KEYPOINT_COORDS[keypoint_coords]
    base = os.path.dirname(os.path.abspath(out_json))
    images: list[dict] = []
    anns: list[dict] = []
    for image_id, stem in enumerate(dataset_samples(dataset_dir, "dataset_dir"), 1):
        sample = read_sample(stem)
        images.append({"id": image_id, "file_name": os.path.relpath(f"{stem}.png", base),
                       "width": sample.camera.width, "height": sample.camera.height})
        for rec in sample.subjects:
            ann = _annotation(rec, sample, image_id, len(anns) + 1, shift)
            if ann is not None:
                anns.append(ann)
    info = {"description": "synmitsuba export", "version": "1", "keypoint_coords": keypoint_coords}
    doc = {"info": info, "images": images, "annotations": anns,
           "categories": [{"id": 1, "name": "person", "supercategory": "person", "keypoints": COCO_KEYPOINTS,
                           "foot_keypoints": FOOT_KEYPOINTS, "skeleton": COCO_SKELETON}]}
    with atomic_path(out_json) as tmp, open(tmp, "w") as fh:
        json.dump(doc, fh)
    return {"images": len(images), "annotations": len(anns)}
