"""``SynDataset``: a PyTorch Dataset over a folder of written samples (a generated dataset or any
folder ``write_sample`` filled). Only complete samples are listed (the JSON sidecar is written
last).

- ``crop=None``: one item per sample: the passes asked for in ``modalities`` (default all:
  ``rgb`` (3, H, W), ``depth``, ``mask``, ``normal`` (3, H, W), ``instance``, ``layer``, ...),
  the camera ``K``, ``R``, ``t`` and, per subject padded to ``max_subjects`` (``subjects_valid``
  says which rows are real), ``keypoints2d`` (S, 23, 3: x, y, visibility class),
  ``keypoints3d_cam`` (S, 23, 3), ``body_rotations_cam`` (S, J, 3), ``body_root_cam`` (S, 3),
  ``instances`` (S,).
- ``image``: ``float`` (linear, HDR, as rendered), ``srgb8`` (uint8) or ``normalized`` (sRGB
  in [0, 1], minus ``mean``, over ``std``: ImageNet's by default) for ``rgb`` and crops;
  ``visibility``: the keypoints' third column as our ``classes`` (annotate.keypoints.VISIBILITY)
  or as ``coco`` flags (2 visible, 1 occluded, 0 outside: the COCO export's table).
- ``crop="person"``: one item per valid subject and sample, the top-down HMR crop: ``image``
  (3, size, size) cut around the keypoint box (centre, side = 200 * scale) and resized,
  ``keypoints2d`` (23, 3) in crop pixels with visibility, ``keypoints3d_cam``,
  ``body_rotations_cam``, ``body_root_cam``, ``mask`` (size, size) of the subject, the crop's
  ``K`` (the camera's, shifted and scaled), ``center``, ``scale``.
- ``keypoints``: the layout of ``keypoints2d`` / ``keypoints3d_cam``: ``ours`` (23), ``coco17``,
  ``coco_wholebody`` (133: ours, the face's 68 and both hands' 21; rows a sample
  written before those labels lacks are 0 with class 0), ``openpose25`` (neck and mid-hip the
  means of shoulders and hips), ``smpl24`` (the skeleton joints SMPL's 24 correspond to,
  projected; no occlusion class: 1 inside the image, 0 outside); ``keypoints_mask`` says which points are labelled
  (``annotate.conventions``).
- After ``synmitsuba fit-smplx`` (or a generation with ``smplx.enabled``), items also hold each
  fitted model's camera-frame parameters in the smplx package's names, ``smplx_betas``,
  ``smplx_global_orient``, ``smplx_body_pose``, ``smplx_transl``, hands, jaw, eyes,
  ``smplx_expression`` (and ``smpl_*``), with ``smplx_valid`` (per subject for whole images).
Items are dicts of tensors (plus ``stem``) that the default collate batches, with
``num_workers > 0`` and ``shuffle`` too: every item holds the same keys. A flow side a sample
lacks (a sequence's first or last frame) reads as zero flow with flag 4 (``NO_TARGET``). A
missing folder, or one with no complete sample, is an error.
"""
from __future__ import annotations

import json

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.io.listing import dataset_samples
from synmitsuba.io.exr import read_sample

CROPS = (None, "person")
IMAGE_FORMATS = ("float", "srgb8", "normalized")
VISIBILITY_CODES = ("classes", "coco")
IMAGENET_MEAN, IMAGENET_STD = (0.485, 0.456, 0.406), (0.229, 0.224, 0.225)


def _torch():
    import torch
    return torch


class _Base:
    def __init__(self, root: str, modalities=None, crop: str | None = None, size: int = 224,
                 max_subjects: int | None = None, image: str = "float", mean=IMAGENET_MEAN, std=IMAGENET_STD,
                 visibility: str = "classes", keypoints: str = "ours"):
        if crop not in CROPS:
            raise ConfigError("crop", crop, "use None (whole images) or 'person' (one crop per subject)")
        if image not in IMAGE_FORMATS:
            raise ConfigError("image", image, f"use one of {', '.join(IMAGE_FORMATS)}")
        if visibility not in VISIBILITY_CODES:
            raise ConfigError("visibility", visibility, f"use one of {', '.join(VISIBILITY_CODES)}")
        from synmitsuba.annotate.conventions import CONVENTIONS, JOINT_CONVENTIONS
        if keypoints not in (*CONVENTIONS, *JOINT_CONVENTIONS):
            raise ConfigError("keypoints", keypoints, f"use one of {', '.join((*CONVENTIONS, *JOINT_CONVENTIONS))}")
        self.image, self.visibility, self.keypoints = image, visibility, keypoints
        self.mean, self.std = np.asarray(mean, np.float32), np.asarray(std, np.float32)
        self.stems = dataset_samples(root, "root")
        self.modalities, self.crop, self.size = modalities, crop, int(size)
        self.index: list[tuple[str, int | None]] = []  # (stem, subject row) per item
        self.body_models: dict[str, dict] = {}  # kind -> {parameter: zeros of its shape}
        counts = []
        for stem in self.stems:
            with open(f"{stem}.json") as fh:
                subjects = json.load(fh).get("subjects", [])
            counts.append(len(subjects))
            for r in subjects:  # body-model fits anywhere in the dataset: every item carries their keys
                for kind in BODY_MODELS:
                    if f"{kind}_cam" in r and kind not in self.body_models:
                        self.body_models[kind] = {k: np.zeros_like(np.asarray(v, np.float32))
                                                  for k, v in r[f"{kind}_cam"].items() if k in BODY_MODEL_KEYS}
            if crop == "person":
                self.index += [(stem, k) for k, r in enumerate(subjects) if r["valid"] and r["bbox_keypoints"]]
        if crop is None:
            self.index = [(stem, None) for stem in self.stems]
            self.modalities = modalities or _default_modalities(self.stems[0])
        self.max_subjects = max_subjects if max_subjects is not None else max(counts, default=0)

    def __len__(self) -> int:
        return len(self.index)

    def __getitem__(self, i: int) -> dict:
        stem, k = self.index[i]
        s = read_sample(stem)
        return self._image(s, stem) if k is None else self._person(s, stem, s.subjects[k])

    def _image(self, s, stem) -> dict:
        torch = _torch()
        item = {}
        for name in self.modalities:
            arr = s.passes[name] if name in s.passes else _missing(name, s)
            if arr is None:
                raise ConfigError("modalities", name, f"this sample has no such pass; it has {', '.join(s.passes)}")
            arr = arr.astype(np.int64) if arr.dtype == np.uint8 else arr
            arr = self._format(arr) if name == "rgb" else arr
            t = torch.from_numpy(np.ascontiguousarray(arr))
            item[name] = t.permute(2, 0, 1) if t.ndim == 3 else t
        item.update(_subjects(s.subjects, self.max_subjects, self.visibility, self.keypoints, s.camera))
        if self.body_models and self.max_subjects:  # per subject row, padded like the keypoints
            rows = [self._fits(r) for r in s.subjects[:self.max_subjects]]
            rows += [self._fits(None)] * (self.max_subjects - len(rows))
            item.update({k: torch.stack([r[k] for r in rows]) for k in rows[0]})
        item.update(K=torch.from_numpy(s.camera.K), R=torch.from_numpy(s.camera.R), t=torch.from_numpy(s.camera.t),
                    stem=stem)
        return item

    def _person(self, s, stem, rec) -> dict:
        torch = _torch()
        side = 200.0 * rec["scale"]
        x0, y0 = rec["center"][0] - side / 2, rec["center"][1] - side / 2
        f = self.size / side
        A = np.array([[f, 0, -f * x0], [0, f, -f * y0], [0, 0, 1.0]])  # image pixels -> crop pixels
        image = _warp(s.rgb, A, self.size)
        mask = _warp((s.instance == rec["instance"]).astype(np.float32)[..., None], A, self.size)[..., 0] > 0.5
        kp2, kp3, vis, kmask = _keypoints(rec, self.keypoints, s.camera)
        kp = np.concatenate([(kp2 * f - [f * x0, f * y0]) * kmask[:, None], _codes(vis, self.visibility)[:, None]], 1)
        return {"image": torch.from_numpy(np.ascontiguousarray(self._format(image.astype(np.float32)).transpose(2, 0, 1))),
                "mask": torch.from_numpy(mask), "keypoints2d": torch.from_numpy(kp.astype(np.float32)),
                "keypoints3d_cam": torch.from_numpy(kp3.astype(np.float32)), "keypoints_mask": torch.from_numpy(kmask),
                "body_rotations_cam": torch.from_numpy(np.asarray(rec["body_params_cam"]["rotations"], np.float32)),
                "body_root_cam": torch.from_numpy(np.asarray(rec["body_params_cam"]["root_translation"], np.float32)),
                "K": torch.from_numpy(A @ s.camera.K), "center": torch.tensor(rec["center"]),
                "scale": torch.tensor(rec["scale"]), "instance": rec["instance"], "stem": stem,
                **self._fits(rec)}

    def _fits(self, rec) -> dict:
        """``<kind>_<parameter>`` (camera frame) of each body model fitted in the dataset, and
        ``<kind>_valid`` (False: zeros, this subject (or a padding row, ``None``) has no fit)."""
        torch = _torch()
        out = {}
        for kind, blank in self.body_models.items():
            params, ok = _body_model(rec, kind, blank)
            out[f"{kind}_valid"] = torch.tensor(ok)
            out.update({f"{kind}_{k}": torch.from_numpy(np.asarray(params[k], np.float32)) for k in blank})
        return out

    def _format(self, rgb: np.ndarray) -> np.ndarray:
        """The image (H, W, 3 linear RGB) as asked: ``float`` linear (HDR, as rendered),
        ``srgb8`` uint8 sRGB, ``normalized`` sRGB in [0, 1] minus ``mean``, over ``std``."""
        if self.image == "float":
            return rgb
        from synmitsuba.io.preview import to_srgb8
        srgb = to_srgb8(rgb)
        return srgb if self.image == "srgb8" else ((srgb.astype(np.float32) / 255.0 - self.mean) / self.std).astype(np.float32)


FLOW_PASSES = ("flow_fwd", "flow_fwd_flag", "flow_bwd", "flow_bwd_flag")
BODY_MODELS = ("smplx", "smpl")
BODY_MODEL_KEYS = ("betas", "global_orient", "body_pose", "transl", "jaw_pose", "leye_pose", "reye_pose",
                   "left_hand_pose", "right_hand_pose", "expression")


def _body_model(rec, kind: str, blank: dict) -> tuple[dict, bool]:
    """A record's ``<kind>_cam`` parameters (the smplx package's names) and whether it has them."""
    params = None if rec is None else rec.get(f"{kind}_cam")
    if not params:
        return blank, False
    return {k: np.asarray(params[k], np.float32) for k in blank}, True


def _default_modalities(stem: str) -> tuple:
    """Every pass of the dataset's first sample, and all four flow passes when it has any: a
    sequence's first and last frames lack one side, and every item must hold the same keys for
    the default collate."""
    import OpenEXR
    from synmitsuba.sample import PASSES
    with OpenEXR.File(f"{stem}.exr", header_only=True) as f:
        channels = {c.name for c in f.header()["channels"]}
    names = [n for n, spec in PASSES.items() if all(c in channels for c in spec.channels)]
    if any(n in FLOW_PASSES for n in names):
        names += [n for n in FLOW_PASSES if n not in names]
    return tuple(names)


def _missing(name: str, s) -> np.ndarray | None:
    """The fill of a flow side the sample lacks: zero flow, flag ``NO_TARGET``; None otherwise."""
    from synmitsuba.annotate.flow import NO_TARGET
    H, W = s.camera.height, s.camera.width
    if name in ("flow_fwd", "flow_bwd"):
        return np.zeros((H, W, 2), np.float32)
    if name in ("flow_fwd_flag", "flow_bwd_flag"):
        return np.full((H, W), NO_TARGET, np.uint8)
    return None


def _warp(img: np.ndarray, A: np.ndarray, size: int) -> np.ndarray:
    """``img`` (H, W, C) resampled (bilinear) into a size x size crop: crop pixel centre c maps
    to image point A^-1 c; outside the image is 0."""
    from scipy.ndimage import map_coordinates
    inv = np.linalg.inv(A)
    u, v = np.meshgrid(np.arange(size) + 0.5, np.arange(size) + 0.5)
    src = np.stack([u, v, np.ones_like(u)], -1) @ inv.T
    coords = [src[..., 1] - 0.5, src[..., 0] - 0.5]  # array indices of the source pixel centres
    return np.stack([map_coordinates(img[..., c], coords, order=1, cval=0.0) for c in range(img.shape[2])], -1)


def _codes(classes: np.ndarray, visibility: str) -> np.ndarray:
    from synmitsuba.annotate.keypoints import coco_flags
    return np.asarray(classes) if visibility == "classes" else coco_flags(classes)


def _keypoints(rec, convention: str, camera):
    """(2D (K, 2), 3D camera frame (K, 3), classes (K,), mask (K,)) in ``convention``."""
    from synmitsuba.annotate.conventions import (CONVENTIONS, JOINT_CONVENTIONS, convert_keypoints, smpl24_bones,
                                                 whole_body_rows)
    if convention in JOINT_CONVENTIONS:  # skeleton joints, projected; inside the image or not
        cam = np.asarray(rec["joints3d_cam"])[list(smpl24_bones())]
        uvw = cam @ camera.K.T
        uv = uvw[:, :2] / np.where(np.abs(uvw[:, 2:]) > 1e-9, uvw[:, 2:], 1e-9)
        inside = (cam[:, 2] > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < camera.width) & (uv[:, 1] >= 0) & (uv[:, 1] < camera.height)
        return uv, cam, inside.astype(np.uint8), np.ones(len(cam), np.uint8)
    if CONVENTIONS[convention].rows == "whole":
        p2, p3, classes = whole_body_rows(rec)
    else:
        p2, p3, classes = np.asarray(rec["keypoints2d"]), np.asarray(rec["keypoints3d_cam"]), rec["visibility"]
    pts, vis = convert_keypoints(np.concatenate([p2, p3], 1), classes, convention)
    return pts[:, :2], pts[:, 2:], vis, CONVENTIONS[convention].mask


def _subjects(records: list, n: int, visibility: str = "classes", convention: str = "ours", camera=None) -> dict:
    from synmitsuba.annotate.conventions import CONVENTIONS, joint_names
    torch = _torch()
    J = len(records[0]["body_params_cam"]["rotations"]) if records else 0
    K = len(CONVENTIONS[convention].names) if convention in CONVENTIONS else len(joint_names(convention))
    kp2 = np.zeros((n, K, 3), np.float32)
    kp3 = np.zeros((n, K, 3), np.float32)
    rot = np.zeros((n, J, 3), np.float32)
    root = np.zeros((n, 3), np.float32)
    inst, valid = np.zeros(n, np.int64), np.zeros(n, bool)
    for k, r in enumerate(records[:n]):
        p2, p3, vis, _ = _keypoints(r, convention, camera)
        kp2[k] = np.concatenate([p2, _codes(vis, visibility)[:, None]], 1)
        kp3[k], rot[k] = p3, r["body_params_cam"]["rotations"]
        root[k], inst[k], valid[k] = r["body_params_cam"]["root_translation"], r["instance"], r["valid"]
    if not n:
        return {}
    return {"keypoints2d": torch.from_numpy(kp2), "keypoints3d_cam": torch.from_numpy(kp3),
            "keypoints_mask": torch.from_numpy(CONVENTIONS[convention].mask if convention in CONVENTIONS
                                               else np.ones(K, np.uint8)),
            "body_rotations_cam": torch.from_numpy(rot), "body_root_cam": torch.from_numpy(root),
            "instances": torch.from_numpy(inst), "subjects_valid": torch.from_numpy(valid)}


def _as_torch_dataset():
    try:
        import torch.utils.data as tud
    except ImportError:  # torch is a dependency, but keep the reader usable without it
        return _Base
    return type("SynDataset", (_Base, tud.Dataset), {"__doc__": __doc__})


SynDataset = _as_torch_dataset()
