"""How true a garment's pattern lies on it (issue 34, garments that look like garments): on its
panels (``body.panels``, today) against over its uv as before (the body's atlas stretched by
``uv_aspect``), over every garment laid on panels of N sampled subjects.

Each texel's rest position (rasterised through the garment's own uv) against its pattern
coordinates in metres, by finite differences with its right and lower neighbours (pairs across
a seam left out): the map from pattern to cloth, J (3 x 2). Per garment, medians over its texels:
- stretch: J's larger singular value over its smaller (1: a square of the pattern is a square);
- scale: their geometric mean (1: the pattern's metres are the cloth's), its 10th-90th range;
- tilt: on the torso between waist and armpits, how far a stripe (along u) runs from level.
Prints JSON: per garment kind and over all, panels against uv, and the ratio.

    python bench/patterns.py [--subjects 20] [--size 256]
"""
import argparse
import dataclasses
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from reference import pattern_jacobians  # noqa: E402  (tests/reference.py: the independent measure)


def measure(J, pos, regions) -> dict:
    s = np.linalg.svd(J, compute_uv=False)
    stretch, scale = s[:, 0] / s[:, 1], np.sqrt(s[:, 0] * s[:, 1])
    along = J[:, :, 0] / np.linalg.norm(J[:, :, 0], axis=1, keepdims=True)
    torso = (pos[:, 1] > regions.waist_y) & (pos[:, 1] < regions.shoulder[1] - 0.12) & \
        (np.abs(pos[:, 0] - regions.neck_xz[0]) < regions.shoulder[0] - 0.03)
    tilt = np.degrees(np.arcsin(np.abs(along[torso, 1]))) if torso.sum() > 50 else np.array([np.nan])
    return {"stretch": float(np.median(stretch)), "stretch_p90": float(np.percentile(stretch, 90)),
            "scale": float(np.median(scale)), "scale_p10": float(np.percentile(scale, 10)),
            "scale_p90": float(np.percentile(scale, 90)), "tilt_deg_p90": float(np.percentile(tilt, 90))}


def garment_rows(h, size: int) -> list:
    from synmitsuba.body.garments import GARMENTS, metres_per_uv
    from synmitsuba.body.textures import _uv_grid, uv_surface
    from synmitsuba.geometry import vertex_normals
    rows = []
    for mesh in h.garments:
        if GARMENTS[mesh.params.kind].panels is None:
            continue
        part = next(p for p in h.parts if p.name == mesh.params.kind)
        faces = mesh.faces[:len(mesh.faces) - mesh.hem[0]]
        surface = uv_surface(mesh.vertices, vertex_normals(mesh.vertices, mesh.faces), faces, mesh.uv, faces, size)
        per_v = metres_per_uv(mesh.vertices, mesh.faces, mesh.uv)[1]
        t = dataclasses.replace(mesh.params.texture, uv_rotation_deg=0.0, uv_scale=1.0, uv_offset=[0.0, 0.0])
        before = np.stack(_uv_grid(t, size), -1).astype(np.float64) * per_v
        now = part.material.pattern_coords.astype(np.float64)
        rows.append({"kind": mesh.params.kind, **{name: measure(*pattern_jacobians(surface.position, C, surface.covered), h.regions)
                                                  for name, C in (("panels", now), ("uv", before))}})
    return rows


def summarise(rows: list) -> dict:
    out = {}
    for name in ("panels", "uv"):
        out[name] = {}
        for k in rows[0][name]:
            values = [r[name][k] for r in rows if np.isfinite(r[name][k])]  # tilt: tops only
            out[name][k] = round(float(np.median(values)), 3) if values else None
    out["stretch_excess_ratio"] = round((out["uv"]["stretch"] - 1) / max(out["panels"]["stretch"] - 1, 1e-9), 1)
    return out


def main(argv=None) -> dict:
    import synmitsuba as sm
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=20)
    ap.add_argument("--size", type=int, default=256)
    args = ap.parse_args(argv)
    rows = []
    for seed in range(args.subjects):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": args.size}))
        rows += garment_rows(h, args.size)
    kinds = sorted({r["kind"] for r in rows})
    return {"bench": "patterns", "subjects": args.subjects, "garments": len(rows), "texture_size": args.size,
            "all": summarise(rows), "by_kind": {k: {"n": sum(r["kind"] == k for r in rows),
                                                    **summarise([r for r in rows if r["kind"] == k])} for k in kinds}}


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))
