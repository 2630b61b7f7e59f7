"""Stages for previews and benches: a large grey ground at y = 0 under a sun and sky, or one
named environment alone."""
from __future__ import annotations

import numpy as np

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


def environment_stage(name: str, rng: np.random.Generator, where: str = "environment") -> Scene:
    """A scene holding only the environment ``name`` (ground or HDRI backdrop, objects, lights)
    under its lighting drawn from ``rng`` (an HDRI's scale and rotation), centred on the
    origin; a subject added at the origin stands in it. With a backdrop, call
    ``backdrop.centre_backdrop(scene, camera.center)`` per view."""
    from synmitsuba.compose.environments import add_environment, load_environment, sample_lighting
    env = load_environment(name, where)
    scene = Scene()
    add_environment(scene, env, sample_lighting(env, rng), rng)
    return scene
