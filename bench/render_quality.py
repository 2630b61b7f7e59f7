"""Image quality per second: synmitsuba (sm.render) against Blender Cycles on the same scenes.

Three kinds of scene (``--scenes``), every material diffuse in both renderers:
- ``sun_sky_subjects``: two posed subjects (textured garments, no hair: curves do not export) on
  a ground under a constant sky and a sun;
- ``hdri_subjects``: the same subjects and ground lit by an HDRI alone (city.exr, its sun in it);
- ``sky_only``: a ground, a box and an 82k-face sphere under a constant sky.
Each renderer is measured against its own high-spp reference (no denoising), at 1/4/16/64 spp,
raw and with Intel Open Image Denoise at its qualities (ours: ``denoise="oidn"``,
``"oidn-balanced"``, ``"oidn-fast"``; Cycles: its default, and quality FAST with prefilter FAST);
PSNR and SSIM on the sRGB-encoded image clipped to [0, 1]; seconds of the render call (ours:
sm.render with its label passes; Cycles: bpy.ops.render.render), medians of ``--repeat`` runs
after a warm-up. Then the seconds each needs to reach 40 and 45 dB, interpolated in log time
between measured points, the best over its defaults (raw, or OIDN at its best quality: what
BlenderProc and Kubric run) and over every choice (the faster OIDN qualities too), and Cycles'
time over ours per scene; the summary quotes the worst scene. Prints JSON.

    python bench/render_quality.py [--res 256] [--ref-spp 4096] [--scenes a,b] [--bpy PYTHON] [--images DIR]

``--bpy``: a Python with ``bpy`` (``make bench-cycles`` makes one in .bpy/; not a dependency of
synmitsuba); without it only our side is measured.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from subject_cache import cached

SPPS = (1, 4, 16, 64, 256)
DEFAULTS = ("none", "oidn")  # raw, or OIDN as each renderer runs it out of the box (its best quality)
OURS_DENOISE = ("none", "oidn", "oidn-balanced", "oidn-fast")
CYCLES_DENOISE = ("none", "oidn", "oidn-fast")
SUN_TOWARDS, SUN_IRRADIANCE, SKY = (0.5, 0.9, 0.7), 3.0, (0.35, 0.45, 0.6)
HDRI = "city.exr"


def _subjects(subjects_path: str | None) -> list:
    import synmitsuba as sm

    def make():
        out = []
        for k, (kind, x) in enumerate((("walk", -0.45), ("wave", 0.5))):
            rng = np.random.default_rng(30 + k)
            human = sm.build_subject(sm.sample_subject(rng, {"hair_style": "bald"}))
            clip = sm.retarget(sm.procedural_motion(kind, rng, seconds=1.0), human.skeleton)
            out.append((human, clip.moved(0, (x, 0, 0))))
        return out
    return cached(subjects_path, make)


def _ground(scene, size: float = 30.0, color: float = 0.45) -> None:
    from synmitsuba.scene.materials import Material
    quad = np.array([[-size, 0, -size], [size, 0, -size], [size, 0, size], [-size, 0, size]], float)
    scene.add_mesh("ground", quad, np.array([[0, 2, 1], [0, 3, 2]]), material=Material(base_color=color))


def _add_subjects(scene, subjects: list) -> None:
    from synmitsuba.scene.materials import Material
    for k, (human, clip) in enumerate(subjects):
        for layer in human.pose(*clip.frame(12)):
            if not layer.is_curves:
                m = layer.material
                scene.add_mesh(f"s{k}_{layer.name}", layer.vertices, layer.faces, uv=layer.uv, instance=k + 1,
                               material=Material(base_color=m.base_color, texture=m.texture))


def _subjects_camera(res: int):
    import synmitsuba as sm
    return sm.Camera.look_at(eye=(0.4, 1.35, 4.4), target=(0.0, 0.95, 0.0), fov_y_deg=38.0, width=res, height=res)


def sun_sky_subjects(res: int, subjects_path: str | None):
    """Two subjects on a ground, a constant sky and a sun (the bench's first scene)."""
    import synmitsuba as sm
    scene = sm.Scene()
    _ground(scene)
    _add_subjects(scene, _subjects(subjects_path))
    scene.set_environment(sm.Constant(SKY))
    scene.add_light(sm.DirectionalLight(direction=tuple(-np.asarray(SUN_TOWARDS)), irradiance=SUN_IRRADIANCE))
    return scene, _subjects_camera(res)


def hdri_subjects(res: int, subjects_path: str | None):
    """The same subjects and ground under an HDRI alone (a city street, its sun in the map)."""
    import synmitsuba as sm
    from synmitsuba.resources import asset_path
    scene = sm.Scene()
    _ground(scene)
    _add_subjects(scene, _subjects(subjects_path))
    scene.set_environment(sm.EnvMap(source=asset_path("scenes", "hdri", HDRI)))
    return scene, _subjects_camera(res)


def sky_only(res: int, subjects_path: str | None):
    """A ground, a box and an 82k-face sphere under a uniform sky (the issue's sky-only kind)."""
    import trimesh

    import synmitsuba as sm
    scene = sm.Scene()
    _ground(scene, color=0.5)
    box = trimesh.creation.box((0.8, 0.8, 0.8))
    box.apply_translation((-0.6, 0.4, 0))
    scene.add_mesh("box", box.vertices, box.faces, material=sm.Material(base_color=(0.7, 0.3, 0.2)))
    ball = trimesh.creation.icosphere(6, 0.5)
    ball.apply_translation((0.6, 0.5, 0.2))
    scene.add_mesh("sphere", ball.vertices, ball.faces, material=sm.Material(base_color=(0.2, 0.4, 0.7)))
    scene.set_environment(sm.Constant(1.0))
    return scene, sm.Camera.look_at((0.3, 1.6, 3.2), (0, 0.4, 0), fov_y_deg=40, width=res, height=res)


SCENES = {"sun_sky_subjects": sun_sky_subjects, "hdri_subjects": hdri_subjects, "sky_only": sky_only}


def build_scene(res: int, subjects_path: str | None, kind: str = "sun_sky_subjects"):
    """The comparison scene ``kind``: what both renderers draw."""
    return SCENES[kind](res, subjects_path)


def export(scene, camera, path: str, threads: int) -> None:
    """The scene as arrays for cycles_render.py (the camera's vertical field of view from K)."""
    import synmitsuba as sm
    data = {"n_meshes": len(scene.meshes), "threads": threads, "width": camera.width, "height": camera.height,
            "fov_y_deg": float(np.degrees(2 * np.arctan(camera.height / (2 * camera.K[1, 1]))))}
    env = scene.environment
    if isinstance(env, sm.Constant):
        data["env_radiance"] = np.asarray(env.radiance, float)
    else:  # an EnvMap, Mitsuba's layout (u = 0.25 looks along +x, 0.5 along +z; row 0 up)
        data["env_map"], data["env_scale"] = env.pixels(), float(env.scale)
        assert env.rotation_deg == 0
    for light in scene.lights:
        d = -np.asarray(light.direction, float)
        data["sun_direction"], data["sun_irradiance"] = d / np.linalg.norm(d), float(np.mean(light.irradiance))
    c2w = np.eye(4)
    c2w[:3, :3], c2w[:3, 3] = camera.R.T, -camera.R.T @ camera.t
    data["cam_to_world"] = c2w
    for i, m in enumerate(scene.meshes.values()):
        data[f"{i}_vertices"], data[f"{i}_faces"] = m.vertices, m.faces.astype(np.int64)
        data[f"{i}_color"] = np.asarray(m.material.base_color, float)
        if m.uv is not None and m.material.texture is not None:
            data[f"{i}_uv"], data[f"{i}_texture"] = m.uv, m.material.texture
    np.savez(path, **data)


def srgb(img: np.ndarray) -> np.ndarray:
    x = np.clip(img, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def score(img, ref) -> dict:
    from synmitsuba.metrics import psnr, ssim
    a, b = srgb(img), srgb(ref)
    return {"psnr_db": round(psnr(a, b), 2), "ssim": round(ssim(a, b), 4)}


def seconds_to(points: list, target: float):
    """Seconds to reach ``target`` dB, interpolated in log time between the measured
    (seconds, psnr) points; None when no point reaches it."""
    pts = sorted((p["seconds"], p["psnr_db"]) for p in points)
    for (t0, q0), (t1, q1) in zip([(pts[0][0], -np.inf)] + pts, pts):
        if q1 >= target:
            if not np.isfinite(q0) or q1 == q0:
                return round(t1, 3)
            w = (target - q0) / (q1 - q0)
            return round(float(np.exp(np.log(t0) + w * (np.log(t1) - np.log(t0)))), 3)
    return None


def ours(scene, camera, ref_spp: int, repeat: int) -> tuple[dict, np.ndarray]:
    import synmitsuba as sm
    chunk = min(ref_spp, 256)  # the wavefront holds every sample: the reference goes in chunks
    ref = np.mean([sm.render(scene, camera, spp=chunk, seed=1000 + k).rgb for k in range(ref_spp // chunk)], 0)
    rows, images = [], {}
    for spp in SPPS:
        for denoise in OURS_DENOISE:
            sm.render(scene, camera, spp=spp, seed=0, denoise=denoise)  # warm-up: kernels for this spp
            times = []
            for _ in range(repeat):
                t = time.perf_counter()
                s = sm.render(scene, camera, spp=spp, seed=0, denoise=denoise)
                times.append(time.perf_counter() - t)
            rgb_s = s.timings["rgb"] + s.timings["denoise"]
            rows.append({"spp": spp, "denoise": denoise, "seconds": round(float(np.median(times)), 4),
                         "rgb_seconds": round(rgb_s, 4), **score(s.rgb, ref)})
            images[(spp, denoise)] = s.rgb
    return {"rows": rows, "images": images}, ref


def cycles(scene, camera, python: str, ref_spp: int, repeat: int, threads: int) -> tuple[dict, np.ndarray]:
    work = tempfile.mkdtemp(prefix="synmitsuba-cycles-")
    export(scene, camera, os.path.join(work, "scene.npz"), threads)
    jobs = [{"name": "ref", "spp": ref_spp, "denoise": "none", "seed": 1000, "adaptive": False}]
    for spp in SPPS:
        for denoise in CYCLES_DENOISE:
            jobs += [{"name": f"{spp}_{denoise}_{r}", "spp": spp, "denoise": denoise, "seed": 0} for r in range(repeat + 1)]
    with open(os.path.join(work, "jobs.json"), "w") as fh:
        json.dump(jobs, fh)
    here = os.path.dirname(os.path.abspath(__file__))
    subprocess.run([python, os.path.join(here, "cycles_render.py"), os.path.join(work, "scene.npz"),
                    os.path.join(work, "jobs.json"), work], check=True, capture_output=True)
    with open(os.path.join(work, "times.json")) as fh:
        times = json.load(fh)
    ref = np.load(os.path.join(work, "ref.npy"))
    rows, images = [], {}
    for spp in SPPS:
        for denoise in CYCLES_DENOISE:
            img = np.load(os.path.join(work, f"{spp}_{denoise}_{repeat}.npy"))
            t = np.median([times[f"{spp}_{denoise}_{r}"] for r in range(1, repeat + 1)])  # run 0 warms up
            rows.append({"spp": spp, "denoise": denoise, "seconds": round(float(t), 4), **score(img, ref)})
            images[(spp, denoise)] = img
    return {"rows": rows, "images": images, "reference_seconds": round(times["ref"], 2)}, ref


def time_to_psnr(rows: list) -> dict:
    """Per denoising choice the seconds to 40 and 45 dB; the best of the defaults (raw or OIDN at
    its best quality) and the best of every choice (OIDN's faster qualities too)."""
    out: dict = {}
    for denoise in dict.fromkeys(r["denoise"] for r in rows):
        pts = [r for r in rows if r["denoise"] == denoise]
        out[denoise] = {f"{db}db": seconds_to(pts, db) for db in (40, 45)}

    def best(names):
        return {db: min([out[n][db] for n in names if out[n][db] is not None], default=None) for db in ("40db", "45db")}
    out["best_defaults"], out["best_any"] = best(DEFAULTS), best(list(out))
    return out


def save_images(folder: str, kind: str, results: dict, refs: dict) -> None:
    """One strip per renderer: reference, then 4 and 16 spp raw and with OIDN."""
    from PIL import Image
    os.makedirs(folder, exist_ok=True)
    for name, res in results.items():
        tiles = [refs[name]] + [res["images"][(spp, d)] for spp in (4, 16) for d in ("none", "oidn")]
        strip = np.concatenate([srgb(t) for t in tiles], 1)
        Image.fromarray((strip * 255 + 0.5).astype(np.uint8)).save(os.path.join(folder, f"quality_{kind}_{name}.png"))


def measure(kind: str, args, threads: int) -> dict:
    scene, camera = build_scene(args.res, args.subjects, kind)
    results, refs = {}, {}
    results["synmitsuba"], refs["synmitsuba"] = ours(scene, camera, args.ref_spp, args.repeat)
    if args.bpy:
        results["cycles"], refs["cycles"] = cycles(scene, camera, args.bpy, args.ref_spp, args.repeat, threads)
    if args.images:
        save_images(args.images, kind, results, refs)
    out: dict = {}
    for name, res in results.items():
        out[name] = {"rows": res["rows"], "time_to_psnr": time_to_psnr(res["rows"]),
                     **{k: v for k, v in res.items() if k not in ("rows", "images")}}
    if "cycles" in results:
        out["cycles_over_synmitsuba_time"] = {}
        for which in ("best_defaults", "best_any"):
            ours_t, theirs = (out[n]["time_to_psnr"][which] for n in ("synmitsuba", "cycles"))
            out["cycles_over_synmitsuba_time"][which] = {db: (round(theirs[db] / ours_t[db], 2)
                                                              if theirs[db] and ours_t[db] else None)
                                                         for db in ("40db", "45db")}
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", default=",".join(SCENES), help=f"comma-separated, of {', '.join(SCENES)}")
    ap.add_argument("--bpy", help="a Python with bpy (Blender as a module) for the Cycles side")
    ap.add_argument("--subjects", help="file of built subjects: read if present, else written (see subject_cache.py)")
    ap.add_argument("--images", help="folder for the image strips (PNG)")
    args = ap.parse_args(argv)
    import synmitsuba as sm
    sm.set_variant()
    threads = os.cpu_count() or 1
    out: dict = {"bench": "render_quality", "res": args.res, "ref_spp": args.ref_spp, "threads": threads}
    for kind in args.scenes.split(","):
        out[kind] = measure(kind, args, threads)
    if args.bpy:  # the worst scene, each renderer at its defaults and at its fastest settings
        ratios = [out[kind]["cycles_over_synmitsuba_time"] for kind in args.scenes.split(",")]
        out["worst_cycles_over_synmitsuba_time"] = {
            which: {db: min((r[which][db] for r in ratios if r[which][db]), default=None) for db in ("40db", "45db")}
            for which in ("best_defaults", "best_any")}
        out["goal_cycles_over_synmitsuba_time"] = 3.0
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
