"""``Sample``: one rendered view with all of its passes and the camera."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from synmitsuba.scene.camera import Camera


@dataclass
class Sample:
    """All passes of one view; H x W arrays. Geometry passes are exact values at pixel centres.

    rgb      (H, W, 3) float32 linear radiance from the path tracer
    alpha    (H, W)    float32 fraction of each pixel covered by geometry (multi-sample)
    depth    (H, W)    float32 z-depth along the optical axis, metres; 0 on background
    mask     (H, W)    bool    True where the pixel-centre ray hits geometry
    normal   (H, W, 3) float32 unit shading normal in the camera frame (OpenCV), facing the camera
    position (H, W, 3) float32 world position, metres
    uv       (H, W, 2) float32 texture coordinates (v up)
    instance (H, W)    int32   instance id, 0 = background
    layer    (H, W)    uint8   semantic layer id (synmitsuba.Layer), 0 = background
    coverage {instance id: (H, W) float32} fraction of each pixel covered by that instance
             (multi-sample soft masks, for ids > 0)
    """

    rgb: np.ndarray
    alpha: np.ndarray
    depth: np.ndarray
    mask: np.ndarray
    normal: np.ndarray
    position: np.ndarray
    uv: np.ndarray
    instance: np.ndarray
    layer: np.ndarray
    camera: Camera
    coverage: dict = field(default_factory=dict)
    meta: dict = field(default_factory=dict)

    PASSES = ("rgb", "alpha", "depth", "mask", "normal", "position", "uv", "instance", "layer")

    @property
    def shape(self) -> tuple[int, int]:
        return self.depth.shape

    def instance_ids(self) -> list[int]:
        """Instance ids visible in this view (background excluded)."""
        return [int(i) for i in np.unique(self.instance) if i != 0]
