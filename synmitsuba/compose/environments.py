"""Environments: a textured ground that reaches the horizon, static objects and lighting, each
described by a YAML file in ``scenes/environments/`` (``ENVIRONMENTS`` lists them by name).

An environment is a template: ``sample_lighting`` draws the sun (direction, turbidity) or
the HDRI's rotation and scale from ranges, and ``add_environment`` puts the ground, the objects
and the drawn lighting into a ``Scene``. Objects are boxes to placement and camera checks:
``object_boxes`` gives their world-space bounds ``(x_min, y_min, z_min, x_max, y_max, z_max)``.
"""
from __future__ import annotations

import dataclasses
import functools
import glob
import os
from dataclasses import dataclass, field
import numpy as np

from synmitsuba.compose.instances import GROUND_INSTANCE, OBJECT_INSTANCE
from synmitsuba.errors import ConfigError
from synmitsuba.compose.architecture import BUILDERS, LAYOUTS, ROLES
from synmitsuba.compose.backdrop import add_backdrop
from synmitsuba.compose.grounds import GROUND_MATERIALS, ground_material
from synmitsuba.geometry import ground_grid
from synmitsuba.resources import asset_path
from synmitsuba.schema import Choice, Flag, ListOf, Nested, Number, Params, Range, Text, Vector, optional, spec
from synmitsuba.scene.layers import Layer
from synmitsuba.scene.materials import AreaLight, EnvMap, Material, SunSky

SCENES_DIR = asset_path("scenes")  # package data: works from a wheel as from a checkout
ENV_DIR = os.path.join(SCENES_DIR, "environments")
GROUND_HALF_SIZE = 20000.0  # metres: the ground's edge lies < 0.01 degrees below the horizon from 3 m up


# -- objects ------------------------------------------------------------------------------
OBJECT_KINDS: dict = BUILDERS  # kind -> (builder(w, h, d, rng) -> [(trimesh, role)], default size w, h, d)


@dataclass
class EnvObject(Params):
    kind: str = spec(check=Choice(OBJECT_KINDS), doc=", ".join(OBJECT_KINDS))
    position: list = spec(factory=lambda: [0.0, 0.0], check=Vector(2, what="x, z metres on the ground"))
    yaw_deg: float = spec(0.0, Number(-360, 360))
    size: list | None = spec(None, optional(Vector(3, 0.01, 500, what="width, height, depth metres")),
                             doc="default: the kind's own")
    color: list = spec(factory=lambda: [0.5, 0.5, 0.5], check=Vector(3, 0, 1, what="linear RGB"))
    roughness: float = spec(0.7, Number(0, 1))
    texture: str | None = spec(None, optional(Choice(GROUND_MATERIALS)), doc="a ground material on its main parts "
                               "(bricks, plaster, wood), laid on by box projection at real scale")
    lift: float = spec(0.0, Number(-50, 50), doc="metres it stands above the ground (a wall above a door)")
    seed: int = spec(0, Number(0, 2 ** 31, integer=True), doc="draws the builder's details (windows, books, leaves)")
    obstacle: bool = spec(True, Flag(), doc="false: people and cameras ignore it (a ceiling; keep cameras under it "
                          "with camera_keep_out)")


@dataclass
class PanelLight(Params):
    """A one-sided rectangular area light at ``position`` facing ``target``."""

    position: list = spec(check=Vector(3, what="x, y, z metres"))
    target: list = spec(check=Vector(3, what="x, y, z metres"))
    size: list = spec(factory=lambda: [1.0, 1.0], check=Vector(2, 0.01, 100, what="width, height metres"))
    radiance: float = spec(10.0, Number(0, 1e6))


@dataclass
class Layout(Params):
    """A procedural layout (``architecture.LAYOUTS``) whose objects join the environment's."""

    kind: str = spec(check=Choice(LAYOUTS), doc=", ".join(LAYOUTS))
    size_m: float = spec(30.0, Number(4, 500), doc="across (a room) or along (a street, a park)")
    seed: int = spec(0, Number(0, 2 ** 31, integer=True))


@dataclass
class Ground(Params):
    texture: str = spec("concrete", Choice(GROUND_MATERIALS), doc=", ".join(GROUND_MATERIALS))
    color: list = spec(factory=lambda: [0.35, 0.35, 0.33], check=Vector(3, 0, 1, what="linear RGB"))
    tile_m: float | None = spec(None, optional(Number(0.05, 20)), doc="metres one tile covers (default: the kind's)")
    roughness: float = spec(1.0, Number(0, 2), doc="scales the material's roughness map")

    @property
    def period_m(self) -> float:
        return float(self.tile_m or GROUND_MATERIALS[self.texture].period_m)


@dataclass
class Lighting(Params):
    type: str = spec("sunsky", Choice(("sunsky", "envmap")))
    sun_elevation_deg: list = spec(factory=lambda: [25.0, 65.0], check=Range(1, 90), doc="sunsky: range")
    sun_azimuth_deg: list = spec(factory=lambda: [0.0, 360.0], check=Range(-360, 720), doc="sunsky: range")
    turbidity: list = spec(factory=lambda: [2.0, 5.0], check=Range(1, 10), doc="sunsky: range")
    file: str | None = spec(None, optional(Text()), doc="envmap: an .exr, relative to the environment file")
    scale: list = spec(factory=lambda: [1.0, 1.0], check=Range(0, 1000), doc="envmap: range")
    rotation_deg: list = spec(factory=lambda: [0.0, 360.0], check=Range(-360, 720), doc="envmap: range")


@dataclass
class Backdrop(Params):
    """The HDRI projected onto the ground (the environment's ``ground`` is then not used)."""

    height_m: float = spec(1.7, Number(0.2, 20), doc="how high above its ground the panorama was shot")
    radius_m: float = spec(30.0, Number(2, 1000), doc="the projected ground's radius; beyond it, the photo on a dome")
    key_light: bool = spec(True, Flag(), doc="the panorama's sun (if it has one) as a directional light")
    floor_m: float | None = spec(None, optional(Number(0.5, 1000)),
                                 doc="how far from where the photo was shot its floor is open in every direction "
                                 "(walls, fences and furniture stand beyond, and would lie flat under people): "
                                 "every view keeps all subjects within it of its camera; default 0.9 radius_m")
    camera_rise_m: float = spec(1.2, Number(0, 1000),
                                doc="how far above or below the shooting height a view's camera may stand: what "
                                "stood on the photo's floor lies flat on the projected ground and looks upright "
                                "only from near that height")
    floor_sectors: list = spec(factory=list, check=ListOf(Vector(3, what="from_deg, to_deg, metres")),
                               doc="where the floor reaches further: panorama azimuths from_deg to to_deg (a column "
                               "over the width times 360, from the left edge) open for metres")

    @property
    def open_floor_m(self) -> float:
        return 0.9 * self.radius_m if self.floor_m is None else float(self.floor_m)

    def floor_reach(self, azimuth_deg) -> np.ndarray:
        """Metres the photo's floor is open along panorama azimuths (degrees, as ``floor_sectors``)."""
        az = np.asarray(azimuth_deg, np.float64) % 360.0
        reach = np.full(az.shape, self.open_floor_m)
        for a, b, metres in self.floor_sectors:
            inside = ((az >= a) & (az <= b)) if a <= b else ((az >= a) | (az <= b))
            reach = np.where(inside, np.maximum(reach, metres), reach)
        return reach


@dataclass
class Environment(Params):
    """An environment template (see ``scenes/environments/*.yaml``)."""

    name: str = spec(check=Text())
    doc: str = spec("", Text())
    area: list = spec(factory=lambda: [-5.0, -5.0, 5.0, 5.0], check=Vector(4, what="x_min, z_min, x_max, z_max"),
                      doc="where subjects may stand")
    ground: Ground = spec(factory=Ground, check=Nested(Ground))
    objects: list = spec(factory=list, check=ListOf(Nested(EnvObject)))
    lighting: Lighting = spec(factory=Lighting, check=Nested(Lighting))
    mesh: str | None = spec(None, optional(Text()), doc="your own scene: a glTF/GLB, OBJ or PLY file (relative to "
                            "this file; y up), its floor found by ray casting; area and ground then come from it")
    mesh_scale: float = spec(1.0, Number(1e-4, 1e4), doc="metres per mesh unit")
    layout: Layout | None = spec(None, optional(Nested(Layout)), doc="objects and area drawn by a layout")
    lights: list = spec(factory=list, check=ListOf(Nested(PanelLight)), doc="ceiling panels and other area lights")
    camera_keep_out: list = spec(factory=list, check=ListOf(Vector(6, what="x0, y0, z0, x1, y1, z1 metres")),
                                 doc="boxes no camera may enter (outside a room, above its ceiling)")
    backdrop: Backdrop | None = spec(None, optional(Nested(Backdrop)),
                                     doc="an envmap's photo as the ground, catching shadows (BEDLAM's HDRI scenes)")
    path: str = field(default="", metadata={"doc": "the file it came from"})

    def __post_init__(self):
        a = self.area
        if not (a[0] < a[2] and a[1] < a[3]):
            raise ConfigError("area", a, "give [x_min, z_min, x_max, z_max] with x_min < x_max and z_min < z_max")
        if self.backdrop is not None and self.lighting.type != "envmap":
            raise ConfigError("backdrop", "set", f"a backdrop projects an HDRI: give lighting.type envmap (not "
                              f"{self.lighting.type}) or remove the backdrop")


def environment_names() -> list[str]:
    return sorted(os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(ENV_DIR, "*.yaml")))


MESH_SUFFIXES = (".glb", ".gltf", ".obj", ".ply")


def load_environment(name_or_path: str, where: str = "environment") -> Environment:
    """An environment by name (``scenes/environments/<name>.yaml``), by file path, or a mesh
    file (glTF/GLB, OBJ, PLY) taken as ``{mesh: <file>}`` under a sun and sky."""
    import yaml
    path = name_or_path if os.path.isfile(str(name_or_path)) else os.path.join(ENV_DIR, f"{name_or_path}.yaml")
    if not os.path.isfile(path):
        raise ConfigError(where, name_or_path, f"no such environment; use one of {', '.join(environment_names())} "
                          "or the path of an environment YAML file or a mesh (.glb, .gltf, .obj, .ply)")
    if path.lower().endswith(MESH_SUFFIXES):
        data = {"name": os.path.splitext(os.path.basename(path))[0], "mesh": os.path.basename(path)}
    else:
        with open(path) as fh:
            data = yaml.safe_load(fh) or {}
    data.pop("path", None)
    env = Environment.from_dict(data, f"{where}({os.path.basename(path)})")
    env.path = os.path.abspath(path)
    if env.mesh is not None:
        env.area = mesh_floor(env, where)[1].area
    if env.layout is not None:
        place = LAYOUTS[env.layout.kind](env.layout.size_m, np.random.default_rng(env.layout.seed))
        seeds = np.random.default_rng(env.layout.seed + 1).integers(2 ** 31, size=len(place.objects))
        env.area = place.area
        env.objects = env.objects + [EnvObject.from_dict({**o, "seed": int(k)}, f"{where}.layout.objects[{i}]")
                                     for i, (o, k) in enumerate(zip(place.objects, seeds))]
        env.camera_keep_out = env.camera_keep_out + place.keep_out
        env.lights = env.lights + [PanelLight.from_dict(d, f"{where}.layout.lights[{i}]") for i, d in enumerate(place.lights)]
    if env.lighting.type == "envmap":
        hdri = os.path.join(os.path.dirname(env.path), env.lighting.file or "")
        if not os.path.isfile(hdri):
            raise ConfigError(f"{where}.lighting.file", env.lighting.file, "give an existing .exr relative to the "
                              "environment file")
    return env


# -- lighting -----------------------------------------------------------------------------
@dataclass
class SunskyLighting:
    """A drawn sun and sky: ``sun_direction`` towards the sun (unit, y up), ``turbidity``."""

    sun_direction: list
    turbidity: float
    type: str = "sunsky"

    def emitter(self) -> SunSky:
        return SunSky(sun_direction=tuple(self.sun_direction), turbidity=self.turbidity)


@dataclass
class EnvmapLighting:
    """A drawn HDRI: ``file`` relative to ``scenes/``, its ``scale`` and ``rotation_deg``."""

    file: str
    scale: float
    rotation_deg: float
    type: str = "envmap"

    def emitter(self) -> EnvMap:
        return EnvMap(source=os.path.join(SCENES_DIR, self.file), scale=self.scale, rotation_deg=self.rotation_deg)


LIGHTINGS: dict[str, type] = {"sunsky": SunskyLighting, "envmap": EnvmapLighting}


def lighting_to_dict(lighting) -> dict:
    """A drawn lighting as a scene spec stores it: ``{"type", ...fields}`` (``{}``: none)."""
    if lighting is None:
        return {}
    d = dataclasses.asdict(lighting)
    return {"type": d.pop("type"), **d}


def lighting_from_dict(d: dict):
    """``lighting_to_dict``'s inverse (``None`` for ``{}``)."""
    if not d:
        return None
    return LIGHTINGS[d["type"]](**{k: v for k, v in d.items() if k != "type"})


def sample_lighting(env: Environment, rng: np.random.Generator) -> SunskyLighting | EnvmapLighting:
    """Draw this environment's lighting."""
    lit = env.lighting
    if lit.type == "sunsky":
        el, az = np.radians(rng.uniform(*lit.sun_elevation_deg)), np.radians(rng.uniform(*lit.sun_azimuth_deg))
        direction = [float(np.cos(el) * np.sin(az)), float(np.sin(el)), float(np.cos(el) * np.cos(az))]
        return SunskyLighting(direction, float(rng.uniform(*lit.turbidity)))
    return EnvmapLighting(os.path.relpath(os.path.join(os.path.dirname(env.path), str(lit.file)), SCENES_DIR),
                          float(rng.uniform(*lit.scale)), float(rng.uniform(*lit.rotation_deg)))


# -- ground -------------------------------------------------------------------------------
def add_ground(scene, ground: Ground, rng: np.random.Generator) -> None:
    """The ground grid to the horizon with its procedural material (``grounds.ground_material``);
    uv is metres over the tile period."""
    v, faces = ground_grid(GROUND_HALF_SIZE)
    mat, period = ground_material(ground.texture, ground.color, rng, ground.period_m, roughness_scale=ground.roughness)
    scene.add_mesh("ground", v, faces, uv=v[:, [0, 2]] / period, normals=np.tile([0, 1.0, 0], (len(v), 1)),
                   material=mat, instance=GROUND_INSTANCE, layer=int(Layer.GROUND))


# -- objects in a scene -------------------------------------------------------------------
def object_parts(obj: EnvObject) -> list:
    """World-space (trimesh, role) parts of one object (``architecture.ROLES``; ``main`` is its
    own colour), built once per object."""
    key = (obj.kind, tuple(obj.position), obj.yaw_deg, tuple(obj.size or ()), obj.lift, obj.seed)
    return _parts(key)


@functools.lru_cache(maxsize=4096)
def _parts(key: tuple) -> list:
    from synmitsuba.geometry import axis_rotation
    kind, position, yaw, size, lift, seed = key
    builder, default = OBJECT_KINDS[kind]
    w, h, d = size or default
    M = np.eye(4)
    M[:3, :3] = axis_rotation("y", np.radians(yaw))
    M[:3, 3] = [position[0], lift, position[1]]
    return [(mesh.apply_transform(M), role) for mesh, role in builder(w, h, d, np.random.default_rng(seed))]


def _box_uv(mesh) -> np.ndarray:
    """Metres along the two axes across each vertex's dominant normal axis (box projection)."""
    v, n = np.asarray(mesh.vertices), np.abs(np.asarray(mesh.vertex_normals))
    axis = n.argmax(1)
    return np.where((axis == 0)[:, None], v[:, [2, 1]], np.where((axis == 1)[:, None], v[:, [0, 2]], v[:, [0, 1]]))


def _look(looks: dict, key: tuple, make) -> tuple:
    """``looks[key]``, made on first use: one ``Material`` object per look of a scene's objects
    (a textured material and colour, a role, a plain colour), so the engine loads one BSDF per
    look (drjit traces a call over every live BSDF: 1,094 of them made a 160x120 frame of
    ``city_street`` cost 3.6 s)."""
    if key not in looks:
        looks[key] = make()
    return looks[key]


def _part_look(obj: EnvObject, role: str, looks: dict) -> tuple:
    """(material, uv period or None) of one part of ``obj``."""
    if role == "main" and obj.texture is not None:
        return _look(looks, ("texture", obj.texture, tuple(obj.color)),
                     lambda: ground_material(obj.texture, obj.color, np.random.default_rng(obj.seed), n=256))
    if role == "main":
        return _look(looks, ("plain", tuple(obj.color), obj.roughness), lambda: (
            Material(base_color=tuple(obj.color), kind="principled", roughness=obj.roughness), None))
    colour, rough, metal = ROLES[role]
    return _look(looks, ("role", role), lambda: (
        Material(base_color=colour, kind="principled", roughness=rough, metallic=metal), None))


def _merged_parts(obj: EnvObject, looks: dict) -> list:
    """``obj``'s parts joined into one mesh per look: [(material, vertices, faces, uv or None)]
    (a tree's twenty branches are one trunk mesh: fewer shapes to trace and to build)."""
    groups: dict = {}
    for mesh, role in object_parts(obj):
        mat, period = _part_look(obj, role, looks)
        uv = None if period is None else _box_uv(mesh) / period
        groups.setdefault(id(mat), (mat, []))[1].append((np.asarray(mesh.vertices), np.asarray(mesh.faces), uv))
    out = []
    for mat, parts in groups.values():
        starts = np.cumsum([0] + [len(v) for v, _, _ in parts[:-1]])
        v = np.concatenate([v for v, _, _ in parts])
        f = np.concatenate([f + s for (_, f, _), s in zip(parts, starts)])
        uv = None if parts[0][2] is None else np.concatenate([u for _, _, u in parts])
        out.append((mat, v, f, uv))
    return out


def object_boxes(env: Environment) -> np.ndarray:
    """(N, 6) world bounds ``(x_min, y_min, z_min, x_max, y_max, z_max)`` of every object (and
    of a mesh environment's obstacles, in floor cells)."""
    boxes = []
    for obj in (o for o in env.objects if o.obstacle):
        pts = np.concatenate([np.asarray(m.vertices) for m, _ in object_parts(obj)])
        boxes.append(np.concatenate([pts.min(0), pts.max(0)]))
    out = np.asarray(boxes, np.float64).reshape(-1, 6)
    return out if env.mesh is None else np.concatenate([out, mesh_floor(env)[1].obstacles])


def mesh_floor(env: Environment, where: str = "environment"):
    """(parts, ``meshenv.MeshFloor``) of a mesh environment (read once per file version)."""
    from synmitsuba.compose.meshenv import mesh_environment
    path = os.path.join(os.path.dirname(env.path), str(env.mesh))
    if not os.path.isfile(path):
        raise ConfigError(f"{where}.mesh", env.mesh, "give an existing glTF/GLB, OBJ or PLY file, relative to the "
                          "environment file")
    return mesh_environment(os.path.abspath(path), float(env.mesh_scale), os.path.getmtime(path))


def add_mesh_environment(scene, env: Environment) -> None:
    """A mesh environment's pieces, lifted so its floor lies at y = 0: floor faces as the ground
    (its instance and layer), the rest as one object."""
    from synmitsuba.compose.meshenv import split_floor
    parts, floor = mesh_floor(env)
    for p in parts:
        lifted = p.vertices + [0.0, floor.offset_y, 0.0]
        for faces, suffix, inst, layer in zip(split_floor(p, floor.offset_y), ("floor", "rest"),
                                              (GROUND_INSTANCE, OBJECT_INSTANCE), (Layer.GROUND, Layer.OBJECT)):
            if faces.any():
                used = np.unique(p.faces[faces])
                remap = np.full(len(lifted), -1)
                remap[used] = np.arange(len(used))
                scene.add_mesh(f"{p.name}_{suffix}", lifted[used], remap[p.faces[faces]],
                               uv=None if p.uv is None else p.uv[used], material=p.material, instance=inst,
                               layer=int(layer))


DOME_KEEP = 0.7   # cameras stay within a square of this share of a backdrop's radius (corners inside it)


def keep_out_boxes(env: Environment) -> np.ndarray:
    """Boxes (N, 6) no camera may enter: around a backdrop's ground disc (a camera past it would
    see its edge and the dome from outside); under a mesh environment's ceilings and past its
    bounds. None for the others."""
    own = np.asarray(env.camera_keep_out, np.float64).reshape(-1, 6)
    if env.mesh is not None:
        return np.concatenate([own, mesh_floor(env)[1].keep_out])
    if env.backdrop is None:
        return own
    cx, cz = (env.area[0] + env.area[2]) / 2, (env.area[1] + env.area[3]) / 2
    s, far = DOME_KEEP * env.backdrop.radius_m, 1e4
    return np.concatenate([own, [[cx + s, -far, -far, far, far, far], [-far, -far, -far, cx - s, far, far],
                                 [-far, -far, cz + s, far, far, far], [-far, -far, -far, far, far, cz - s]]])


def add_environment(scene, env: Environment, lighting: SunskyLighting | EnvmapLighting,
                    rng: np.random.Generator) -> None:
    """Ground, objects (instances 2, 3, ...) and ``lighting`` (from ``sample_lighting``); with a
    backdrop, the ground is the HDRI's own, projected around the area's centre."""
    if env.mesh is not None:
        add_mesh_environment(scene, env)
    elif env.backdrop is None:
        add_ground(scene, env.ground, rng)
    else:
        centre = ((env.area[0] + env.area[2]) / 2, (env.area[1] + env.area[3]) / 2)
        add_backdrop(scene, lighting, env.backdrop.height_m, env.backdrop.radius_m, centre, env.backdrop.key_light)
    looks: dict = {}   # look -> (Material, uv period or None)
    for i, obj in enumerate(env.objects):
        for n, (mat, v, f, uv) in enumerate(_merged_parts(obj, looks)):
            scene.add_mesh(f"object{i}_{obj.kind}_{n}", v, f, uv=uv, material=mat,
                           instance=OBJECT_INSTANCE + i, layer=int(Layer.OBJECT))
    if env.backdrop is None:
        scene.set_environment(lighting.emitter())
    for light in env.lights:
        scene.add_light(AreaLight(tuple(light.position), tuple(light.target), tuple(light.size), light.radiance))
