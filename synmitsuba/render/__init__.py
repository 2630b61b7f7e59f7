"""Rendering: variant selection, scene building, the RGB and exact geometry passes."""
from synmitsuba.render.passes import render
from synmitsuba.render.sample import Sample
from synmitsuba.render.variant import current_variant, set_variant

__all__ = ["render", "Sample", "set_variant", "current_variant"]
