"""Where a top's rest shell goes through itself (issue 34, realism): for the tops and dresses
(layers TOP, DRESS) of subjects ``--first`` .. ``--first + --subjects - 1`` as ``sample_subject``
draws them, the faces of each shell (its turned-in band left out, merged by position) that an
edge of another face not touching them passes through (tests/reference.py's ``self_crossing``),
counted beside the armpits (within 0.1 m of the shoulder joints' reach either side of the neck's
axis, up to 0.3 m under them), under the crotch's height + 4 cm (a long top's front and back
meeting between the legs) and elsewhere (shirt collars' falls and hoods lie over their own shell
by design). Prints JSON: per garment and totals by place.

    python bench/shell_crossings.py [--first 200] [--subjects 30]
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))  # reference.py

def crossing_faces(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(face centres (F, 3), whether each face crosses another of the mesh (F,)), merged by
    position (trimesh)."""
    import trimesh
    from reference import self_crossing
    mesh = trimesh.Trimesh(vertices, faces, process=True)
    return mesh.triangles_center, self_crossing(mesh.vertices, mesh.faces)


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
