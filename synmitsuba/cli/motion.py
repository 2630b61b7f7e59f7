"""``synmitsuba motion preview CLIP --out DIR``: a strip of frames of a clip.

CLIP is a procedural kind (``walk``, ``run``, ...), a BVH file or an AMASS npz. The motion is
retargeted onto a sampled subject when the layered human is available, else shown as a stick
figure on the humanoid skeleton.
"""
from __future__ import annotations

import os

import numpy as np


def load_clip(clip: str, rng: np.random.Generator, seconds: float):
    import synmitsuba as sm
    if clip in sm.MOTION_KINDS:
        return sm.procedural_motion(clip, rng, seconds=seconds)
    if clip.lower().endswith(".bvh"):
        return sm.load_bvh(clip)
    if clip.lower().endswith(".npz"):
        return sm.load_amass(clip)
    raise sm.ConfigError("CLIP", clip, f"give a .bvh or .npz file or one of {', '.join(sm.MOTION_KINDS)}")


def _frame_scene(sm, motion, f: int, human=None):
    scene = sm.Scene()
    ground = np.array([[-50, 0, -50], [50, 0, -50], [50, 0, 50], [-50, 0, 50]], float)
    scene.add_mesh("ground", ground, np.array([[0, 2, 1], [0, 3, 2]]), material=sm.Material(base_color=0.5),
                   layer=sm.Layer.GROUND)
    scene.set_environment(sm.SunSky(sun_direction=(0.4, 0.8, 0.5)))
    if human is not None:
        human.add_to(scene, rotations=motion.rotations[f], root_translation=motion.root_translation[f], instance=1)
    else:
        v, faces = sm.scene.figures.stick_figure(motion.joint_positions()[f], motion.skeleton.parents)
        scene.add_mesh("figure", v, faces, material=sm.Material(base_color=(0.8, 0.45, 0.2)), instance=1,
                       layer=sm.Layer.BODY)
    return scene


def preview(args) -> int:
    import synmitsuba as sm
    import synmitsuba.scene.figures  # noqa: F401
    sm.set_variant(args.variant)
    rng = np.random.default_rng(args.seed)
    motion = load_clip(args.clip, rng, args.seconds)
    human = None
    if not args.stick and hasattr(sm, "build_subject"):
        human = sm.build_subject(sm.sample_subject(rng))
        motion = sm.retarget(motion, human.skeleton)
    frames = np.linspace(0, motion.n_frames - 1, args.frames).round().astype(int)
    pelvis = motion.joint_positions()[:, 0]
    height = float(motion.skeleton.rest_positions[:, 1].max()) + 0.15
    w, h = (int(x) for x in args.res.split("x"))
    images = []
    for f in frames:
        scene = _frame_scene(sm, motion, f, human)
        centre = np.array([pelvis[f, 0], 0.5 * height, pelvis[f, 2]])  # follow the subject
        cam = sm.Camera.look_at(eye=centre + [3.6 * height / 1.8, 0.3, 1.8 * height / 1.8], target=centre,
                                fov_y_deg=38, width=w, height=h)
        images.append(sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=args.seed).rgb))
    os.makedirs(args.out, exist_ok=True)
    name = os.path.splitext(os.path.basename(args.clip))[0]
    path = sm.write_png(os.path.join(args.out, f"{name}_strip.png"), sm.contact_sheet(images, columns=len(images)))
    print(path)
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("motion", help="motion tools")
    msub = p.add_subparsers(dest="motion_command", metavar="SUBCOMMAND", required=True)
    pv = msub.add_parser("preview", help="render a strip of frames of a clip")
    pv.add_argument("clip", help="procedural kind (walk, run, ...), .bvh or AMASS .npz")
    pv.add_argument("--out", required=True)
    pv.add_argument("--frames", type=int, default=6)
    pv.add_argument("--seconds", type=float, default=2.0, help="length of a procedural clip")
    pv.add_argument("--res", default="200x260")
    pv.add_argument("--spp", type=int, default=16)
    pv.add_argument("--seed", type=int, default=0)
    pv.add_argument("--variant")
    pv.add_argument("--stick", action="store_true", help="show a stick figure, not a subject")
    pv.set_defaults(func=preview)
