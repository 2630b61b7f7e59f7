"""Rendering: the path-traced RGB and the exact geometry passes (on ``synmitsuba.engine``).

``synmitsuba.render`` is this package and, called, the ``render`` function
(``sm.render(scene, camera, spp=16)``, see ``synmitsuba.render.passes.render``): one name for
both, so ``sm.render(...)`` and ``sm.render.passes`` both work.
"""
import sys as _sys
import types as _types

from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "set_variant": "synmitsuba.engine.variant", "current_variant": "synmitsuba.engine.variant",
    "exact_pass": "synmitsuba.render.passes", "Sample": "synmitsuba.sample"})
__all__ = ["set_variant", "current_variant", "exact_pass"]


class _CallableRenderPackage(_types.ModuleType):
    def __call__(self, *args, **kwargs):
        from synmitsuba.render.passes import render
        return render(*args, **kwargs)


_sys.modules[__name__].__class__ = _CallableRenderPackage
