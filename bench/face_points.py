"""Our 68 face keypoints against a face model trained on real photos (MediaPipe FaceMesh's
landmarks at the same 68 points, ``face_points_derive.MEDIAPIPE_68``), on subjects, views and
expressions the table was not picked on: random subjects (no accessories), head-and-shoulders
crops turned -30..30 deg, eyes on the camera, an expression drawn for an idle clip at a random
time with the jaw and the lids set at random. Reported: faces found, and the normalised mean
error (NME: mean 2D distance over the inter-ocular distance, outer eye corners, as 300W
reports it) overall and per region, median over faces.

    python bench/face_points.py [--faces 24] [--res 384] [--spp 64] [--sheet face_points.png]
"""
import argparse
import json

import numpy as np

from face_points_derive import MEDIAPIPE_68, overlay

REGIONS = {"jaw": range(0, 17), "brows": range(17, 27), "nose": range(27, 36), "eyes": range(36, 48),
           "lips": range(48, 68)}


def _face(k: int) -> np.ndarray:
    from synmitsuba.body.expressions import FACE_UNITS
    from synmitsuba.motion.faces import sample_face
    rng = np.random.default_rng(7000 + k)
    w = sample_face(rng, "idle", seconds=2.0).weights(np.array([rng.uniform(0, 2)]))[0]
    w[FACE_UNITS.index("jawOpen")] = rng.uniform(0, 0.6)
    w[[FACE_UNITS.index("eyeBlinkLeft"), FACE_UNITS.index("eyeBlinkRight")]] = rng.uniform(0, 0.6)
    return w


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--faces", type=int, default=24)
    ap.add_argument("--res", type=int, default=384)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--sheet")
    args = ap.parse_args(argv)
    import mediapipe as mp

    import synmitsuba as sm
    from synmitsuba.body.eyes import GazeTarget, aim_eyes
    from synmitsuba.compose.stage import preview_stage
    from synmitsuba.scene.camera import Camera
    variant = sm.set_variant()
    errors, drawn, yaws = [], [], []
    with mp.solutions.face_mesh.FaceMesh(static_image_mode=True, refine_landmarks=True, max_num_faces=1) as fm:
        for k in range(args.faces):
            human = sm.build_subject(sm.sample_subject(np.random.default_rng(8000 + k), {"accessories": []}))
            J = len(human.skeleton)
            rot = np.broadcast_to(np.eye(3), (J, 3, 3)).copy()
            w = _face(k)
            ours = human.face_keypoints(rot, np.zeros(3), face=w)
            centre = ours[36:48].mean(0) + np.array([0.0, -0.03, 0.0])
            yaw = np.radians(-30 + 60 * ((k * 0.618034) % 1.0))
            cam = Camera.look_at(eye=tuple(centre + 0.5 * np.array([np.sin(yaw), 0.05, np.cos(yaw)])),
                                 target=tuple(centre), fov_y_deg=30, width=args.res, height=args.res)
            rot = aim_eyes(human.skeleton, rot[None], np.zeros((1, 3)), GazeTarget("camera", tuple(cam.center)))[0]
            ours = human.face_keypoints(rot, np.zeros(3), face=w)
            scene = preview_stage()
            human.add_to(scene, rot, np.zeros(3), instance=1, face=w)
            img = np.ascontiguousarray(sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=k, denoise="oidn").rgb))
            uv = cam.project(ours)[0]
            found = fm.process(img).multi_face_landmarks
            if args.sheet:
                drawn.append(overlay(img, uv))
            if not found:
                errors.append(np.full(68, np.nan))
                continue
            theirs = np.array([[a.x * args.res, a.y * args.res] for a in found[0].landmark])[list(MEDIAPIPE_68)]
            iod = np.linalg.norm(theirs[36] - theirs[45])
            errors.append(np.linalg.norm(uv - theirs, axis=1) / iod)
            yaws.append(float(np.degrees(yaw)))
    E = np.array(errors)
    ok = np.isfinite(E[:, 0])
    if args.sheet:
        sm.write_png(args.sheet, sm.contact_sheet(drawn, columns=6))
    result = {"variant": variant, "faces": args.faces, "found": int(ok.sum()),
              "nme_median": round(float(np.median(E[ok].mean(1))), 4),
              "nme_per_region": {name: round(float(np.median(E[ok][:, list(r)].mean(1))), 4) for name, r in REGIONS.items()},
              "nme_per_face": [round(float(e), 4) for e in E[ok].mean(1)], "yaw_deg": [round(y, 1) for y in yaws]}
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
