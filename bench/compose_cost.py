"""Scene composition costs (issue 7), printed as JSON:

- occlusion scoring throughput: our first-hit casts (Mitsuba's scene.ray_intersect_preliminary
  on the loaded scene) against embreex (Embree 4 through Python) casting the same rays at the
  same triangles, in the same run, as a ratio (goal: >= 1);
- composition time for 4 subjects and 4 views (subject building included and reported apart);
- render_sequence: the first frame (scene load, kernel compilation) against the next ones.

    python bench/compose_cost.py [--subjects 4] [--views 4] [--frames 6]
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np


def _rays(spec, scene, placed, cameras: int, points: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Eyes on a ring around the group and points on the bodies: what occlusion scoring casts."""
    from synmitsuba.compose.occlusion import surface_samples
    centre = np.mean([[(s.footprint[0] + s.footprint[2]) / 2, 0.9, (s.footprint[1] + s.footprint[3]) / 2]
                      for s in spec.subjects], 0)
    a = np.linspace(0, 2 * np.pi, cameras, endpoint=False)
    eyes = centre + np.stack([6 * np.sin(a), np.full_like(a, 1.5), 6 * np.cos(a)], 1)
    targets = []
    for p in placed:
        body = p.human.pose(*p.motion.frame(0))[0]
        targets.append(surface_samples(body.vertices, body.faces, points, rng).on(body.vertices))
    targets = np.concatenate(targets)
    return np.repeat(eyes, len(targets), 0), np.tile(targets, (cameras, 1))


def _triangles_only(scene):
    import synmitsuba as sm
    tri = sm.Scene()
    for name, m in scene.meshes.items():
        tri.add_mesh(name, m.vertices, m.faces, instance=m.instance)
    return tri


def _embree(scene):
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh
    es = rtcs.EmbreeScene()
    ids = []
    for m in scene.meshes.values():
        TriangleMesh(es, m.vertices[m.faces].astype(np.float32))
        ids.append(m.instance)
    return es, np.array(ids)


def _best(fn, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def occlusion_throughput(spec, rng) -> dict:
    from synmitsuba.engine.raycast import first_hits
    scene, placed = spec.build()
    origins, targets = _rays(spec, scene, placed, 64, 256, rng)
    tri = _triangles_only(scene)
    ours = first_hits(tri, origins, targets)  # warm: load + kernel compilation
    es, geom_ids = _embree(tri)
    d = targets - origins
    length = np.linalg.norm(d, axis=1)
    dirs = (d / length[:, None]).astype(np.float32)
    o32, far = origins.astype(np.float32), (length - 1e-4).astype(np.float32)

    def embree():
        g = es.run(o32, dirs, dists=far, output=1)["geomID"]
        return np.where(g >= 0, geom_ids[np.maximum(g, 0)], 0)
    agree = float((embree() == ours).mean())
    t_ours = _best(lambda: first_hits(tri, origins, targets))
    t_embree = _best(embree)
    n = len(origins)
    return {"rays": n, "triangles": int(sum(len(m.faces) for m in tri.meshes.values())),
            "ours_rays_per_s": round(n / t_ours), "embreex_rays_per_s": round(n / t_embree),
            "ratio_ours_over_embreex": round(t_embree / t_ours, 2), "same_first_hit": round(agree, 5),
            "with_hair_rays_per_s": round(n / _best(lambda: first_hits(scene, origins, targets)))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=4)
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--frames", type=int, default=6)
    args = ap.parse_args(argv)
    import synmitsuba as sm
    from synmitsuba.body import subject as subject_mod
    from synmitsuba.engine.build import STATS
    build_time = [0.0]
    original = subject_mod.build_subject

    def timed_build(recipe):
        t = time.perf_counter()
        try:
            return original(recipe)
        finally:
            build_time[0] += time.perf_counter() - t
    sm.set_variant()
    sm.build_subject(sm.sample_subject(np.random.default_rng(0), {"texture_size": 64}))  # anny loaded once, not timed
    subject_mod.build_subject = timed_build
    cfg = {"environments": ["plaza"], "subjects": {"count": args.subjects, "motions": ["walk", "idle", "wave", "jog"]},
           "cameras": {"count": args.views, "motion": ["static", "tracking", "orbit", "handheld"]}}
    t = time.perf_counter()
    spec = sm.compose_scene(cfg, np.random.default_rng(1), seed=1)
    compose_s = time.perf_counter() - t
    subject_mod.build_subject = original
    result = {"compose": {"subjects": len(spec.subjects), "views": len(spec.views), "seconds": round(compose_s, 2),
                          "of_which_building_subjects_s": round(build_time[0], 2),
                          "candidates_scored_frames": spec.scored_frames}}
    result["occlusion"] = occlusion_throughput(spec, np.random.default_rng(2))
    times, loads = [], STATS["loads"]
    t = time.perf_counter()
    for f, view, sample in sm.render_sequence(spec, frames=range(args.frames), views=[spec.views[0].name], spp=16):
        times.append(time.perf_counter() - t)
        t = time.perf_counter()
    result["render_sequence"] = {"resolution": [spec.views[0].cameras[0].width, spec.views[0].cameras[0].height],
                                 "spp": 16, "first_frame_s": round(times[0], 3),
                                 "next_frames_median_s": round(float(np.median(times[1:])), 3),
                                 "next_over_first": round(float(np.median(times[1:]) / times[0]), 3),
                                 "scene_loads": STATS["loads"] - loads}
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
