"""The Warp kernel of ``outside.keep_outside`` (imported when it first runs: Warp loads then).
Warp's kernel language is typed and checked by Warp's own compiler, not mypy (pyproject.toml)."""
import warp as wp


@wp.kernel
def push(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), margin: float, reach: float,
         out: wp.array(dtype=wp.vec3), moved: wp.array(dtype=wp.int32)):
    i = wp.tid()
    p = points[i]
    out[i] = p
    moved[i] = 0
    hit = wp.mesh_query_point_sign_winding_number(mesh, p, reach)
    if hit.result:
        c = wp.mesh_eval_position(mesh, hit.face, hit.u, hit.v)
        d = p - c
        dist = wp.length(d)
        if hit.sign < 0.0 or dist < 0.99 * margin:  # (0.99: what a pass set at the margin stays)
            n = wp.mesh_eval_face_normal(mesh, hit.face)
            if dist > 1.0e-7:
                n = d / dist
                if hit.sign < 0.0:
                    n = -n
            out[i] = c + margin * n
            moved[i] = 1
