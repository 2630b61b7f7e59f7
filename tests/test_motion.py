"""Motion: BVH import against scipy's Euler conventions, retargeting, clips, procedural motions."""
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import synmitsuba as sm
from synmitsuba.errors import ConfigError
from synmitsuba.motion.bvh import BVHError
from synmitsuba.motion.retargeting import pelvis_height

BVH = """HIERARCHY
ROOT Hips
{{
  OFFSET 0 {h} 0
  CHANNELS 6 Xposition Yposition Zposition {root_order}
  JOINT Chest
  {{
    OFFSET 0 {c} 0
    CHANNELS 3 {order}
    JOINT LeftArm
    {{
      OFFSET {a} 0 0
      CHANNELS 3 {order}
      End Site
      {{
        OFFSET {a} 0 0
      }}
    }}
  }}
}}
MOTION
Frames: 2
Frame Time: 0.0083333
{frames}
"""


def rotations(order):
    return " ".join(f"{c}rotation" for c in order)


@pytest.mark.parametrize("order", ["ZXY", "XYZ", "ZYX", "YZX"])
def test_bvh_forward_kinematics_matches_scipy(order, tmp_path):
    rng = np.random.default_rng(1)
    ang = np.round(rng.uniform(-60, 60, (2, 3, 3)), 4)
    root = np.array([[10.0, 90.0, -5.0], [12.0, 91.0, -3.0]])
    lines = [" ".join(f"{x:.6f}" for x in np.concatenate([root[f], ang[f].ravel()])) for f in range(2)]
    text = BVH.format(h=90, c=40, a=30, root_order=rotations(order), order=rotations(order), frames="\n".join(lines))
    path = tmp_path / "t.bvh"
    path.write_text(text)
    m = sm.load_bvh(path, units="cm")
    assert m.skeleton.names == ("Hips", "Chest", "LeftArm", "LeftArm_end")
    assert m.fps == pytest.approx(120.0, rel=1e-4)
    pos = m.joint_positions()
    for f in range(2):
        R = [Rotation.from_euler(order, ang[f, j], degrees=True) for j in range(3)]
        hips = root[f] / 100
        chest = hips + R[0].apply([0, 0.40, 0])
        arm = chest + (R[0] * R[1]).apply([0.30, 0, 0])
        end = arm + (R[0] * R[1] * R[2]).apply([0.30, 0, 0])
        np.testing.assert_allclose(pos[f], [hips, chest, arm, end], atol=1e-9)


def test_bvh_units_are_detected(tmp_path):
    frames = "0 0 0 0 0 0 0 0 0 0 0 0"
    for unit, scale in [("cm", 1.0), ("m", 0.01), ("inch", 1 / 2.54)]:
        text = BVH.format(h=90 * scale, c=80 * scale, a=80 * scale, root_order=rotations("ZXY"),
                          order=rotations("ZXY"), frames=frames + "\n" + frames)
        (tmp_path / f"{unit}.bvh").write_text(text)
        m = sm.load_bvh(tmp_path / f"{unit}.bvh")
        assert m.meta["metres_per_unit"] == pytest.approx({"cm": 0.01, "m": 1.0, "inch": 0.0254}[unit])
        assert m.skeleton.rest_positions[1, 1] == pytest.approx(1.70)


@pytest.mark.parametrize("mutate,where", [
    (lambda t: t.replace("OFFSET 0 40 0", "OFFSET 0 forty 0"), "line 8"),
    (lambda t: t.replace("CHANNELS 3", "CHANNELS 3 Wrotation", 1), "line 9"),
    (lambda t: t.rsplit("\n", 2)[0] + "\n1 2 3\n", "frame 2"),
    (lambda t: t.replace("Frame Time: 0.0083333", "Frame Time: 0"), "Frame Time"),
    (lambda t: t.rsplit("\n", 2)[0] + "\n0 90 0 0 nan 0 0 0 0 0 0 0\n", "frame 2, "),  # named now, not at posing
])
def test_malformed_bvh_names_the_line(mutate, where, tmp_path):
    frames = "0 90 0 0 0 0 0 0 0 0 0 0\n0 90 0 0 0 0 0 0 0 0 0 0"
    text = BVH.format(h=90, c=40, a=30, root_order=rotations("ZXY"), order=rotations("ZXY"), frames=frames)
    (tmp_path / "bad.bvh").write_text(mutate(text))
    with pytest.raises(BVHError) as e:
        sm.load_bvh(tmp_path / "bad.bvh")
    assert "bad.bvh" in str(e.value) and where in str(e.value)


def test_identity_retarget():
    m = sm.procedural_motion("walk", np.random.default_rng(0), seconds=1.0)
    r = sm.retarget(m, m.skeleton)
    assert np.abs(r.rotations - m.rotations).max() <= 1e-5
    assert np.abs(r.joint_positions() - m.joint_positions()).max() <= 1e-5


def a_pose_giant(scale=1.25):
    """The humanoid, 25% taller, with an A-pose rest (arms 45 deg down) and longer forearms."""
    h = sm.humanoid_skeleton()
    rest = h.rest_positions * scale
    for side, s in (("l", 1), ("r", -1)):
        sh = rest[h.index(f"{side}_shoulder")]
        for j in ("elbow", "wrist", "hand_end"):
            i = h.index(f"{side}_{j}")
            v = rest[i] - sh
            if j != "elbow":
                v = v * 1.1
            rest[i] = sh + np.array([v[0] * np.cos(np.pi / 4), -abs(v[0]) * np.sin(np.pi / 4), v[2]])
    return rest


def bone_dirs(m, pairs):
    p = m.joint_positions()
    d = np.stack([p[:, c] - p[:, j] for j, c in pairs], 1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def test_retarget_keeps_bone_directions_and_scales_root():
    from synmitsuba.body.skeleton import Skeleton
    src = sm.procedural_motion("jog", np.random.default_rng(3), seconds=1.0)
    h = src.skeleton
    tgt_rest = a_pose_giant()
    target = Skeleton(h.names, h.parents, tgt_rest)
    r = sm.retarget(src, target)
    bones = [(h.index(a), h.index(b)) for a, b in [("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"),
                                                   ("r_hip", "r_knee"), ("r_knee", "r_ankle"), ("spine1", "spine2")]]
    assert np.abs(bone_dirs(r, bones) - bone_dirs(src, bones)).max() < 1e-6
    ratio = pelvis_height(target) / pelvis_height(h)
    assert ratio == pytest.approx(1.25)
    np.testing.assert_allclose(r.joint_positions()[:, 0], ratio * src.joint_positions()[:, 0], atol=1e-9)


def _cmu_spine_bvh(names, path):
    text = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n"
    for n in names[1:]:
        text += f"JOINT {n}\n{{\n OFFSET 0 4 0\n CHANNELS 3 Zrotation Yrotation Xrotation\n"
    text += "End Site\n{\n OFFSET 0 3 0\n}\n" + "}\n" * len(names)
    values = " ".join(["0 0 30"] * (len(names) - 1))
    text += "MOTION\nFrames: 2\nFrame Time: 0.0083333\n" + f"0 17 0 0 0 0 {values}\n" * 2
    path.write_text(text)
    return sm.load_bvh(path, units="cmu")


def test_retarget_cmu_names_onto_humanoid(tmp_path):
    """A CMU-named BVH drives the humanoid through the built-in name map: the six CMU spine
    joints are matched to their canonical names by name alone, and the bones follow."""
    from synmitsuba.motion.retargeting import _pairs
    names = ["Hips", "LowerBack", "Spine", "Spine1", "Neck", "Head"]
    m = _cmu_spine_bvh(names, tmp_path / "cmu.bvh")
    h = sm.humanoid_skeleton()
    canon = ["pelvis", "spine1", "spine2", "chest", "neck", "head"]
    expected = {h.index(c): m.skeleton.index(n) for n, c in zip(names + ["Head_end"], canon + ["head_end"])}
    assert _pairs(m.skeleton, h, None) == expected  # the end site matches too
    r = sm.retarget(m, h)
    # each spine joint bends 30 deg about x: the neck->head bone tilts by 5 x 30 deg in both
    src_dir = np.diff(m.joint_positions()[0, [4, 5]], axis=0)[0]
    tgt_dir = np.diff(r.joint_positions()[0, [h.index("neck"), h.index("head")]], axis=0)[0]
    assert np.allclose(src_dir / np.linalg.norm(src_dir), tgt_dir / np.linalg.norm(tgt_dir), atol=1e-6)
    # three recognisable joints are too few to match by name: the error asks for a name_map
    few = _cmu_spine_bvh(["Hips", "LowerBack", "Spine"], tmp_path / "few.bvh")
    with pytest.raises(ConfigError, match="could not match the skeletons' joint names"):
        sm.retarget(few, h)
    with pytest.raises(ConfigError, match="name_map = 'nope'"):  # a map naming a joint that is not there
        sm.retarget(m, h, name_map={"Hips": "nope"})


def test_resample_slerps_rotations():
    h = sm.humanoid_skeleton()
    F, fps = 121, 120.0
    t = np.arange(F) / fps
    R = np.broadcast_to(np.eye(3), (F, len(h), 3, 3)).copy()
    R[:, h.index("neck")] = Rotation.from_euler("y", 2.0 * t[:, None]).as_matrix()  # 2 rad/s about y
    m = sm.Motion(h, R, np.stack([t, 0 * t, 0 * t], 1), fps)
    r = m.resample(30)
    assert r.n_frames == 31 and r.fps == 30
    want = Rotation.from_euler("y", 2.0 * np.arange(31)[:, None] / 30).as_matrix()
    assert np.abs(r.rotations[:, h.index("neck")] - want).max() < 1e-9
    np.testing.assert_allclose(r.root_translation[:, 0], np.arange(31) / 30, atol=1e-12)
    # 7/120 s steps don't land on source frames: interpolated angles stay exact for a constant rate
    r7 = m.resample(120 / 7)
    assert np.abs(r7.rotations[:, h.index("neck")] - Rotation.from_euler("y", 2.0 * np.arange(r7.n_frames)[:, None] * 7 / 120).as_matrix()).max() < 1e-9


def test_clips_filters_and_library(tmp_path):
    rng = np.random.default_rng(0)
    long = sm.procedural_motion("walk", rng, seconds=5.0, fps=60)
    clip = sm.random_window(long, rng)
    assert clip.n_frames == 60 and clip.fps == 30
    with pytest.raises(ConfigError):
        sm.random_window(sm.procedural_motion("walk", rng, seconds=1.5), rng)
    assert sm.is_allowed(["walk forward"]) and not sm.is_allowed(["sit down on chair"])
    assert not sm.is_allowed(["swim"]) and not sm.is_allowed(["fall and get up"])
    # a user folder: one short clip, one excluded by label, one usable
    for name, n in [("wave_hello", 300), ("short", 120), ("sit_down", 300)]:
        frames = "\n".join(["0 90 0 0 0 0 0 0 0 0 0 0"] * n)
        text = BVH.format(h=90, c=40, a=30, root_order=rotations("ZXY"), order=rotations("ZXY"), frames=frames)
        (tmp_path / f"{name}.bvh").write_text(text.replace("Frames: 2", f"Frames: {n}"))
    (tmp_path / "labels.json").write_text(json.dumps({"wave_hello.bvh": ["wave", "greet"]}))
    lib = sm.MotionLibrary.default()
    assert lib.add_folder(str(tmp_path)) == 3
    usable = lib.filter().entries
    names = {e.name for e in usable}
    assert "wave_hello" in names and "short" not in names and "sit_down" not in names
    assert {"walk", "run", "jump"} <= names


@pytest.mark.parametrize("kind", sm.MOTION_KINDS)
def test_procedural_motions_are_plausible(kind):
    m = sm.procedural_motion(kind, np.random.default_rng(7), seconds=2.0)
    assert m.n_frames == 60 and m.labels == (kind,)
    R = m.rotations
    assert np.allclose(R @ np.swapaxes(R, -1, -2), np.eye(3), atol=1e-9)
    angles = np.degrees(np.arccos(np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1, 1)))
    assert angles.max() < 170  # within plausible joint ranges
    step = np.degrees(np.arccos(np.clip((np.trace(np.swapaxes(R[1:], -1, -2) @ R[:-1], axis1=-2, axis2=-1) - 1) / 2, -1, 1)))
    assert step.max() < 30  # smooth: < 900 deg/s at 30 fps
    y = m.joint_positions()[..., 1]
    assert y.min() > -0.01
    on_ground = np.abs(y.min(1)) < 0.01
    if kind in ("jog", "run", "jump"):  # these have flight phases, but not all the time
        assert 0.3 < on_ground.mean() < 1.0
    else:
        assert on_ground.all()  # a foot on the ground in every frame


@pytest.mark.parametrize("kind,limit", [("walk", 0.03), ("jog", 0.03), ("run", 0.03), ("side_step", 0.08),
                                        ("idle", 0.01), ("squat", 0.01)])
def test_feet_stay_planted(kind, limit):
    for seed in range(3):
        m = sm.procedural_motion(kind, np.random.default_rng(seed), seconds=2.0)
        assert sm.foot_sliding(m) < limit, (kind, seed)


@pytest.mark.parametrize("kind", ["walk", "jog", "run"])
def test_feet_roll_from_the_heel_over_the_ball(kind):
    """A step lands on the heel, toe up; the foot comes down flat and pushes off over the ball,
    heel up, the toes flat on the ground. While a foot comes down its heel's contact point holds
    still; while its heel rises its toes' tip does. No sole point is ever under the ground, and
    in a walk one is on it at every frame."""
    for seed in range(2):
        m = sm.procedural_motion(kind, np.random.default_rng(seed), seconds=2.0, fps=60)
        sk, P, G = m.skeleton, m.joint_positions(), m.global_rotations()
        lowest = np.full(m.n_frames, np.inf)
        for s in "lr":
            a, ball, tip = (sk.index(f"{s}_{j}") for j in ("ankle", "toe", "toe_end"))
            pitch = np.degrees(np.arcsin(G[:, a, 1, 2]))  # the foot's long axis (z) against the ground
            heel = P[:, a] + G[:, a] @ np.array([0.0, -0.085, -0.055])  # under and behind the ankle
            under_ball = P[:, ball] + G[:, a] @ np.array([0.0, -0.02, 0.0])
            toes_flat = np.abs(G[:, ball, 1, 2]) < 1e-9
            assert pitch.max() > {"walk": 10, "jog": 5, "run": 2}[kind] and pitch.min() < -20, (kind, seed, s)
            landing = 3 if kind == "walk" else 0  # a run lands nearer the midfoot, for a frame or none at 60 fps
            for point, when, frames in ((heel, (pitch > 1) & (heel[:, 1] < 1e-6), landing),
                                        (P[:, tip], (pitch < -1) & (P[:, tip, 1] < 1e-6) & toes_flat, 3)):
                both = when[1:] & when[:-1]
                assert both.sum() >= frames, (kind, seed, s)
                assert np.abs(np.diff(point, axis=0)[both]).max(initial=0.0) < 1e-3, (kind, seed, s)
            lowest = np.minimum(lowest, np.min([heel[:, 1], under_ball[:, 1], P[:, tip, 1]], axis=0))
        assert lowest.min() > -1e-6
        if kind == "walk":
            assert lowest.max() < 1e-6


def test_walk_parameters_change_the_motion():
    base = dict(speed=1.2, stride=1.4, amplitude=1.0, style="normal")
    ref = sm.procedural_motion("walk", np.random.default_rng(0), **base)
    assert ref.root_translation[-1, 2] == pytest.approx(1.2 * 59 / 30, rel=1e-6)
    for key, value in [("speed", 1.5), ("stride", 1.2), ("amplitude", 1.3), ("style", "brisk")]:
        other = sm.procedural_motion("walk", np.random.default_rng(0), **{**base, key: value})
        assert not np.allclose(other.rotations, ref.rotations), key


def test_amass_synthetic_npz(tmp_path):
    F = 12
    rng = np.random.default_rng(0)
    trans = np.tile([0.4, -0.2, 0.95], (F, 1))
    trans[:, 0] += np.linspace(0, 0.5, F)
    np.savez(tmp_path / "a.npz", root_orient=np.tile([np.pi / 2, 0, 0], (F, 1)), pose_body=np.zeros((F, 63)),
             pose_hand=rng.normal(0, 0.1, (F, 90)), pose_jaw=np.zeros((F, 3)), trans=trans, betas=np.zeros(16),
             mocap_frame_rate=np.array(60.0))
    m = sm.load_amass(tmp_path / "a.npz")
    assert m.fps == 60 and len(m.skeleton) == 55
    pos = m.joint_positions()
    sk = m.skeleton
    head, pelvis = pos[:, sk.index("head")], pos[:, sk.index("pelvis")]
    assert (head[:, 1] - pelvis[:, 1] > 0.5).all()  # upright in y-up
    # AMASS z-up (x, y, z) -> our (x, z, -y): pelvis = J0 + trans
    np.testing.assert_allclose(pelvis[:, 0], trans[:, 0] + 0.0031, atol=1e-9)
    np.testing.assert_allclose(pelvis[:, 1], trans[:, 2] + 0.0120, atol=1e-9)
    np.testing.assert_allclose(pelvis[:, 2], -(trans[:, 1] - 0.3514), atol=1e-9)
    r = sm.retarget(m, sm.humanoid_skeleton())
    assert r.n_frames == F and np.isfinite(r.rotations).all()
    with pytest.raises(ConfigError) as e:
        np.savez(tmp_path / "b.npz", trans=trans)
        sm.load_amass(tmp_path / "b.npz")
    assert "root_orient" in str(e.value)


def test_bad_motion_requests():
    with pytest.raises(ConfigError) as e:
        sm.procedural_motion("moonwalk", np.random.default_rng(0))
    assert "moonwalk" in str(e.value) and "walk" in str(e.value)
    with pytest.raises(ConfigError) as e:
        sm.procedural_motion("walk", np.random.default_rng(0), sped=1.0)
    assert "walk.sped" in str(e.value)
    m = sm.procedural_motion("idle", np.random.default_rng(0), seconds=1.0)
    with pytest.raises(ConfigError):
        m.clip(0.5, 1.0)


def test_motion_preview_cli_writes_a_strip(tmp_path):
    from PIL import Image

    from synmitsuba.cli import main
    assert main(["motion", "preview", "walk", "--out", str(tmp_path), "--frames", "3", "--res", "40x50",
                 "--spp", "2", "--stick"]) == 0
    img = np.asarray(Image.open(tmp_path / "walk_strip.png"))
    assert img.shape[1] > 3 * 40 and img.shape[0] >= 50
    assert img[..., 0].std() > 5  # not a blank picture



def test_motion_preview_both_rows_skinned_as_cloth_skinned_builds_them(tmp_path, monkeypatch):
    """``--cloth both``: its skinned row is the subject ``cloth: skinned`` builds (trouser legs cut
    for skinning), not the simulated subject's finer legs skinned; the other row is the simulated
    subject with its cloth. The simulation is stubbed out: only which subject each row shows counts."""
    import dataclasses

    import synmitsuba as sm
    from synmitsuba.cli import main, motion as cli_motion

    class Stub:
        def at(self, f):
            return None

    shown, figure = [], cli_motion._figure_scene
    monkeypatch.setattr(sm, "simulate_cloth", lambda human, motion: Stub())
    monkeypatch.setattr(cli_motion, "_figure_scene",
                        lambda motion, f, human=None, cloth=None: shown.append((human, cloth)) or figure(motion, f, human))
    assert main(["motion", "preview", "walk", "--out", str(tmp_path), "--frames", "1", "--res", "24x32", "--spp", "1",
                 "--seconds", "0.2", "--outfit", "tshirt,trousers", "--cloth", "both", "--seed", "3"]) == 0
    (top, no_cloth), (bottom, stub) = shown
    assert no_cloth is None and isinstance(stub, Stub)
    assert (top.recipe.cloth, bottom.recipe.cloth) == ("skinned", "simulated")
    assert dataclasses.replace(top.recipe, cloth="simulated") == bottom.recipe
    skinned = sm.build_subject(top.recipe)
    legs = [[g.vertices for g in h.garments if g.params.kind == "trousers"][0] for h in (top, skinned, bottom)]
    assert np.array_equal(legs[0], legs[1])
    assert len(legs[2]) > 1.5 * len(legs[0])  # the simulated subject's legs are cut finer

CMU_TREE = [  # name, parent, offset in CMU units (~5.6 cm), T-pose
    ("Hips", None, (0, 0, 0)), ("LHipJoint", "Hips", (0, 0, 0)), ("LeftUpLeg", "LHipJoint", (1.6, -1.7, 0.8)),
    ("LeftLeg", "LeftUpLeg", (0, -7.5, 0)), ("LeftFoot", "LeftLeg", (0, -7.4, 0)), ("LeftToeBase", "LeftFoot", (0, -0.4, 2.2)),
    ("RHipJoint", "Hips", (0, 0, 0)), ("RightUpLeg", "RHipJoint", (-1.6, -1.7, 0.8)), ("RightLeg", "RightUpLeg", (0, -7.5, 0)),
    ("RightFoot", "RightLeg", (0, -7.4, 0)), ("RightToeBase", "RightFoot", (0, -0.4, 2.2)),
    ("LowerBack", "Hips", (0, 2.0, -0.2)), ("Spine", "LowerBack", (0, 2.0, 0)), ("Spine1", "Spine", (0, 2.0, 0)),
    ("Neck", "Spine1", (0, 1.7, 0)), ("Neck1", "Neck", (0, 1.0, 0)), ("Head", "Neck1", (0, 1.0, 0)),
    ("LeftShoulder", "Spine1", (0, 1.5, 0)), ("LeftArm", "LeftShoulder", (3.0, 0, 0)), ("LeftForeArm", "LeftArm", (5.0, 0, 0)),
    ("LeftHand", "LeftForeArm", (4.3, 0, 0)), ("RightShoulder", "Spine1", (0, 1.5, 0)), ("RightArm", "RightShoulder", (-3.0, 0, 0)),
    ("RightForeArm", "RightArm", (-5.0, 0, 0)), ("RightHand", "RightForeArm", (-4.3, 0, 0)),
]


def cmu_bvh(frames: np.ndarray) -> str:
    children = {}
    for name, parent, _ in CMU_TREE:
        children.setdefault(parent, []).append(name)
    offsets = {n: o for n, _, o in CMU_TREE}

    def block(name, depth):
        pad = "  " * depth
        kind = "ROOT" if depth == 0 else "JOINT"
        chans = "6 Xposition Yposition Zposition Zrotation Yrotation Xrotation" if depth == 0 else "3 Zrotation Yrotation Xrotation"
        text = f"{pad}{kind} {name}\n{pad}{{\n{pad}  OFFSET {' '.join(map(str, offsets[name]))}\n{pad}  CHANNELS {chans}\n"
        for c in children.get(name, []):
            text += block(c, depth + 1)
        if name not in children:
            text += f"{pad}  End Site\n{pad}  {{\n{pad}    OFFSET 0 1 0\n{pad}  }}\n"
        return text + f"{pad}}}\n"
    lines = "\n".join(" ".join(f"{x:.4f}" for x in row) for row in frames)
    return f"HIERARCHY\n{block('Hips', 0)}MOTION\nFrames: {len(frames)}\nFrame Time: 0.0083333\n{lines}\n"


def test_cmu_bvh_retargets_onto_anny_with_the_builtin_map(tmp_path):
    from synmitsuba.body.anny_model import anny_body
    n = len(CMU_TREE)
    rng = np.random.default_rng(5)
    frames = np.zeros((4, 3 + 3 * n))
    frames[:, 1] = 17.0
    frames[:, 3:] = np.round(rng.uniform(-40, 40, (4, 3 * n)), 3)
    (tmp_path / "cmu.bvh").write_text(cmu_bvh(frames))
    m = sm.load_bvh(tmp_path / "cmu.bvh")
    assert m.meta["metres_per_unit"] == pytest.approx(0.0254 / 0.45)
    anny = anny_body().skeleton
    r = sm.retarget(m, anny)
    ps, pt = m.joint_positions(), r.joint_positions()
    for (a, b), (c, d) in [(("LeftArm", "LeftForeArm"), ("upperarm01.L", "lowerarm01.L")),
                           (("RightForeArm", "RightHand"), ("lowerarm01.R", "wrist.R")),
                           (("LeftUpLeg", "LeftLeg"), ("upperleg01.L", "lowerleg01.L")),
                           (("RightLeg", "RightFoot"), ("lowerleg01.R", "foot.R"))]:
        u = ps[:, m.skeleton.index(b)] - ps[:, m.skeleton.index(a)]
        v = pt[:, anny.index(d)] - pt[:, anny.index(c)]
        cos = (u * v).sum(1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        assert cos.min() > 1 - 1e-6, (a, c)


def test_pose_between_frames_is_the_slerp_of_its_neighbours():
    """Motion.at (motion blur's sub-frames) against scipy's Slerp per joint (geometry.slerp_matrices)
    and the root's linear interpolation; whole times are the frames themselves, and times
    outside the clip clamp to its ends."""
    from synmitsuba.geometry import slerp_matrices
    m = sm.procedural_motion("walk", np.random.default_rng(0), seconds=0.5)
    rot, root = m.at(3.3)
    assert np.allclose(rot, slerp_matrices(m.rotations, np.array([3.3]))[0], atol=1e-9)
    assert np.allclose(root, 0.7 * m.root_translation[3] + 0.3 * m.root_translation[4])
    assert np.array_equal(m.at(3)[0], m.rotations[3]) and np.array_equal(m.at(-1.0)[1], m.root_translation[0])
    assert np.array_equal(m.at(m.n_frames + 2.5)[0], m.rotations[-1])


@pytest.mark.parametrize("kind", ["idle", "walk", "run"])
def test_retargeted_feet_pitch_as_the_source_feet_do_from_their_flat_rests(kind):
    """Both rest poses stand flat-footed: anny's feet and toes turn from their rests at every
    frame exactly as the humanoid source's do from its own (their ankle-to-toe slopes differ, 19
    against 26.6 degrees, which the T-pose must not turn into a toe-down tilt), and each of the
    five toes bends as the source's one toe joint does."""
    from synmitsuba.body.anny_model import anny_body
    src = sm.procedural_motion(kind, np.random.default_rng(2), seconds=1.0)
    anny = anny_body().skeleton
    out = sm.retarget(src, anny)
    Gs, Gt = src.global_rotations(), out.global_rotations()
    for s in ("l", "r"):
        side = "L" if s == "l" else "R"
        np.testing.assert_allclose(Gt[:, anny.index(f"foot.{side}")], Gs[:, src.skeleton.index(f"{s}_ankle")], atol=1e-9)
        for k in range(1, 6):
            np.testing.assert_allclose(Gt[:, anny.index(f"toe{k}-1.{side}")], Gs[:, src.skeleton.index(f"{s}_toe")],
                                       atol=1e-9)


@pytest.mark.parametrize("family,tol", [("cmu", 1e-4), ("smplx", 6e-3)])
@pytest.mark.parametrize("kind", ["walk", "run", "jump"])
def test_mocap_sole_clearance_matches_the_humanoids_exact_one(kind, family, tol):
    """``contacts.foot_clearance`` estimates a clip's sole heights from its ankles and toes alone
    (a copy of a procedural clip with a mocap family's joint names, so nothing tells it the
    skeleton is the humanoid's): it matches the humanoid's own sole clearance (heel, ball and toe
    tip, written separately) within 0.1 mm at every frame with CMU's names, which have the toe's
    end; SMPL-X's have none, so the tip is taken under the toe joint: within 6 mm in a run's
    flight, and on the ground wherever a foot is. Wherever the source's floor is; a skeleton
    without feet has none."""
    from dataclasses import replace
    from reference import named_as
    from synmitsuba.body.skeleton import Skeleton
    from synmitsuba.motion.contacts import foot_clearance
    from synmitsuba.motion.humanoid import sole_clearance
    m = sm.procedural_motion(kind, np.random.default_rng(2), seconds=2.0)
    sk = m.skeleton
    cmu = named_as(m, family)
    exact = sole_clearance(m.rotations, m.root_translation)
    assert np.abs(foot_clearance(cmu) - exact).max() < tol
    assert np.all(foot_clearance(cmu)[exact < 1e-9] < 1e-4)
    raised = replace(cmu, root_translation=cmu.root_translation + [0.0, 0.37, 0.0])  # a floor 37 cm up
    assert np.abs(foot_clearance(raised) - exact).max() < tol
    if kind != "walk":
        assert exact.max() > 0.05  # the flight is in it
    legless = [i for i, n in enumerate(sk.names) if not n.startswith(("l_", "r_"))]
    assert foot_clearance(replace(cmu, skeleton=Skeleton(tuple(cmu.skeleton.names[i] for i in legless),
                                                         np.array([legless.index(p) if p >= 0 else -1 for p in sk.parents[legless]]),
                                                         sk.rest_positions[legless]),
                                  rotations=cmu.rotations[:, legless])) is None
