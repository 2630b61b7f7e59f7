"""Differentiable rendering (stage 7): gradients of images with respect to textures (bitmap
and procedural, written in drjit), environment light; texture fitting with Adam."""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "DiffScene": "synmitsuba.diff.scene",
    "ProceduralTexture": "synmitsuba.diff.texture", "VARIABLES": "synmitsuba.diff.texture",
    "fit_texture": "synmitsuba.diff.fit", "FitResult": "synmitsuba.diff.fit"})
__all__ = ["DiffScene", "ProceduralTexture", "VARIABLES", "fit_texture", "FitResult"]
