"""Where a top's rest shell goes through itself (issue 34, realism): for the tops and dresses (layers TOP, DRESS)
of subjects ``--first`` .. ``--first + --subjects - 1`` as ``sample_subject`` draws them, the faces
of each shell (its turned-in band left out, merged by position) that an edge of another face
not touching them passes through (Moller and Trumbore), counted beside the armpits (within
0.1 m of the shoulder joints' reach either side of the neck's axis, up to 0.3 m under them),
under the crotch's height + 4 cm (a long top's front and back meeting between the legs) and
elsewhere (shirt collars' falls and hoods lie over their own shell by design). Prints JSON:
per garment and totals by place.

    python bench/shell_crossings.py [--first 200] [--subjects 30]
"""
from __future__ import annotations

import argparse
import json

import numpy as np

def _through(p, q, a, b, c) -> np.ndarray:
    """(N,) whether each segment p-q passes through the triangle a-b-c."""
    d, e1, e2 = q - p, b - a, c - a
    h = np.cross(d, e2)
    det = (e1 * h).sum(1)
    ok = np.abs(det) > 1e-14
    inv = 1.0 / np.where(ok, det, 1.0)
    s = p - a
    u = (s * h).sum(1) * inv
    k = np.cross(s, e1)
    w = (d * k).sum(1) * inv
    t = (e2 * k).sum(1) * inv
    return ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (t >= 0) & (t <= 1)


def crossing_faces(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(face centres (F, 3), whether each face crosses another of the mesh (F,))."""
    import trimesh
    from scipy.spatial import cKDTree
    mesh = trimesh.Trimesh(vertices, faces, process=True)
    f, v, c = mesh.faces, mesh.vertices, mesh.triangles_center
    reach = 2 * np.linalg.norm(v[f] - c[:, None], axis=2).max()
    i, j = cKDTree(c).query_pairs(reach, output_type="ndarray").T
    apart = ~(f[i][:, :, None] == f[j][:, None, :]).any((1, 2))
    i, j = i[apart], j[apart]
    hit = np.zeros(len(i), bool)
    for x, y in ((i, j), (j, i)):
        for k in range(3):
            hit |= _through(v[f[x, k]], v[f[x, (k + 1) % 3]], v[f[y, 0]], v[f[y, 1]], v[f[y, 2]])
    out = np.zeros(len(f), bool)
    out[i[hit]] = out[j[hit]] = True
    return c, out


def places(h, c: np.ndarray) -> np.ndarray:
    """'armpits', 'crotch' or 'elsewhere' for each point ``c`` on subject ``h``."""
    r = h.regions
    beside = np.abs(np.abs(c[:, 0] - r.neck_xz[0]) - r.shoulder[0]) < 0.1
    armpit = beside & (c[:, 1] > r.shoulder[1] - 0.3) & (c[:, 1] < r.shoulder[1])
    return np.where(armpit, "armpits", np.where(c[:, 1] < r.crotch_y + 0.04, "crotch", "elsewhere"))


def main() -> None:
    import synmitsuba as sm
    from synmitsuba.scene.layers import Layer
    loose = {k for k, kind in sm.GARMENT_KINDS.items() if kind.layer in (Layer.TOP, Layer.DRESS)}
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first", type=int, default=200)
    ap.add_argument("--subjects", type=int, default=30)
    a = ap.parse_args()
    rows, total = [], {"armpits": 0, "crotch": 0, "elsewhere": 0}
    for seed in range(a.first, a.first + a.subjects):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        for g in h.garments:
            if g.params.kind not in loose:
                continue
            c, bad = crossing_faces(g.vertices, g.faces[:len(g.faces) - g.hem[0]])
            where = places(h, c[bad])
            row = {"seed": seed, "kind": g.params.kind, "offset_mm": round(g.offset * 1000, 1),
                   "faces": int(len(c))} | {k: int((where == k).sum()) for k in total}
            for k in total:
                total[k] += row[k]
            rows.append(row)
    print(json.dumps({"subjects": a.subjects, "first": a.first, "garments": len(rows), "crossing_faces": total,
                      "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
