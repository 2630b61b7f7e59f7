"""Subsurface scattering for skin on this machine's variant (issue 32 item 4): what each option
costs and what it does to a backlit ear and a front-lit face. One subject's body alone (bald,
nothing worn, rest pose) under sun and sky, in Mitsuba scenes built here from its posed mesh:

- ``principled``: the skin's textured principled BSDF, path tracer (max depth 6): the skin
  before thin-skin translucency;
- ``thin``: the same blended with ``principledthin`` where the skin is thin (ears, nose wings,
  hands): what ``synmitsuba`` renders;
- ``volume<D>``: a rough dielectric boundary (IOR 1.4, roughness 0.3) round a homogeneous skin
  medium (Jensen et al. 2001's measured skin: reduced scattering 0.74 / 0.88 / 1.01 per mm,
  absorption 0.032 / 0.17 / 0.48 per mm, isotropic), volumetric path tracer at max depth D. It
  has no albedo map: lips, brows' skin, freckles and the tone's texture are lost unless a
  heterogeneous medium or a textured layer is added (more cost again).

Per option and view: median seconds of ``--repeats`` warm renders at ``--res`` px / ``--spp`` spp,
the mean linear RGB of the view's centre window, and its noise (per-pixel RMS difference of two
seeds' renders over sqrt 2, relative to the window's mean); printed with each option's time and
colour as ratios to ``principled``. Equal noise costs time x noise ratio squared.

    python bench/skin_sss.py [--res 128] [--spp 64] [--repeats 2] [--depths 64,256]
"""
import argparse
import json
import os
import tempfile
import time

import numpy as np

# Jensen, Marschner, Levoy, Hanrahan 2001, skin1: reduced scattering and absorption, per metre
SKIN_SIGMA_S = np.array([0.74, 0.88, 1.01]) * 1000.0
SKIN_SIGMA_A = np.array([0.032, 0.17, 0.48]) * 1000.0
SUNS = {"backlit_ear": (0.35, 0.3, -0.9), "front_face": (0.6, 0.5, 0.6)}


def _subject():
    import synmitsuba as sm
    recipe = sm.sample_subject(np.random.default_rng(3), {"hair_style": "bald", "accessories": []})
    human = sm.build_subject(recipe)
    scene = sm.Scene()
    human.add_to(scene)
    return human, scene.meshes["subject1_body"]


def _cameras(human, res: int) -> dict:
    import synmitsuba as sm
    kp = human.keypoints()
    ear, nose = kp[3], kp[0]
    return {"backlit_ear": sm.Camera.look_at(eye=tuple(ear + [0.12, 0.02, 0.3]), target=tuple(ear), fov_y_deg=16,
                                             width=res, height=res),
            "front_face": sm.Camera.look_at(eye=tuple(nose + [0.1, 0.0, 0.45]), target=tuple(nose - [0, 0.02, 0]),
                                            fov_y_deg=22, width=res, height=res)}


def _body(shape, option: str, folder: str) -> dict:
    """The body as a Mitsuba shape dict for ``option`` (a PLY written once per option)."""
    from dataclasses import replace
    import mitsuba as mi
    from synmitsuba.engine.build import _mesh, bsdf_dict
    material = shape.material if option == "thin" else replace(shape.material, translucency=None)
    path = os.path.join(folder, "body.ply")
    if not os.path.exists(path):
        _mesh(shape).write_ply(path)
    body = {"type": "ply", "filename": path}
    if not option.startswith("volume"):
        return {**body, "bsdf": mi.load_dict(bsdf_dict(material))}
    sigma_t = SKIN_SIGMA_S + SKIN_SIGMA_A
    return {**body, "bsdf": {"type": "roughdielectric", "int_ior": 1.4, "ext_ior": 1.0, "alpha": 0.3},
            "interior": {"type": "homogeneous", "phase": {"type": "isotropic"},
                         "albedo": {"type": "rgb", "value": (SKIN_SIGMA_S / sigma_t).tolist()},
                         "sigma_t": {"type": "rgb", "value": (sigma_t / sigma_t.max()).tolist()},
                         "scale": float(sigma_t.max())}}


def _render(body: dict, cam, sun, option: str, spp: int, repeats: int) -> tuple[float, np.ndarray, np.ndarray]:
    """Median warm seconds, the image at seed 1 and at seed 2 (linear RGB)."""
    import mitsuba as mi
    import synmitsuba as sm
    from synmitsuba.engine.build import environment_dict
    from synmitsuba.rendering import sensor as sensor_mod
    depth = int(option[6:]) if option.startswith("volume") else 6
    integrator = {"type": "volpath" if option.startswith("volume") else "path", "max_depth": depth}
    scene = mi.load_dict({"type": "scene", "integrator": integrator, "body": body,
                          "sky": environment_dict(sm.SunSky(sun_direction=sun))})
    sensor = mi.load_dict(sensor_mod.sensor_dict(cam, spp, "box", "independent"))
    other = np.array(mi.render(scene, sensor=sensor, spp=spp, seed=2))[..., :3]  # and compiles the kernels
    times = []
    for r in range(repeats):
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, sensor=sensor, spp=spp, seed=1))[..., :3]
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), img, other


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--depths", default="64,256", help="the volume's max path depths")
    ap.add_argument("--images", help="write each option's views here (PNG)")
    args = ap.parse_args(argv)
    import synmitsuba as sm
    from synmitsuba.rendering import sensor as sensor_mod
    variant = sm.set_variant()
    sensor_mod.register(variant)
    human, shape = _subject()
    cams = _cameras(human, args.res)
    options = ["principled", "thin"] + [f"volume{d}" for d in args.depths.split(",")]
    out: dict = {"variant": variant, "res": args.res, "spp": args.spp, "options": {}}
    lo, hi = args.res * 5 // 16, args.res * 11 // 16
    with tempfile.TemporaryDirectory() as folder:
        for option in options:
            body = _body(shape, option, folder)
            row = {}
            for view, cam in cams.items():
                seconds, img, other = _render(body, cam, SUNS[view], option, args.spp, args.repeats)
                a, b = img[lo:hi, lo:hi], other[lo:hi, lo:hi]
                row[view] = {"seconds": round(seconds, 3),
                             "centre_rgb": [round(float(c), 4) for c in a.reshape(-1, 3).mean(0)],
                             "noise": round(float(np.sqrt(np.mean((a - b) ** 2) / 2) / np.mean(a)), 3)}
                if args.images:
                    sm.write_png(os.path.join(args.images, f"{option}_{view}.png"), sm.to_srgb8(img))
            out["options"][option] = row
    base = out["options"]["principled"]
    for option, row in out["options"].items():
        for view, r in row.items():
            r["time_ratio"] = round(r["seconds"] / base[view]["seconds"], 2)
            r["rgb_ratio"] = [round(a / b, 3) for a, b in zip(r["centre_rgb"], base[view]["centre_rgb"])]
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()
