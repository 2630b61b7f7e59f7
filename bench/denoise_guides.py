"""Denoising guide variants for OIDN at its three qualities (issue 39): PSNR against a 2048-spp
reference and seconds, on render_quality.py's three scenes.

- aov16 / aov4: Mitsuba's aov integrator (albedo, shading normal) through our sensor at 16 / 4
  spp (what sm.render uses: 16), passed as clean guides;
- aov1_noisy: the same at 1 spp, passed as noisy (OIDN filters them with the colour, as Cycles'
  "fast" prefilter does);
- first_hit1 / 9: primary rays only (1 = the pixel centre, as the exact passes; 9 stratified
  jittered), the hit BSDF's diffuse reflectance and normal averaged per pixel.

    python bench/denoise_guides.py [RES]
"""
import json
import sys
import time

import numpy as np
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


def variants():
    """name -> (guides(built, camera, sensor_dict, seed), clean): ``clean`` guides go to OIDN as
    noise-free (cleanAux); the others it filters with the colour (Cycles' "fast" prefilter)."""
    from synmitsuba.rendering.denoise import guides
    out = {f"aov{n}": ((lambda built, cam, sd, seed, n=n: guides(built.mi_scene, sd, seed, n)), True) for n in (16, 4)}
    out["aov1_noisy"] = ((lambda built, cam, sd, seed: guides(built.mi_scene, sd, seed, 1)), False)
    out.update({f"first_hit{n}": ((lambda built, cam, sd, seed, n=n: first_hit_guides(built.mi_scene, cam, n, seed)),
                                  True) for n in (1, 9)})
    return out


def measure(scene, cam, qualities) -> dict:
    import mitsuba as mi
    import pyoidn

    from synmitsuba.engine.build import build
    from synmitsuba.io.preview import to_srgb8
    from synmitsuba.metrics import psnr
    from synmitsuba.rendering import sensor as sensor_mod
    from synmitsuba.rendering.passes import render_rgb

    def srgb(x):
        return to_srgb8(x).astype(np.float64) / 255

    def denoise(noisy, a, n, quality, clean):
        return np.maximum(pyoidn.denoise(np.ascontiguousarray(noisy, np.float32), a, np.clip(n, -1, 1), hdr=True,
                                         clean_aux=clean, quality=quality), 0)
    sensor_mod.register(mi.variant())
    built = build(scene)
    ref = np.mean([render_rgb(scene, cam, 256, 99 + k)[0] for k in range(8)], 0)
    sd = sensor_mod.sensor_dict(cam, 4)
    row: dict = {}
    for spp in (1, 4, 16):
        noisy = render_rgb(scene, cam, spp, 5)[0]
        row[f"raw@{spp}"] = round(psnr(srgb(noisy), srgb(ref)), 2)
        for name, (fn, clean) in variants().items():
            fn(built, cam, sd, 1)  # compiled once before timing
            t = time.perf_counter()
            a, n = fn(built, cam, sd, 1)
            tg = time.perf_counter() - t
            for q in qualities:
                denoise(noisy, a, n, q, clean)
                t = time.perf_counter()
                den = denoise(noisy, a, n, q, clean)
                row[f"{name}/{q}@{spp}"] = {"psnr": round(psnr(srgb(den), srgb(ref)), 2), "guide_s": round(tg, 3),
                                            "oidn_s": round(time.perf_counter() - t, 3)}
    return row


def main() -> dict:
    from render_quality import SCENES, build_scene
    res = int(sys.argv[1]) if len(sys.argv) > 1 else 256
    sm.set_variant()
    out = {kind: measure(*build_scene(res, None, kind), ("high", "balanced", "fast")) for kind in SCENES}
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.path.insert(0, "bench")
    main()
