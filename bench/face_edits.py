"""What MediaPipe's face detector responds to in our face crops (issue 32's detection goal):
faces.py's 24 crops, read back from its contact sheet (``--sheet``, default docs/faces.png),
edited in 2D one way at a time and scored again with the same detector (short range), against
the unedited crops. No render: about a minute. Edits:

- ``brows`` / ``lips`` / ``eyes`` / ``nostrils``: the region FaceMesh finds (its landmark
  polygons, softened by a pixel) darkened or lightened by a factor;
- ``lower_face``: the image below the detector's eye line squeezed (< 1) or stretched (> 1)
  vertically about it: the eye-to-mouth distance over the eyes' spacing;
- ``blur``: a Gaussian over the whole crop; and the two real photographs of faces.py, framed
  like our crops, blurred the same (how much detail a real face's score rests on).

Also prints the detector's keypoint ratios (eye-to-mouth and eye-to-nose over the eyes'
spacing, the eyes' spacing over the face box) for ours and the photographs.

    python bench/face_edits.py [--sheet docs/faces.png]
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import faces as fb  # noqa: E402 - the crops' framing and the real photographs

RES, PAD, COLUMNS = 320, 2, 8  # faces.py's crops and io.preview.contact_sheet's layout
REGIONS = {  # FaceMesh landmark polygons
    "brows": [[70, 63, 105, 66, 107, 55, 65, 52, 53, 46], [300, 293, 334, 296, 336, 285, 295, 282, 283, 276]],
    "eyes": [[33, 7, 163, 144, 145, 153, 154, 155, 133, 173, 157, 158, 159, 160, 161, 246],
             [263, 249, 390, 373, 374, 380, 381, 382, 362, 398, 384, 385, 386, 387, 388, 466]],
    "nostrils": [[98, 97, 2, 326, 327, 294, 278, 344, 440, 275, 4, 45, 220, 115, 48, 64]],
    "lips": [[61, 146, 91, 181, 84, 17, 314, 405, 321, 375, 291, 409, 270, 269, 267, 0, 37, 39, 40, 185]],
}
LIPS_INNER = [78, 95, 88, 178, 87, 14, 317, 402, 318, 324, 308, 415, 310, 311, 312, 13, 82, 81, 80, 191]
EDITS = (("brows", 0.6), ("brows", 0.4), ("lips", 0.75), ("lips", 0.6), ("eyes", 0.7), ("eyes", 1.25),
         ("nostrils", 0.8))


def read_crops(path: str, n: int = 24) -> list[np.ndarray]:
    from PIL import Image
    sheet = np.asarray(Image.open(path).convert("RGB"))
    out = []
    for i in range(n):
        r, k = divmod(i, COLUMNS)
        y, x = PAD + r * (RES + PAD), PAD + k * (RES + PAD)
        out.append(np.ascontiguousarray(sheet[y:y + RES, x:x + RES]))
    return out


def region_mask(landmarks, name: str) -> np.ndarray:
    from PIL import Image, ImageDraw
    from scipy.ndimage import gaussian_filter
    m = Image.new("L", (RES, RES), 0)
    draw = ImageDraw.Draw(m)
    for ids in REGIONS[name]:
        draw.polygon([(landmarks[i].x * RES, landmarks[i].y * RES) for i in ids], fill=255)
    if name == "lips":
        draw.polygon([(landmarks[i].x * RES, landmarks[i].y * RES) for i in LIPS_INNER], fill=0)
    return gaussian_filter(np.asarray(m) / 255.0, 1.0)[..., None]


def squeeze_below_eyes(img: np.ndarray, eye_y: float, s: float) -> np.ndarray:
    from scipy.ndimage import map_coordinates
    yy, xx = np.mgrid[0:RES, 0:RES].astype(float)
    src = np.where(yy > eye_y, eye_y + (yy - eye_y) / s, yy)
    out = [map_coordinates(img[..., c].astype(float), [src, xx], order=1, mode="nearest") for c in range(3)]
    return np.ascontiguousarray(np.stack(out, -1).astype(np.uint8))


def blurred(img: np.ndarray, sigma: float) -> np.ndarray:
    from scipy.ndimage import gaussian_filter
    out = np.stack([gaussian_filter(img[..., c].astype(float), sigma) for c in range(3)], -1)
    return np.ascontiguousarray(out.astype(np.uint8))


def ratios(detection) -> list[float]:
    """Eye-to-mouth and eye-to-nose over the eyes' spacing, and that spacing over the box width."""
    k = np.array([[p.x, p.y] for p in detection.location_data.relative_keypoints])
    mid, iod = (k[0] + k[1]) / 2, np.linalg.norm(k[0] - k[1])
    return [float(np.linalg.norm(k[3] - mid) / iod), float(np.linalg.norm(k[2] - mid) / iod),
            float(iod / detection.location_data.relative_bounding_box.width)]


def main(argv=None) -> dict:
    import mediapipe as mp
    ap = argparse.ArgumentParser()
    ap.add_argument("--sheet", default=os.path.join(os.path.dirname(fb.__file__), "..", "docs", "faces.png"))
    args = ap.parse_args(argv)
    crops = read_crops(args.sheet)
    with mp.solutions.face_detection.FaceDetection(model_selection=0, min_detection_confidence=0.05) as fd, \
            mp.solutions.face_mesh.FaceMesh(static_image_mode=True, refine_landmarks=True, max_num_faces=1) as fm:
        def best(img):
            found = fd.process(img).detections
            return max(found, key=lambda d: d.score[0]) if found else None

        def score(img) -> float:
            d = best(img)
            return float(d.score[0]) if d else 0.0

        def summary(scores: list, base: np.ndarray) -> dict:
            s = np.array(scores)
            return {"median": round(float(np.median(s)), 4), "mean_change": round(float((s - base).mean()), 4)}

        found = [best(c) for c in crops]
        base = np.array([float(d.score[0]) for d in found])
        marks = [fm.process(c).multi_face_landmarks[0].landmark for c in crops]
        result: dict = {"crops": len(crops), "median": round(float(np.median(base)), 4), "edits": {}}
        for name, factor in EDITS:
            edited = [np.clip(c * (1 + (factor - 1) * region_mask(lm, name)), 0, 255).astype(np.uint8)
                      for c, lm in zip(crops, marks)]
            result["edits"][f"{name} x{factor}"] = summary([score(e) for e in edited], base)
        for s in (0.87, 0.93, 1.07):
            eye_y = [RES * (d.location_data.relative_keypoints[0].y + d.location_data.relative_keypoints[1].y) / 2
                     for d in found]
            result["edits"][f"lower_face x{s}"] = summary([score(squeeze_below_eyes(c, y, s))
                                                           for c, y in zip(crops, eye_y)], base)
        photos = fb._real_photos()
        boxes = [fb._box([d]) for d in found]
        framed = []
        for p in photos:
            b = fb._box(fd.process(p).detections) * [p.shape[1], p.shape[0], p.shape[1], p.shape[0]]
            framed += [fb._framed_like(p, b, box, RES) for box in boxes]
        real = np.array([score(np.ascontiguousarray(f)) for f in framed])
        result["real_photos_median"] = round(float(np.median(real)), 4)
        for sigma in (1.0, 2.0):
            result["edits"][f"blur {sigma}"] = summary([score(blurred(c, sigma)) for c in crops], base)
            result[f"real_photos_blur_{sigma}_median"] = round(float(np.median([score(blurred(f, sigma))
                                                                                for f in framed])), 4)
        ours = np.array([ratios(d) for d in found])
        result["keypoint_ratios"] = {
            "ours_median": [round(float(x), 3) for x in np.median(ours, 0)],
            "photos": [[round(x, 3) for x in ratios(best(p))] for p in photos],
            "order": ["eye_mouth/eye_spacing", "eye_nose/eye_spacing", "eye_spacing/box_width"]}
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
