"""The Mitsuba engine under every stage that needs it: the variant (and a libLLVM that works),
a ``Scene`` turned into a Mitsuba scene and updated in place, and ray casts on it. Composition
scores cameras with its ray casts; rendering draws with its scenes."""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "set_variant": "synmitsuba.engine.variant", "current_variant": "synmitsuba.engine.variant",
    "build": "synmitsuba.engine.build", "BuiltScene": "synmitsuba.engine.build",
    "first_hits": "synmitsuba.engine.raycast", "SAMPLERS": "synmitsuba.engine.settings",
    "DENOISERS": "synmitsuba.engine.settings"})
__all__ = ["BuiltScene", "DENOISERS", "SAMPLERS", "build", "current_variant", "first_hits", "set_variant"]
