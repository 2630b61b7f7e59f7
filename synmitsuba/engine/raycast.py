"""Ray casts on the loaded Mitsuba scene (``scene.ray_intersect``, Embree-class BVH in
Mitsuba's own kernels): what stands first between points and a viewer."""
from __future__ import annotations

import numpy as np

from synmitsuba.engine.build import build
from synmitsuba.engine.variant import current_variant
from synmitsuba.scene.scene import Scene


def first_hits(scene: Scene, origins, targets, shrink: float = 1e-4) -> np.ndarray:
    """Instance id of the first surface each segment ``origins[i] -> targets[i]`` (N, 3)
    meets before reaching ``targets[i]``; 0 where nothing is in between. ``shrink`` (metres)
    stops the segment short of its target so the target's own surface is not counted."""
    import drjit as dr
    import mitsuba as mi
    current_variant()
    built = build(scene)
    o = np.ascontiguousarray(np.broadcast_to(np.asarray(origins, np.float64), np.shape(targets)), np.float32)
    t = np.asarray(targets, np.float64)
    d = t - o
    length = np.linalg.norm(d, axis=-1)
    d = d / np.maximum(length, 1e-12)[:, None]
    ray = mi.Ray3f(mi.Point3f(*(mi.Float(o[:, k]) for k in range(3))),
                   mi.Vector3f(*(mi.Float(d[:, k].astype(np.float32)) for k in range(3))))
    ray.maxt = mi.Float(np.maximum(length - shrink, 0.0).astype(np.float32))
    si = built.mi_scene.ray_intersect_preliminary(ray, coherent=False)
    hit = si.is_valid()
    reg = dr.reinterpret_array(mi.UInt32, si.shape)
    ids = built.lookup("instance", reg, hit)
    return np.asarray(ids.numpy(), np.int64)
