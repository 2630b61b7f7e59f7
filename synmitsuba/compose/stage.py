"""A plain stage for previews: a large grey ground at y = 0 under a sun and sky."""
from __future__ import annotations

from synmitsuba.geometry import ground_grid
from synmitsuba.scene.layers import Layer
from synmitsuba.scene.materials import Material, SunSky
from synmitsuba.scene.scene import Scene


def preview_stage(sun_direction=(0.5, 0.9, 0.7), ground: float = 0.45, sky_scale: float = 1.5,
                  half_size: float = 20000.0) -> Scene:
    """A scene holding only a ground square (``2 * half_size`` metres wide: its edge lies within
    0.01 degrees of the horizon from a standing eye, so no black band shows there) and a sun and
    sky."""
    scene = Scene()
    scene.add_mesh("ground", *ground_grid(half_size), material=Material(base_color=ground),
                   layer=Layer.GROUND)
    scene.set_environment(SunSky(sun_direction=sun_direction, sky_scale=sky_scale))
    return scene
