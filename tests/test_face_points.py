"""The face's 68 keypoints (COCO-WholeBody's 300W layout): skin vertices of the posed body as
rendered, laid out as 300W lays them out on a frontal face, mirror-symmetric, opening with the
jaw and closing with the lids; labelled visible from the front and hidden from behind."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.body.face_points import FACE68_VERTICES, face_keypoint_names

from reference import unit_weights

# 300W's mirror pairs, written out here (the subject's right <-> left)
PAIRS = ([(i, 16 - i) for i in range(8)] + [(17 + i, 26 - i) for i in range(5)] + [(31, 35), (32, 34)]
         + [(36, 45), (37, 44), (38, 43), (39, 42), (40, 47), (41, 46)]
         + [(48, 54), (49, 53), (50, 52), (55, 59), (56, 58), (60, 64), (61, 63), (65, 67)])
MIDLINE = (8, 27, 28, 29, 30, 33, 51, 57, 62, 66)


@pytest.fixture(scope="module")
def human():
    recipe = sm.sample_subject(np.random.default_rng(33), {"hair_style": "bald", "accessories": [], "texture_size": 64})
    return sm.build_subject(recipe)


def _rest(human):
    return np.broadcast_to(np.eye(3), (len(human.skeleton), 3, 3)).copy(), np.zeros(3)


def test_points_are_the_rendered_skin_vertices(human):
    """Each point is where the body mesh put in the scene has that anny vertex (any of its
    copies along the uv seams), with an expression on and a turned head."""
    rot, root = _rest(human)
    from scipy.spatial.transform import Rotation
    rot[human.skeleton.index("neck02")] = Rotation.from_rotvec([0.1, 0.5, 0.0]).as_matrix()
    w = unit_weights(jawOpen=0.5, mouthSmileLeft=0.6, eyeBlinkRight=1.0)
    scene = sm.Scene()
    human.add_to(scene, rot, root, instance=1, face=w)
    mesh = scene.meshes["subject1_body"].vertices
    source = human.split.source
    expected = np.array([mesh[np.flatnonzero(source == v)[0]] for v in FACE68_VERTICES])
    assert np.array_equal(human.face_keypoints(rot, root, face=w), expected)
    assert len(face_keypoint_names()) == 68 and face_keypoint_names()[67] == "face-67"


def test_the_layout_is_300w_on_a_frontal_face(human):
    """Projected from the front: the jaw runs down the image's left (the subject's right) to the
    chin and up its right, brows above eyes above the nose tip above the lips, the right
    eye left of the left one; on the rest template pairs mirror each other and the midline
    points lie on it."""
    rot, root = _rest(human)
    pts = human.face_keypoints(rot, root)
    eyes = pts[36:48].mean(0)
    cam = sm.Camera.look_at(eye=tuple(eyes + [0, 0, 0.6]), target=tuple(eyes), fov_y_deg=30, width=400, height=400)
    uv = cam.project(pts)[0]
    x, y = uv[:, 0], uv[:, 1]
    assert (np.diff(y[:9]) > 0).all() and (np.diff(y[8:17]) < 0).all() and x[:8].max() < x[8] < x[9:17].min()
    assert y[17:27].max() < y[36:48].min() and y[36:48].max() < y[30] < y[48:68].min()
    assert x[36:42].max() < x[42:48].min() and x[17:22].max() < x[22:27].min()
    assert y[51] < y[62] <= y[66] < y[57] and x[48] < x[51] < x[54]
    rest = human.body.vertices[FACE68_VERTICES]
    for i, j in PAIRS:
        assert np.allclose(rest[i] * [-1, 1, 1], rest[j], atol=2e-3), (i, j)
    assert np.abs(rest[list(MIDLINE), 0]).max() < 2e-3


def test_points_open_with_the_jaw_and_close_with_the_lids(human):
    rot, root = _rest(human)
    gap = human.face_keypoints(rot, root)
    shut = human.face_keypoints(rot, root, face=unit_weights(jawOpen=0.8, eyeBlinkLeft=1.0, eyeBlinkRight=1.0))
    lips = lambda p: p[66, 1] - p[62, 1]  # noqa: E731  (below: negative y is down)
    assert lips(gap) > -3e-3 and lips(shut) < lips(gap) - 0.015
    for upper, lower in ((37, 41), (38, 40), (43, 47), (44, 46)):  # the upper lid comes down to the lower
        opened, closed = gap[upper, 1] - gap[lower, 1], shut[upper, 1] - shut[lower, 1]
        assert opened > 4e-3 and closed < 0.25 * opened


def test_face_points_are_visible_from_the_front_and_hidden_from_behind(human):
    from synmitsuba.annotate import Annotator
    from synmitsuba.compose.subjects import MotionSpec, PlacedSubject, retargeted_clip
    clip = retargeted_clip(human, MotionSpec("idle", 3, 0.2, 10))
    placed = PlacedSubject(human, clip, 0, 100, "subject0")
    scene = sm.Scene()
    scene.set_environment(sm.Constant(1.0))
    placed.pose_in(scene, 0)
    rot, root = clip.frame(0)
    face = human.face_keypoints(rot, root)
    centre = face[36:48].mean(0)
    forward = np.cross([0, 1, 0], face[0] - face[16])  # up x (towards the subject's right)
    forward /= np.linalg.norm(forward)
    classes = []
    for sign in (1, -1):
        eye = centre + sign * 0.8 * forward
        cam = sm.Camera.look_at(eye=tuple(eye), target=tuple(centre), fov_y_deg=30, width=64, height=64)
        sample = sm.render(scene, cam, spp=1)
        rec = Annotator([placed]).annotate(sample, scene, 0)[0]
        assert np.allclose(rec.face2d, cam.project(face)[0]) and rec.face3d_cam.shape == (68, 3)
        classes.append(rec.face_visibility)
    front, back = classes
    # brows, nose, eyes and outer lips all seen (through the brow hairs and lashes), the jaw line
    # mostly; the inner lips' corners lie inside a closed mouth's corners
    assert (front[17:60] == 1).all() and (front == 1).mean() > 0.9
    assert (back[17:] == 2).all() and (back == 2).mean() > 0.9  # a jaw point by the ear may show past the head
