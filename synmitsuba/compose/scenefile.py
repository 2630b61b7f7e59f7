"""Scene files (YAML): render settings, objects (trimesh primitives or mesh files), materials,
lights, an environment, cameras and subjects. See ``scenes/demo.yaml`` for every key. A scene
file compiles to a ``SceneSpec`` like a composed scene (``compose.scenefile_spec``).

The whole file is checked before anything is built (a typo in the last camera is reported
before seconds of subject building); errors name the key path (``objects[2].mesh``,
``render.spp``, ``subjects[1].motion``), the value and the fix.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from synmitsuba.compose.subjects import ClipSettings, PlacedSubject, SubjectEntry, subject_instances
from synmitsuba.errors import ConfigError
from synmitsuba.engine.settings import DENOISERS, SAMPLERS
from synmitsuba.rendering.photo import PhotoOptions
from synmitsuba.scene.lens import LENS_MODELS
from synmitsuba.schema import (AnyOf, Check, Choice, Flag, ListOf, MapOf, Nested, Number, Params, POSITIVE, Text, Vector,
                               construct, mapping, optional, read_yaml, spec)
from synmitsuba.scene import (AreaLight, Camera, Constant, DirectionalLight, EnvMap, Layer, Material, PointLight,
                              Scene, SunSky)

PRIMITIVES = ("box", "icosphere", "uv_sphere", "cylinder", "capsule", "cone", "torus", "annulus")
ENVIRONMENTS = {"constant": Constant, "sunsky": SunSky, "envmap": EnvMap}
LIGHTS = {"point": PointLight, "directional": DirectionalLight, "area": AreaLight}
MATERIAL_KEYS = ("kind", "base_color", "roughness", "metallic", "specular", "two_sided", "melanin", "redness")


class _Typed(Check):
    """A mapping ``{type: <kind>, ...}`` whose kind picks a plain-data class and whose other
    keys are that class's fields (``rename`` maps a file key onto a field)."""

    def __init__(self, classes: dict, rename: dict | None = None):
        self.classes, self.rename = classes, rename or {}

    def __call__(self, where: str, data):
        mapping(where, data)
        kind = Choice(tuple(self.classes))(f"{where}.type", data.get("type"))
        cls = self.classes[kind]
        allowed = {"type", *self.rename} | {f.name for f in fields(cls)} - set(self.rename.values())
        mapping(where, data, allowed)
        return data


class _MaterialKeys(Check):
    def __call__(self, where: str, data):
        return mapping(where, data, MATERIAL_KEYS)


class _Layer(Check):
    def __call__(self, where: str, value):
        if isinstance(value, str):
            names = tuple(layer.name.lower() for layer in Layer)
            return int(Layer[Choice(names)(where, value.lower()).upper()])
        return Number(0, 255, integer=True)(where, value)


@dataclass
class RenderSettings(Params):
    spp: int = spec(64, POSITIVE, doc="samples per pixel")
    max_depth: int = spec(6, POSITIVE, doc="path length")
    seed: int = spec(0, Number(0, 2 ** 32 - 1, integer=True))
    width: int = spec(320, POSITIVE, doc="pixels (cameras may override)")
    height: int = spec(240, POSITIVE)
    sampler: str = spec("auto", Choice(SAMPLERS), doc="auto: the best that keeps spp exactly")
    denoise: str = spec("none", Choice(DENOISERS), doc="oidn: Intel Open Image Denoise (synmitsuba[denoise])")
    shutter_deg: float = spec(0.0, Number(0, 360), doc="shutter angle (180: open half the frame interval); 0: no motion blur")
    subframes: int = spec(8, POSITIVE, doc="motion blur: renders across the exposure, spp shared among them")
    photo: PhotoOptions = spec(factory=PhotoOptions, check=Nested(PhotoOptions),
                               doc="exposure, white balance, sensor noise, JPEG (off by default)")


@dataclass
class ObjectSpec(Params):
    name: str | None = spec(None, optional(Text()))
    primitive: object = spec(None, doc="a kind name or {type: kind, ...trimesh.creation arguments}")
    mesh: str | None = spec(None, optional(Text()), doc="a mesh file, relative to the scene file")
    position: list = spec(factory=lambda: [0.0, 0.0, 0.0], check=Vector(3, what="x, y, z metres"))
    rotation_deg: list = spec(factory=lambda: [0.0, 0.0, 0.0], check=Vector(3, what="xyz Euler degrees"))
    scale: object = spec(1.0, AnyOf((Number(1e-9), Vector(3, 1e-9)), "give a positive number or 3 of them"))
    material: object = spec(None, doc="a name from materials or an inline material")
    instance: int | None = spec(None, optional(Number(0, 2 ** 31 - 1, integer=True)))
    layer: int = spec(int(Layer.OBJECT), _Layer())
    smooth: bool = spec(False, Flag())


@dataclass
class LookAt(Params):
    eye: list = spec(check=Vector(3, what="camera position, metres"), doc="[x, y, z] metres")
    target: list = spec(factory=lambda: [0.0, 1.0, 0.0], check=Vector(3))
    up: list = spec(factory=lambda: [0.0, 1.0, 0.0], check=Vector(3))
    fov_y_deg: float = spec(45.0, Number(1, 179))


@dataclass
class CameraSpec(Params):
    name: str | None = spec(None, optional(Text()))
    look_at: LookAt | None = spec(None, optional(Nested(LookAt)))
    K: list | None = spec(None, optional(ListOf(Vector(3), 3, 3)), doc="3x3 intrinsics, pixels")
    R: list | None = spec(None, optional(ListOf(Vector(3), 3, 3)), doc="3x3 world->camera rotation")
    t: list | None = spec(None, optional(Vector(3)))
    width: int | None = spec(None, optional(POSITIVE))
    height: int | None = spec(None, optional(POSITIVE))
    lens: str = spec("brown_conrady", Choice(tuple(LENS_MODELS)), doc="distortion model (OpenCV's)")
    dist: list | None = spec(None, optional(ListOf(Number(-10, 10))),
                             doc="distortion coefficients: k1, k2, p1, p2, k3 (fisheye: k1..k4)")
    aperture_radius: float = spec(0.0, Number(0, 1), doc="thin-lens aperture radius, metres (0: pinhole)")
    focus_distance: float = spec(1.0, Number(0.01, 1e4), doc="metres along the optical axis")

    def __post_init__(self):
        if (self.look_at is None) == (self.K is None):
            raise ConfigError("camera", "look_at" if self.look_at else None,
                              "give either look_at: {eye, target} or K (with R, t)")


@dataclass(kw_only=True)
class SceneDoc(Params):
    render: RenderSettings = spec(factory=RenderSettings, check=Nested(RenderSettings))
    environment: dict | None = spec(None, optional(_Typed(ENVIRONMENTS, {"file": "source"})))
    lights: list = spec(factory=list, check=ListOf(_Typed(LIGHTS)))
    materials: dict = spec(factory=dict, check=MapOf(_MaterialKeys()), doc="name: material")
    objects: list = spec(factory=list, check=ListOf(Nested(ObjectSpec)))
    cameras: list = spec(check=ListOf(Nested(CameraSpec), 1), doc="at least one camera")
    subjects: list = spec(factory=list, check=ListOf(Nested(SubjectEntry)))
    clip: ClipSettings = spec(factory=ClipSettings, check=Nested(ClipSettings), doc="the subjects' clips")

    def __post_init__(self):
        subject_instances(self.subjects, set(self.object_instances()))  # ids clash: fail before building

    def object_instances(self) -> list[int]:
        """Each object's id: its own or its index + 1."""
        return [i + 1 if o.instance is None else int(o.instance) for i, o in enumerate(self.objects)]


@dataclass
class SceneFile:
    """A loaded scene file: the scene (with its subjects posed), named cameras, settings."""

    scene: Scene
    cameras: list[tuple[str, Camera]]
    settings: RenderSettings
    subjects: list[PlacedSubject] = field(default_factory=list)
    path: str = ""


def _material(spec_, materials: dict, where: str) -> Material:
    if spec_ is None:
        return Material()
    if isinstance(spec_, str):
        return materials[Choice(tuple(materials) or ("<none defined>",))(where, spec_)]
    return construct(Material, dict(_MaterialKeys()(where, spec_)), where)


def _transform(obj: ObjectSpec) -> np.ndarray:
    from scipy.spatial.transform import Rotation
    M = np.eye(4)
    M[:3, :3] = Rotation.from_euler("xyz", obj.rotation_deg, degrees=True).as_matrix() @ np.diag(
        np.broadcast_to(np.asarray(obj.scale, dtype=np.float64), (3,)))
    M[:3, 3] = obj.position
    return M


def _mesh(obj: ObjectSpec, where: str, base: str):
    import trimesh
    if obj.primitive is not None:
        prim = dict(obj.primitive) if isinstance(obj.primitive, dict) else {"type": obj.primitive}
        kind = Choice(PRIMITIVES)(f"{where}.primitive.type", prim.pop("type", None))
        try:
            return getattr(trimesh.creation, kind)(**prim)
        except TypeError as exc:
            raise ConfigError(f"{where}.primitive", obj.primitive, f"bad arguments for trimesh.creation.{kind}: {exc}") from None
    if obj.mesh is not None:
        path = os.path.join(base, obj.mesh)
        if not os.path.isfile(path):
            raise ConfigError(f"{where}.mesh", obj.mesh, f"file not found ({path}); paths are relative to the scene file")
        mesh: Any = trimesh.load(path, force="mesh", process=False)
        if len(mesh.faces) == 0:
            raise ConfigError(f"{where}.mesh", obj.mesh, "the file holds no triangles")
        return mesh
    raise ConfigError(where, obj.name, "give either 'primitive' or 'mesh'")


def _add_object(scene: Scene, obj: ObjectSpec, i: int, instance: int, materials: dict, base: str) -> None:
    where = f"objects[{i}]"
    mesh = _mesh(obj, where, base)
    mesh.apply_transform(_transform(obj))
    scene.add_mesh(obj.name or f"object_{i}", mesh.vertices, mesh.faces, uv=getattr(mesh.visual, "uv", None),
                   normals=mesh.vertex_normals if obj.smooth else None,
                   material=_material(obj.material, materials, f"{where}.material"),
                   instance=instance, layer=obj.layer)


def _typed(classes: dict, data: dict, where: str, base: str):
    args = {k: v for k, v in data.items() if k != "type"}
    if "file" in args:
        args["source"] = os.path.join(base, str(args.pop("file")))
    return construct(classes[data["type"]], args, where)


def _camera(spec_: CameraSpec, where: str, settings: RenderSettings) -> tuple[str, Camera]:
    w = settings.width if spec_.width is None else spec_.width
    h = settings.height if spec_.height is None else spec_.height
    name = spec_.name or where.replace("[", "_").replace("]", "")
    optics = {"lens": spec_.lens, "dist": spec_.dist, "aperture_radius": spec_.aperture_radius,
              "focus_distance": spec_.focus_distance}
    if spec_.look_at is not None:
        la = spec_.look_at
        try:
            cam = Camera.look_at(eye=la.eye, target=la.target, up=la.up, fov_y_deg=la.fov_y_deg, width=w, height=h)
        except ConfigError as exc:
            raise ConfigError(f"{where}.look_at.{exc.field.split('.')[-1]}", exc.value, exc.fix) from None
        return name, construct(Camera, {"K": cam.K, "R": cam.R, "t": cam.t, "width": w, "height": h, **optics}, where)
    R = np.eye(3) if spec_.R is None else spec_.R
    t = [0.0, 0.0, 0.0] if spec_.t is None else spec_.t
    return name, construct(Camera, {"K": spec_.K, "R": R, "t": t, "width": w, "height": h, **optics}, where)


def read_scene_doc(path: str) -> SceneDoc:
    """The checked contents of a scene file (nothing built yet)."""
    return SceneDoc.from_dict(read_yaml(path, "scene file", "objects, cameras, ..."), "")


def check_scene_file(path: str, where: str = "") -> SceneDoc:
    """The scene file read and every key and file it names checked (nothing built); errors
    name the key path in the file (after ``where``, the setting that named the file), the
    value and the fix."""
    if not os.path.isfile(path):
        raise ConfigError(where or "scene file", path, "no such file; give a YAML scene file (scenes/demo.yaml shows "
                          "every key)")
    try:
        doc = read_scene_doc(path)
        base = os.path.dirname(os.path.abspath(path))
        for i, e in enumerate(doc.subjects):
            e.check_files(f"subjects[{i}]", base)
        for i, o in enumerate(doc.objects):
            if o.mesh is not None and not os.path.isfile(os.path.join(base, o.mesh)):
                raise ConfigError(f"objects[{i}].mesh", o.mesh, "file not found; paths are relative to the scene file")
    except ConfigError as exc:
        if not where:
            raise
        raise ConfigError(f"{where}: {exc.field}", exc.value, f"{exc.fix} (in {path})") from None
    return doc


def static_scene(doc: SceneDoc, path: str) -> Scene:
    """The scene file's objects, environment and lights; relative paths are taken from
    ``path``'s folder."""
    base = os.path.dirname(os.path.abspath(path))
    materials = {name: _material(m, {}, f"materials.{name}") for name, m in doc.materials.items()}
    scene = Scene()
    for i, (obj, instance) in enumerate(zip(doc.objects, doc.object_instances())):
        _add_object(scene, obj, i, instance, materials, base)
    if doc.environment is not None:
        scene.set_environment(_typed(ENVIRONMENTS, doc.environment, "environment", base))
    for i, light in enumerate(doc.lights):
        scene.add_light(_typed(LIGHTS, light, f"lights[{i}]", base))
    return scene


def scene_cameras(doc: SceneDoc) -> list[tuple[str, Camera]]:
    return [_camera(c, f"cameras[{i}]", doc.render) for i, c in enumerate(doc.cameras)]
