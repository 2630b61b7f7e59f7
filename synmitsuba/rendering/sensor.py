"""An exact OpenCV pinhole sensor for Mitsuba (any K: off-centre principal point, fx != fy).

Mitsuba's ``perspective`` sensor only knows square pixels, so we register a small Python
sensor: a film sample at pixel coordinates (u, v) becomes the ray from the camera centre along
R^T K^-1 [u, v, 1] (``engine.rays.pixel_directions``, through the lens distortion when the
camera has one); with an aperture, a thin lens (``_thin_lens``). Its numbers are opaque drjit
values: a new camera reuses compiled kernels.
"""
from __future__ import annotations

import json

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
            self.camera = Camera.from_dict(json.loads(props["camera"]))
            self.size = mi.ScalarVector2f(self.film().size())

        def _ray(self, time, pos, lens):
            from synmitsuba.engine.rays import pixel_directions
            cam = self.camera
            px = pos * self.size
            o, d = mi.Point3f(*cam.center.tolist()), pixel_directions(cam, px.x, px.y)
            dr.make_opaque(o)
            if cam.aperture_radius > 0:
                o, d = _thin_lens(cam, o, d, lens)
            return mi.Ray3f(o, d, time, [])

        def sample_ray(self, time, sample1, sample2, sample3, active=True):
            return self._ray(time, sample2, sample3), mi.Spectrum(1.0)

        def sample_ray_differential(self, time, sample1, sample2, sample3, active=True):
            return mi.RayDifferential3f(self._ray(time, sample2, sample3)), mi.Spectrum(1.0)

        def to_string(self):
            return "OpenCVSensor[]"

    mi.register_sensor(PLUGIN, lambda props: OpenCVSensor(props))
    _registered.add(variant)


def _thin_lens(camera: Camera, o, d, lens):
    """A ray from a point of the aperture disc (``lens`` in [0, 1)^2) through the point the
    pinhole ray ``o + s d`` meets on the plane of focus (camera z = focus distance)."""
    import drjit as dr
    import mitsuba as mi
    R = camera.R
    ex, ey, ez = (mi.Vector3f(*R[i].tolist()) for i in range(3))  # camera axes in the world
    a, s = mi.Float(camera.aperture_radius), mi.Float(camera.focus_distance)
    dr.make_opaque(ex, ey, ez, a, s)
    focus = o + d * (s / dr.dot(d, ez))
    disk = mi.warp.square_to_uniform_disk_concentric(lens) * a
    origin = o + ex * disk.x + ey * disk.y
    return origin, dr.normalize(focus - origin)


def sensor_dict(camera: Camera, spp: int, rfilter: str = "box", sampler: str = "independent") -> dict:
    """A Mitsuba dict for the camera with a float32 RGB film of the camera's size."""
    return {"type": PLUGIN, "camera": json.dumps(camera.to_dict()),
            "film": {"type": "hdrfilm", "width": camera.width, "height": camera.height,
                     "pixel_format": "rgb", "component_format": "float32",
                     "rfilter": {"type": rfilter}},
            "sampler": {"type": sampler, "sample_count": spp}}
