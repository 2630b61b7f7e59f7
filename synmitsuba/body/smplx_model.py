"""SMPL-X and SMPL model files the user supplies (MPI licence: never shipped, downloaded or
vendored here).

Point ``SMPLX_MODEL_PATH`` (or ``path=``) at a folder holding ``SMPLX_NEUTRAL.npz`` (or
``SMPLX_MALE.npz`` / ``SMPLX_FEMALE.npz``), or at one such file; SMPL files (``SMPL_NEUTRAL.npz``
or ``.pkl``) go in ``SMPL_MODEL_PATH`` (or the same folder). ``load_model`` reads one as arrays
for fitting (``synmitsuba.annotate.smplx_fit``); ``smplx_body`` gives a bare shaped body that
our skinning poses like every other body.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from synmitsuba.body.anny_model import BodyMesh
from synmitsuba.body.skeleton import Skeleton
from synmitsuba.errors import ConfigError

_BODY = ("pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
         "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
         "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
         "jaw", "left_eye_smplhf", "right_eye_smplhf")
FINGERS = tuple(f"{f}{k}" for f in ("index", "middle", "pinky", "ring", "thumb") for k in (1, 2, 3))
# SMPL-X joint order (body, then left and right hand); AMASS motions use it too
SMPLX_JOINT_NAMES = _BODY + tuple(f"left_{f}" for f in FINGERS) + tuple(f"right_{f}" for f in FINGERS)
SMPL_JOINT_NAMES = _BODY[:22] + ("left_hand", "right_hand")
_HAND = [p for f in range(5) for p in (-1, 0, 1)]  # each finger: wrist, then its previous joint
SMPLX_PARENTS = ([-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 15, 15, 15] +
                 [20 if p < 0 else 25 + 3 * (i // 3) + p for i, p in enumerate(_HAND)] +
                 [21 if p < 0 else 40 + 3 * (i // 3) + p for i, p in enumerate(_HAND)])
SMPL_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
REQUIRED = ("v_template", "f", "shapedirs", "J_regressor", "weights", "kintree_table")
KINDS = {"smplx": ("SMPLX", "SMPLX_MODEL_PATH", "smpl-x.is.tue.mpg.de"),
         "smpl": ("SMPL", "SMPL_MODEL_PATH", "smpl.is.tue.mpg.de")}
GENDERS = ("neutral", "male", "female")
SHAPE_BASIS = {"smplx": 300, "smpl": 300}  # shapedirs columns before the expression basis (SMPL-X)
LEGACY_SMPLX_DIRS = 20  # SMPL-X v1.0 files: 10 shape and 10 expression columns (as the smplx package reads them)


def _model_root(kind: str, path: str | None) -> tuple[str, str]:
    """The folder or file the user named: ``path``, else ``<KIND>_MODEL_PATH`` (SMPL falls back
    on ``SMPLX_MODEL_PATH``, where many keep both)."""
    if kind not in KINDS:
        raise ConfigError("kind", kind, f"use one of {', '.join(KINDS)}")
    prefix, var, site = KINDS[kind]
    path = path or os.environ.get(var) or (os.environ.get("SMPLX_MODEL_PATH") if kind == "smpl" else None)
    if not path:
        raise ConfigError(var, None, f"{kind.upper().replace('X', '-X')} model files are not shipped (MPI licence): "
                          f"register at {site}, download "
                          f"the model files and set {var} (or pass --model-path / model_path=) to the folder "
                          f"holding {prefix}_NEUTRAL.npz")
    return os.path.expanduser(os.fspath(path)), var


def find_model(path: str | None = None, gender: str = "neutral", kind: str = "smplx") -> str:
    """The model file of ``kind`` and ``gender``: ``path`` itself when it is a file, else
    ``<KIND>_<GENDER>.npz`` (or ``.pkl``) in that folder or its ``<kind>/`` subfolder."""
    path, var = _model_root(kind, path)
    prefix = KINDS[kind][0]
    if os.path.isfile(path):
        return path
    names = [f"{prefix}_{gender.upper()}.{ext}" for ext in ("npz", "pkl")]
    for folder in (path, os.path.join(path, kind)):
        for name in names:
            if os.path.isfile(os.path.join(folder, name)):
                return os.path.join(folder, name)
    raise ConfigError(var, path, f"no {names[0]} there (nor {names[1]}); put the {prefix} model files in that folder")


def available_genders(path: str | None = None, kind: str = "smplx") -> list[str]:
    """The genders whose model files are present."""
    out = []
    for g in GENDERS:
        try:
            find_model(path, g, kind)
            out.append(g)
        except ConfigError:
            pass
    return out


@dataclass
class ModelFile:
    """An SMPL or SMPL-X model file as arrays (y up, metres): what posing and fitting need."""

    kind: str
    gender: str
    path: str
    v_template: np.ndarray      # (V, 3)
    faces: np.ndarray           # (F, 3)
    shapedirs: np.ndarray       # (V, 3, B) shape basis only
    exprdirs: np.ndarray        # (V, 3, E) expression basis (SMPL-X), else (V, 3, 0)
    posedirs: np.ndarray        # (V, 3, 9 (J - 1)) pose correctives, zeros when the file has none
    J_regressor: np.ndarray     # (J, V)
    weights: np.ndarray         # (V, J)
    parents: np.ndarray         # (J,), -1 for the root
    joint_names: tuple
    hands_components: np.ndarray | None = None  # (2, 45, 45) left, right: rows are the hand pose components (SMPL-X)
    hands_mean: np.ndarray | None = None        # (2, 45) left, right mean hand pose

    @property
    def n_betas(self) -> int:
        return self.shapedirs.shape[2]


def _read(path: str) -> dict:
    if path.endswith(".pkl"):
        import pickle
        try:
            with open(path, "rb") as fh:
                data = pickle.load(fh, encoding="latin1")
        except ModuleNotFoundError as exc:
            raise ConfigError("model file", path, f"it holds {exc.name} objects; convert it to .npz with the "
                              "smplx package's tools (or pip install chumpy) and point at the .npz") from None
        return {k: (v.toarray() if hasattr(v, "toarray") else np.asarray(v)) for k, v in data.items()}
    with np.load(path, allow_pickle=True) as data:
        return {k: data[k] for k in data.files}


def load_model(path: str | None = None, gender: str = "neutral", kind: str = "smplx") -> ModelFile:
    """Read the user's model file (``find_model``); every array checked against the layout."""
    file = find_model(path, gender, kind)
    data = _read(file)
    missing = [k for k in REQUIRED if k not in data]
    if missing:
        raise ConfigError("model file", file, f"the file lacks {', '.join(missing)}; is it an {kind.upper()} model?")
    v = np.asarray(data["v_template"], np.float64)
    V = len(v)
    dirs = np.asarray(data["shapedirs"], np.float64)
    n_shape = min(dirs.shape[2], SHAPE_BASIS[kind])
    if kind == "smplx" and dirs.shape[2] == LEGACY_SMPLX_DIRS:  # SMPL-X v1.0: 10 shape, then 10 expression
        n_shape = LEGACY_SMPLX_DIRS // 2
    J = np.asarray(data["J_regressor"], np.float64)
    weights = np.asarray(data["weights"], np.float64)
    parents = np.asarray(data["kintree_table"])[0].astype(np.int64)
    parents[0] = -1
    n = len(parents)
    posedirs = np.asarray(data["posedirs"], np.float64) if "posedirs" in data else np.zeros((V, 3, 9 * (n - 1)))
    bad = {"shapedirs": dirs.shape[:2] != (V, 3), "J_regressor": J.shape != (n, V), "weights": weights.shape != (V, n),
           "posedirs": posedirs.shape != (V, 3, 9 * (n - 1))}
    for key, wrong in bad.items():
        if wrong:
            raise ConfigError(f"model file {key}", f"array{np.shape(data[key])}", f"expected the {kind.upper()} "
                              f"layout for {V} vertices and {n} joints")
    table = SMPLX_JOINT_NAMES if kind == "smplx" else SMPL_JOINT_NAMES
    names = table[:n] if n <= len(table) else tuple(f"joint{i}" for i in range(n))
    hands = [np.asarray(data[k], np.float64) for k in ("hands_componentsl", "hands_componentsr",
                                                        "hands_meanl", "hands_meanr") if k in data]
    if len(hands) == 4 and (any(h.size != 45 * 45 for h in hands[:2]) or any(h.size != 45 for h in hands[2:])):
        raise ConfigError("model file hands_components", file, "expected 45 x 45 components and 45 means a hand")
    return ModelFile(kind, gender, file, v, np.asarray(data["f"], np.int64), dirs[:, :, :n_shape],
                     dirs[:, :, n_shape:], posedirs, J, weights, parents, names,
                     np.stack([h.reshape(45, 45) for h in hands[:2]]) if len(hands) == 4 else None,
                     np.stack([h.reshape(45) for h in hands[2:]]) if len(hands) == 4 else None)


def smplx_body(betas=None, path: str | None = None, gender: str = "neutral") -> BodyMesh:
    """The SMPL-X body shaped by ``betas``, y up (SMPL-X's own frame), soles on y = 0."""
    m = load_model(path, gender, "smplx")
    b = np.zeros(m.n_betas) if betas is None else np.asarray(betas, dtype=np.float64)
    n = min(len(b), m.n_betas)
    v = m.v_template + m.shapedirs[:, :, :n] @ b[:n]
    J = m.J_regressor @ v
    lift = -v[:, 1].min()
    v[:, 1] += lift
    J[:, 1] += lift
    return BodyMesh(v, m.faces, m.weights.astype(np.float32), Skeleton(m.joint_names, m.parents, J),
                    np.zeros((1, 2)), np.zeros_like(m.faces), np.zeros((0, len(v))), ())
