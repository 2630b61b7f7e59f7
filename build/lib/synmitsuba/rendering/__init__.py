"""Rendering: the path-traced RGB and the exact geometry passes (on ``synmitsuba.engine``).

``sm.render(scene, camera, spp=16)`` is ``synmitsuba.rendering.passes.render``, a plain function;
this package holds it with the sensor, the passes and the denoiser.
"""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "render": "synmitsuba.rendering.passes", "set_variant": "synmitsuba.engine.variant",
    "current_variant": "synmitsuba.engine.variant", "exact_pass": "synmitsuba.rendering.passes",
    "Sample": "synmitsuba.sample"})
__all__ = ["render", "set_variant", "current_variant", "exact_pass"]
