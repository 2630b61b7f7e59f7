"""Turn a ``synmitsuba.Scene`` into a Mitsuba scene, updated in place as the scene moves.

The engine owns its builds: ``build(scene)`` keeps one per live ``Scene`` in a weak table here
(never on the scene, so copying or pickling a scene carries no renderer state), keyed by the
scene's identity and checked against its versions; ``load(scene)`` makes a private build that
nobody else sees (``DiffScene`` drives its parameters without touching what ``render`` uses).
"""
from __future__ import annotations

import os
import time
import tempfile
import weakref
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from synmitsuba.geometry import frame
from synmitsuba.process import SETTINGS
from synmitsuba.scene.materials import (AreaLight, Blend, Constant, DirectionalLight, EnvMap, Material,
                                        PointLight, SunSky, hair_pigments, hair_sigma_a)
from synmitsuba.scene.scene import CurveShape, MeshShape, Scene

DIFFUSE_TRANSMISSION = 0.8  # principledthin's diff_trans where a skin is fully translucent (0 .. 2: none .. all)


def _bitmap(arr: np.ndarray) -> dict:
    import mitsuba as mi
    data = arr[..., None] if arr.ndim == 2 else arr
    return {"type": "bitmap", "data": mi.TensorXf(np.ascontiguousarray(data, dtype=np.float32)),
            "raw": True, "filter_type": "bilinear", "wrap_mode": "repeat"}


def _repeated(tiles: dict, repeat: tuple) -> dict:
    if tuple(repeat) != (1.0, 1.0):
        import mitsuba as mi
        tiles["to_uv"] = mi.ScalarTransform4f().scale([*repeat, 1.0])
    return tiles


def _blend_dict(mat: Blend) -> dict:
    bsdf = {"type": "blendbsdf", "weight": _repeated(_bitmap(mat.weight), mat.weight_repeat),
            "bsdf_0": bsdf_dict(mat.a), "bsdf_1": bsdf_dict(mat.b)}
    if mat.normal_map is not None:
        bsdf = {"type": "normalmap", "normalmap": _repeated(_bitmap(mat.normal_map), mat.normal_map_repeat), "bsdf": bsdf}
    return bsdf


def bsdf_dict(mat: Material | Blend) -> dict:
    """Mitsuba BSDF dict for a Material (or a Blend of two)."""
    if isinstance(mat, Blend):
        return _blend_dict(mat)
    color = (_repeated(_bitmap(mat.texture), mat.texture_repeat) if mat.texture is not None
             else {"type": "rgb", "value": _rgb_list(mat.base_color)})
    if mat.kind == "hair":
        rough = {"longitudinal_roughness": 0.3, "azimuthal_roughness": 0.3}
        if mat.strand_melanin is None:
            eu, pheo = hair_pigments(mat.melanin, mat.redness)
            return {"type": "hair", "eumelanin": float(eu), "pheomelanin": float(pheo), **rough}
        # curves' v runs over all segments in order, so a one-column bitmap of one row per strand
        # (nearest) gives each strand its own absorption
        sigma = hair_sigma_a(mat.strand_melanin, mat.redness)[:, None, :]
        return {"type": "hair", "sigma_a": {**_bitmap(sigma), "filter_type": "nearest", "wrap_mode": "clamp"}, **rough}
    if mat.kind == "principled":
        roughness: Any = (_repeated(_bitmap(mat.roughness_map), mat.texture_repeat) if mat.roughness_map is not None
                          else mat.roughness)
        bsdf = {"type": "principled", "base_color": color, "roughness": roughness,
                "metallic": mat.metallic, "specular": mat.specular}
    else:
        bsdf = {"type": "diffuse", "reflectance": color}
    if mat.two_sided:
        bsdf = {"type": "twosided", "bsdf": bsdf}
    if mat.translucency is not None and mat.kind == "principled":
        bsdf = {"type": "blendbsdf", "weight": _repeated(_bitmap(mat.translucency), mat.texture_repeat),
                "bsdf_0": bsdf, "bsdf_1": _thin_dict(mat, roughness)}
    if mat.bump is not None:
        bsdf = {"type": "bumpmap", "height": _bitmap(mat.bump), "scale": float(mat.bump_scale), "bsdf": bsdf}
    if mat.normal_map is not None:
        bsdf = {"type": "normalmap", "normalmap": _repeated(_bitmap(mat.normal_map), mat.normal_map_repeat), "bsdf": bsdf}
    return bsdf


def _thin_dict(mat: Material, roughness: Any) -> dict:
    """The translucent side of a ``translucency`` blend: principledthin passing
    ``DIFFUSE_TRANSMISSION`` / 2 of its diffuse light through, its colour raised (past 1 where
    need be) so that what it reflects matches the opaque side: a front-lit ear keeps its
    brightness and a backlit one adds the light through it, reddened by the skin's colour on the
    way in and out (at half the texture's resolution: thin skin is small)."""
    lift = 1.0 / (1.0 - DIFFUSE_TRANSMISSION / 2)
    if mat.texture is not None:
        t = mat.texture[: mat.texture.shape[0] // 2 * 2, : mat.texture.shape[1] // 2 * 2]
        half = 0.25 * (t[::2, ::2] + t[1::2, ::2] + t[::2, 1::2] + t[1::2, 1::2])
        color = _repeated(_bitmap(half * lift), mat.texture_repeat)
    else:
        color = {"type": "rgb", "value": _rgb_list(np.asarray(mat.base_color) * lift)}
    return {"type": "principledthin", "base_color": color, "roughness": roughness, "diff_trans": DIFFUSE_TRANSMISSION}


def _mesh(shape: MeshShape, bsdfs: dict | None = None):
    """A Mitsuba mesh of ``shape``; with ``bsdfs`` (Material id -> BSDF), meshes that hold the
    same Material object share one BSDF."""
    import mitsuba as mi
    m = mi.Mesh(shape.name, len(shape.vertices), len(shape.faces),
                has_vertex_normals=shape.normals is not None, has_vertex_texcoords=shape.uv is not None)
    p = mi.traverse(m)
    p["vertex_positions"] = mi.Float(shape.vertices.astype(np.float32).ravel())
    p["faces"] = mi.UInt32(shape.faces.ravel())
    if shape.normals is not None:
        p["vertex_normals"] = mi.Float(_unit(shape.normals).astype(np.float32).ravel())
    if shape.uv is not None:  # our uv has v up (OBJ); Mitsuba's bitmap row 0 is at v = 0
        uv = np.stack([shape.uv[:, 0], 1.0 - shape.uv[:, 1]], 1)
        p["vertex_texcoords"] = mi.Float(uv.astype(np.float32).ravel())
    p.update()
    if bsdfs is None:
        m.set_bsdf(mi.load_dict(bsdf_dict(shape.material)))
        return m
    key = id(shape.material)
    if key not in bsdfs:
        bsdfs[key] = mi.load_dict(bsdf_dict(shape.material))
    m.set_bsdf(bsdfs[key])
    return m


def _unit(n: np.ndarray) -> np.ndarray:
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def _curves(shape: CurveShape):
    """linearcurve reads a text file (one 'x y z r' line per control point, blank line between
    strands): a file of placeholder strands with the right counts is written (formatting tens
    of thousands of real strands took a second), loaded, deleted, and the real control points
    are set through ``mi.traverse``, as every later frame sets them."""
    import mitsuba as mi
    n, k = shape.points.shape[:2]
    strand = "".join(f"0 {j * 1e-3:g} 0 1e-4\n" for j in range(k)) + "\n"
    with tempfile.TemporaryDirectory(prefix="synmitsuba-curves-") as tmp:
        path = os.path.join(tmp, f"{shape.name}.txt")
        with open(path, "w") as fh:
            fh.write(strand * n)
        curves = mi.load_dict({"type": "linearcurve", "filename": path, "id": shape.name,
                               "bsdf": bsdf_dict(shape.material)})
    params = mi.traverse(curves)
    rows = np.concatenate([shape.points, shape.radius[..., None]], -1).astype(np.float32)
    params["control_points"] = aligned_floats(rows)
    params.update()
    return curves


def aligned_floats(arr: np.ndarray, align: int = 64):
    """``mi.Float`` of ``arr``'s values (as float32) from a buffer at an address divisible by
    ``align``: for every array a kernel reads lane by lane. drjit maps a float32 numpy array
    without copying (and converts a float64 one into a copy on the heap), and its LLVM backend
    writes the alignment it finds into the kernel: from numpy's allocations (16-byte aligned at
    varying offsets) the path tracer came in two or three variants (the curves' control points)
    and a ray cast in up to 2^7 (its seven inputs), one compiled, or read from disk, whenever
    the heap handed out a new offset."""
    import mitsuba as mi
    flat = np.ravel(arr).astype(np.float32, copy=False)
    buf = np.empty(len(flat) + align // 4, np.float32)
    start = (-buf.ctypes.data % align) // 4
    out = buf[start:start + len(flat)]
    out[:] = flat
    return mi.Float(out)


def _rgb_list(value) -> list[float]:
    """A colour field (a grey value or RGB; materials store RGB tuples) as Mitsuba's rgb value."""
    return [float(c) for c in np.broadcast_to(np.asarray(value, np.float64), (3,))]


def environment_dict(env) -> dict | None:
    """The Mitsuba emitter dict of a Constant, SunSky or EnvMap (None: no environment)."""
    import mitsuba as mi
    if env is None:
        return None
    if isinstance(env, Constant):
        return {"type": "constant", "radiance": {"type": "rgb", "value": _rgb_list((env.radiance))}}
    if isinstance(env, SunSky):
        # Mitsuba's sky model is z-up in its local frame; sun_direction is taken in world space.
        return {"type": "sunsky", "sun_direction": list(env.sun_direction), "turbidity": env.turbidity,
                "albedo": env.albedo, "sun_scale": env.sun_scale, "sky_scale": env.sky_scale,
                "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], -90)}
    if isinstance(env, EnvMap):
        to_world = mi.ScalarTransform4f().rotate([0, 1, 0], env.rotation_deg)
        return {"type": "envmap", "bitmap": mi.Bitmap(env.pixels()), "scale": env.scale, "to_world": to_world}
    raise TypeError(env)


def _light(light) -> dict:
    import mitsuba as mi
    if isinstance(light, PointLight):
        return {"type": "point", "position": list(light.position),
                "intensity": {"type": "rgb", "value": _rgb_list((light.intensity))}}
    if isinstance(light, DirectionalLight):
        return {"type": "directional", "direction": list(light.direction),
                "irradiance": {"type": "rgb", "value": _rgb_list((light.irradiance))}}
    if isinstance(light, AreaLight):  # Mitsuba's rectangle spans [-1, 1]^2 in xy and faces +z
        facing = np.subtract(light.target, light.position)
        try:
            F = frame(facing, [0, 1, 0], keep="forward")
        except ValueError:  # pointing straight up or down
            F = frame(facing, [0, 0, 1], keep="forward")
        M = np.eye(4)
        M[:3, :3], M[:3, 3] = F @ np.diag([light.size[0] / 2, light.size[1] / 2, 1.0]), light.position
        return {"type": "rectangle", "to_world": mi.ScalarTransform4f(M.tolist()),
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": _rgb_list((light.radiance))}},
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}}}
    raise TypeError(light)


LUMINANCE = (0.2126, 0.7152, 0.0722)


def _probe_point(scene: Scene) -> np.ndarray:
    """Where emitters are weighed: the centre of the subjects' (instances') bounds, else 1 m
    above the origin."""
    boxes = [(m.vertices.min(0), m.vertices.max(0)) for m in scene.meshes.values() if m.instance > 0]
    if not boxes:
        return np.array([0.0, 1.0, 0.0])
    return (np.min([b[0] for b in boxes], 0) + np.max([b[1] for b in boxes], 0)) / 2


def direct_light(emitter_dict: dict, at, n: int = 32) -> float:
    """The luminance an emitter sends to a point ``at``, as the mean irradiance on the faces of
    a cube there, the floor face left out (what lights heads, faces and flanks): an n x n grid
    of the emitter's own importance samples, so delta lights, suns and area lights are exact
    or nearly so. Deterministic (no random numbers)."""
    import drjit as dr
    import mitsuba as mi
    obj = mi.load_dict(emitter_dict)
    emitter = obj if isinstance(obj, mi.Emitter) else obj.emitter()
    u = (np.arange(n) + 0.5) / n
    su, sv = np.meshgrid(u, u)
    it = dr.zeros(mi.Interaction3f, n * n)
    it.p = mi.Point3f(*(float(x) for x in at))
    ds, weight = emitter.sample_direction(it, mi.Point2f(mi.Float(su.ravel()), mi.Float(sv.ravel())), True)  # type: ignore[arg-type]
    d, w = np.array(ds.d).reshape(3, -1).T, np.array(weight).reshape(3, -1).T
    g = (np.maximum(d[:, 1], 0) + np.abs(d[:, 0]) + np.abs(d[:, 2])) / 5
    return float(np.mean((w @ LUMINANCE) * g))


ENVIRONMENT_SHARE = 0.25  # an environment's light counts a quarter: BSDF samples find it too


def quarters(light: list[float]) -> list[int]:
    """Up to four emitters' shares of the light samples in whole quarters, each at least one
    (largest remainders): the low-discrepancy samplers stratify the emitter choice, so with
    shares of k/4 every 4 samples of a pixel go to the emitters in exactly those numbers."""
    n = len(light)
    share = np.asarray(light, float) / max(sum(light), 1e-12)
    extra = np.clip(4 * share - 1, 0, None)
    q = np.ones(n, int) + np.floor(extra * (4 - n) / max(extra.sum(), 1e-12)).astype(int)
    for i in np.argsort(-(extra - np.floor(extra)), kind="stable")[: 4 - int(q.sum())]:
        q[i] += 1
    return q.tolist()


def _weigh_emitters(emitters: list[dict], at, environment: bool) -> None:
    """Set each emitter's ``sampling_weight`` from its direct light at ``at``. Mitsuba picks
    one emitter per light sample, uniformly unless told: with a sky and a sun lamp half the
    light samples went to the sky. Lamps (the sun, points, panels) are found only by light
    samples, while a wide sky is found by BSDF samples too, so the environment's light counts
    ``ENVIRONMENT_SHARE`` of its value; up to four emitters get whole ``quarters``, more get
    their light (at least 1 % of the mean, so no light is left unsampled). On
    bench/render_quality.py's scene (sky and sun lamp, 128 px, 1024-spp reference), PSNR at
    1/4/16/64 spp: uniform 15.5/32.0/38.5/43.5 dB, by light alone 14.6/26.3/35.9/43.1, sun 3 :
    sky 1 18.6/33.8/40.9/45.5.
    ``environment``: the first dict is the environment."""
    light = [direct_light(e, at) for e in emitters]
    if environment:
        light[0] *= ENVIRONMENT_SHARE
    floor = 0.01 * max(float(np.mean(light)), 1e-12)
    weights = quarters(light) if len(light) <= 4 else [max(w, floor) for w in light]
    for e, w in zip(emitters, weights):
        (e["emitter"] if "emitter" in e else e)["sampling_weight"] = float(w)


# how often a Scene was loaded into Mitsuba and updated in place (tests assert on these)
STATS = {"loads": 0, "updates": 0, "gc_seconds": 0.0}


@dataclass
class BuiltScene:
    """A loaded Mitsuba scene plus per-shape tables indexed by drjit registry id (``si.shape``
    reinterpreted as UInt32): instance id, layer id and whether the shape has texture coords."""

    mi_scene: Any
    moving: Any             # mi.SceneParameters of vertex positions, normals and control points only
    versions: tuple[int, int]
    tables: dict               # name -> numpy array indexed by registry id ("shape": 1 + index in names)
    instance_ids: list         # instance ids > 0 present in the scene
    names: list = field(default_factory=list)  # shape names (meshes, then curves), as the "shape" table counts them
    _dr_tables: dict = field(default_factory=dict)
    _pushed: dict = field(default_factory=dict)  # name (+ '.normals', '.radius') -> the array Mitsuba holds (identity)
    _params: object = None

    @property
    def params(self):
        """Every parameter of the scene (``mi.traverse``), made on first use (diff binds textures
        and lights through it). Animation goes through ``moving`` instead: ``update()`` evaluates
        every parameter it holds, and a full traverse holds a 3-channel view of each texture,
        which would then stay in memory beside the texture (50 MB a subject at 1024 px)."""
        if self._params is None:
            import mitsuba as mi
            self._params = mi.traverse(self.mi_scene)
        return self._params

    def lookup(self, name: str, reg, active):
        """Per-ray table value (UInt32) for registry ids ``reg``; 0 where not ``active``."""
        import drjit as dr
        import mitsuba as mi
        if name not in self._dr_tables:
            self._dr_tables[name] = mi.UInt32(self.tables[name].astype(np.uint32))
        return dr.gather(mi.UInt32, self._dr_tables[name], reg, active)


def _update_in_place(cached: BuiltScene, scene: Scene) -> None:
    """Push the shapes whose positions array was replaced since the last push (the static
    ground and props are left alone: Mitsuba then re-derives only what moved)."""
    import mitsuba as mi
    for name, m in scene.meshes.items():
        if cached._pushed.get(name) is not m.vertices:
            cached.moving[f"{name}.vertex_positions"] = mi.Float(m.vertices.astype(np.float32).ravel())
            cached._pushed[name] = m.vertices
    for name, c in scene.curves.items():
        if cached._pushed.get(name) is not c.points or cached._pushed.get(f"{name}.radius") is not c.radius:
            rows = np.concatenate([c.points, c.radius[..., None]], -1).astype(np.float32)
            cached.moving[f"{name}.control_points"] = aligned_floats(rows)
            cached._pushed[name], cached._pushed[f"{name}.radius"] = c.points, c.radius
    cached.moving.update()
    normals = [(name, m.normals) for name, m in scene.meshes.items()
               if m.normals is not None and cached._pushed.get(f"{name}.normals") is not m.normals]
    for name, n in normals:  # after the positions: moving them made Mitsuba recompute its own
        cached.moving[f"{name}.vertex_normals"] = mi.Float(_unit(n).astype(np.float32).ravel())
        cached._pushed[f"{name}.normals"] = n
    if normals:
        cached.moving.update()  # normals alone: no rebuild (under a millisecond)
    cached.versions = (scene.structure_version, scene.geometry_version)
    STATS["updates"] += 1


def _moving_params(mi_scene):
    """The scene's parameters that animation sets: mesh vertex positions and normals, curve
    control points."""
    import mitsuba as mi
    params = mi.traverse(mi_scene)
    params.keep([r".*\.(vertex_positions|vertex_normals|control_points)$"])
    return params


def _tables(mi_scene, scene: Scene) -> tuple[dict, list]:
    import drjit as dr
    import mitsuba as mi
    shapes = {**{n: (m.instance, m.layer, m.uv is not None) for n, m in scene.meshes.items()},
              **{n: (c.instance, c.layer, False) for n, c in scene.curves.items()}}
    reg = (dr.reinterpret_array(mi.UInt32, mi_scene.shapes_dr()).numpy()  # type: ignore[attr-defined]
           if mi_scene.shapes() else np.zeros(0, np.uint32))
    size = int(reg.max()) + 1 if len(reg) else 1
    tables = {k: np.zeros(size, np.uint32) for k in ("instance", "layer", "has_uv", "shape")}
    names = list(shapes)
    for r, shape in zip(reg, mi_scene.shapes()):
        inst, lay, has_uv = shapes.get(shape.id(), (0, 0, False))  # emitters' rectangles get (0, 0)
        tables["instance"][r], tables["layer"][r], tables["has_uv"][r] = inst, lay, has_uv
        tables["shape"][r] = names.index(shape.id()) + 1 if shape.id() in shapes else 0  # 1 + index in names
    return tables, sorted({v[0] for v in shapes.values() if v[0] > 0})


# one build per live Scene, by identity; an entry goes when its scene is collected
_BUILDS: "weakref.WeakKeyDictionary[Scene, BuiltScene]" = weakref.WeakKeyDictionary()


def _release_dead_objects(scene: Scene) -> None:
    """Drop this scene's previous build and, when opted in, free unreachable Mitsuba objects
    before a load. drjit traces a virtual call over every live instance of its domain (BSDFs,
    shapes, emitters), so garbage left by an earlier scene is compiled into the new scene's
    kernels; when Python collects it a few frames later, the path tracer recompiles (about a
    second). Collecting here keeps kernels stable per load."""
    _BUILDS.pop(scene, None)
    if SETTINGS.collect_before_load:  # process-wide: only where the CLI or a worker opted in
        import gc
        t = time.perf_counter()
        gc.collect()
        STATS["gc_seconds"] += time.perf_counter() - t


def cached_build(scene: Scene) -> BuiltScene | None:
    """The build ``render`` would reuse for ``scene`` (None before its first render)."""
    return _BUILDS.get(scene)


def forget(scene: Scene) -> None:
    """Drop the engine's build of ``scene`` (the next render loads it again)."""
    _BUILDS.pop(scene, None)


def release_memory() -> None:
    """Give back what drjit keeps between scenes: every kernel compiled so far and its freed
    allocations. Each new mix of BSDF, shape and emitter types compiles a new path tracer of a
    few MB that stays in memory for the life of the process (about +1 % RSS a sequence in a
    generation run); the disk cache keeps the kernels, so reloading one costs milliseconds. Then
    glibc returns freed heap pages.
    Call between scenes (generation does, after each sequence), never inside a render."""
    import gc

    import drjit as dr
    gc.collect()
    dr.flush_kernel_cache()
    dr.flush_malloc_cache()
    _trim_heap()


def settle_frame_memory() -> None:
    """Between frames of a sequence: hand back drjit's cached CPU buffers (each frame's
    edge-coverage rays come in a new count, so the cache kept one block of every size seen)
    and glibc's freed pages. On a 4-subject, 4-view sequence RSS rose 493 -> 535 MB over 40
    frames without this and 445 -> 471 MB with it, flat after frame 10; it costs a few
    milliseconds. A CUDA variant keeps its cache (device memory, and re-allocating is slow)."""
    import drjit as dr
    import mitsuba as mi
    if not str(mi.variant()).startswith("cuda"):
        dr.flush_malloc_cache()
    _trim_heap()


def _trim_heap() -> None:
    """Hand glibc's freed heap pages back to the system (about 90 MB after a sequence)."""
    import ctypes
    import ctypes.util
    name = ctypes.util.find_library("c")
    try:
        ctypes.CDLL(name).malloc_trim(0)
    except (OSError, AttributeError, TypeError):  # not glibc (macOS, musl): nothing to trim
        pass


def build(scene: Scene) -> BuiltScene:
    """The engine's build of ``scene``: loaded into Mitsuba once, then reused, moving meshes and
    curves in place when only positions changed (no reload, compiled kernels reused)."""
    cached = _BUILDS.get(scene)
    if cached is not None and cached.versions[0] == scene.structure_version:
        if cached.versions[1] != scene.geometry_version:
            _update_in_place(cached, scene)
        return cached
    _release_dead_objects(scene)
    built = load(scene)
    _BUILDS[scene] = built
    return built


def load(scene: Scene, share_bsdfs: bool = True) -> BuiltScene:
    """A fresh Mitsuba build of ``scene`` that the engine does not keep: its owner may change
    its parameters (``DiffScene``) without affecting ``build`` or ``render``. Meshes holding
    one Material object share one BSDF (drjit traces every live BSDF into each kernel);
    ``share_bsdfs=False`` gives each mesh its own, under its own parameter keys."""
    import mitsuba as mi
    d: dict = {"type": "scene"}
    bsdfs: dict | None = {} if share_bsdfs else None
    for name, m in scene.meshes.items():
        d[name] = _mesh(m, bsdfs)
    for name, c in scene.curves.items():
        d[name] = _curves(c)
    env = environment_dict(scene.environment)
    if env is not None:
        d["environment"] = env
    for i, light in enumerate(scene.lights):
        d[f"light_{i}"] = _light(light)
    emitters = [v for k, v in d.items() if k == "environment" or k.startswith("light_")]
    if len(emitters) > 1:
        _weigh_emitters(emitters, _probe_point(scene), environment="environment" in d)
    mi_scene = mi.load_dict(d)
    tables, ids = _tables(mi_scene, scene)
    built = BuiltScene(mi_scene, _moving_params(mi_scene), (scene.structure_version, scene.geometry_version), tables, ids,
                       names=[*scene.meshes, *scene.curves])
    built._pushed.update({n: m.vertices for n, m in scene.meshes.items()})
    built._pushed.update({f"{n}.normals": m.normals for n, m in scene.meshes.items()})
    built._pushed.update({k: v for n, c in scene.curves.items() for k, v in ((n, c.points), (f"{n}.radius", c.radius))})
    STATS["loads"] += 1
    return built
