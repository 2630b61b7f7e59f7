"""Places (issue 36): what each environment costs to build and render, the ground materials'
repeat over 30 m, the new ground against a single-tile one, and the HDRI backdrops' resolution
at 1280 x 720. Prints JSON.

Per environment (``sm.environment_names()``): ``build_s`` (its ground, objects, lighting into a
Scene, as the compose stage does), ``render_s`` (Mitsuba's scene load and one 640 x 360 frame at
16 spp, no people, from 1.6 m up, 7 m from the area's centre), triangles and texture megabytes;
the 6 original environments (with their new grounds) are the reference the new kinds are
compared to as a ratio. ``ground``: plaza's blended ground against its first tile alone (what
one repeating texture costs). ``repeat``: per ground material, how much more alike 20 cm blocks
of a rendered top view are one tile period apart than at other lags (0: nothing repeats; the
single tile for reference). ``backdrop``: HDRI texels per image pixel. ``projection``: one
frame of a composed ``hdri_city`` scene (2 people, 4 views, motion blur) with each view's own
projection (the ground rebuilt per view and sub-frame) against one projection for all views.

    python bench/places.py
"""
import json
import time

import numpy as np

ORIGINAL = ("plaza", "park", "street", "courtyard", "beach", "gallery")


def _camera(env, width=640, height=360):
    import synmitsuba as sm
    cx, cz = (env.area[0] + env.area[2]) / 2, (env.area[1] + env.area[3]) / 2
    return sm.Camera.look_at((cx + 2.0, 1.6, cz + 7.0), (cx, 1.0, cz), fov_y_deg=40, width=width, height=height)


def environment_cost(name: str) -> dict:
    import synmitsuba as sm
    from synmitsuba.compose import environments as E
    from synmitsuba.rendering.passes import render_rgb
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    env = E.load_environment(name)
    scene = sm.Scene()
    E.add_environment(scene, env, E.sample_lighting(env, rng), rng)
    t1 = time.perf_counter()
    render_rgb(scene, _camera(env), spp=16)
    t2 = time.perf_counter()
    tex = 0
    for m in scene.meshes.values():
        for mat in ((m.material.a, m.material.b) if isinstance(m.material, sm.Blend) else (m.material,)):
            tex += sum(a.nbytes for a in (mat.texture, mat.roughness_map, mat.normal_map) if a is not None)
        if isinstance(m.material, sm.Blend):
            tex += m.material.weight.nbytes + (m.material.normal_map.nbytes if m.material.normal_map is not None else 0)
    return {"build_s": round(t1 - t0, 3), "render_s": round(t2 - t1, 3), "objects": len(env.objects),
            "triangles": int(sum(len(m.faces) for m in scene.meshes.values())), "texture_mb": round(tex / 2 ** 20, 1),
            "area_m": [round(env.area[2] - env.area[0], 1), round(env.area[3] - env.area[1], 1)]}


def ground_against_single_tile() -> dict:
    import synmitsuba as sm
    from synmitsuba.compose import environments as E
    from synmitsuba.rendering.passes import render_rgb
    env = E.load_environment("plaza")
    out = {}
    for label in ("single_tile", "blended"):
        rng = np.random.default_rng(0)
        scene = sm.Scene()
        E.add_environment(scene, env, E.sample_lighting(env, rng), rng)
        if label == "single_tile":
            g = scene.meshes["ground"]
            scene.meshes["ground"] = type(g)(g.name, g.vertices, g.faces, g.uv, g.normals, g.material.a, g.instance, g.layer)
        cam = _camera(env)
        render_rgb(scene, cam, spp=1)   # load and compile once
        t = time.perf_counter()
        render_rgb(scene, cam, spp=16)
        out[label] = round(time.perf_counter() - t, 3)
    out["ratio"] = round(out["blended"] / out["single_tile"], 2)
    return out


def _corr(b, lag):
    pairs = [(b[:-lag], b[lag:]), (b[:, :-lag], b[:, lag:])]
    return float(np.mean([np.corrcoef(x.ravel(), y.ravel())[0, 1] for x, y in pairs]))


def repeat(material, period: float, span=30.0, px=300) -> float:
    """Excess correlation one tile period apart of 20 cm blocks of a top view's albedo."""
    import synmitsuba as sm
    from synmitsuba.geometry import ground_grid
    from synmitsuba.rendering.passes import render_rgb
    scene = sm.Scene()
    v, f = ground_grid(200.0)
    scene.add_mesh("ground", v, f, uv=v[:, [0, 2]] / period, normals=np.tile([0, 1.0, 0], (len(v), 1)), material=material)
    scene.set_environment(sm.Constant(1.0))
    fov = 2 * np.degrees(np.arctan(span / 2 / 1000.0))
    cam = sm.Camera.look_at((0, 1000.0, 0), (0, 0, 0), up=(0, 0, -1), fov_y_deg=fov, width=px, height=px)
    img = render_rgb(scene, cam, spp=1, guide_spp=64)[1][0].mean(-1)
    n = px // 2
    b = img[: 2 * n, : 2 * n].reshape(n, 2, n, 2).mean((1, 3))
    lag = int(round(period / (span / px) / 2))
    others = [_corr(b, k) for k in range(max(lag // 2, 1), 2 * lag + 1) if abs(k - lag) > 1]
    return round(_corr(b, lag) - float(np.median(others)), 3)


def projection_cost(spp: int = 16, shutter: float = 0.5) -> dict:
    """Seconds for one frame of 4 views, each projected from its camera, against all views
    seen with the first projection (``centre_backdrop`` a no-op), same scene and seed."""
    import synmitsuba as sm
    from synmitsuba import pipeline
    cfg = {"environments": ["hdri_city"], "subjects": {"count": 2, "seconds": 1.0},
           "cameras": {"count": 4, "width": 320, "height": 180, "hfov_deg": [40, 70]}}
    spec = sm.compose_scene(cfg, np.random.default_rng(2), seed=2)
    frame = spec.n_frames // 2
    out = {}
    own = pipeline.centre_backdrop
    for label, fn in (("per_view", own), ("one_projection", lambda scene, point: False)):
        pipeline.centre_backdrop = fn
        try:
            list(pipeline.render_sequence(spec, frames=[frame], spp=spp, seed=1, shutter=shutter, annotate=False))
            t = time.perf_counter()
            list(pipeline.render_sequence(spec, frames=[frame], spp=spp, seed=1, shutter=shutter, annotate=False))
            out[label] = round(time.perf_counter() - t, 2)
        finally:
            pipeline.centre_backdrop = own
    out["ratio"] = round(out["per_view"] / out["one_projection"], 2)
    return out


def main():
    import synmitsuba as sm
    from synmitsuba.compose import grounds
    names = sm.environment_names()
    envs = {n: environment_cost(n) for n in names}
    ref = {k: float(np.median([envs[n][k] for n in ORIGINAL])) for k in ("build_s", "render_s")}
    kinds = {"original": ORIGINAL, "backdrop": [n for n in names if n.startswith("hdri_")],
             "layout": [n for n in names if n in ("city_street", "living_room", "city_park")]}
    ratios = {kind: {k: round(float(np.median([envs[n][k] for n in members])) / max(ref[k], 1e-9), 2)
                     for k in ("build_s", "render_s")} for kind, members in kinds.items()}
    reps = {}
    for kind in grounds.GROUND_MATERIALS:
        mat, period = grounds.ground_material(kind, [0.3, 0.3, 0.3], np.random.default_rng(5), n=256)
        reps[kind] = {"blended": repeat(mat, period), "single_tile": repeat(mat.a, period)}
    texel_deg = 360.0 / 1024
    backdrop = {f"hfov_{h}": round(texel_deg * 1280 / h, 1) for h in (30, 60, 90)}
    print(json.dumps({"environments": envs, "median_ratio_to_original": ratios, "ground": ground_against_single_tile(),
                      "repeat": reps, "backdrop_pixels_per_hdri_texel": backdrop, "projection": projection_cost()},
                     indent=1))


if __name__ == "__main__":
    main()
