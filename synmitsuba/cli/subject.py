"""``synmitsuba subject --seed N --out DIR``: a turntable of one sampled subject (PNG views, EXR
samples with every pass, the recipe JSON, a contact image); ``--sheet K`` instead renders K
random subjects into one contact sheet (``--closeup``: head and shoulders, as HMR crops and
human NeRF views see them)."""
from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from synmitsuba.cli.args import add_variant_option, natural_int, output_dir, output_file, positive_int, resolution

# layer id -> preview colour (background, body, top, bottom, dress, shoes, hair, beard, accessory, object, ground,
# eyes, teeth)
LAYER_COLOURS = np.array([[0, 0, 0], [230, 190, 160], [200, 40, 40], [40, 80, 200], [180, 60, 180], [40, 40, 40],
                          [120, 80, 30], [90, 60, 20], [40, 200, 200], [200, 200, 40], [110, 110, 110],
                          [250, 250, 250], [250, 120, 200]], np.uint8)


def _camera(human, angle_deg: float, w: int, h: int):
    from synmitsuba.scene.camera import Camera
    top = human.body.vertices[:, 1].max()
    a = np.radians(angle_deg)
    dist = 1.15 * top / np.tan(np.radians(35) / 2) / 2 + 0.3
    eye = (dist * np.sin(a), 0.55 * top + 0.25, dist * np.cos(a))
    return Camera.look_at(eye=eye, target=(0, 0.5 * top, 0), fov_y_deg=35, width=w, height=h)


def _closeup_camera(human, w: int, h: int):
    """Head and shoulders from the front right, framed on anny's face and shoulder keypoints."""
    from synmitsuba.scene.camera import Camera
    kp = human.keypoints()
    face, shoulders = kp[:5].mean(0), kp[5:7].mean(0)
    target = face + 0.35 * (shoulders - face)
    a = np.radians(25.0)
    dist = 0.8 * np.linalg.norm(kp[5] - kp[6]) / np.tan(np.radians(35) / 2)
    return Camera.look_at(eye=tuple(target + dist * np.array([np.sin(a), 0.08, np.cos(a)])), target=tuple(target),
                          fov_y_deg=35, width=w, height=h)


def _feet_camera(human, w: int, h: int):
    """Both feet from the front right and a little above, as a full-body crop's feet show."""
    from synmitsuba.scene.camera import Camera
    sk = human.body.skeleton
    ankles = sk.rest_positions[[sk.index("foot.L"), sk.index("foot.R")]]
    target = np.array([ankles[:, 0].mean(), 0.06, ankles[:, 2].mean() + 0.06])
    a = np.radians(30.0)
    return Camera.look_at(eye=tuple(target + 0.75 * np.array([np.sin(a), 0.45, np.cos(a)])), target=tuple(target),
                          fov_y_deg=35, width=w, height=h)


def _mouth_camera(human, w: int, h: int):
    """Nose to chin from 20 deg to the right, level with the mouth."""
    from synmitsuba.scene.camera import Camera
    kp = human.keypoints()
    target = kp[0] + [0.0, -0.04, 0.0]
    a = np.radians(20.0)
    return Camera.look_at(eye=tuple(target + 0.26 * np.array([np.sin(a), 0.05, np.cos(a)])), target=tuple(target),
                          fov_y_deg=25, width=w, height=h)


# what the mouth close-ups show, subject by subject in turn: ARKit unit weights
MOUTHS = ({"jawOpen": 0.6}, {"mouthSmileLeft": 0.9, "mouthSmileRight": 0.9, "jawOpen": 0.15},
          {"jawOpen": 0.3, "mouthFunnel": 0.3}, {"jawOpen": 0.8, "browInnerUp": 0.6},
          {"mouthSmileLeft": 0.7, "mouthSmileRight": 0.7, "mouthUpperUpLeft": 0.5, "mouthUpperUpRight": 0.5},
          {"jawOpen": 0.35, "mouthStretchLeft": 0.3, "mouthStretchRight": 0.3})


# what the portraits show, in turn: at rest, a closed smile, a smile with the lips parted
PORTRAITS: tuple[dict[str, float], ...] = (
    {}, {"mouthSmileLeft": 0.5, "mouthSmileRight": 0.5, "cheekSquintLeft": 0.2, "cheekSquintRight": 0.2},
    {"mouthSmileLeft": 0.7, "mouthSmileRight": 0.7, "jawOpen": 0.12, "eyeSquintLeft": 0.2, "eyeSquintRight": 0.2})


def _weights(units: dict) -> np.ndarray:
    from synmitsuba.body.expressions import FACE_UNITS
    w = np.zeros(len(FACE_UNITS))
    for name, x in units.items():
        w[FACE_UNITS.index(name)] = x
    return w


def _mouth_face(k: int) -> np.ndarray:
    return _weights(MOUTHS[k % len(MOUTHS)])


def _portrait_face(k: int) -> np.ndarray:
    return _weights(PORTRAITS[k % len(PORTRAITS)])


def _portrait_cameras(human, w: int, h: int) -> list:
    """The face from the front and from three-quarter (40 deg to the subject's left), framed
    from the crown to the collar, as a portrait photographer frames it."""
    from synmitsuba.scene.camera import Camera
    kp = human.keypoints()
    face, shoulders = kp[1:3].mean(0), kp[5:7].mean(0)
    target = face + 0.25 * (shoulders - face)
    cams = []
    for yaw in (0.0, 40.0):
        a = np.radians(yaw)
        eye = target + 0.68 * np.array([np.sin(a), 0.05, np.cos(a)])
        cams.append(Camera.look_at(eye=tuple(eye), target=tuple(target), fov_y_deg=30, width=w, height=h))
    return cams


@dataclass(frozen=True)
class Closeup:
    """A sheet's close-up: its cameras for a built subject and size (one tile each), the face
    it wears (ARKit weights for the k-th subject; None: at rest), and whether the eyes look
    into each camera (else ahead)."""

    cameras: Callable[..., list]
    face: Callable[[int], np.ndarray | None] = lambda k: None
    eyes_on_camera: bool = False


def _one(camera: Callable) -> Callable[..., list]:
    """A one-camera close-up's ``cameras``."""
    return lambda human, w, h: [camera(human, w, h)]


CLOSEUPS = {"head": Closeup(_one(_closeup_camera)), "feet": Closeup(_one(_feet_camera)),
            "mouth": Closeup(_one(_mouth_camera), _mouth_face),
            "portrait": Closeup(_portrait_cameras, _portrait_face, eyes_on_camera=True)}


def _built_subject(seed: int, cloth: str = "skinned"):
    """The sampled subject (recipe, built human) and, with ``cloth`` "simulated", its simulated
    garments settled in the rest pose by the cloth stage (else None; the same subject either way:
    the mode draws nothing)."""
    from synmitsuba.body.recipe import sample_subject
    from synmitsuba.body.subject import build_subject
    from synmitsuba.cloth import simulate_cloth
    recipe = sample_subject(np.random.default_rng(seed), {"cloth": cloth})
    human = build_subject(recipe)
    track = simulate_cloth(human, _rest_motion(human)) if cloth == "simulated" else None
    return recipe, human, None if track is None else track.at(0)


def _rest(human):
    """One frame of the rest pose as the subject stands in its shoes: rotations (1, J, 3, 3), root (1, 3)."""
    rot, root = human.standing()
    return rot[None], root[None]


def _rest_motion(human):
    """The rest pose as a one-frame clip (what the cloth stage settles a garment on)."""
    from synmitsuba.motion.motion import Motion
    rot, root = _rest(human)
    return Motion(human.skeleton, rot, root, 30.0)


def _stage(env: str | None, seed: int):
    """The preview stage (sun, sky, grey ground), or the environment ``env`` with its lighting
    drawn from ``seed`` (an HDRI's scale and rotation)."""
    from synmitsuba.compose.stage import environment_stage, preview_stage
    return preview_stage() if env is None else environment_stage(env, np.random.default_rng(seed), "--env")


def _place(human, scene, camera=None, face=None, garments=None):
    """The subject at rest in ``scene`` (moved there if already in), its eyes on ``camera``
    when one is given."""
    rot, root = _rest(human)
    if camera is not None:
        from synmitsuba.body.eyes import GazeTarget, aim_eyes
        rot = aim_eyes(human.skeleton, rot, root, GazeTarget("camera", tuple(camera.center)))
    human.add_to(scene, rot[0], root[0], instance=1, face=face, garments=garments)


def turntable(args) -> int:
    import synmitsuba as sm
    from synmitsuba.compose.backdrop import centre_backdrop
    output_dir(args.out)
    sm.set_variant(args.variant)
    recipe, human, garments = _built_subject(args.seed, args.cloth)
    scene = _stage(args.env[0] if args.env else None, args.seed)
    _place(human, scene, garments=garments)
    with open(os.path.join(args.out, "recipe.json"), "w") as fh:
        json.dump(recipe.to_dict(), fh, indent=1, sort_keys=True)
    images = []
    for k in range(args.views):
        cam = _camera(human, 360.0 * k / args.views, *args.res)
        centre_backdrop(scene, cam.center)
        sample = sm.render(scene, cam, spp=args.spp, seed=args.seed)
        sm.write_sample(sample, os.path.join(args.out, f"view_{k:02d}"))
        images += [sm.to_srgb8(sample.rgb), LAYER_COLOURS[np.clip(sample.layer, 0, len(LAYER_COLOURS) - 1)]]
    sheet = sm.write_png(os.path.join(args.out, "turntable.png"), sm.contact_sheet(images, columns=2 * min(args.views, 4)))
    print(sheet)
    return 0


def sheet(args) -> int:
    import synmitsuba as sm
    from synmitsuba.compose.backdrop import centre_backdrop
    from synmitsuba.io.preview import write_image
    path = args.out if args.out.lower().endswith((".png", ".jpg", ".jpeg")) else os.path.join(args.out, "subjects.png")
    output_file(path)
    sm.set_variant(args.variant)
    images = []
    view = CLOSEUPS[args.closeup] if args.closeup else Closeup(lambda human, w, h: [_camera(human, 25.0, w, h)])
    for k in range(args.sheet):
        _, human, garments = _built_subject(args.seed + k, args.cloth)
        scene = _stage(args.env[k % len(args.env)] if args.env else None, args.seed + k)
        for cam in view.cameras(human, *args.res):
            _place(human, scene, cam if view.eyes_on_camera else None, view.face(k), garments)
            centre_backdrop(scene, cam.center)
            images.append(sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=k, denoise=args.denoise).rgb))
    columns = 8 if not args.closeup else 4 if len(images) > args.sheet else 6
    print(write_image(path, sm.contact_sheet(images, columns=min(columns, len(images)))))
    return 0


def environment_list(value: str) -> list[str]:
    """``--env``'s value: environment names, comma-separated (checked before any work)."""
    import argparse
    from synmitsuba.compose.environments import environment_names
    names, known = [n.strip() for n in value.split(",")], environment_names()
    bad = [n for n in names if n not in known]
    if bad:
        raise argparse.ArgumentTypeError(f"{bad[0]!r} is not an environment: give one or more of "
                                         f"{', '.join(known)}, comma-separated")
    return names


def add_parser(sub) -> None:
    p = sub.add_parser("subject", help="render a turntable of a sampled layered human (or a contact sheet)",
                       description="Render a turntable of one sampled layered human: PNG views with layer ids, "
                                   "EXR samples and recipe.json; or, with --sheet K, K subjects in one image.")
    p.add_argument("--seed", type=natural_int, default=0, help="subject seed (with --sheet: the first of K seeds)")
    p.add_argument("--out", required=True, help="output folder (with --sheet: a .png or .jpg path, or a folder)")
    p.add_argument("--views", type=positive_int, default=6, help="turntable views")
    p.add_argument("--res", type=resolution, default="240x320", help="WIDTHxHEIGHT of each view")
    p.add_argument("--spp", type=positive_int, default=32, help="samples per pixel")
    p.add_argument("--sheet", type=natural_int, default=0, help="render this many subjects into one contact sheet "
                   "instead of a turntable")
    p.add_argument("--closeup", nargs="?", const="head", choices=tuple(CLOSEUPS), default=None,
                   help="with --sheet: head and shoulders (default: the whole body; docs/closeups.png is --sheet 12 "
                   "--closeup --res 512x512 --spp 64), with 'feet' both feet (docs/shoes.png), with 'mouth' the "
                   "mouth open, smiling or speaking (docs/mouths.png), with 'portrait' the face from the front and from "
                   "three-quarter, eyes on the camera (docs/portraits.jpg)")
    p.add_argument("--env", type=environment_list, default=None,
                   help="render in this environment (comma-separated: subject k in the k-th, in turn; its lighting "
                   "drawn from the subject's seed), e.g. hdri_studio,hdri_courtyard (default: the grey preview stage "
                   "under sun and sky)")
    p.add_argument("--denoise", choices=("none", "oidn"), default="none", help="with --sheet: denoise each tile (OIDN)")
    p.add_argument("--cloth", choices=("skinned", "simulated"), default="skinned",
                   help="skirts and dresses skinned, or settled by the cloth stage (synmitsuba.cloth)")
    add_variant_option(p)
    p.set_defaults(func=lambda a: sheet(a) if a.sheet else turntable(a))
