"""Denoising guide variants for OIDN (issue 39): PSNR against a 2048-spp reference and seconds,
on a sky-only diffuse scene and render_quality.py's sun + sky scene with two subjects.

- aov16 / aov4: Mitsuba's aov integrator (albedo, shading normal) through our sensor at 16 / 4
  spp (what sm.render uses: 16);
- first_hit1 / 4 / 9: primary rays only (1 = the pixel centre, as the exact passes; 4 / 9
  stratified jittered), the hit BSDF's diffuse reflectance and normal averaged per pixel.

    python bench/denoise_guides.py [RES]
"""
import json
import sys
import time

import numpy as np
import trimesh

import synmitsuba as sm


def first_hit_guides(mi_scene, camera, per_pixel, seed):
    """(albedo, normal) from primary rays alone: per pixel the mean over ``per_pixel`` rays."""
    import drjit as dr
    from synmitsuba.engine.rays import camera_rays
    ray, d = camera_rays(camera, per_pixel, None if per_pixel == 1 else seed)
    si = mi_scene.ray_intersect(ray)
    hit = si.is_valid()
    albedo = dr.select(hit, si.bsdf().eval_diffuse_reflectance(si, hit), 0.0)
    n = si.sh_frame.n
    normal = dr.select(hit, dr.select(dr.dot(n, d) > 0, -n, n), 0.0)
    dr.eval(albedo, normal)
    H, W = camera.height, camera.width

    def mean(v):
        return np.ascontiguousarray(np.array(v).T.reshape(H, W, per_pixel, 3).mean(2), np.float32)
    return mean(albedo), mean(normal)


def sky_scene(res):
    """A ground, a box and a sphere under a uniform sky (the issue's sky-only kind)."""
    scene = sm.Scene()
    quad = np.array([[-30, 0, -30], [30, 0, -30], [30, 0, 30], [-30, 0, 30]], float)
    scene.add_mesh("ground", quad, np.array([[0, 2, 1], [0, 3, 2]]), material=sm.Material(base_color=0.5))
    box = trimesh.creation.box((0.8, 0.8, 0.8))
    box.apply_translation((-0.6, 0.4, 0))
    scene.add_mesh("box", box.vertices, box.faces, material=sm.Material(base_color=(0.7, 0.3, 0.2)))
    ball = trimesh.creation.icosphere(5, 0.5)
    ball.apply_translation((0.6, 0.5, 0.2))
    scene.add_mesh("sphere", ball.vertices, ball.faces, material=sm.Material(base_color=(0.2, 0.4, 0.7)))
    scene.set_environment(sm.Constant(1.0))
    return scene, sm.Camera.look_at((0.3, 1.6, 3.2), (0, 0.4, 0), fov_y_deg=40, width=res, height=res)


def subjects_scene(res):
    from render_quality import build_scene
    return build_scene(res, None)


def variants():
    from synmitsuba.rendering.denoise import guides
    out = {f"aov{n}": (lambda built, cam, sd, seed, n=n: guides(built.mi_scene, sd, seed, n)) for n in (16, 4)}
    out.update({f"first_hit{n}": (lambda built, cam, sd, seed, n=n: first_hit_guides(built.mi_scene, cam, n, seed))
                for n in (1, 4, 9)})
    return out


def measure(scene, cam) -> dict:
    import mitsuba as mi

    from synmitsuba.engine.build import build
    from synmitsuba.io.preview import to_srgb8
    from synmitsuba.metrics import psnr
    from synmitsuba.rendering import sensor as sensor_mod
    from synmitsuba.rendering.denoise import oidn
    from synmitsuba.rendering.passes import render_rgb

    def srgb(x):
        return to_srgb8(x).astype(np.float64) / 255
    sensor_mod.register(mi.variant())
    built = build(scene)
    ref = render_rgb(scene, cam, 2048, 99)[0]
    sd = sensor_mod.sensor_dict(cam, 4)
    row: dict = {}
    for spp in (4, 16):
        noisy = render_rgb(scene, cam, spp, 5)[0]
        row[f"raw@{spp}"] = round(psnr(srgb(noisy), srgb(ref)), 2)
        for name, fn in variants().items():
            fn(built, cam, sd, 1)  # compiled once before timing
            t = time.perf_counter()
            a, n = fn(built, cam, sd, 1)
            tg = time.perf_counter() - t
            oidn(noisy, a, n)
            t = time.perf_counter()
            den = oidn(noisy, a, n)
            row[f"{name}@{spp}"] = {"psnr": round(psnr(srgb(den), srgb(ref)), 2), "guide_s": round(tg, 3),
                                    "oidn_s": round(time.perf_counter() - t, 3)}
    return row


def main() -> dict:
    res = int(sys.argv[1]) if len(sys.argv) > 1 else 256
    sm.set_variant()
    out = {name: measure(*make(res)) for name, make in (("sky_only", sky_scene), ("sun_sky_subjects", subjects_scene))}
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.path.insert(0, "bench")
    main()
