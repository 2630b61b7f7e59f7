"""A scene rendered differentiably: named variables, bound to Mitsuba parameters, and images
that carry their gradients.

``DiffScene(scene)`` loads a ``synmitsuba.Scene`` on an AD variant (``llvm_ad_rgb`` by
default) and renders it with Mitsuba's ``prb`` integrator (``direct_projective`` or
``prb_projective`` when moving shadows or silhouettes matter). Variables are named
``<mesh>.texture`` (a mesh's bitmap albedo), ``<mesh>.<name>`` for the procedural garment
texture's ``VARIABLES`` once bound with ``bind_procedural``, and ``environment.radiance``
(a constant environment) or ``environment.intensity`` (an environment map's multiplier).

The sun: Mitsuba 3.9's ``prb`` differentiates an emitter only through its radiance at fixed
directions; the sun is a small disk (``sunsky``) or a delta (``directional``), so moving it is
a boundary effect that ``prb`` leaves out (measured against central differences, ``sunsky``'s
``sun_direction`` gradient is off by 66-116 %, and a ``directional`` light's is detached).
``DiffScene(scene, soft_sun_deg=2)`` therefore replaces a ``SunSky`` by its baked sky plus a
soft sun lobe in drjit (``diff.sun``), with the variables ``environment.sun_elevation`` and
``environment.sun_azimuth`` (degrees), ``environment.sun_scale`` and ``environment.sky_scale``.
"""
from __future__ import annotations

import copy

import numpy as np

from synmitsuba.diff.sun import SoftSun, check_sun
from synmitsuba.diff.texture import VARIABLES, ProceduralTexture, Variable, as_numbers, drjit_value
from synmitsuba.errors import ConfigError
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.materials import Constant, EnvMap
from synmitsuba.scene.scene import Scene

INTEGRATORS = ("prb", "direct_projective", "prb_projective")
ENVIRONMENT = {
    "environment.radiance": Variable("rgb", 0.0, 1e4, 0.02),
    "environment.intensity": Variable("float", 0.0, 1e4, 0.02),
    "environment.sun_elevation": Variable("float", 0.5, 90.0, 0.5),
    "environment.sun_azimuth": Variable("float", -720.0, 720.0, 0.5),
    "environment.sun_scale": Variable("float", 0.0, 1e4, 0.02),
    "environment.sky_scale": Variable("float", 0.0, 1e4, 0.02),
}
SUN = ("environment.sun_elevation", "environment.sun_azimuth", "environment.sun_scale", "environment.sky_scale")


class DiffScene:
    """A loaded scene whose named variables a render differentiates with respect to."""

    def __init__(self, scene: Scene, integrator: str = "prb", max_depth: int = 4, soft_sun_deg: float | None = None):
        import mitsuba as mi
        from synmitsuba.engine.build import load
        from synmitsuba.engine.variant import current_variant, set_variant
        if not isinstance(scene, Scene):
            raise ConfigError("scene", type(scene).__name__, "give a synmitsuba.Scene")
        if integrator not in INTEGRATORS:
            raise ConfigError("integrator", integrator, f"use one of {', '.join(INTEGRATORS)}")
        if "_ad_" not in (current_variant() or set_variant()):
            raise ConfigError("variant", current_variant(), "gradients need an AD variant: llvm_ad_rgb or cuda_ad_rgb "
                              "(SYNMITSUBA_VARIANT)")
        check_sun(scene.environment, soft_sun_deg)
        self.sun = None if soft_sun_deg is None else SoftSun(scene.environment, soft_sun_deg)
        if self.sun is not None:  # the same scene under the baked sky (the user's scene is left as it is)
            scene = copy.copy(scene)
            scene.set_environment(EnvMap(self.sun.image()))
        self.scene = scene
        # its own build, a BSDF per mesh (a key per mesh): apply() never changes what sm.render(scene) sees
        self.built = load(scene, share_bsdfs=False)
        self.params = self.built.params
        self.integrator = mi.load_dict({"type": integrator, "max_depth": max_depth})
        self.variables: dict = {}    # name -> drjit value
        self.specs: dict = {}        # name -> Variable
        self._textures: dict = {}    # mesh -> (parameter key, ProceduralTexture | None)
        self._bind_environment(scene.environment)

    # -- binding -------------------------------------------------------------------------
    def texture_key(self, mesh: str) -> str:
        """The Mitsuba parameter holding ``mesh``'s bitmap albedo."""
        if mesh not in self.scene.meshes:
            raise ConfigError("mesh", mesh, f"use one of the scene's meshes: {', '.join(self.scene.meshes)}")
        keys = [k for k in self.params.keys() if k.startswith(f"{mesh}.bsdf.")
                and k.endswith(("base_color.data", "reflectance.data"))]
        if not keys:
            raise ConfigError(f"{mesh}.material.texture", None, "give the mesh a textured Material (uv and texture)")
        return keys[0]

    def bind_texture(self, mesh: str) -> str:
        """Make ``mesh``'s bitmap albedo the variable ``<mesh>.texture``; returns its name."""
        key = self.texture_key(mesh)
        self._textures[mesh] = (key, None)
        return self._add(f"{mesh}.texture", Variable("texture", 0.0, 1.0, 0.02), type(self.params[key])(self.params[key]))

    def bind_procedural(self, mesh: str, texture) -> list[str]:
        """Replace ``mesh``'s bitmap by the procedural garment texture ``texture``
        (``GarmentTextureParams``) written in drjit, its pattern over the mesh material's
        ``pattern_coords`` (a garment's panels) where it has them; returns the variable names it adds."""
        key = self.texture_key(mesh)
        material = self.scene.meshes[mesh].material
        proc = ProceduralTexture(texture, self.params[key].shape[0], material.pattern_coords, material.texture_shade)
        self._textures[mesh] = (key, proc)
        return [self._add(f"{mesh}.{k}", VARIABLES[k], v) for k, v in proc.initial().items()]

    def bind_garments(self, recipe, prefix: str = "subject1") -> list[str]:
        """``bind_procedural`` for every garment of a subject added as ``prefix``."""
        names = []
        for g in recipe.garments:
            if f"{prefix}_{g.kind}" in self.scene.meshes:
                names += self.bind_procedural(f"{prefix}_{g.kind}", g.texture)
        return names

    def _bind_environment(self, env) -> None:
        import mitsuba as mi
        if self.sun is not None:
            start = (self.sun.elevation, self.sun.azimuth, 1.0, 1.0)
            for name, value in zip(SUN, start):
                self._add(name, ENVIRONMENT[name], mi.Float(value))
        elif isinstance(env, Constant):
            self._add("environment.radiance", ENVIRONMENT["environment.radiance"], mi.Color3f(*env.radiance))  # type: ignore[misc]
        elif isinstance(env, EnvMap):
            self._envmap = type(self.params["environment.data"])(self.params["environment.data"])
            self._add("environment.intensity", ENVIRONMENT["environment.intensity"], mi.Float(1.0))

    def _add(self, name: str, spec: Variable, value) -> str:
        self.variables[name], self.specs[name] = value, spec
        return name

    # -- values --------------------------------------------------------------------------
    def set(self, name: str, value) -> None:
        """Set a variable from numbers (or a drjit value, kept as is so gradients flow)."""
        spec = self._spec(name)
        self.variables[name] = value if _is_drjit(value) else drjit_value(spec.kind, value)

    def get(self, name: str):
        """A variable as plain numbers (float or list; the texture as an array)."""
        kind = self._spec(name).kind
        return np.array(self.variables[name]) if kind == "texture" else as_numbers(self.variables[name])

    def _spec(self, name: str) -> Variable:
        if name not in self.specs:
            raise ConfigError("params", name, f"use one of the bound variables: {', '.join(self.specs)} "
                              "(bind_texture / bind_procedural / bind_garments add more)")
        return self.specs[name]

    def apply(self) -> None:
        """Push every variable into the Mitsuba parameters (textures evaluated in drjit)."""
        for mesh, (key, proc) in self._textures.items():
            if proc is None:
                self.params[key] = self.variables[f"{mesh}.texture"]
            else:
                self.params[key] = proc.evaluate({k: self.variables[f"{mesh}.{k}"] for k in VARIABLES})
        v = self.variables
        if "environment.radiance" in v:
            self.params["environment.radiance.value"] = v["environment.radiance"]
        if "environment.intensity" in v:
            self.params["environment.data"] = self._envmap * v["environment.intensity"]
        if self.sun is not None:
            self.params["environment.data"] = self.sun.evaluate(*(v[k] for k in SUN))
        self.params.update()

    def _driven_keys(self) -> list:
        keys = [key for key, _ in self._textures.values()]
        if "environment.radiance" in self.variables:
            keys.append("environment.radiance.value")
        if "environment.intensity" in self.variables or self.sun is not None:
            keys.append("environment.data")
        return keys

    def render(self, camera: Camera, spp: int = 16, seed: int = 0):
        """The RGB image (H, W, 3) as a drjit tensor, differentiable in the variables whose
        gradients are enabled (``dr.enable_grad(ds.variables[name])``). The gradient pass traces
        its own paths (seed ``seed + 1``), so a loss's gradient is unbiased."""
        import mitsuba as mi
        from synmitsuba.rendering import sensor as sensor_mod
        from synmitsuba.engine.variant import require_variant
        if not isinstance(camera, Camera):
            raise ConfigError("camera", type(camera).__name__, "give a synmitsuba.Camera")
        sensor_mod.register(require_variant())
        self.apply()
        sensor = mi.load_dict(sensor_mod.sensor_dict(camera, spp))
        # only the parameters the variables drive (a full dict(params) fails on curve shapes' entries)
        driven = self.params.copy()
        driven.keep(self._driven_keys())
        img = mi.render(self.built.mi_scene, driven, sensor=sensor, integrator=self.integrator, spp=spp,
                        seed=seed, seed_grad=seed + 1)
        return img[:, :, :3] if img.shape[2] > 3 else img


def _is_drjit(value) -> bool:
    import drjit as dr
    return dr.is_array_v(value)
