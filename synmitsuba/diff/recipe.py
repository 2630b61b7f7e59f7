"""Fitted variables back into a subject recipe, and the rest-pose scene the fit uses."""
from __future__ import annotations

import copy
from typing import Callable

from synmitsuba.body.textures import linear_rgb_to_lab

# variable -> (texture field, conversion)
_FIELDS: dict[str, tuple[str, Callable]] = {
           "base_rgb": ("base_lab", linear_rgb_to_lab), "pattern_rgb": ("pattern_lab", linear_rgb_to_lab),
           "decal_rgb": ("decal_lab", linear_rgb_to_lab), "pattern_scale": ("pattern_scale", float),
           "pattern_width": ("pattern_width", float), "pattern_alpha": ("pattern_alpha", float),
           "phase": ("uv_offset", list), "decal_center": ("decal_center", list), "decal_size": ("decal_size", float)}


def fitted_recipe(recipe, values: dict, prefix: str = "subject1"):
    """A copy of ``recipe`` whose garment textures take the fitted ``values`` ({variable: numbers},
    as ``FitResult.values``); ``decal_alpha`` has no recipe field and is left out."""
    out = copy.deepcopy(recipe)
    for g in out.garments:
        for name, (field, convert) in _FIELDS.items():
            key = f"{prefix}_{g.kind}.{name}"
            if key in values:
                setattr(g.texture, field, convert(values[key]))
    return out


def rest_scene(recipe, radiance: float = 1.0, prefix: str = "subject1"):
    """The subject of ``recipe`` in its rest pose at the origin under a constant environment:
    the scene ``synmitsuba fit-texture`` renders targets of and fits in."""
    from synmitsuba.body.subject import build_subject
    from synmitsuba.scene.materials import Constant
    from synmitsuba.scene.scene import Scene
    scene = Scene()
    scene.set_environment(Constant(radiance))
    build_subject(recipe).add_to(scene, instance=1, prefix=prefix)
    return scene
