"""Building 4 subjects (the first, which loads anny, apart; goal <= 2 s for each other) and posing 4 subjects x 60 frames with all layers (body, garments, hair, accessories): ms per
frame with and without pushing garments out of the body (body.collide), and its share of a
512x512, 64 spp render of the same frame (goal <= 10 %). Prints JSON."""
from __future__ import annotations

import json
import time

import numpy as np


def main(render: bool = True) -> dict:
    import synmitsuba as sm
    sm.set_variant()
    rng = np.random.default_rng(0)
    t = time.perf_counter()
    humans = [sm.build_subject(sm.sample_subject(np.random.default_rng(0)))]  # loads anny (from its disk cache)
    first_s = time.perf_counter() - t
    t = time.perf_counter()
    humans += [sm.build_subject(sm.sample_subject(np.random.default_rng(s))) for s in range(1, 4)]
    build_s = (time.perf_counter() - t) / 3
    motions = [sm.retarget(sm.procedural_motion(k, rng, seconds=2.0), h.skeleton)
               for k, h in zip(("walk", "jog", "wave", "idle"), humans)]
    ms = {}
    for resolve in (False, True):
        t = time.perf_counter()
        for f in range(60):
            for h, m in zip(humans, motions):
                h.pose(*m.frame(f), resolve=resolve)
        ms[resolve] = 1e3 * (time.perf_counter() - t) / 60
    pose_ms = ms[True]
    garments = sum(len(h.garments) for h in humans)
    out = {"bench": "subject_pose", "subjects": 4, "frames": 60, "first_build_s": round(first_s, 2),
           "build_s_per_subject": round(build_s, 2), "build_goal_s": 2.0,
           "pose_ms_per_frame_all_subjects": round(pose_ms, 2),
           "pose_ms_per_frame_without_collisions": round(ms[False], 2),
           "collision_ms_per_garment_frame": round((ms[True] - ms[False]) / garments, 2), "garments": garments,
           "triangles": int(sum(len(p.faces) for h in humans for p in h.parts)),
           "strands": int(sum(len(h.hair) for h in humans))}
    if render:
        scene = sm.Scene()
        for i, (h, m) in enumerate(zip(humans, motions)):
            R, T = m.frame(30)
            h.add_to(scene, R, T + [1.2 * i - 1.8, 0, 0], instance=i + 1)
        scene.set_environment(sm.SunSky())
        cam = sm.Camera.look_at(eye=(0, 1.5, 6), target=(0, 0.9, 0), fov_y_deg=40, width=512, height=512)
        sm.render(scene, cam, spp=4)  # compile
        t = time.perf_counter()
        for i, (h, m) in enumerate(zip(humans, motions)):  # one animated frame: pose + update + render
            R, T = m.frame(31)
            h.add_to(scene, R, T + [1.2 * i - 1.8, 0, 0], instance=i + 1)
        s = sm.render(scene, cam, spp=64)
        frame_s = time.perf_counter() - t
        out.update(render_512_64spp_s=round(s.timings["rgb"] + s.timings["exact"], 2),
                   frame_total_s=round(frame_s, 2), pose_share=round(pose_ms / 1e3 / frame_s, 4), goal_share=0.10)
    return out


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))
