"""``Scene``: what to render, as plain numpy data (meshes, curves, lights, environment).

The renderer (``synmitsuba.engine``) turns it into a Mitsuba scene and keeps that build
itself, checked against the scene's two versions: ``structure_version`` moves whenever shapes,
lights or the environment change (a reload), ``geometry_version`` when ``update_mesh`` /
``update_curves`` move positions (an update in place, compiled kernels reused). Assigning
``meshes``, ``curves``, ``lights`` or ``environment`` directly bumps the structure version
too, so no change can leave a stale build behind.
"""
from __future__ import annotations

import contextlib
import re
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.geometry import vertex_normals
from synmitsuba.schema import Number
from synmitsuba.scene.materials import (AreaLight, Constant, DirectionalLight, EnvMap, Material,
                                        PointLight, SunSky)

INSTANCE = Number(0, 2 ** 31 - 1, integer=True)
LAYER_ID = Number(0, 255, integer=True)
ENVIRONMENTS = (Constant, SunSky, EnvMap)
LIGHTS = (PointLight, DirectionalLight, AreaLight)


@dataclass
class MeshShape:
    name: str
    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray | None
    normals: np.ndarray | None
    material: Material
    instance: int
    layer: int
    previous_vertices: np.ndarray | None = None  # before the last update_mesh (for flow)


@dataclass
class CurveShape:
    name: str
    points: np.ndarray   # (N, K, 3) control points
    radius: np.ndarray   # (N, K)
    material: Material
    instance: int
    layer: int
    previous_points: np.ndarray | None = None  # before the last update_curves (for flow)


def _ids(name: str, instance, layer) -> tuple[int, int]:
    """Instance id in [0, 2^31) (0 = background/none) and layer id in [0, 255] (synmitsuba.Layer)."""
    return INSTANCE(f"{name}.instance", instance), LAYER_ID(f"{name}.layer", layer)


def _finite(field_name: str, arr: np.ndarray, shape_desc: str, ok: bool) -> np.ndarray:
    if not ok:
        raise ConfigError(field_name, f"array{arr.shape}", f"give a {shape_desc} array")
    if not np.isfinite(arr).all():
        bad = int(np.argwhere(~np.isfinite(arr))[0][0])
        raise ConfigError(field_name, f"array{arr.shape} with a non-finite value at row {bad}",
                          "all coordinates must be finite numbers")
    return arr


_STRUCTURE = frozenset({"meshes", "curves", "lights", "environment"})


@dataclass(eq=False)  # compared and hashed by identity: the engine keys its builds on scenes
class Scene:
    """Meshes, curves, lights and an environment in metres, world y up."""

    meshes: dict = field(default_factory=dict)
    curves: dict = field(default_factory=dict)
    lights: list = field(default_factory=list)
    environment: object = None
    structure_version: int = 0
    geometry_version: int = 0

    def __setattr__(self, name: str, value) -> None:
        object.__setattr__(self, name, value)
        if name in _STRUCTURE and "structure_version" in self.__dict__:
            object.__setattr__(self, "structure_version", self.structure_version + 1)

    def __copy__(self) -> "Scene":
        """A shallow copy with its own containers (adding to the copy leaves this scene alone)."""
        return Scene(dict(self.meshes), dict(self.curves), list(self.lights), self.environment)

    def _check_name(self, name: str) -> str:
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_\-]*", name):
            raise ConfigError("shape name", name, "use letters, digits, '_' or '-', starting with a letter or '_'")
        if name in self.meshes or name in self.curves:
            raise ConfigError("shape name", name, "names must be unique in a scene; pick another")
        return name

    def add_mesh(self, name: str, vertices, faces, uv=None, normals=None, material: Material | None = None,
                 instance: int = 0, layer: int = 0) -> MeshShape:
        """Add a triangle mesh: vertices (V, 3) metres, faces (F, 3) vertex indices, optional
        per-vertex uv (V, 2) and normals (V, 3); ``instance`` and ``layer`` go to the id passes."""
        self._check_name(name)
        v = np.asarray(vertices, dtype=np.float64)
        _finite(f"{name}.vertices", v, "V x 3 (V > 0)", v.ndim == 2 and v.shape[1:] == (3,) and len(v) > 0)
        f = np.asarray(faces)
        if f.ndim != 2 or f.shape[1:] != (3,) or len(f) == 0 or not np.issubdtype(f.dtype, np.integer):
            raise ConfigError(f"{name}.faces", f"array{f.shape} of {f.dtype}",
                              "give an F x 3 integer array with F > 0 (an empty mesh cannot be rendered)")
        if f.min() < 0 or f.max() >= len(v):
            raise ConfigError(f"{name}.faces", f"indices in [{f.min()}, {f.max()}]",
                              f"face indices must lie in [0, {len(v) - 1}] (the mesh has {len(v)} vertices)")
        if uv is not None:
            uv = np.asarray(uv, dtype=np.float64)
            _finite(f"{name}.uv", uv, f"{len(v)} x 2", uv.shape == (len(v), 2))
        if normals is not None:
            normals = np.asarray(normals, dtype=np.float64)
            _finite(f"{name}.normals", normals, f"{len(v)} x 3", normals.shape == (len(v), 3))
        inst, lay = _ids(name, instance, layer)
        shape = MeshShape(name, v, f.astype(np.uint32), uv, normals, material or Material(), inst, lay)
        self.meshes[name] = shape
        self.structure_version += 1
        return shape

    def add_curves(self, name: str, points, radius=0.001, material: Material | None = None,
                   instance: int = 0, layer: int = 0) -> CurveShape:
        """Add strands: points (N, K, 3) with K >= 2 joined by round segments (Mitsuba's
        ``linearcurve``; its ``bsplinecurve`` crashed on dense hair), radius (N, K) or scalar."""
        self._check_name(name)
        p = np.asarray(points, dtype=np.float64)
        _finite(f"{name}.points", p, "N x K x 3 (K >= 2)", p.ndim == 3 and p.shape[2] == 3 and p.shape[1] >= 2
                and p.shape[0] > 0)
        r = np.broadcast_to(np.asarray(radius, dtype=np.float64), p.shape[:2]).copy()
        if not (np.isfinite(r).all() and (r > 0).all()):
            raise ConfigError(f"{name}.radius", float(r.min()), "radii must be finite and > 0 metres")
        shade = None if material is None else material.strand_melanin
        if shade is not None and len(shade) != len(p):
            raise ConfigError(f"{name}.material.strand_melanin", f"{len(shade)} values",
                              f"give one melanin per strand: {len(p)}")
        inst, lay = _ids(name, instance, layer)
        shape = CurveShape(name, p, r, material or Material(), inst, lay)
        self.curves[name] = shape
        self.structure_version += 1
        return shape

    def update_mesh(self, name: str, vertices, normals=None) -> None:
        """Move a mesh's vertices (same count), with new per-vertex normals if given (else a mesh
        that has normals gets area-weighted ones from its faces); the next render updates
        Mitsuba in place."""
        if name not in self.meshes:
            raise ConfigError("shape name", name, f"no mesh of that name; meshes: {', '.join(self.meshes)}")
        mesh = self.meshes[name]
        v = np.asarray(vertices, dtype=np.float64)
        _finite(f"{name}.vertices", v, f"{len(mesh.vertices)} x 3", v.shape == mesh.vertices.shape)
        if normals is not None:
            n = np.asarray(normals, dtype=np.float64)
            _finite(f"{name}.normals", n, f"{len(mesh.vertices)} x 3", n.shape == mesh.vertices.shape)
            if mesh.normals is None:
                raise ConfigError(f"{name}.normals", "new normals", "add the mesh with normals to move them with it")
            mesh.normals = n
        elif mesh.normals is not None:
            mesh.normals = vertex_normals(v, mesh.faces)
        mesh.previous_vertices, mesh.vertices = mesh.vertices, v
        self.geometry_version += 1

    def update_curves(self, name: str, points, radius=None) -> None:
        """Move curves' control points (same strand and point count), optionally with new radii;
        the next render updates Mitsuba in place (no reload)."""
        if name not in self.curves:
            raise ConfigError("shape name", name, f"no curves of that name; curves: {', '.join(self.curves)}")
        c = self.curves[name]
        p = np.asarray(points, dtype=np.float64)
        _finite(f"{name}.points", p, "x".join(map(str, c.points.shape)), p.shape == c.points.shape)
        if radius is not None:
            r = np.broadcast_to(np.asarray(radius, dtype=np.float64), c.radius.shape)
            if not (np.isfinite(r).all() and (r > 0).all()):
                raise ConfigError(f"{name}.radius", float(np.min(r)), "radii must be finite and > 0 metres")
            c.radius = r.copy()
        c.previous_points, c.points = c.points, p
        self.geometry_version += 1

    @contextlib.contextmanager
    def keeping_previous(self):
        """Shapes moved inside the block (to another frame and back, sub-frames) keep the
        previous positions (flow's) they had before it."""
        meshes = {n: m.previous_vertices for n, m in self.meshes.items()}
        curves = {n: c.previous_points for n, c in self.curves.items()}
        try:
            yield self
        finally:
            for n, prev in meshes.items():
                self.meshes[n].previous_vertices = prev
            for n, prev in curves.items():
                self.curves[n].previous_points = prev

    def remove(self, name: str) -> None:
        if self.meshes.pop(name, None) is None and self.curves.pop(name, None) is None:
            raise ConfigError("shape name", name, "no shape of that name")
        self.structure_version += 1

    def set_environment(self, env) -> None:
        """Constant, SunSky or EnvMap; None for a black background."""
        if env is not None and not isinstance(env, ENVIRONMENTS):
            raise ConfigError("environment", type(env).__name__, "use sm.Constant, sm.SunSky or sm.EnvMap")
        self.environment = env
        self.structure_version += 1

    def add_light(self, light) -> None:
        if not isinstance(light, LIGHTS):
            raise ConfigError("light", type(light).__name__, "use sm.PointLight, sm.DirectionalLight or sm.AreaLight")
        self.lights.append(light)
        self.structure_version += 1
