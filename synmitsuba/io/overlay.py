"""A panel of a sample's labels, what a user opens first: RGB with keypoints (coloured by
visibility) and boxes, depth, normals, instance ids, layer ids, each subject's amodal mask
over its visible pixels, and the optical flow (colour wheel)."""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.io.preview import contact_sheet, to_srgb8
from synmitsuba.sample import Sample

# visibility class -> colour: outside grey, visible green, self-occluded yellow, by a subject
# red, by an object blue
VIS_COLOURS = {0: (128, 128, 128), 1: (40, 220, 60), 2: (250, 210, 30), 3: (240, 40, 40), 4: (40, 120, 250)}
SKELETON = [(15, 13), (13, 11), (16, 14), (14, 12), (11, 12), (5, 11), (6, 12), (5, 6), (5, 7), (6, 8), (7, 9),
            (8, 10), (1, 2), (0, 1), (0, 2), (1, 3), (2, 4)]  # COCO limbs


def _ids_to_colours(ids: np.ndarray) -> np.ndarray:
    """A fixed, distinct colour per id (0 black), the same in every picture."""
    h = (ids.astype(np.uint64) * np.uint64(2654435761)) & np.uint64(0xFFFFFF)
    rgb = np.stack([(h >> np.uint64(s)) & np.uint64(255) for s in (16, 8, 0)], -1).astype(np.uint8)
    rgb = (rgb // 2 + 96).astype(np.uint8)
    rgb[ids == 0] = 0
    return rgb


def _depth(sample: Sample) -> np.ndarray:
    """Depth by inverse depth (near bright): a ground running to the horizon would otherwise take
    the whole scale and leave the people one colour with the ground under them."""
    d = sample.depth
    m = d > 0
    out = np.zeros(d.shape + (3,), np.uint8)
    if m.any():
        lo, hi = np.percentile(d[m], [1, 99])
        inv = 1.0 / np.maximum(d, 1e-6)
        v = np.clip((inv - 1.0 / hi) / max(1.0 / lo - 1.0 / hi, 1e-9), 0, 1)
        out[m] = (np.stack([v, v ** 0.5, 1 - v], -1)[m] * 255).astype(np.uint8)
    return out


def caption(tile: np.ndarray, text: str) -> np.ndarray:
    """``tile`` with ``text`` in its top-left corner, white on a dark band."""
    from PIL import Image, ImageDraw
    img = Image.fromarray(np.ascontiguousarray(tile))
    d = ImageDraw.Draw(img)
    x0, y0, x1, y1 = d.textbbox((2, 1), text)
    d.rectangle([0, 0, x1 + 2, y1 + 1], fill=(0, 0, 0))
    d.text((2, 1), text, fill=(255, 255, 255))
    return np.asarray(img)


def _annotated_rgb(sample: Sample):
    from PIL import Image, ImageDraw
    img = Image.fromarray(to_srgb8(sample.rgb))
    d = ImageDraw.Draw(img)
    for rec in sample.subjects:
        for key, colour in (("bbox_amodal", (255, 255, 255)), ("bbox_visible", (255, 140, 0))):
            if rec.get(key):
                d.rectangle([rec[key][0], rec[key][1], rec[key][2] - 1, rec[key][3] - 1], outline=colour)
        kp, vis = np.asarray(rec["keypoints2d"]), np.asarray(rec["visibility"])
        for a, b in SKELETON:
            if vis[a] and vis[b]:
                d.line([tuple(kp[a]), tuple(kp[b])], fill=(230, 230, 230), width=1)
        for (x, y), v in zip(kp, vis):
            if v:
                d.ellipse([x - 2, y - 2, x + 2, y + 2], fill=VIS_COLOURS[int(v)])
    return np.asarray(img)


def _amodal(sample: Sample) -> np.ndarray:
    out = (to_srgb8(sample.rgb) // 3).astype(np.uint8)
    for rec in sample.subjects:
        colour = _ids_to_colours(np.array([rec["instance"]]))[0]
        hidden = rec["amodal_mask"] & (sample.instance != rec["instance"])
        out[hidden] = colour // 2
        out[sample.instance == rec["instance"]] = colour
    return out


def flow_colours(flow: np.ndarray, scale: float | None = None) -> np.ndarray:
    """The usual flow colour wheel: hue = direction, saturation = length / ``scale`` (default:
    the 99th percentile length)."""
    import colorsys
    mag = np.linalg.norm(flow, axis=-1)
    scale = scale or max(float(np.percentile(mag, 99)), 1e-6)
    hue = (np.arctan2(-flow[..., 1], -flow[..., 0]) / (2 * np.pi) + 0.5) % 1.0
    sat = np.clip(mag / scale, 0, 1)
    rgb = np.vectorize(lambda h, s: colorsys.hsv_to_rgb(h, s, 1.0), otypes=[float, float, float])(hue, sat)
    return (np.stack(rgb, -1) * 255).astype(np.uint8)


def sample_panel(sample: Sample, columns: int = 3) -> np.ndarray:
    """(H', W', 3) uint8 panel of the sample's labels."""
    tiles = [caption(_annotated_rgb(sample), "rgb, keypoints, boxes"), caption(_depth(sample), "depth (near bright)")]
    if "normal" in sample.passes:
        n = sample.normal
        tiles.append(caption((np.where(sample.mask[..., None], (n * [1, -1, -1] + 1) / 2, 0) * 255).astype(np.uint8),
                             "normal"))
    tiles.append(caption(_ids_to_colours(sample.instance), "instance"))
    tiles.append(caption(_ids_to_colours(sample.layer.astype(np.int64) * 7919), "layer"))
    if sample.subjects:
        tiles.append(caption(_amodal(sample), "amodal (hidden dim)"))
    if "body_part" in sample.passes:
        tiles.append(caption(_ids_to_colours(sample.body_part.astype(np.int64) * 7919), "body part"))
    for name in ("flow_fwd", "flow_bwd"):
        if name in sample.passes:
            tiles.append(caption(flow_colours(sample.passes[name]), name.replace("_", " ")))
            break
    return contact_sheet(tiles, columns)


def dataset_sheet(stems: list, count: int = 6) -> np.ndarray:
    """A contact sheet of up to ``count`` samples spread over ``stems``: per row the RGB with
    keypoints and boxes, depth, instance ids, layer ids."""
    from synmitsuba.io.exr import read_sample
    picks = [stems[int(k)] for k in np.linspace(0, len(stems) - 1, min(count, len(stems)))]
    tiles = []
    for stem in picks:
        s = read_sample(stem)
        name = os.path.join(os.path.basename(os.path.dirname(stem)), os.path.basename(stem))
        tiles += [caption(_annotated_rgb(s), name), caption(_depth(s), "depth (near bright)"),
                  caption(_ids_to_colours(s.instance), "instance"),
                  caption(_ids_to_colours(s.layer.astype(np.int64) * 7919), "layer")]
    return contact_sheet(tiles, 4)
