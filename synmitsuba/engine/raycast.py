"""Ray casts on the loaded Mitsuba scene (``ray_intersect_preliminary``: Mitsuba's own BVH
traversal, no shading): what stands first along a ray or between points and a viewer."""
from __future__ import annotations

import numpy as np

from synmitsuba.engine.build import build
from synmitsuba.engine.variant import current_variant
from synmitsuba.scene.scene import Scene


def _intersect(scene: Scene, origins, directions, maxt=None, coherent: bool = False):
    """(built scene, preliminary intersection, hit mask, shape registry ids) of the rays."""
    import drjit as dr
    import mitsuba as mi
    current_variant()
    built = build(scene)
    d = np.asarray(directions, np.float64)
    o = np.broadcast_to(np.asarray(origins, np.float64), d.shape)
    ray = mi.Ray3f(mi.Point3f(*(mi.Float(o[:, k].astype(np.float32)) for k in range(3))),
                   mi.Vector3f(*(mi.Float(d[:, k].astype(np.float32)) for k in range(3))))
    if maxt is not None:
        ray.maxt = mi.Float(np.broadcast_to(np.asarray(maxt, np.float64), len(d)).astype(np.float32))
    si = built.mi_scene.ray_intersect_preliminary(ray, coherent=coherent)
    hit = si.is_valid()
    return built, si, hit, dr.reinterpret_array(mi.UInt32, si.shape)


def cast(scene: Scene, origins, directions, maxt=None) -> tuple[np.ndarray, np.ndarray]:
    """Instance id (0: nothing) and distance (inf: nothing) of the first surface each ray
    ``origins[i] + s * directions[i]`` (N, 3; unit directions) meets for s < ``maxt[i]``."""
    import drjit as dr
    built, si, hit, reg = _intersect(scene, origins, directions, maxt)
    t = dr.select(hit, si.t, dr.inf)
    return np.asarray(built.lookup("instance", reg, hit).numpy(), np.int64), np.asarray(t.numpy(), np.float64)


def first_hits(scene: Scene, origins, targets, shrink: float = 1e-4) -> np.ndarray:
    """Instance id of the first surface each segment ``origins[i] -> targets[i]`` (N, 3)
    meets before reaching ``targets[i]``; 0 where nothing is in between. ``shrink`` (metres)
    stops the segment short of its target so the target's own surface is not counted."""
    t = np.asarray(targets, np.float64)
    d = t - np.broadcast_to(np.asarray(origins, np.float64), t.shape)
    length = np.linalg.norm(d, axis=-1)
    ids, _ = cast(scene, origins, d / np.maximum(length, 1e-12)[:, None], np.maximum(length - shrink, 0.0))
    return ids


def surface_hits(scene: Scene, origins, directions) -> dict:
    """The first surface along each ray (N, 3; unit directions): ``instance``, ``shape`` (an
    index into ``names``, -1 where nothing is hit), ``names`` (the scene's shape names),
    ``prim`` (triangle or curve segment index), ``u``, ``v`` (Mitsuba's ``prim_uv``: barycentric
    weights of vertices 1 and 2 on a triangle) and ``t`` (inf where nothing is hit)."""
    import drjit as dr
    built, si, hit, reg = _intersect(scene, origins, directions, coherent=True)
    shape = built.lookup("shape", reg, hit).numpy().astype(np.int64) - 1
    return {"instance": built.lookup("instance", reg, hit).numpy().astype(np.int64), "shape": shape,
            "names": list(built.names),
            "prim": np.asarray(dr.select(hit, si.prim_index, 0).numpy(), np.int64),
            "u": np.asarray(dr.select(hit, si.prim_uv.x, 0.0).numpy(), np.float64),  # garbage (NaN) on misses
            "v": np.asarray(dr.select(hit, si.prim_uv.y, 0.0).numpy(), np.float64),
            "t": np.asarray(dr.select(hit, si.t, dr.inf).numpy(), np.float64)}
