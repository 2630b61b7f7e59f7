"""A top-down picture of a composed scene: object boxes (grey), each subject's per-frame boxes
(faint) and whole-clip footprint (outlined, its colour), the cameras' paths and their frusta at
the first frame (blue; red when a subject is not valid in that view). Looking down the y
axis: x to the right, z downwards."""
from __future__ import annotations

import numpy as np

from synmitsuba.compose.environments import load_environment, object_boxes
from synmitsuba.compose.spec import SceneSpec

COLOURS = [(230, 90, 40), (40, 160, 80), (150, 60, 200), (200, 170, 30), (30, 150, 200), (200, 60, 120)]


def draw_topdown(spec: SceneSpec, size: int = 640) -> np.ndarray:
    """(size, size, 3) uint8 picture of ``spec`` seen from above."""
    from PIL import Image, ImageDraw
    env = load_environment(spec.environment)
    boxes = object_boxes(env)
    eyes = np.concatenate([[c.center for c in v.cameras] for v in spec.views]) if spec.views else np.zeros((0, 3))
    corners = [boxes[:, [0, 2]], boxes[:, [3, 5]]] if len(boxes) else []
    pts = np.concatenate([*corners, eyes[:, [0, 2]], np.reshape(env.area, (2, 2))])
    lo, hi = pts.min(0) - 1.0, pts.max(0) + 1.0
    scale = (size - 1) / float((hi - lo).max())

    def px(x, z):
        return (float((x - lo[0]) * scale), float((z - lo[1]) * scale))

    img = Image.new("RGB", (size, size), (250, 250, 248))
    d = ImageDraw.Draw(img, "RGBA")
    d.rectangle([px(env.area[0], env.area[1]), px(env.area[2], env.area[3])], outline=(180, 180, 180))
    for b in boxes:
        d.rectangle([px(b[0], b[2]), px(b[3], b[5])], fill=(120, 120, 120, 200))
    for i, s in enumerate(spec.subjects):
        c = COLOURS[i % len(COLOURS)]
        for fb in s.frames:
            d.rectangle([px(fb[0], fb[1]), px(fb[2], fb[3])], outline=c + (40,))
        d.rectangle([px(s.footprint[0], s.footprint[1]), px(s.footprint[2], s.footprint[3])], outline=c + (255,), width=2)
    for v in spec.views:
        _draw_view(d, v, px, scale)
    return np.asarray(img)


def _draw_view(d, view, px, scale: float) -> None:
    path = [px(c.center[0], c.center[2]) for c in view.cameras]
    colour = (40, 80, 220, 255) if view.valid.all() else (220, 40, 40, 255)
    if len(path) > 1:
        d.line(path, fill=colour[:3] + (120,), width=1)
    cam = view.cameras[0]
    rays = cam.ray_matrix @ np.array([[0, cam.height / 2, 1], [cam.width, cam.height / 2, 1.0]]).T
    eye = cam.center
    length = 1.5
    ends = [eye + length * r / np.linalg.norm(r[[0, 2]]) for r in rays.T]
    d.polygon([px(eye[0], eye[2])] + [px(e[0], e[2]) for e in ends], outline=colour, fill=colour[:3] + (40,))
    d.text((px(eye[0], eye[2])[0] + 3, px(eye[0], eye[2])[1] + 3), view.name, fill=colour)
