"""An exact OpenCV pinhole sensor for Mitsuba (any K: off-centre principal point, fx != fy).

Mitsuba's ``perspective`` sensor only knows square pixels, so we register a small Python
sensor: a film sample at pixel coordinates (u, v) becomes the ray from the camera centre along
R^T K^-1 [u, v, 1]. Its matrices are opaque drjit values: a new camera reuses compiled kernels.
"""
from __future__ import annotations

import numpy as np

from synmitsuba.scene.camera import Camera

PLUGIN = "synmitsuba_opencv"
_registered: set[str] = set()


def register(variant: str) -> None:
    """Register the sensor plugin for the active variant (once per variant)."""
    if variant in _registered:
        return
    import drjit as dr
    import mitsuba as mi

    class OpenCVSensor(mi.Sensor):
        def __init__(self, props):
            super().__init__(props)
            m = np.array(props["ray_matrix"].matrix, dtype=np.float64)  # [[R^T K^-1, c], [0, 1]]
            self.M = mi.Matrix3f(m[:3, :3])
            self.o = mi.Point3f(m[:3, 3])
            self.size = mi.ScalarVector2f(self.film().size())
            dr.make_opaque(self.M, self.o)

        def _ray(self, time, pos):
            px = pos * self.size
            d = dr.normalize(self.M @ mi.Vector3f(px.x, px.y, 1.0))
            return mi.Ray3f(mi.Point3f(self.o), d, time, [])

        def sample_ray(self, time, sample1, sample2, sample3, active=True):
            return self._ray(time, sample2), mi.Spectrum(1.0)

        def sample_ray_differential(self, time, sample1, sample2, sample3, active=True):
            return mi.RayDifferential3f(self._ray(time, sample2)), mi.Spectrum(1.0)

        def to_string(self):
            return "OpenCVSensor[]"

    mi.register_sensor(PLUGIN, lambda props: OpenCVSensor(props))
    _registered.add(variant)


def sensor_dict(camera: Camera, spp: int, rfilter: str = "box", sampler: str = "independent") -> dict:
    """A Mitsuba dict for the camera with a float32 RGB film of the camera's size."""
    import mitsuba as mi
    m = np.eye(4)
    m[:3, :3] = camera.ray_matrix
    m[:3, 3] = camera.center
    return {"type": PLUGIN, "ray_matrix": mi.ScalarTransform4f(m.tolist()),
            "film": {"type": "hdrfilm", "width": camera.width, "height": camera.height,
                     "pixel_format": "rgb", "component_format": "float32",
                     "rfilter": {"type": rfilter}},
            "sampler": {"type": sampler, "sample_count": spp}}
