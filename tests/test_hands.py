"""Hands: finger behaviours that curl towards the palm within anatomical limits, tracks that
blend and follow the motion, COCO-WholeBody hand keypoints against our own re-posing of the
skeleton and the skin, and hand tracks carried by scene specs and scene files."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.compose.subjects import MotionSpec, draw_hands, fixed_hands, retargeted_clip
from synmitsuba.errors import ConfigError
from synmitsuba.motion import hands as H


@pytest.fixture(scope="module")
def human():
    recipe = sm.sample_subject(np.random.default_rng(5), {"hair_style": "bald", "accessories": [], "texture_size": 64})
    return sm.build_subject(recipe)


def _posed_with(human, behaviour: str, seed: int = 0, variant: int = 0):
    """Rest body, both hands holding ``behaviour``: (rotations, root)."""
    clip = retargeted_clip(human, MotionSpec("idle", 3, 0.2, 10))
    m = H.with_hands(clip, H.HandTrack([H.HandKey(0.0, behaviour, seed, variant)],
                                       [H.HandKey(0.0, behaviour, seed + 1, variant)], drift_deg=0.0))
    return m.rotations[0], m.root_translation[0]


def _own_pose(human, rot, root):
    """Joint positions and skinned vertices, written here: G_i = G_parent R_i, p_i = p_parent +
    G_parent (rest_i - rest_parent); v = sum_j w_j (G_j (v_rest - rest_j) + p_j)."""
    sk = human.skeleton
    P = sk.rest_positions
    G, p = np.zeros((len(sk), 3, 3)), np.zeros((len(sk), 3))
    for i, par in enumerate(sk.parents):
        if par < 0:
            G[i], p[i] = rot[i], P[i] + root
        else:
            G[i], p[i] = G[par] @ rot[i], p[par] + G[par] @ (P[i] - P[par])
    return G, p


def test_hand_keypoints_are_the_posed_joints_and_finger_tips(human):
    rot, root = _posed_with(human, "point")
    G, p = _own_pose(human, rot, root)
    kp = human.hand_keypoints(rot, root)
    sk, body = human.skeleton, human.body
    local = np.einsum("jab,vjb->vja", G, body.vertices[:, None] - sk.rest_positions[None]) + p[None]
    skinned = np.einsum("vj,vja->va", body.weights.astype(np.float64), local)
    for h, s in enumerate("LR"):
        assert np.allclose(kp[h, 0], p[sk.index(f"wrist.{s}")], atol=1e-9)
        for f in range(5):
            joints = [p[sk.index(f"finger{f + 1}-{k}.{s}")] for k in (1, 2, 3)]
            assert np.allclose(kp[h, 1 + 4 * f:4 + 4 * f], joints, atol=1e-9)
            # the tip: a skin vertex, skinned here, lying beyond the end joint along the end bone
            tip = kp[h, 4 + 4 * f]
            assert np.min(np.linalg.norm(skinned - tip, axis=1)) < 1e-9
            assert (tip - joints[2]) @ (joints[2] - joints[1]) > 0


def _bends(kp: np.ndarray) -> np.ndarray:
    """(2, 5, 3) degrees each finger turns at its three joints (thumb: MCP, IP; the CMC is left
    out: the wrist is not on the thumb's line), from the points alone."""
    out = np.zeros((2, 5, 3))
    for h in range(2):
        for f in range(5):
            chain = kp[h, [0, 1 + 4 * f, 2 + 4 * f, 3 + 4 * f, 4 + 4 * f]]
            seg = np.diff(chain, axis=0)
            seg /= np.linalg.norm(seg, axis=1, keepdims=True)
            out[h, f] = np.degrees(np.arccos(np.clip(np.einsum("ka,ka->k", seg[:-1], seg[1:]), -1, 1)))
    return out


def test_behaviours_bend_the_fingers_within_their_limits(human):
    rest = _bends(human.hand_keypoints())
    tips = {}
    for behaviour in H.BEHAVIOURS:
        for seed in range(6):
            kp = human.hand_keypoints(*_posed_with(human, behaviour, seed))
            change = _bends(kp) - rest
            # PIP and DIP of the four fingers: at most their flexion limit (+ 8 deg for the axes
            # not being square to both bones), never bent backwards past 10 deg
            assert change[:, 1:, 1].max() <= H.LIMITS[H.ANGLES.index("index_pip"), 1] + 8
            assert change[:, 1:, 2].max() <= H.LIMITS[H.ANGLES.index("index_dip"), 1] + 8
            assert change[:, 1:, 1:].min() >= -10
            tips.setdefault(behaviour, []).append(np.linalg.norm(kp[:, 8::4] - kp[:, :1], axis=2).mean())
    # a fist brings the finger tips towards the wrist; an open hand keeps them out
    assert np.mean(tips["fist"]) < 0.72 * np.mean(tips["open"])
    assert np.mean(tips["relaxed"]) < np.mean(tips["open"]) and np.mean(tips["relaxed"]) > np.mean(tips["fist"])


def test_fingers_curl_towards_the_palm_not_the_nails(human):
    """The back of the hand found from anny's nail mask (the nails' mean surface normal), not
    from the thumb as the code does: a fist and a relaxed hand move each finger tip
    away from that side (a fist's tips come back towards the palm), an open hand hardly."""
    from synmitsuba.geometry import vertex_normals
    from synmitsuba.body.anny_model import anny_uv_masks
    body, sk = human.body, human.skeleton
    nails = anny_uv_masks(256)["nails"]
    uv = np.zeros((len(body.vertices), 2))
    uv[body.faces.ravel()] = body.uv[body.face_uv.ravel()]
    on_nail = nails[np.clip(((1 - uv[:, 1]) * 256).astype(int), 0, 255), np.clip((uv[:, 0] * 256).astype(int), 0, 255)] > 0.5
    rest = human.hand_keypoints()
    moved = {}
    for behaviour in ("fist", "relaxed", "open"):
        rot, _ = _posed_with(human, behaviour)
        only_fingers = np.broadcast_to(np.eye(3), rot.shape).copy()
        fingers = [i for i, n in enumerate(sk.names) if n.startswith("finger")]
        only_fingers[fingers] = rot[fingers]
        kp = human.hand_keypoints(only_fingers, np.zeros(3))
        for h, s in enumerate("LR"):
            end = sk.rest_positions[sk.index(f"finger3-3.{s}")]
            near = on_nail & (np.linalg.norm(body.vertices - end, axis=1) < 0.03)
            back = vertex_normals(body.vertices, body.faces)[near].mean(0)
            back /= np.linalg.norm(back)
            moved.setdefault(behaviour, []).append((kp[h, 8::4] - rest[h, 8::4]) @ back)  # index .. pinky tips
    assert (np.concatenate(moved["fist"]) < -0.015).all()
    assert (np.concatenate(moved["relaxed"]) < 0).all()
    assert np.abs(np.concatenate(moved["open"])).max() < 0.02


def test_a_track_blends_from_key_to_key():
    track = H.HandTrack([H.HandKey(0.0, "open", 1), H.HandKey(1.0, "fist", 2)], [H.HandKey(0.0, "relaxed", 3)],
                        blend_s=0.4, drift_deg=0.0)
    t = np.array([0.0, 0.99, 1.2, 1.4, 2.0])
    a = track.angles("left", t)
    assert np.allclose(a[:2], H.HandKey(0.0, "open", 1).pose().vector())
    assert np.allclose(a[3:], H.HandKey(1.0, "fist", 2).pose().vector())
    mid = a[2]  # half-way through the smoothstep: the mean of the two poses
    assert np.allclose(mid, 0.5 * (a[0] + a[3]))
    fine = track.angles("left", np.arange(0, 2, 1 / 30))
    assert np.abs(np.diff(fine, axis=0)).max() < 1.5 * 100 / (0.4 * 30)  # smoothstep's steepest slope


def test_hands_follow_the_motion():
    rng = np.random.default_rng(0)
    wave = H.sample_hands(rng, "wave", {"handedness": "left"})
    assert [k.behaviour for k in wave.left] == ["open"]
    point = H.sample_hands(rng, "gesture", {"style": "point", "handedness": "right"})
    assert point.right[0].behaviour == "point"
    runs = [H.sample_hands(rng, "run").left[0].behaviour for _ in range(200)]
    assert runs.count("fist") > 90 and "thumbs_up" not in runs
    walks = [H.sample_hands(rng, "walk").right[0].behaviour for _ in range(200)]
    assert walks.count("relaxed") > 120


def test_a_source_with_fingers_keeps_them(human):
    clip = retargeted_clip(human, MotionSpec("walk", 1, 0.3, 10))
    from dataclasses import replace
    own = replace(clip, meta={**clip.meta, "fingers": True})
    assert H.with_hands(own, draw_hands(np.random.default_rng(0), clip)) is own
    handed = H.with_hands(clip, draw_hands(np.random.default_rng(0), clip))
    index = human.skeleton.index("finger2-2.R")
    assert not np.allclose(handed.rotations[:, index], np.eye(3))
    assert np.array_equal(handed.rotations[:, 0], clip.rotations[:, 0])  # the body is untouched


def test_hand_tracks_round_trip_and_bad_ones_are_named():
    track = H.sample_hands(np.random.default_rng(3), "idle", seconds=2.0)
    again = H.HandTrack.from_dict(track.to_dict())
    assert again == track
    assert np.array_equal(again.angles("right", np.arange(5) / 10), track.angles("right", np.arange(5) / 10))
    with pytest.raises(ConfigError, match=r"hands\.left\[0\].*claw"):
        H.HandTrack.from_dict({"left": [[0, "claw", 1]], "right": [[0, "fist", 1]]})
    with pytest.raises(ConfigError, match=r"hands\.right\[0\]"):
        H.HandTrack.from_dict({"left": [[0, "fist", 1]], "right": [[0, "fist"]]})
    with pytest.raises(ConfigError, match=r"subjects\[0\]\.hands"):
        from synmitsuba.compose.subjects import SubjectEntry
        SubjectEntry.from_dict({"hands": "claw"}, "subjects[0]")


def test_scene_file_subjects_take_a_behaviour_or_draw_one():
    from synmitsuba.compose.subjects import SubjectEntry, subject_specs
    entries = [SubjectEntry.from_dict({"seed": 4, "motion": "run", "hands": "thumbs_up", "config": {
        "hair_style": "bald", "accessories": [], "texture_size": 64}}, "s"),
               SubjectEntry.from_dict({"seed": 4, "motion": "wave", "position": [2, 0], "config": {
                   "hair_style": "bald", "accessories": [], "texture_size": 64}}, "s")]
    specs, _ = subject_specs(entries, np.random.default_rng(0), set())
    assert [k.behaviour for k in specs[0].hands.left + specs[0].hands.right] == ["thumbs_up", "thumbs_up"]
    assert fixed_hands("thumbs_up", 0).left[0].behaviour == "thumbs_up"
    waving = specs[1].hands
    assert "open" in [waving.left[0].behaviour, waving.right[0].behaviour]


def test_amass_fingers_drive_annys_fingers(human, tmp_path):
    """Each of an AMASS clip's 30 finger rotations reaches its anny finger bone turned by the
    same angle (retargeting only re-expresses it in anny's hand frame); the clip then keeps its
    own fingers, and a clip with flat hands takes the drawn behaviour instead."""
    from scipy.spatial.transform import Rotation

    from synmitsuba.body.smplx_model import SMPLX_JOINT_NAMES
    from synmitsuba.motion.names import finger_pairs
    F = 6
    rng = np.random.default_rng(2)
    common = dict(root_orient=np.tile([np.pi / 2, 0, 0], (F, 1)), pose_body=np.zeros((F, 63)), pose_jaw=np.zeros((F, 3)),
                  trans=np.tile([0.0, 0.0, 0.95], (F, 1)), betas=np.zeros(16), mocap_frame_rate=np.array(30.0))
    hand = rng.normal(0, 0.4, (F, 90))
    np.savez(tmp_path / "hands.npz", pose_hand=hand, **common)
    np.savez(tmp_path / "flat.npz", pose_hand=np.zeros((F, 90)), **common)
    m = sm.retarget(sm.load_amass(tmp_path / "hands.npz"), human.skeleton)
    pairs = finger_pairs(SMPLX_JOINT_NAMES, human.skeleton.names)
    assert len(pairs) == 30 and m.meta["fingers"]
    for anny, smplx in pairs.items():
        k = SMPLX_JOINT_NAMES.index(smplx) - 25  # pose_hand: left hand's 15 joints, then the right's
        source = np.linalg.norm(hand[:, 3 * k:3 * k + 3], axis=1)
        ours = np.linalg.norm(Rotation.from_matrix(m.rotations[:, human.skeleton.index(anny)]).as_rotvec(), axis=1)
        np.testing.assert_allclose(ours, source, atol=1e-9)
    assert H.with_hands(m, draw_hands(np.random.default_rng(0), m)) is m
    flat = sm.retarget(sm.load_amass(tmp_path / "flat.npz"), human.skeleton)
    assert not flat.meta["fingers"]
    assert H.with_hands(flat, draw_hands(np.random.default_rng(0), flat)) is not flat


def test_a_fists_thumb_lies_over_the_fingers(human):
    """In a fist (and the fingers folded for a point or a count of one), the thumb's tip lies
    over the index and middle fingers' middle bones (within half a hand size of their joints'
    keypoints, nearer them than the wrist), not curled back to the wrist beside the fist."""
    for behaviour, variant in (("fist", 0), ("point", 0), ("count", 1)):
        for seed in range(4):
            rot, root = _posed_with(human, behaviour, seed, variant)
            for kp in human.hand_keypoints(rot, root):
                size = np.ptp(kp, axis=0).max()
                near = np.linalg.norm(kp[[10, 11] if behaviour != "fist" else [6, 7, 10, 11]] - kp[4], axis=1).min()
                assert near < 0.5 * size and near < np.linalg.norm(kp[4] - kp[0]), (behaviour, seed, near / size)
