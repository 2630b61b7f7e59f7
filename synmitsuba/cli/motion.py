"""``synmitsuba motion preview CLIP --out DIR``: a strip of frames of a clip.

CLIP is a procedural kind (``walk``, ``run``, ...), a BVH file or an AMASS npz. The motion is
retargeted onto a sampled subject, or shown as a stick figure (``--stick``) on its own skeleton.
``--outfit tshirt,skirt --cloth both`` shows the skinned skirt over the simulated one.
"""
from __future__ import annotations

import copy
import dataclasses
import os

import numpy as np

from synmitsuba.cli.args import add_variant_option, natural_int, output_dir, positive_float, positive_int, resolution
from synmitsuba.engine.settings import DENOISERS
from synmitsuba.errors import ConfigError


def _figure_scene(motion, f: int, human=None, cloth=None):
    from synmitsuba.compose.stage import preview_stage
    from synmitsuba.scene import Layer, Material
    from synmitsuba.scene.figures import stick_figure
    scene = preview_stage(sun_direction=(0.4, 0.8, 0.5), ground=0.5, sky_scale=1.0)
    if human is not None:
        human.add_to(scene, *motion.frame(f), instance=1, garments=None if cloth is None else cloth.at(f))
    else:
        v, faces = stick_figure(motion.joint_positions()[f], motion.skeleton.parents)
        scene.add_mesh("figure", v, faces, material=Material(base_color=(0.8, 0.45, 0.2)), instance=1, layer=Layer.BODY)
    return scene


def preview(args) -> int:
    import synmitsuba as sm
    from synmitsuba.motion.sources import check_motion_source, load_motion
    from synmitsuba.compose.subjects import heeled_roll, retarget_to_subject
    from synmitsuba.body.recipe import SubjectConfig
    kind, _ = check_motion_source(args.clip, field="CLIP")  # before anything heavy
    try:
        config = SubjectConfig.from_dict({"cloth": "skinned" if args.cloth == "skinned" else "simulated",  # its mesh
                                          **({"outfit": args.outfit.split(",")} if args.outfit else {})}, "config")
    except ConfigError as e:
        raise ConfigError("--outfit", args.outfit, e.fix) from None
    output_dir(args.out)
    sm.set_variant(args.variant)
    rng = np.random.default_rng(args.seed)
    again = copy.deepcopy(rng)  # the same clip once more, its feet rolling as the subject's heels let them
    motion = load_motion(args.clip, rng, seconds=args.seconds, field="CLIP")
    rows = [(None, None)]  # (subject, its simulated cloth or None: skinned)
    if not args.stick:
        recipe = sm.sample_subject(rng, config)
        human = sm.build_subject(recipe)
        if human.heels and kind == "procedural":  # a file's clip has no roll to scale: not read twice
            motion = load_motion(args.clip, again, seconds=args.seconds, field="CLIP", roll=heeled_roll(human.heels))
        motion = retarget_to_subject(motion, human)
        simulated = sm.simulate_cloth(human, motion) if args.cloth != "skinned" else None
        # the skinned row as ``cloth: skinned`` builds it: its garments cut for skinning (a simulated
        # skirt's flare and trousers' legs are cut finer), not the simulated subject's skinned
        skinned = human if args.cloth == "skinned" else sm.build_subject(dataclasses.replace(recipe, cloth="skinned"))
        rows = {"skinned": [(human, None)], "simulated": [(human, simulated)],
                "both": [(skinned, None), (human, simulated)]}[args.cloth]
    frames = np.linspace(0, motion.n_frames - 1, args.frames).round().astype(int)
    pelvis = motion.joint_positions()[:, 0]
    height = float(motion.skeleton.rest_positions[:, 1].max()) + 0.15
    images = []
    for human, cloth in rows:
        for f in frames:
            centre = np.array([pelvis[f, 0], 0.5 * height, pelvis[f, 2]])  # follow the subject
            cam = sm.Camera.look_at(eye=centre + [3.6 * height / 1.8, 0.3, 1.8 * height / 1.8], target=centre,
                                    fov_y_deg=38, width=args.res[0], height=args.res[1])
            scene = _figure_scene(motion, f, human, cloth)
            images.append(sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=args.seed, denoise=args.denoise).rgb))
    name = os.path.splitext(os.path.basename(args.clip))[0]
    print(sm.write_png(os.path.join(args.out, f"{name}_strip.png"), sm.contact_sheet(images, columns=len(frames))))
    return 0


def add_parser(sub) -> None:
    from synmitsuba.cli import Parser
    p = sub.add_parser("motion", help="motion tools", description="Motion tools.")
    msub = p.add_subparsers(dest="motion_command", metavar="SUBCOMMAND", required=True, parser_class=Parser)
    pv = msub.add_parser("preview", help="render a strip of frames of a clip",
                         description="Render a strip of frames of a clip on a sampled subject (or a stick figure).")
    pv.add_argument("clip", help="procedural kind (walk, run, ...), a .bvh file or an AMASS .npz")
    pv.add_argument("--out", required=True, help="output folder (created)")
    pv.add_argument("--frames", type=positive_int, default=6, help="frames in the strip")
    pv.add_argument("--seconds", type=positive_float, default=2.0, help="length of a procedural clip")
    pv.add_argument("--res", type=resolution, default="200x260", help="WIDTHxHEIGHT of each frame")
    pv.add_argument("--spp", type=positive_int, default=16, help="samples per pixel")
    pv.add_argument("--seed", type=natural_int, default=0, help="seed of the subject and of a procedural clip")
    add_variant_option(pv)
    pv.add_argument("--stick", action="store_true", help="show a stick figure, not a subject")
    pv.add_argument("--outfit", help="garment kinds the subject wears, comma-separated, e.g. tshirt,skirt "
                    "(default: a sampled outfit)")
    pv.add_argument("--cloth", choices=("skinned", "simulated", "both"), default="skinned",
                    help="garments skinned, simulated over the clip (skirts, dresses, outer tops, jackets, trousers, "
                    "jumpsuits), or both (two rows)")
    pv.add_argument("--denoise", choices=DENOISERS, default="none", help="denoiser (none, oidn, ...)")
    pv.set_defaults(func=preview)
