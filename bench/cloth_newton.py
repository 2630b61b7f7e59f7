"""Newton's cloth solvers on our garments (issue 34, a first measurement before the cloth stage).

A subject's garment (skirt by default; uv seams welded), its top 2 cm held (a waistband), its
body a mesh collider and a ground, 30 fps with substeps, per solver (VBD, XPBD, Style3D) on
the CPU. Without ``--motion`` the garment hangs from the rest pose; with it the body walks
(jogs, ...) under the cloth: the collider and the waistband move to each substep's pose. Per
solver: seconds per frame after the first (the very first run also compiles Warp's kernels,
cached on disk afterwards), the garment's largest and median drop, the worst frame's share of
garment vertices inside the body and the deepest (behind the closest body point with a winding
number over 0.5, as garment_collisions.py checks), and whether two runs give bit-identical
positions. Prints JSON.

    python bench/cloth_newton.py [--garment skirt] [--motion walk] [--frames 30] [--substeps 10]
                                 [--iterations 5] [--solvers vbd,xpbd,style3d] [--no-full-contact]
                                 [--figure PNG]
"""
import argparse
import json
import os
import sys
import time

import numpy as np


class Subject:
    """A built subject and one of its garments, posed per clip frame: the closed body (the body
    layer splits its uv seams) and the garment with its seams welded (else the cloth's panels
    fall apart), the weld fixed at the first pose."""

    def __init__(self, garment: str, seed: int, motion: str | None):
        import synmitsuba as sm
        rng = np.random.default_rng(seed)
        outfit = ["tshirt", garment] if garment != "tshirt" else ["tshirt", "trousers"]
        self.human = sm.build_subject(sm.sample_subject(rng, {"outfit": outfit, "hair_style": "bald", "jacket": False,
                                                             "shoes": False, "accessories": []}))
        self.clip = (sm.retarget(sm.procedural_motion(motion, np.random.default_rng(0), seconds=2.0),
                                 self.human.skeleton) if motion else None)
        self.garment, self.body_faces = garment, self.human.body.faces
        body, g = self._layers(0)
        _, self.first, inverse = np.unique(np.round(g.vertices / 1e-6).astype(np.int64), axis=0, return_index=True,
                                           return_inverse=True)
        self.faces = inverse.reshape(-1)[g.faces]

    def _layers(self, frame: int):
        layers = self.human.pose(*self.clip.frame(frame)) if self.clip else self.human.pose()
        body = np.empty_like(self.human.body.vertices)
        body[self.human.split.source] = layers[0].vertices
        return body, next(p for p in layers if p.name == self.garment)

    def at(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """(closed body vertices, welded garment vertices) at a clip frame (the rest pose without a clip)."""
        body, g = self._layers(frame)
        return body, g.vertices[self.first]


def build_model(solver: str, body, garment, density: float = 0.2):
    """The Newton model: ground, the body as a mesh collider (returned to move it), the garment
    as cloth with its top 2 cm held (a waistband; moved with the body, not simulated)."""
    import newton
    import warp as wp
    bv, bf, gv, gf = body + garment
    builder = newton.ModelBuilder(up_axis=newton.Axis.Y)  # gravity along -y
    if solver == "style3d":
        newton.solvers.SolverStyle3D.register_custom_attributes(builder)
    builder.add_ground_plane()
    collider = newton.Mesh(bv.astype(np.float32), bf.astype(np.int32).ravel())
    builder.add_shape_mesh(body=-1, mesh=collider)
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
    held = gv[:, 1] > gv[:, 1].max() - 0.02
    flags = model.particle_flags.numpy()
    flags[held] &= ~newton.ParticleFlags.ACTIVE
    model.particle_flags = wp.array(flags, dtype=model.particle_flags.dtype)
    model.soft_contact_ke, model.soft_contact_kd, model.soft_contact_mu = 1.0e3, 1.0e-2, 0.5
    return model, collider, held


def make_solver(name: str, model, iterations: int):
    import newton
    if name == "vbd":
        return newton.solvers.SolverVBD(model=model, iterations=iterations)
    if name == "xpbd":
        return newton.solvers.SolverXPBD(model=model, iterations=iterations)
    return newton.solvers.SolverStyle3D(model=model, config=newton.solvers.SolverStyle3D.Config(iterations=iterations))


def simulate(name: str, subject: Subject, frames: int, substeps: int, iterations: int,
             full_contact: bool) -> tuple[np.ndarray, list, list]:
    """Final garment vertices, seconds per frame, and (inside share, deepest) per frame. With a
    clip the body collider and the held waistband move to each substep's pose (linear between
    frames); ``full_contact``: Newton's edge and face contacts against the body besides the
    per-vertex ones (VBD only), which catch a leg passing between the cloth's vertices."""
    import newton
    b0, g0 = subject.at(0)
    model, collider, held = build_model(name, (b0, subject.body_faces), (g0, subject.faces))
    solver = make_solver(name, model, iterations)
    s0, s1, control = model.state(), model.state(), model.control()
    pipeline = newton.CollisionPipeline(model, soft_contact_gap=0.01,
                                        enable_rigid_soft_full_surface_contact=full_contact)
    contacts = pipeline.contacts()
    dt = 1.0 / 30 / substeps
    seconds, inside, (prev_b, prev_g) = [], [], (b0, g0)
    for f in range(1, frames + 1):
        t = time.perf_counter()
        b, g = subject.at(f) if subject.clip else (b0, g0)
        for k in range(substeps):
            w = (k + 1) / substeps
            if subject.clip:
                collider.mesh.points.assign((prev_b + w * (b - prev_b)).astype(np.float32))
                collider.mesh.velocities.assign(((b - prev_b) * 30).astype(np.float32))
                collider.mesh.refit()
                q = s0.particle_q.numpy()
                q[held] = (prev_g + w * (g - prev_g))[held]
                s0.particle_q.assign(q)
            pipeline.collide(s0, contacts)
            s0.clear_forces()
            solver.step(s0, s1, control, contacts, dt)
            s0, s1 = s1, s0
        q = s0.particle_q.numpy().astype(np.float64)
        seconds.append(time.perf_counter() - t)
        inside.append(inside_share(q, b, subject.body_faces) if np.isfinite(q).all() else (np.nan, np.nan))
        prev_b, prev_g = b, g
    return q, seconds, inside


def inside_share(points, bv, bf) -> tuple[float, float]:
    """(share of points inside the body, deepest metres): behind the closest body point and a
    winding number over 0.5 (garment_collisions.py's check)."""
    from reference import winding_numbers  # tests/reference.py: the independent check

    from synmitsuba.body.binding import signed_distance
    d = signed_distance(bv, bf, points, k=8)
    behind = np.flatnonzero(d < 0)
    inside = behind[winding_numbers(bv, bf, points[behind]) > 0.5]
    return float(len(inside) / len(points)), float(-d[inside].min()) if len(inside) else 0.0


def figure(path: str, body, faces, garment, draped) -> None:
    """Front and side views of the garment as built (left) and as the first solver left it."""
    from PIL import Image

    import synmitsuba as sm
    tiles, centre = [], body.mean(0)
    for verts in (garment, draped):
        scene = sm.Scene()
        scene.set_environment(sm.SunSky(sun_direction=(0.4, 1.0, 0.6)))
        scene.add_mesh("body", body, faces[0], material=sm.Material(base_color=(0.7, 0.5, 0.4)))
        scene.add_mesh("garment", verts, faces[1], material=sm.Material(base_color=(0.2, 0.3, 0.6)))
        for eye in ((0, 0.1, 2.2), (2.2, 0.1, 0.3)):
            cam = sm.Camera.look_at(eye=tuple(centre + eye), target=tuple(centre - (0, 0.1, 0)), fov_y_deg=38,
                                    width=256, height=320)
            tiles.append(np.clip(sm.render(scene, cam, spp=32, denoise="oidn").rgb, 0, 1) ** (1 / 2.2))
    Image.fromarray((np.concatenate(tiles, 1) * 255 + 0.5).astype(np.uint8)).save(path)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--garment", default="skirt")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--motion", help="a procedural motion (walk, jog, ...): the body moves under the cloth")
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--substeps", type=int, default=10)
    ap.add_argument("--iterations", type=int, default=5)
    ap.add_argument("--solvers", default="vbd,xpbd,style3d")
    ap.add_argument("--no-full-contact", action="store_true", help="VBD with per-vertex body contacts only")
    ap.add_argument("--figure", help="PNG: the garment as built and as the first solver left it (last frame)")
    args = ap.parse_args(argv)
    import warp as wp

    import synmitsuba as sm
    sm.set_variant()
    subject = Subject(args.garment, args.seed, args.motion)
    b0, g0 = subject.at(0)
    out: dict = {"bench": "cloth_newton", "garment": args.garment, "motion": args.motion,
                 "garment_vertices": len(g0), "body_faces": len(subject.body_faces), "frames": args.frames,
                 "substeps": args.substeps, "iterations": args.iterations}
    draped = {}
    with wp.ScopedDevice("cpu"):
        for name in args.solvers.split(","):
            full = name == "vbd" and not args.no_full_contact  # the other solvers refuse those contacts
            try:
                q, secs, inside = simulate(name, subject, args.frames, args.substeps, args.iterations, full)
                runs = [simulate(name, subject, min(args.frames, 3), args.substeps, args.iterations, full)[0]
                        for _ in range(2)]
            except Exception as e:  # a solver that does not build on this mesh is reported, not fatal
                out[name] = {"error": f"{type(e).__name__}: {e}"[:300]}
                continue
            draped[name] = q
            drop = g0[:, 1] - q[:, 1]
            shares = np.array(inside)
            out[name] = {"full_contact": full, "first_frame_s": round(secs[0], 2),
                         "s_per_frame": round(float(np.median(secs[1:])), 3),
                         "drop_max_m": round(float(drop.max()), 4), "drop_median_m": round(float(np.median(drop)), 4),
                         "finite": bool(np.isfinite(q).all()),
                         "inside_share_worst_frame": round(float(shares[:, 0].max()), 5),
                         "deepest_inside_m": round(float(shares[:, 1].max()), 4),
                         "bit_identical_runs": bool(np.array_equal(runs[0], runs[1]))}
            print(name, json.dumps(out[name]), file=sys.stderr, flush=True)
    if args.figure and draped:
        body, garment = subject.at(args.frames) if subject.clip else (b0, g0)
        figure(args.figure, body, (subject.body_faces, subject.faces), garment, next(iter(draped.values())))
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
    main()
