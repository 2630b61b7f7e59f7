"""A sun whose direction has gradients: Mitsuba's sky baked into an environment map, plus the
sun as a smooth lobe written in drjit over that map's texels.

Mitsuba 3.9's ``prb`` differentiates an emitter only through its radiance at fixed directions,
so moving ``sunsky``'s tiny disk (or a ``directional`` light) is a boundary effect it leaves
out. Here the sun is radiance in fixed directions: a von Mises-Fisher lobe
``E * k / (2 pi (1 - exp(-2k))) * exp(k (w . s - 1))`` on the texels of an equirectangular
map, with ``k = 1 / sigma^2`` for an angular spread ``sigma`` (``soft_sun_deg``) a few texels
wide. Its integral over the sphere is the sun's irradiance ``E``, measured from Mitsuba's own
sun disk, so a surface facing it is lit as by the sunsky; shadows are softer (a penumbra of
about ``2 sigma``). Moving ``s`` changes texel values only, and ``prb`` follows that exactly.
The sky stays as baked for the starting sun: only the sun moves.

Directions follow ``compose.environments``: elevation above the ground, azimuth from +z
towards +x, ``(cos el sin az, sin el, cos el cos az)``.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from synmitsuba.engine.build import aligned_floats
from synmitsuba.errors import ConfigError
from synmitsuba.schema import Number

CAP_DEG = 0.5         # the cap around the sun over which its disk's irradiance is integrated
CAP_SAMPLES = 65536


def sun_angles(direction) -> tuple[float, float]:
    """(elevation, azimuth) in degrees of a direction towards the sun."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    return float(np.degrees(np.arcsin(np.clip(d[1], -1, 1)))), float(np.degrees(np.arctan2(d[0], d[2])))


def texel_directions(height: int, width: int) -> np.ndarray:
    """World directions (height, width + 2, 3) of the texels Mitsuba's ``envmap`` stores for an
    identity ``to_world``: rows from the zenith (v = i / (H - 1)) to the nadir, columns at
    u = (j + 0.5) / W, padded with the last column in front and the first behind."""
    v = np.arange(height) / (height - 1)
    u = (np.arange(-1, width + 1) % width + 0.5) / width
    theta, phi = np.pi * v[:, None], 2 * np.pi * u[None, :]
    return np.stack(np.broadcast_arrays(np.sin(theta) * np.sin(phi), np.cos(theta),
                                        -np.sin(theta) * np.cos(phi)), -1)


def _evaluate(emitter, directions: np.ndarray) -> np.ndarray:
    """An emitter's radiance (N, 3) seen along world directions (N, 3) towards the sky."""
    import drjit as dr
    import mitsuba as mi
    si = dr.zeros(mi.SurfaceInteraction3f, len(directions))
    si.wi = mi.Vector3f(*(aligned_floats(-c) for c in directions.T))  # one kernel at any address
    return np.asarray(emitter.eval(si), dtype=np.float64).T


class SoftSun:
    """The baked sky and the sun's lobe for a ``SunSky`` environment; ``evaluate`` gives the
    envmap's ``data`` tensor from (differentiable) sun angles and scales."""

    def __init__(self, env, soft_sun_deg: float = 2.0, width: int = 512):
        import mitsuba as mi
        from synmitsuba.engine.build import environment_dict
        self.sigma = float(Number(0.25, 20)("soft_sun_deg", soft_sun_deg))
        self.kappa = float(1.0 / np.radians(self.sigma) ** 2)
        self.height, self.width = width // 2, width
        self.elevation, self.azimuth = sun_angles(env.sun_direction)
        full = mi.load_dict(environment_dict(env))  # type: ignore[arg-type]  # a SunSky: never None
        sky = mi.load_dict(environment_dict(dataclasses.replace(env, sun_scale=0.0)))  # type: ignore[arg-type]
        dirs = texel_directions(self.height, self.width)
        self.sky = _evaluate(sky, dirs.reshape(-1, 3)).reshape(*dirs.shape[:2], 3).astype(np.float32)
        self.irradiance = self._sun_irradiance(full, sky, np.asarray(env.sun_direction, dtype=np.float64))
        self._dirs = mi.Vector3f(*(aligned_floats(c) for c in dirs.reshape(-1, 3).T))
        self._sky = mi.Color3f(*(aligned_floats(c) for c in self.sky.reshape(-1, 3).T))

    @staticmethod
    def _sun_irradiance(full, sky, sun: np.ndarray) -> np.ndarray:
        """The sun disk's irradiance (RGB): (full - sky) radiance integrated over a cap around
        it, stratified in solid angle."""
        from synmitsuba.geometry import frame
        n = int(np.sqrt(CAP_SAMPLES))
        a, b = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n)
        cos_cap = np.cos(np.radians(CAP_DEG))
        ct = 1 - a.ravel() * (1 - cos_cap)
        st, ph = np.sqrt(1 - ct ** 2), 2 * np.pi * b.ravel()
        F = frame(sun, [0, 0, 1] if abs(sun[1]) > 0.99 else [0, 1, 0], keep="forward")
        d = np.stack([st * np.cos(ph), st * np.sin(ph), ct], 1) @ F.T
        solid_angle = 2 * np.pi * (1 - cos_cap)
        return (_evaluate(full, d) - _evaluate(sky, d)).mean(0) * solid_angle

    def image(self) -> np.ndarray:
        """The sky alone (H, W, 3), what the envmap is built from before the sun is added."""
        return self.sky[:, 1:-1]

    def evaluate(self, elevation_deg, azimuth_deg, sun_scale, sky_scale):
        """The envmap ``data`` tensor (H, W + 2, 3): sky * sky_scale + the sun's lobe * sun_scale."""
        import drjit as dr
        import mitsuba as mi
        el, az = dr.deg2rad(elevation_deg), dr.deg2rad(azimuth_deg)
        s = mi.Vector3f(dr.cos(el) * dr.sin(az), dr.sin(el), dr.cos(el) * dr.cos(az))
        k = self.kappa
        lobe = float(k / (2 * np.pi * (1 - np.exp(-2 * k)))) * dr.exp(k * (dr.dot(self._dirs, s) - 1))
        E = mi.Color3f(*(float(x) for x in self.irradiance))
        value = self._sky * sky_scale + E * (lobe * sun_scale)
        return mi.TensorXf(dr.ravel(value), shape=(self.height, self.width + 2, 3))


def check_sun(env, soft_sun_deg) -> None:
    from synmitsuba.scene.materials import SunSky
    if soft_sun_deg is not None and not isinstance(env, SunSky):
        raise ConfigError("soft_sun_deg", soft_sun_deg, "a soft sun replaces a SunSky environment; this scene's is "
                          f"{type(env).__name__}: leave soft_sun_deg=None")
