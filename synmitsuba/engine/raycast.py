"""Ray casts on the loaded Mitsuba scene (``ray_intersect_preliminary``: Mitsuba's own BVH
traversal, no shading): what stands first along a ray or between points and a viewer."""
from __future__ import annotations

import numpy as np

from synmitsuba.engine.build import aligned_floats, build
from synmitsuba.engine.variant import require_variant
from synmitsuba.geometry import bounds
from synmitsuba.scene.scene import Scene


def _intersect(scene: Scene, origins, directions, maxt=None, coherent: bool = False):
    """(built scene, preliminary intersection, hit mask, shape registry ids) of the rays."""
    import drjit as dr
    import mitsuba as mi
    require_variant()
    built = build(scene)
    d = np.asarray(directions, np.float64)
    o = np.broadcast_to(np.asarray(origins, np.float64), d.shape)
    ray = mi.Ray3f(mi.Point3f(*(aligned_floats(o[:, k]) for k in range(3))),  # one kernel at any address
                   mi.Vector3f(*(aligned_floats(d[:, k]) for k in range(3))))
    if maxt is not None:
        ray.maxt = aligned_floats(np.broadcast_to(np.asarray(maxt, np.float64), len(d)))  # type: ignore[assignment]
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


def surface_hits(scene: Scene, origins, directions, maxt=None) -> dict:
    """The first surface along each ray (N, 3; unit directions) before ``maxt``: ``instance``,
    ``shape`` (an index into ``names``, -1 where nothing is hit), ``names`` (the scene's shape
    names), ``prim`` (triangle or curve segment index), ``u``, ``v`` (Mitsuba's ``prim_uv``:
    barycentric weights of vertices 1 and 2 on a triangle) and ``t`` (inf where nothing is hit)."""
    built, si, hit, reg = _intersect(scene, origins, directions, maxt, coherent=True)
    return _hit_arrays(built, hit, reg, si.prim_index, si.prim_uv.x, si.prim_uv.y, si.t)


def _hit_arrays(built, hit, reg, prim, u, v, t) -> dict:
    """``surface_hits``' dict from per-ray drjit values: the registry ids ``reg`` read through
    the scene's tables, misses (``hit`` false) as instance 0, shape -1, zeros and t = inf."""
    import drjit as dr
    return {"instance": built.lookup("instance", reg, hit).numpy().astype(np.int64),
            "shape": built.lookup("shape", reg, hit).numpy().astype(np.int64) - 1, "names": list(built.names),
            "prim": np.asarray(dr.select(hit, prim, 0).numpy(), np.int64),
            "u": np.asarray(dr.select(hit, u, 0.0).numpy(), np.float64),  # garbage (NaN) on misses
            "v": np.asarray(dr.select(hit, v, 0.0).numpy(), np.float64),
            "t": np.asarray(dr.select(hit, t, dr.inf).numpy(), np.float64)}


STEP = 1e-4  # metres a ray restarts past what it passed through: beyond float32's error at tens of metres


def hits_through(scene: Scene, origins, directions, onto, maxt=None, rounds: int = 4096) -> dict:
    """``surface_hits`` of the first surface along each ray that belongs to a shape named in
    ``onto``, passing through every other: a ray that meets something else goes on from
    ``STEP`` past it, up to ``rounds`` times, in one drjit loop (through a head of long hair
    takes a few hundred). ``t`` counts from ``origins``; a ray that meets none of ``onto``
    before ``maxt`` reads as a miss. One subject, or the bodies under the clothes, seen in the
    loaded scene: a scene of their own would be another BVH for Mitsuba to rebuild every frame
    (30-70 ms each with hair)."""
    import drjit as dr
    import mitsuba as mi
    require_variant()
    built = build(scene)
    d = np.asarray(directions, np.float64).reshape(-1, 3)
    o = np.broadcast_to(np.asarray(origins, np.float64), d.shape)
    limit = np.broadcast_to(np.inf if maxt is None else np.asarray(maxt, np.float64), len(d))
    if not len(d):
        return {"instance": np.zeros(0, np.int64), "shape": np.zeros(0, np.int64), "names": list(built.names),
                "prim": np.zeros(0, np.int64), "u": np.zeros(0), "v": np.zeros(0), "t": np.zeros(0)}
    onto = set(onto)
    wanted = np.array([False] + [n in onto for n in built.names])[built.tables["shape"]]  # by registry id
    table = mi.UInt32(wanted.astype(np.uint32))
    origin = mi.Point3f(*(aligned_floats(o[:, k]) for k in range(3)))  # one kernel at any address
    direction = mi.Vector3f(*(aligned_floats(d[:, k]) for k in range(3)))
    far = aligned_floats(np.minimum(limit, np.finfo(np.float32).max))

    def cond(k, start, active, found, reg, prim, u, v, t):
        return active

    def body(k, start, active, found, reg, prim, u, v, t):
        ray = mi.Ray3f(origin + direction * start, direction)
        ray.maxt = far - start
        si = built.mi_scene.ray_intersect_preliminary(ray, coherent=False, active=active)
        met = active & si.is_valid()
        r = dr.reinterpret_array(mi.UInt32, si.shape)
        done = met & (dr.gather(mi.UInt32, table, r, met) > 0)
        return (k + 1, dr.select(met, start + si.t + STEP, start), met & ~done & (k + 1 < rounds), found | done,
                dr.select(done, r, reg), dr.select(done, si.prim_index, prim), dr.select(done, si.prim_uv.x, u),
                dr.select(done, si.prim_uv.y, v), dr.select(done, start + si.t, t))
    n = len(d)
    state = (mi.UInt32(0), dr.zeros(mi.Float, n), far > 0, dr.zeros(mi.Bool, n), dr.zeros(mi.UInt32, n),
             dr.zeros(mi.UInt32, n), dr.zeros(mi.Float, n), dr.zeros(mi.Float, n), dr.zeros(mi.Float, n))
    _, _, _, found, reg, prim, u, v, t = dr.while_loop(state, cond, body)
    dr.eval(found, reg, prim, u, v, t)  # one kernel: read one by one, each would run the loop again
    return _hit_arrays(built, found, reg, prim, u, v, t)


def far_side(points, eye, margin: float = 0.01) -> float:
    """A ``maxt`` for rays from ``eye`` that look for ``points`` (N, 3): the far side of their
    bounding sphere, ``margin`` metres on (strand radii)."""
    lo, hi = bounds(np.asarray(points, np.float64).reshape(-1, 3))
    return float(np.linalg.norm((lo + hi) / 2 - np.asarray(eye, np.float64)) + np.linalg.norm(hi - lo) / 2 + margin)
