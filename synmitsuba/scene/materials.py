"""Materials, environments and lights: plain data that the renderer turns into Mitsuba dicts.

Colours are linear RGB in [0, 1]. Textures are float32 arrays (H, W, 3) of linear albedo (a
uint8 array is taken as sRGB-encoded and decoded once, so it stays differentiable downstream);
bump, normal and roughness maps are data: a uint8 one is only scaled to [0, 1].
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.schema import Number

UNIT = Number(0.0, 1.0)

MATERIAL_KINDS = ("diffuse", "principled", "hair")


def _rgb(name: str, value) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if arr.size == 1:
        arr = np.repeat(arr, 3)
    if arr.size != 3 or not np.isfinite(arr).all() or (arr < 0).any():
        raise ConfigError(name, value, "give 3 finite, non-negative linear RGB values (or one grey value)")
    return float(arr[0]), float(arr[1]), float(arr[2])


def _image(name: str, value, channels: int | None, colour: bool = False) -> np.ndarray:
    """A float32 image; uint8 is read as 8-bit [0, 1], sRGB-decoded only for ``colour`` (an
    albedo): heights, normals and roughness are data, not colours."""
    arr = np.asarray(value)
    if arr.dtype == np.uint8:
        arr = arr.astype(np.float32) / 255.0
        if colour:
            from synmitsuba._colour import srgb_decode
            arr = srgb_decode(arr)
    arr = np.ascontiguousarray(arr, dtype=np.float32)
    want = "H x W" if channels is None else f"H x W x {channels}"
    ok = arr.ndim == 2 if channels is None else (arr.ndim == 3 and arr.shape[2] == channels)
    if not ok or min(arr.shape[:2]) < 1:
        raise ConfigError(name, f"array{arr.shape}", f"give an {want} array")
    if not np.isfinite(arr).all():
        raise ConfigError(name, f"array{arr.shape}", "texture values must be finite")
    return arr


@dataclass
class Material:
    """A surface material.

    kind: ``diffuse`` (Lambertian), ``principled`` (Disney-style; roughness, metallic,
    specular) or ``hair`` (Mitsuba's hair BSDF for curves, coloured by ``melanin``, 0 blond .. 1
    black, and ``redness``, the pheomelanin share, 0 .. 1 red).
    ``strand_melanin`` (N,) in [0, 1] gives a ``hair`` material on curves of N strands one
    melanin per strand (replacing ``melanin``): locks of slightly different shade.
    ``texture`` replaces ``base_color``; ``roughness_map`` (H, W in [0, 1]) replaces
    ``roughness`` for ``principled``; both are repeated ``texture_repeat`` (u, v) times over the
    uv square; ``bump`` (H, W height map, scaled by ``bump_scale``)
    and ``normal_map`` (H, W, 3 tangent-space, [0, 1]-encoded, repeated ``normal_map_repeat``
    (u, v) times over the uv square; over the bump when both are given) perturb shading normals.
    ``translucency`` (H, W in [0, 1], over the uv square as ``texture``) blends a ``principled``
    surface towards a thin one that passes light through diffusely, tinted by its colour: skin
    where it is thin (ears, nostrils, the webs between fingers) glows when lit from behind.
    """

    base_color: float | tuple = (0.5, 0.5, 0.5)
    texture: np.ndarray | None = None
    kind: str = "diffuse"
    roughness: float = 0.5
    metallic: float = 0.0
    specular: float = 0.5
    bump: np.ndarray | None = None
    bump_scale: float = 1.0
    normal_map: np.ndarray | None = None
    normal_map_repeat: tuple = (1.0, 1.0)
    roughness_map: np.ndarray | None = None
    texture_repeat: tuple = (1.0, 1.0)
    two_sided: bool = True
    melanin: float = 0.3
    redness: float = 0.0
    strand_melanin: np.ndarray | None = None
    translucency: np.ndarray | None = None
    name: str = ""
    pattern_coords: np.ndarray | None = None  # (H, W, 2): where a garment's pattern was drawn per texel
    # (body.panels; not rendered: diff.ProceduralTexture redraws the texture over the same coordinates)
    texture_shade: np.ndarray | None = None  # (H, W): what a garment's pattern was multiplied by for ``texture``
    # (its folds' creases, body.folds; not rendered: diff.ProceduralTexture shades its texture the same)

    def __post_init__(self):
        self.base_color = _rgb("material.base_color", self.base_color)
        if self.kind not in MATERIAL_KINDS:
            raise ConfigError("material.kind", self.kind, f"use one of {', '.join(MATERIAL_KINDS)}")
        for f in ("roughness", "metallic", "specular", "melanin", "redness"):
            setattr(self, f, UNIT(f"material.{f}", getattr(self, f)))
        if self.strand_melanin is not None:
            m = np.asarray(self.strand_melanin, np.float64).ravel()
            if not np.isfinite(m).all() or m.min() < 0 or m.max() > 1:
                raise ConfigError("material.strand_melanin", f"values in [{m.min():.3g}, {m.max():.3g}]",
                                  "give melanin values in [0, 1], one per strand")
            self.strand_melanin = m
        if self.texture is not None:
            self.texture = _image("material.texture", self.texture, 3, colour=True)
        if self.bump is not None:
            self.bump = _image("material.bump", self.bump, None)
        if self.normal_map is not None:
            self.normal_map = _image("material.normal_map", self.normal_map, 3)
        self.normal_map_repeat = _repeat("material.normal_map_repeat", self.normal_map_repeat)
        self.texture_repeat = _repeat("material.texture_repeat", self.texture_repeat)
        for f in ("roughness_map", "translucency"):
            m = getattr(self, f)
            if m is not None:
                setattr(self, f, m := _image(f"material.{f}", m, None))
                if m.min() < 0 or m.max() > 1:
                    raise ConfigError(f"material.{f}", f"values in [{m.min():.3g}, {m.max():.3g}]",
                                      "give values in [0, 1]")


@dataclass
class Blend:
    """Two materials mixed by a weight map (H, W) in [0, 1] (0: ``a``, 1: ``b``) repeated
    ``weight_repeat`` (u, v) times over the uv square, under one optional tangent-space
    ``normal_map`` (as ``Material``'s). Grounds use it to vary a tiled material over tens of metres."""

    a: Material
    b: Material
    weight: np.ndarray
    weight_repeat: tuple = (1.0, 1.0)
    normal_map: np.ndarray | None = None
    normal_map_repeat: tuple = (1.0, 1.0)
    name: str = ""

    def __post_init__(self):
        for f in ("a", "b"):
            if not isinstance(getattr(self, f), Material) or getattr(self, f).normal_map is not None:
                raise ConfigError(f"blend.{f}", type(getattr(self, f)).__name__,
                                  "give a Material without a normal map (the blend carries it)")
        self.weight = _image("blend.weight", self.weight, None)
        if self.weight.min() < 0 or self.weight.max() > 1:
            raise ConfigError("blend.weight", f"values in [{self.weight.min():.3g}, {self.weight.max():.3g}]",
                              "give weights in [0, 1]")
        if self.normal_map is not None:
            self.normal_map = _image("blend.normal_map", self.normal_map, 3)
        self.weight_repeat = _repeat("blend.weight_repeat", self.weight_repeat)
        self.normal_map_repeat = _repeat("blend.normal_map_repeat", self.normal_map_repeat)


def _repeat(name: str, value) -> tuple[float, float]:
    rep = np.asarray(value, np.float64).ravel()
    if rep.size != 2 or not np.isfinite(rep).all() or (rep <= 0).any():
        raise ConfigError(name, value, "give two positive repeats (u, v)")
    return float(rep[0]), float(rep[1])


# Mitsuba's hair BSDF absorption per unit eumelanin and pheomelanin concentration (linear RGB)
EUMELANIN_SIGMA_A = np.array([0.419, 0.697, 1.37])
PHEOMELANIN_SIGMA_A = np.array([0.187, 0.4, 1.05])


def hair_pigments(melanin, redness) -> tuple:
    """(eumelanin, pheomelanin) concentrations of a ``hair`` material: melanin 0 .. 1 maps to
    eumelanin 0 .. 8 (blond .. black), redness to pheomelanin 0.2 .. 3."""
    return 8.0 * np.asarray(melanin, np.float64), 0.2 + 2.8 * np.asarray(redness, np.float64)


def hair_sigma_a(melanin, redness) -> np.ndarray:
    """Absorption coefficient (..., 3) of hair of this melanin and redness."""
    eu, pheo = hair_pigments(melanin, redness)
    return eu[..., None] * EUMELANIN_SIGMA_A + pheo[..., None] * PHEOMELANIN_SIGMA_A


# -- environments ----------------------------------------------------------------------
@dataclass
class Constant:
    """Uniform environment light of the given radiance (grey value or RGB)."""

    radiance: float | tuple = 1.0

    def __post_init__(self):
        self.radiance = _rgb("environment.radiance", self.radiance)


@dataclass
class SunSky:
    """Mitsuba's physical sun and sky (Hosek-Wilkie); ``sun_direction`` points towards the sun,
    world y up."""

    sun_direction: tuple = (0.3, 1.0, 0.2)
    turbidity: float = 3.0
    albedo: float = 0.3
    sun_scale: float = 1.0
    sky_scale: float = 1.0

    def __post_init__(self):
        d = np.asarray(self.sun_direction, dtype=np.float64)
        if d.shape != (3,) or not np.isfinite(d).all() or np.linalg.norm(d) == 0:
            raise ConfigError("environment.sun_direction", self.sun_direction, "give a non-zero 3-vector")
        if d[1] <= 0:
            raise ConfigError("environment.sun_direction", self.sun_direction,
                              "the sun must be above the horizon: y component > 0")
        self.sun_direction = tuple(float(x) for x in d / np.linalg.norm(d))
        if not 1 <= self.turbidity <= 10:
            raise ConfigError("environment.turbidity", self.turbidity, "give a value in [1, 10]")


@dataclass
class EnvMap:
    """An equirectangular HDR environment (EXR/HDR file or (H, W, 3) array), y up; negative
    pixels of lossy files are clamped to 0. ``rotation_deg`` turns it about the y axis. With a
    ``dome`` (``scene.panorama.Dome``), pixels that see the background show the panorama as
    projected on that dome (a ground-projected HDRI's walls), not at infinity."""

    source: object = None
    scale: float = 1.0
    rotation_deg: float = 0.0
    dome: object = None   # a scene.panorama.Dome: the camera sees the panorama on it (lighting stays at infinity)

    def __post_init__(self):
        if isinstance(self.source, np.ndarray):
            self.source = _image("environment.source", self.source, 3, colour=True)
        elif not isinstance(self.source, (str, os.PathLike)) or not os.path.isfile(self.source):
            raise ConfigError("environment.file", self.source, "give the path of an existing .exr or .hdr file "
                              "(or an H x W x 3 array)")
        if not (isinstance(self.scale, (int, float)) and self.scale >= 0):
            raise ConfigError("environment.scale", self.scale, "give a number >= 0")

    def pixels(self) -> np.ndarray:
        if isinstance(self.source, np.ndarray):
            arr = self.source
        elif str(self.source).lower().endswith(".exr"):
            # OpenEXR's own reader: mi.Bitmap's EXR loader hangs when drjit runs one thread
            # (SYNMITSUBA_THREADS=1, as each worker of a 2-worker run on 2 cores does)
            import OpenEXR
            with OpenEXR.File(str(self.source), separate_channels=True) as f:
                ch = f.channels()
                arr = np.stack([ch[c].pixels for c in "RGB"], -1).astype(np.float32)
        else:
            import mitsuba as mi
            bmp = mi.Bitmap(str(self.source)).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
            arr = np.array(bmp, dtype=np.float32)
        return np.clip(np.nan_to_num(arr, nan=0.0, posinf=0.0), 0.0, None)


# -- lights ----------------------------------------------------------------------------
@dataclass
class PointLight:
    position: tuple = (0.0, 3.0, 0.0)
    intensity: float | tuple = 10.0  # W/sr per channel

    def __post_init__(self):
        self.intensity = _rgb("light.intensity", self.intensity)


@dataclass
class DirectionalLight:
    direction: tuple = (0.0, -1.0, 0.0)  # direction the light travels
    irradiance: float | tuple = 3.0

    def __post_init__(self):
        self.irradiance = _rgb("light.irradiance", self.irradiance)


@dataclass
class AreaLight:
    """A one-sided rectangle emitter of ``size`` (w, h) metres at ``position`` facing ``target``."""

    position: tuple = (0.0, 3.0, 0.0)
    target: tuple = (0.0, 0.0, 0.0)
    size: tuple = (1.0, 1.0)
    radiance: float | tuple = 5.0

    def __post_init__(self):
        self.radiance = _rgb("light.radiance", self.radiance)
