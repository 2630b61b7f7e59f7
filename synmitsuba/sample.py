"""``Sample``: one rendered view, its passes and its camera, as plain numpy data; and the pass
registry that declares, once, every pass's in-memory type and its OpenEXR channels.

The renderer fills a Sample, the writers and readers in ``synmitsuba.io`` consume it; neither
knows the other. A new pass is one ``register_pass`` entry here plus its computation in the
renderer (``synmitsuba.rendering.passes.exact_pass``); the EXR writer, the reader and the
dataset pick it up from this table.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from synmitsuba.scene.camera import Camera


@dataclass(frozen=True)
class PassSpec:
    """One pass: its components' EXR channel names, numpy dtype in memory, EXR pixel type."""

    name: str
    channels: tuple[str, ...]
    dtype: str                # in memory: float32, bool, int32, uint8
    exr_type: str = "float32"  # in the file: float32, uint32 or half
    doc: str = ""

    @property
    def components(self) -> int:
        return len(self.channels)


PASSES: dict[str, PassSpec] = {}


def register_pass(name: str, channels, dtype: str, exr_type: str = "float32", doc: str = "") -> PassSpec:
    """Declare a pass (idempotent for an identical declaration)."""
    spec = PassSpec(name, tuple(channels), dtype, exr_type, doc)
    if PASSES.get(name, spec) != spec:
        raise ValueError(f"pass {name!r} is already registered differently")
    PASSES[name] = spec
    return spec


register_pass("rgb", ("R", "G", "B"), "float32", doc="linear radiance from the path tracer")
register_pass("rgb_clean", ("clean.R", "clean.G", "clean.B"), "float32",
              doc="with photo development only: the rendered linear radiance before it (rgb is the photo)")
register_pass("rgb_noisy", ("noisy.R", "noisy.G", "noisy.B"), "float32",
              doc="the path tracer's RGB before denoising (only when rendered with a denoiser)")
register_pass("alpha", ("A",), "float32", doc="fraction of the pixel covered by geometry (stratified sub-pixel rays)")
register_pass("depth", ("depth.Z",), "float32", doc="z-depth along the optical axis, metres; 0 on background")
register_pass("mask", ("mask",), "bool", "uint32", doc="1 where the pixel-centre ray hits geometry")
register_pass("normal", ("normal.X", "normal.Y", "normal.Z"), "float32",
              doc="unit shading normal in the camera frame, facing the camera")
register_pass("position", ("position.X", "position.Y", "position.Z"), "float32", doc="world position, metres")
register_pass("uv", ("uv.U", "uv.V"), "float32", doc="texture coordinates (v up); 0 where uv_valid is 0")
register_pass("uv_valid", ("uv.valid",), "bool", "uint32", doc="1 where the hit shape has texture coordinates")
register_pass("instance", ("instance",), "int32", "uint32", doc="instance id; 0 = background")
register_pass("layer", ("layer",), "uint8", "uint32", doc="semantic layer id (synmitsuba.Layer); 0 = background")
register_pass("flow_fwd", ("flow_fwd.X", "flow_fwd.Y"), "float32",
              doc="pixels each pixel's surface point moves to the next frame (exact; render_sequence)")
register_pass("flow_bwd", ("flow_bwd.X", "flow_bwd.Y"), "float32", doc="the same to the previous frame")
register_pass("motion_blur", ("blur.X", "blur.Y"), "float32",
              doc="motion blur: image displacement over the exposure (end minus start), pixels, of the point "
                  "the pixel-centre ray hits at its centre; 0 on background")
register_pass("flow_fwd_flag", ("flow_fwd.flag",), "uint8", "uint32",
              doc="0 seen at the next frame, 1 hidden there, 2 outside its image, 3 background")
register_pass("flow_bwd_flag", ("flow_bwd.flag",), "uint8", "uint32", doc="the same for the previous frame")
register_pass("body_part", ("body.part",), "uint8", "uint32", doc="1 + body part (synmitsuba.body.segments.PART_NAMES) "
              "under the pixel's subject, clothes and hair included; 0 elsewhere")
register_pass("body_face", ("body.face",), "int32", "uint32", doc="1 + anny face index of the body point under the pixel")
register_pass("body_bary", ("body.u", "body.v"), "float32", doc="barycentric weights of that face's vertices 1 and 2")
register_pass("body_depth", ("body.Z",), "float32", doc="z-depth of the body alone under clothes and hair; 0 elsewhere")
register_pass("body_normal", ("body.X", "body.Y", "body.Z_normal"), "float32",
              doc="unit normal of that body point, camera frame, facing the camera")
register_pass("cloth_thickness", ("cloth.thickness",), "float32",
              doc="body depth minus visible depth where a garment covers the body, metres")


@dataclass
class Sample:
    """All passes of one view as H x W (x C) arrays, by name (see ``PASSES``), readable as
    attributes: ``sample.rgb``, ``sample.depth``, ... Geometry passes are exact values at pixel
    centres. ``coverage`` maps each instance id > 0 to its (H, W) soft mask."""

    camera: Camera
    passes: dict = field(default_factory=dict)
    coverage: dict = field(default_factory=dict)
    meta: dict = field(default_factory=dict)      # render settings, written to the sidecar
    timings: dict = field(default_factory=dict)   # seconds per stage; never written (no clock in files)
    subjects: list = field(default_factory=list)  # per-subject label records (synmitsuba.annotate)

    def __getattr__(self, name: str):
        passes = self.__dict__.get("passes", {})
        if name in passes:
            return passes[name]
        raise AttributeError(f"Sample has no pass or attribute {name!r}; passes: {', '.join(passes)}")

    @property
    def shape(self) -> tuple[int, int]:
        return self.camera.height, self.camera.width

    def instance_ids(self) -> list[int]:
        """Instance ids visible in this view (background excluded)."""
        return [int(i) for i in np.unique(self.passes["instance"]) if i != 0]
