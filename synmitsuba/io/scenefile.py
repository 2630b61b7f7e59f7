"""Scene files (YAML): objects (trimesh primitives or mesh files), materials, lights, an
environment and cameras. See ``scenes/demo.yaml`` for every key.

Errors name the offending key path (``objects[2].mesh``), its value and the fix.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np
import yaml

from synmitsuba.errors import ConfigError
from synmitsuba.scene import (AreaLight, Camera, Constant, DirectionalLight, EnvMap, Layer, Material,
                              PointLight, Scene, SunSky)

PRIMITIVES = ("box", "icosphere", "uv_sphere", "cylinder", "capsule", "cone", "torus", "annulus")
TOP_KEYS = {"render", "environment", "lights", "materials", "objects", "cameras", "subjects"}


@dataclass
class RenderSettings:
    spp: int = 64
    max_depth: int = 6
    seed: int = 0
    width: int = 320
    height: int = 240


@dataclass
class SceneFile:
    scene: Scene
    cameras: list[tuple[str, Camera]]
    settings: RenderSettings
    subjects: list = field(default_factory=list)  # raw subject entries, for later stages
    path: str = ""


def _get(d: dict, key: str, where: str, default=None, required: bool = False):
    if not isinstance(d, dict):
        raise ConfigError(where, d, "expected a mapping (key: value)")
    if required and key not in d:
        raise ConfigError(f"{where}.{key}", None, f"the key '{key}' is required")
    return d.get(key, default)


def _check_keys(d: dict, allowed: set, where: str) -> None:
    if not isinstance(d, dict):
        raise ConfigError(where, d, "expected a mapping (key: value)")
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise ConfigError(f"{where}.{unknown[0]}", d[unknown[0]], f"unknown key; allowed: {', '.join(sorted(allowed))}")


def _material(spec, materials: dict, where: str) -> Material:
    if spec is None:
        return Material()
    if isinstance(spec, str):
        if spec not in materials:
            raise ConfigError(where, spec, f"no such material; defined: {', '.join(materials) or 'none'}")
        return materials[spec]
    _check_keys(spec, {"kind", "base_color", "roughness", "metallic", "specular", "two_sided"}, where)
    try:
        return Material(**spec)
    except ConfigError as exc:
        raise ConfigError(f"{where}.{exc.field.split('.', 1)[-1]}", exc.value, exc.fix) from None


def _transform(obj: dict, where: str) -> np.ndarray:
    from scipy.spatial.transform import Rotation
    M = np.eye(4)
    scale = np.broadcast_to(np.asarray(obj.get("scale", 1.0), dtype=np.float64), (3,))
    rot = obj.get("rotation_deg", [0, 0, 0])
    pos = obj.get("position", [0, 0, 0])
    try:
        M[:3, :3] = Rotation.from_euler("xyz", rot, degrees=True).as_matrix() @ np.diag(scale)
        M[:3, 3] = np.asarray(pos, dtype=np.float64).reshape(3)
    except (ValueError, TypeError):
        raise ConfigError(f"{where}.position/rotation_deg/scale", {"position": pos, "rotation_deg": rot},
                          "give position [x, y, z] metres, rotation_deg [rx, ry, rz] and scale (number or 3)") from None
    return M


def _mesh(obj: dict, where: str, base: str):
    import trimesh
    if "primitive" in obj:
        prim = dict(obj["primitive"]) if isinstance(obj["primitive"], dict) else {"type": obj["primitive"]}
        kind = prim.pop("type", None)
        if kind not in PRIMITIVES:
            raise ConfigError(f"{where}.primitive.type", kind, f"use one of {', '.join(PRIMITIVES)}")
        try:
            return getattr(trimesh.creation, kind)(**prim)
        except TypeError as exc:
            raise ConfigError(f"{where}.primitive", obj["primitive"], f"bad arguments for trimesh.creation.{kind}: {exc}") from None
    if "mesh" in obj:
        path = os.path.join(base, str(obj["mesh"]))
        if not os.path.isfile(path):
            raise ConfigError(f"{where}.mesh", obj["mesh"], f"file not found ({path}); paths are relative to the scene file")
        mesh = trimesh.load(path, force="mesh", process=False)
        if len(mesh.faces) == 0:
            raise ConfigError(f"{where}.mesh", obj["mesh"], "the file holds no triangles")
        return mesh
    raise ConfigError(where, obj.get("name"), "give either 'primitive' or 'mesh'")


def _layer(value, where: str) -> int:
    if isinstance(value, str):
        try:
            return int(Layer[value.upper()])
        except KeyError:
            raise ConfigError(where, value, f"use a number or one of {', '.join(l.name.lower() for l in Layer)}") from None
    return value


def _add_object(scene: Scene, obj: dict, i: int, materials: dict, base: str) -> None:
    where = f"objects[{i}]"
    _check_keys(obj, {"name", "primitive", "mesh", "position", "rotation_deg", "scale", "material",
                      "instance", "layer", "smooth"}, where)
    mesh = _mesh(obj, where, base)
    mesh.apply_transform(_transform(obj, where))
    normals = mesh.vertex_normals if obj.get("smooth", False) else None
    uv = getattr(mesh.visual, "uv", None)
    scene.add_mesh(str(obj.get("name", f"object_{i}")), mesh.vertices, mesh.faces, uv=uv, normals=normals,
                   material=_material(obj.get("material"), materials, f"{where}.material"),
                   instance=obj.get("instance", i + 1), layer=_layer(obj.get("layer", int(Layer.OBJECT)), f"{where}.layer"))


def _environment(spec, where: str, base: str):
    if spec is None:
        return None
    kind = _get(spec, "type", where, required=True)
    args = {k: v for k, v in spec.items() if k != "type"}
    if kind == "envmap" and "file" in args:
        args["source"] = os.path.join(base, str(args.pop("file")))
    classes = {"constant": Constant, "sunsky": SunSky, "envmap": EnvMap}
    if kind not in classes:
        raise ConfigError(f"{where}.type", kind, f"use one of {', '.join(classes)}")
    try:
        env = classes[kind](**args)
    except TypeError as exc:
        raise ConfigError(where, spec, f"bad keys for {kind}: {exc}") from None
    if isinstance(env, EnvMap):
        env.pixels()  # fail now on a missing file
    return env


def _light(spec, where: str):
    classes = {"point": PointLight, "directional": DirectionalLight, "area": AreaLight}
    kind = _get(spec, "type", where, required=True)
    if kind not in classes:
        raise ConfigError(f"{where}.type", kind, f"use one of {', '.join(classes)}")
    try:
        return classes[kind](**{k: v for k, v in spec.items() if k != "type"})
    except TypeError as exc:
        raise ConfigError(where, spec, f"bad keys for a {kind} light: {exc}") from None


def _camera(spec, where: str, settings: RenderSettings) -> tuple[str, Camera]:
    _check_keys(spec, {"name", "look_at", "K", "R", "t", "width", "height"}, where)
    w, h = spec.get("width", settings.width), spec.get("height", settings.height)
    name = str(spec.get("name", where.replace("[", "_").replace("]", "")))
    if "look_at" in spec:
        la = spec["look_at"]
        _check_keys(la, {"eye", "target", "up", "fov_y_deg"}, f"{where}.look_at")
        cam = Camera.look_at(eye=_get(la, "eye", f"{where}.look_at", required=True),
                             target=la.get("target", [0, 1, 0]), up=la.get("up", [0, 1, 0]),
                             fov_y_deg=la.get("fov_y_deg", 45.0), width=w, height=h)
    else:
        cam = Camera(K=_get(spec, "K", where, required=True), R=spec.get("R", np.eye(3)),
                     t=spec.get("t", [0, 0, 0]), width=w, height=h)
    return name, cam


def load_scene_file(path: str) -> SceneFile:
    """Parse a YAML scene file into a Scene, its cameras and render settings."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ConfigError("scene file", path, "no such file")
    try:
        with open(path) as fh:
            doc = yaml.safe_load(fh)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ConfigError("scene file", path, f"malformed YAML{at}: {getattr(exc, 'problem', exc)}") from None
    if not isinstance(doc, dict):
        raise ConfigError("scene file", path, "the top level must be a mapping with objects, cameras, ...")
    _check_keys(doc, TOP_KEYS, "scene")
    base = os.path.dirname(os.path.abspath(path))
    rs = doc.get("render") or {}
    _check_keys(rs, set(RenderSettings.__dataclass_fields__), "render")
    settings = RenderSettings(**rs)
    materials = {}
    for name, spec in (doc.get("materials") or {}).items():
        materials[name] = _material(spec, {}, f"materials.{name}")
    scene = Scene()
    for i, obj in enumerate(doc.get("objects") or []):
        _add_object(scene, obj, i, materials, base)
    scene.set_environment(_environment(doc.get("environment"), "environment", base))
    for i, spec in enumerate(doc.get("lights") or []):
        scene.add_light(_light(spec, f"lights[{i}]"))
    cams = [_camera(spec, f"cameras[{i}]", settings) for i, spec in enumerate(doc.get("cameras") or [])]
    if not cams:
        raise ConfigError("cameras", None, "define at least one camera (look_at: {eye, target} or K, R, t)")
    return SceneFile(scene, cams, settings, list(doc.get("subjects") or []), path)
