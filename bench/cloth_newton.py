"""Newton's cloth solvers on our garments (issue 34, a first measurement before the cloth stage).

A subject's skirt (or another garment) in the rest pose, its top 2 cm held (a waistband), its
body a static mesh collider and a ground, let hang under gravity for ``--frames`` frames at 30 fps; per solver (VBD, XPBD,
Style3D where it builds) on the CPU: seconds per frame after the first (which compiles Warp
kernels, cached on disk afterwards), the garment's largest and median drop from where it
started (does it hang, or stay a shell?), the share of its vertices inside the body (sign of
the nearest body face's normal, as the issue's independent check) and whether two runs give
bit-identical positions. Prints JSON.

    python bench/cloth_newton.py [--garment skirt] [--frames 30] [--substeps 10] [--iterations 5]
                                 [--solvers vbd,xpbd,style3d] [--figure PNG]
"""
import argparse
import json
import os
import sys
import time

import numpy as np


def subject_meshes(garment: str, seed: int):
    """(body vertices, body faces, garment vertices, garment faces) in the rest pose, metres, y up."""
    import synmitsuba as sm
    rng = np.random.default_rng(seed)
    human = sm.build_subject(sm.sample_subject(rng, {"outfit": ["tshirt", garment] if garment != "tshirt"
                                                     else ["tshirt", "trousers"], "hair_style": "bald",
                                                     "jacket": False, "shoes": False, "accessories": []}))
    layers = human.pose()
    body = np.empty_like(human.body.vertices)
    body[human.split.source] = layers[0].vertices  # the closed body (the layer splits its uv seams)
    g = next(p for p in layers if p.name == garment)
    gv, gf = weld(g.vertices, g.faces)
    return body, human.body.faces, gv, gf


def weld(vertices, faces):
    """One vertex where the layer splits its uv seams (else the cloth's panels fall apart)."""
    _, first, inverse = np.unique(np.round(vertices / 1e-6).astype(np.int64), axis=0, return_index=True,
                                  return_inverse=True)
    return vertices[first], inverse.reshape(-1)[faces]


def build_model(solver: str, body, garment, density: float = 0.2):
    import newton
    import warp as wp
    bv, bf, gv, gf = body + garment
    builder = newton.ModelBuilder(up_axis=newton.Axis.Y)  # gravity along -y
    if solver == "style3d":
        newton.solvers.SolverStyle3D.register_custom_attributes(builder)
    builder.add_ground_plane()
    builder.add_shape_mesh(body=-1, mesh=newton.Mesh(bv.astype(np.float32), bf.astype(np.int32).ravel()))
    cloth = dict(pos=wp.vec3(0, 0, 0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0, 0, 0),
                 vertices=[wp.vec3(*v) for v in gv.astype(np.float32)], indices=gf.astype(np.int32).ravel().tolist(),
                 density=density, particle_radius=0.004)
    if solver == "style3d":
        from newton.solvers import style3d
        style3d.add_cloth_mesh(builder, **cloth, tri_aniso_ke=wp.vec3(1.0e2, 1.0e2, 1.0e1),
                               edge_aniso_ke=wp.vec3(2.0e-5, 1.0e-5, 5.0e-6))
    elif solver == "xpbd":
        builder.add_cloth_mesh(**cloth, add_springs=True, spring_ke=1.0e3, spring_kd=1.0)
    else:
        builder.add_cloth_mesh(**cloth, tri_ke=1.0e3, tri_ka=1.0e3, tri_kd=1.0e-1, edge_ke=1.0e-2)
        builder.color(include_bending=True)
    model = builder.finalize()
    flags = model.particle_flags.numpy()  # the waistband (top 2 cm) held where it is, as a belt would
    flags[gv[:, 1] > gv[:, 1].max() - 0.02] &= ~newton.ParticleFlags.ACTIVE
    model.particle_flags = wp.array(flags, dtype=model.particle_flags.dtype)
    model.soft_contact_ke, model.soft_contact_kd, model.soft_contact_mu = 1.0e3, 1.0e-2, 0.5
    return model


def make_solver(name: str, model, iterations: int):
    import newton
    if name == "vbd":
        return newton.solvers.SolverVBD(model=model, iterations=iterations)
    if name == "xpbd":
        return newton.solvers.SolverXPBD(model=model, iterations=iterations)
    return newton.solvers.SolverStyle3D(model=model, config=newton.solvers.SolverStyle3D.Config(iterations=iterations))


def simulate(name: str, body, garment, frames: int, substeps: int, iterations: int) -> tuple[np.ndarray, list]:
    import newton
    model = build_model(name, body, garment)
    solver = make_solver(name, model, iterations)
    s0, s1, control = model.state(), model.state(), model.control()
    pipeline = newton.CollisionPipeline(model)
    contacts = pipeline.contacts()
    dt = 1.0 / 30 / substeps
    seconds = []
    for _ in range(frames):
        t = time.perf_counter()
        pipeline.collide(s0, contacts)
        for _ in range(substeps):
            s0.clear_forces()
            solver.step(s0, s1, control, contacts, dt)
            s0, s1 = s1, s0
        q = s0.particle_q.numpy()
        seconds.append(time.perf_counter() - t)
    return q.astype(np.float64), seconds


def inside_share(points, bv, bf) -> tuple[float, float]:
    """(share of points inside the body, deepest metres): behind the closest body point and a
    winding number over 0.5 (garment_collisions.py's check)."""
    from reference import winding_numbers  # tests/reference.py: the independent check

    from synmitsuba.body.binding import signed_distance
    d = signed_distance(bv, bf, points, k=8)
    behind = np.flatnonzero(d < 0)
    inside = behind[winding_numbers(bv, bf, points[behind]) > 0.5]
    return float(len(inside) / len(points)), float(-d[inside].min()) if len(inside) else 0.0


def figure(path: str, body, garment, draped) -> None:
    """Front and side views of the garment as built (left) and as the first solver left it."""
    from PIL import Image

    import synmitsuba as sm
    tiles = []
    for verts in (garment[0], draped):
        scene = sm.Scene()
        scene.set_environment(sm.SunSky(sun_direction=(0.4, 1.0, 0.6)))
        scene.add_mesh("body", *body, material=sm.Material(base_color=(0.7, 0.5, 0.4)))
        scene.add_mesh("garment", verts, garment[1], material=sm.Material(base_color=(0.2, 0.3, 0.6)))
        for eye in ((0, 1.0, 2.2), (2.2, 1.0, 0.3)):
            cam = sm.Camera.look_at(eye=eye, target=(0, 0.85, 0), fov_y_deg=35, width=256, height=320)
            tiles.append(np.clip(sm.render(scene, cam, spp=32, denoise="oidn").rgb, 0, 1) ** (1 / 2.2))
    Image.fromarray((np.concatenate(tiles, 1) * 255 + 0.5).astype(np.uint8)).save(path)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--garment", default="skirt")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--substeps", type=int, default=10)
    ap.add_argument("--iterations", type=int, default=5)
    ap.add_argument("--solvers", default="vbd,xpbd,style3d")
    ap.add_argument("--figure", help="PNG: the garment as built and as the first solver draped it")
    args = ap.parse_args(argv)
    import warp as wp
    import synmitsuba as sm
    sm.set_variant()
    bv, bf, gv, gf = subject_meshes(args.garment, args.seed)
    out: dict = {"bench": "cloth_newton", "garment": args.garment, "garment_vertices": len(gv),
                 "body_faces": len(bf), "frames": args.frames, "substeps": args.substeps,
                 "iterations": args.iterations, "start_inside": inside_share(gv, bv, bf)}
    draped = {}
    with wp.ScopedDevice("cpu"):
        for name in args.solvers.split(","):
            try:
                q, secs = simulate(name, (bv, bf), (gv, gf), args.frames, args.substeps, args.iterations)
                q2, _ = simulate(name, (bv, bf), (gv, gf), min(args.frames, 3), args.substeps, args.iterations)
                q3, _ = simulate(name, (bv, bf), (gv, gf), min(args.frames, 3), args.substeps, args.iterations)
            except Exception as e:  # a solver that does not build on this mesh is reported, not fatal
                out[name] = {"error": f"{type(e).__name__}: {e}"[:300]}
                continue
            draped[name] = q
            drop = gv[:, 1] - q[:, 1]
            share, deepest = inside_share(q, bv, bf) if np.isfinite(q).all() else (float("nan"), float("nan"))
            out[name] = {"first_frame_s": round(secs[0], 2), "s_per_frame": round(float(np.median(secs[1:])), 3),
                         "drop_max_m": round(float(drop.max()), 4), "drop_median_m": round(float(np.median(drop)), 4),
                         "finite": bool(np.isfinite(q).all()), "inside_share": round(share, 5),
                         "deepest_inside_m": round(deepest, 4), "bit_identical_runs": bool(np.array_equal(q2, q3))}
            print(name, json.dumps(out[name]), flush=True)
    if args.figure and draped:
        figure(args.figure, (bv, bf), (gv, gf), next(iter(draped.values())))
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
    main()
