"""Where a top's rest shell goes through itself (issue 34, realism): for the tops and dresses
(layers TOP, DRESS) of subjects ``--first`` .. ``--first + --subjects - 1`` as ``sample_subject``
draws them, the faces of each shell (its turned-in band left out, merged by position) that an
edge of another face not touching them passes through (tests/reference.py's ``self_crossing``),
counted beside the armpits (within 0.1 m of the shoulder joints' reach either side of the neck's
axis, up to 0.3 m under them), under the crotch's height + 4 cm (a long top's front and back
meeting between the legs) and elsewhere (shirt collars' falls and hoods lie over their own shell
by design). For a top (not a coat: its skirt is a flare) reaching 4 cm under the crotch, also how far behind its own front (back) it
lies seen straight on at the middle between the legs under the crotch (``reference.middle_notch``:
a shell of each thigh left a notch there; inf where another layer shows through). For each top or
dress standing 3 cm or more off the body, the shelf under the bust (``reference.hang_shelf``: seen
from the front down columns across the chest, from 8 cm under the shoulder joints to the waist,
how far it lies behind a line falling in 1 cm for every 2 cm down from any point of it over it).
Prints JSON: per garment, totals by place, the notches' and the shelves' median and largest.

    python bench/shell_crossings.py [--first 200] [--subjects 30] [--cloth skinned|simulated]

``--cloth simulated`` builds the cloth stage's rest shapes (what a simulated top is cut as and
starts from) in place of the skinned shells.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from synmitsuba.body.garments import GARMENTS
from synmitsuba.scene.layers import Layer

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
    loose = {k for k, kind in GARMENTS.items() if kind.layer in (Layer.TOP, Layer.DRESS)}
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first", type=int, default=200)
    ap.add_argument("--subjects", type=int, default=30)
    ap.add_argument("--cloth", choices=("skinned", "simulated"), default=None,
                    help="the subjects' cloth key (default: as sample_subject draws it)")
    a = ap.parse_args()
    cloth = {"cloth": a.cloth} if a.cloth else {}
    rows, total, notches, shelves = [], {"armpits": 0, "crotch": 0, "elsewhere": 0}, [], []
    for seed in range(a.first, a.first + a.subjects):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64} | cloth))
        for g in h.garments:
            if g.params.kind not in loose:
                continue
            c, bad = crossing_faces(g.vertices, g.faces[:len(g.faces) - g.hem[0]])
            where = places(h, c[bad])
            row = {"seed": seed, "kind": g.params.kind, "offset_mm": round(g.offset * 1000, 1),
                   "faces": int(len(c))} | {k: int((where == k).sum()) for k in total}
            shell = GARMENTS[g.params.kind].shape in ("shell", "shell+collar", "shell+hood")  # not a coat's skirt
            if shell and GARMENTS[g.params.kind].layer == Layer.TOP and g.vertices[:, 1].min() < h.regions.crotch_y - 0.04:
                row["middle_notch_mm"] = notch_mm(h, g)
                notches.append(row["middle_notch_mm"])
            if g.offset >= 0.03:
                row["bust_shelf_mm"] = shelf_mm(h, g)
                shelves.append(row["bust_shelf_mm"])
            for k in total:
                total[k] += row[k]
            rows.append(row)
    print(json.dumps({"subjects": a.subjects, "first": a.first, "cloth": a.cloth, "garments": len(rows), "crossing_faces": total,
                      "middle_notch_mm": {"tops": len(notches), "another_layer_first": notches.count(None),
                                          "median": _median([n for n in notches if n is not None]),
                                          "largest": max((n for n in notches if n is not None), default=None)},
                      "bust_shelf_mm": {"garments": len(shelves), "median": _median(shelves),
                                        "largest": max(shelves, default=None)},
                      "rows": rows}, indent=1))


def _median(x: list) -> float | None:
    return float(np.median(x)) if x else None


def shelf_mm(h, g) -> float:
    """``reference.hang_shelf`` of garment ``g`` (its band left out) on subject ``h`` at rest, in
    millimetres: columns 0.6 of the shoulder joints' reach either side of the neck's axis, from
    8 cm under the shoulder joints to the waist, a fall of 1 in 2."""
    from reference import hang_shelf
    r = h.regions
    xs = r.neck_xz[0] + np.arange(-0.6, 0.61, 0.1) * r.shoulder[0]
    return round(1000 * hang_shelf(g.vertices, g.faces[:len(g.faces) - g.hem[0]], xs, r.shoulder[1] - 0.08,
                                   r.waist_y, slope=0.5), 1)


def notch_mm(h, g) -> float | None:
    """``reference.middle_notch`` of garment ``g`` on subject ``h`` at rest, in millimetres (None
    where another layer shows first; garments over it left out), the middle between the legs
    the thighs' mean x."""
    from reference import middle_notch
    y = h.body.vertices[:, 1] - h.regions.crotch_y
    middle = float(h.body.vertices[(y < -0.05) & (y > -0.25), 0].mean())
    k = h.garments.index(g)  # it and what is under it: a shirt under a blazer is its own shape
    layers = [(h.body.vertices, h.body.faces)] + [(m.vertices, m.faces) for m in h.garments[:k + 1]]
    notch = middle_notch(layers, 1 + k, middle, h.regions.crotch_y)
    return round(1000 * notch, 1) if np.isfinite(notch) else None


if __name__ == "__main__":
    main()
