"""The per-subject label records of a sample (``sample.subjects``), as typed dataclasses that
also read as mappings (``rec["keypoints2d"]``, ``dict(rec)``), in the key order of the sample
JSON (docs/FORMAT.md, "Subjects"). ``from_json`` reads a JSON record back with each array's
dtype from the field that holds it."""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np


class _Record(Mapping):
    """A dataclass read as a mapping of its public fields (an ``extra`` dict field's items follow
    them as keys of their own)."""

    def _names(self) -> list[str]:
        return [f.name for f in dataclasses.fields(self) if f.name != "extra"]  # type: ignore[arg-type]

    def __getitem__(self, key: str):
        if key in self._names():
            return getattr(self, key)
        return getattr(self, "extra", {})[key]

    def __iter__(self):
        yield from self._names()
        yield from getattr(self, "extra", {})

    def __len__(self) -> int:
        return len(self._names()) + len(getattr(self, "extra", {}))


def _array(dtype=np.float64):
    """A field read back from JSON as a numpy array of ``dtype``."""
    return field(default_factory=lambda: np.zeros(0, dtype), metadata={"dtype": dtype})


@dataclass(eq=False)
class BodyParams(_Record):
    """A subject's skeleton pose in one frame of reference (world or camera)."""

    rotations: np.ndarray = _array()         # (J, 3) axis-angle, local, root first in skeleton order
    root_translation: np.ndarray = _array()  # (3,) metres
    phenotypes: dict = field(default_factory=dict)

    @classmethod
    def from_json(cls, d: Mapping) -> "BodyParams":
        return cls(np.asarray(d["rotations"]), np.asarray(d["root_translation"]), dict(d["phenotypes"]))


@dataclass(eq=False)
class SubjectLabels(_Record):
    """One subject's labels in one view at one frame (fields as in docs/FORMAT.md)."""

    instance: int
    keypoints3d_world: np.ndarray = _array()           # (23, 3) metres
    keypoints3d_cam: np.ndarray = _array()             # (23, 3)
    keypoints2d: np.ndarray = _array()                 # (23, 2) pixels
    visibility: np.ndarray = _array(np.uint8)          # (23,) annotate.keypoints.VISIBILITY classes
    visible_fraction_kp: np.ndarray = _array()         # (23,)
    joints3d_world: np.ndarray = _array()              # (J, 3) joint centres
    joints3d_cam: np.ndarray = _array()                # (J, 3)
    amodal_mask: np.ndarray | None = None              # (H, W) bool; an EXR channel, not in the JSON
    visible_fraction: float = 0.0
    bbox_visible: list | None = None                   # [x_min, y_min, x_max, y_max] pixel edges
    bbox_amodal: list | None = None
    bbox_keypoints: list | None = None
    center: list | None = None
    scale: float | None = None
    body_params_world: BodyParams = field(default_factory=BodyParams)
    body_params_cam: BodyParams = field(default_factory=BodyParams)
    root_world: np.ndarray = _array()                  # (3,)
    gaze_cam: np.ndarray = _array()                    # (2, 3) unit gaze of the left, right eye, camera frame
    hands3d_world: np.ndarray = _array()               # (2, 21, 3) left, right hand (COCO-WholeBody order)
    hands3d_cam: np.ndarray = _array()                 # (2, 21, 3)
    hands2d: np.ndarray = _array()                     # (2, 21, 2) pixels
    hands_visibility: np.ndarray = _array(np.uint8)    # (2, 21) annotate.keypoints.VISIBILITY classes
    face3d_world: np.ndarray = _array()                # (68, 3) face points (COCO-WholeBody's 300W order)
    face3d_cam: np.ndarray = _array()                  # (68, 3)
    face2d: np.ndarray = _array()                      # (68, 2) pixels
    face_visibility: np.ndarray = _array(np.uint8)     # (68,) annotate.keypoints.VISIBILITY classes
    expression: np.ndarray = _array()                  # (52,) ARKit face unit weights (body.expressions.FACE_UNITS)
    valid: bool = False
    layer_pixels: dict = field(default_factory=dict)   # visible pixels per layer name
    extra: dict = field(default_factory=dict)          # body-model fits: smplx_world, smplx_cam, smpl_world, ...

    def add_body_models(self, params: dict) -> None:
        """Body-model parameters by key (``smplx_world``, ``smpl_cam``, ...)."""
        self.extra.update(params)

    @classmethod
    def from_json(cls, d: Mapping, amodal_mask: np.ndarray | None = None) -> "SubjectLabels":
        """A record from its JSON form (and its amodal mask, from the EXR)."""
        known = {f.name: f for f in dataclasses.fields(cls)}
        args: dict[str, Any] = {}
        extra: dict[str, Any] = {}
        for k, v in d.items():
            f = known.get(k)
            if f is None or k == "extra":
                extra[k] = ({n: (np.asarray(x, np.float64) if isinstance(x, list) else x) for n, x in v.items()}
                            if isinstance(v, dict) and "model" in v else v)
            elif "dtype" in f.metadata:
                args[k] = np.asarray(v, f.metadata["dtype"])
            elif k in ("body_params_world", "body_params_cam"):
                args[k] = BodyParams.from_json(v)
            else:
                args[k] = v
        return cls(**args, amodal_mask=amodal_mask, extra=extra)
