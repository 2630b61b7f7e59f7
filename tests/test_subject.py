"""Layered humans: recipes, garments, skinning, hair, accessories, textures, the smplx backend."""
import json

import numpy as np
import pytest
import trimesh

import synmitsuba as sm
from synmitsuba.body.binding import signed_distance
from synmitsuba.body.garments import GARMENTS, hem_sources

from reference import bound_points, hang_shelf, uv_to_rest, winding_numbers
from synmitsuba.body.lbs import bone_transforms, skin
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import axis_rotation

from conftest import colour_science


@pytest.fixture(scope="module")
def human():
    recipe = sm.sample_subject(np.random.default_rng(11), {"outfit": ["tshirt", "trousers"], "jacket": True,
                                                           "shoes": True, "hair_style": "bob",
                                                           "accessories": ["glasses", "watch", "backpack"]})
    return sm.build_subject(recipe)


def strong_poses(sk):
    """Arms raised, a deep knee bend, a torso twist, a forward bend."""
    poses = []
    R = np.broadcast_to(np.eye(3), (len(sk), 3, 3)).copy()
    arms = R.copy()
    arms[sk.index("upperarm01.L")] = axis_rotation("z", np.radians(100))
    arms[sk.index("upperarm01.R")] = axis_rotation("z", np.radians(-100))
    arms[sk.index("lowerarm01.L")] = axis_rotation("y", np.radians(-90))
    poses.append(arms)
    knees = R.copy()
    for s in "LR":
        knees[sk.index(f"upperleg01.{s}")] = axis_rotation("x", np.radians(-80))
        knees[sk.index(f"lowerleg01.{s}")] = axis_rotation("x", np.radians(90))
    poses.append(knees)
    twist = R.copy()
    twist[sk.index("spine03")] = axis_rotation("y", np.radians(35))
    twist[sk.index("spine01")] = axis_rotation("x", np.radians(30))
    poses.append(twist)
    return poses


def test_recipe_json_round_trip_and_byte_identical_rebuild(human):
    text = human.recipe.to_json()
    again = sm.SubjectRecipe.from_json(text)
    assert again.to_json() == text
    other = sm.build_subject(again)
    for a, b in zip(human.pose(), other.pose()):
        assert a.name == b.name
        for field in ("vertices", "faces", "uv", "points", "radius"):
            x, y = getattr(a, field), getattr(b, field)
            assert (x is None and y is None) or x.tobytes() == y.tobytes(), (a.name, field)
        if a.material.texture is not None:
            assert a.material.texture.tobytes() == b.material.texture.tobytes()


def test_sampling_is_deterministic_and_varied():
    a = [sm.sample_subject(np.random.default_rng(s)).to_json() for s in range(6)]
    b = [sm.sample_subject(np.random.default_rng(s)).to_json() for s in range(6)]
    assert a == b and len(set(a)) == 6


@pytest.mark.parametrize("patch,field", [
    ({"phenotypes": {"height": 1.5}}, "recipe.phenotypes.height"),
    ({"phenotypes": {"wingspan": 0.5}}, "recipe.phenotypes.wingspan"),
    ({"hair": {"style": "mohawk"}}, "recipe.hair.style"),
    ({"colour": "red"}, "recipe.colour"),
    ({"garments": [{"kind": "tshirt", "ease": 0.5}]}, "recipe.garments[0].ease"),
    ({"garments": [{"kind": "cape"}]}, "recipe.garments[0].kind"),
    ({"garments": [{"kind": "tshirt", "texture": {"pattern": "paisley"}}]}, "recipe.garments[0].texture.pattern"),
    ({"skin": {"ita_deg": 90}}, "recipe.skin.ita_deg"),
])
def test_bad_recipe_fields_are_named(patch, field):
    d = sm.sample_subject(np.random.default_rng(0)).to_dict()
    d.update(patch)
    with pytest.raises(ConfigError) as e:
        sm.SubjectRecipe.from_dict(d)
    assert field in str(e.value)


def test_no_garment_vertex_inside_the_body_at_rest_and_layers_nest(human):
    body = human.body
    dist = {}
    for g in human.garments:
        d = signed_distance(body.vertices, body.faces, g.vertices)
        assert d.min() > 0, g.params.kind
        seat = g.vertices[:, 1] >= human.regions.crotch_y  # under it trouser legs hang as tubes (test_legs.py)
        dist[g.params.kind] = np.median(d[seat])
    assert dist["trousers"] < dist["tshirt"] < dist["jacket"]


def test_garments_follow_strong_poses(human, record_property):
    sk = human.skeleton
    body = human.body
    shares = []
    for R in strong_poses(sk):
        T = bone_transforms(sk, R)
        posed_body = skin(body.vertices, body.weights, T)
        for part, g in zip([p for p in human.parts if p.name in {g.params.kind for g in human.garments}], human.garments):
            posed = skin(part.rest, part.weights, T)
            shares.append((signed_distance(posed_body, body.faces, posed) < -0.003).mean())
    record_property("penetrating_share_max", float(max(shares)))
    assert max(shares) < 0.08  # small and bounded: skinning without simulation


def test_posing_pushes_garments_out_of_the_body_under_motion(human):
    """The strong poses and two motions, skinned alone and then resolved (``body.collide``):
    penetration measured with the closest triangle (not the resolver's tangent planes) drops to
    at most 0.5 % of the garment vertices, a third or less of skinning alone, and no garment
    vertex moves at rest."""
    from synmitsuba.motion.retargeting import retarget
    from synmitsuba.motion.sources import load_motion
    body, sk = human.body, human.skeleton
    frames = [(R, None) for R in strong_poses(sk)]
    for kind in ("run", "squat"):
        m = retarget(load_motion(kind, np.random.default_rng(0), seconds=1.0), sk)
        frames += [m.frame(f) for f in (7, 14, 21)]
    kinds = {g.params.kind for g in human.garments}
    inside = {True: 0, False: 0}
    total = 0
    for rot, root in frames:
        posed_body = skin(body.vertices, body.weights, bone_transforms(sk, rot, root))
        for resolve in (False, True):
            for layer in human.pose(rot, root, resolve=resolve):
                if layer.name in kinds:
                    inside[resolve] += int((signed_distance(posed_body, body.faces, layer.vertices) < 0).sum())
                    total += len(layer.vertices) * resolve
    assert inside[True] <= 0.005 * total and inside[True] <= inside[False] / 3, (inside, total)
    for a, b in zip(human.pose(resolve=False), human.pose()):
        if a.name in kinds:
            np.testing.assert_array_equal(a.vertices, b.vertices)


def _unstyled(recipe):
    """The recipe with every garment drawn in a style (``GARMENT_STYLES``) made as its base kind
    again, with the cut that kind draws: the subjects regression tests were written on."""
    import dataclasses
    from synmitsuba.body.garments import GARMENT_STYLES, sample_skirt_cut
    base = {st.kind: kind for kind, styles in GARMENT_STYLES.items() for st in styles}
    garments = [sample_skirt_cut(dataclasses.replace(g, kind=base[g.kind], cut=None)) if g.kind in base else g
                for g in recipe.garments]
    return dataclasses.replace(recipe, garments=garments)


def _ungraded(recipe):
    """The recipe with every garment cut as before size grading (``grade`` None: its ``size``
    scales its ease); body/sizing.py's tests cover graded fits."""
    import dataclasses
    return dataclasses.replace(recipe, garments=[dataclasses.replace(g, grade=None) for g in recipe.garments])


def test_pushes_do_not_carry_garments_into_the_next_body_part():
    """Frames where the resolver used to leave garment vertices deep inside the body: a dress
    between belly and thigh in a squat (carried by its neighbours' push into the thigh), a
    jacket pushed out of its sleeve into the chest, and one whose side was read from
    interpolated vertex normals. Vertices over 5 mm inside (winding number over 1/2), measured
    on the closest triangle: 20, 20 and 2 before, 0, 2 and 0 now."""
    from synmitsuba.motion.retargeting import retarget
    from synmitsuba.motion.sources import load_motion
    deep = []
    for seed, motion, frame, kind in ((1, "squat", 15, "dress"), (3, "run", 20, "jacket"), (0, "walk", 0, "jacket")):
        h = sm.build_subject(_unstyled(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64, "jacket": True})))
        m = retarget(load_motion(motion, np.random.default_rng(seed), seconds=1.0), h.skeleton)
        layers = h.pose(*m.frame(frame))
        body = np.empty_like(h.body.vertices)
        body[h.split.source] = layers[0].vertices
        v = next(x for x in layers if x.name == kind).vertices
        v = v[signed_distance(body, h.body.faces, v, k=8) < -0.005]
        deep.append(int((winding_numbers(body, h.body.faces, v) > 0.5).sum()) if len(v) else 0)
    assert sum(deep) <= 3, deep


def test_shorts_are_not_left_inside_a_thigh():
    """Squat and run frames where shorts vertices were left 18-29 mm inside a thigh: pushed by
    their margin out of one thigh into the other, or read outside by the exact test around two
    vertices, which missed the closest face (13/run/25: its nearest vertex on the other thigh).
    Vertices inside (winding number over 1/2, behind the closest triangle) and the deepest:
    51 before, 29 mm deep; 8 now, 0.8 mm (where the posed thighs overlap, inside both)."""
    from synmitsuba.motion.retargeting import retarget
    from synmitsuba.motion.sources import load_motion
    inside, deepest = 0, 0.0
    for seed, motion, frames in ((8, "squat", (14, 26)), (4, "squat", (16, 28)), (13, "run", (25,))):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        m = retarget(load_motion(motion, np.random.default_rng(seed), seconds=1.0), h.skeleton)
        for frame in frames:
            layers = h.pose(*m.frame(frame))
            body = np.empty_like(h.body.vertices)
            body[h.split.source] = layers[0].vertices
            v = next(x for x in layers if x.name == "shorts").vertices
            d = signed_distance(body, h.body.faces, v, k=8)
            behind = np.flatnonzero(d < 0)
            found = behind[winding_numbers(body, h.body.faces, v[behind]) > 0.5]
            inside += len(found)
            deepest = max(deepest, float(-d[found].min()) if len(found) else 0.0)
    assert inside <= 12 and deepest < 0.0015, (inside, deepest)


def _openings(vertices, faces) -> np.ndarray:
    """The edges (E, 2) of openings, in vertices welded within a micrometre (so UV seams are
    not openings), and the welded index of every vertex."""
    from synmitsuba.body.topology import weld
    inv = weld(vertices)
    f = inv[faces]
    edges, counts = np.unique(np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), 1), axis=0, return_counts=True)
    return edges[(counts == 1) & (edges[:, 0] != edges[:, 1])], inv


def _boundary_loops(vertices, faces) -> list:
    """Per boundary loop of 8 vertices or more (vertices merged by position, so UV seams are not
    edges): its points and their surface normals, in order."""
    from synmitsuba.geometry import vertex_normals
    _, first, inv = np.unique(np.round(vertices, 6), axis=0, return_index=True, return_inverse=True)
    v, f = vertices[first], inv.ravel()[faces]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])]
    edges, counts = np.unique(np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), 1), axis=0, return_counts=True)
    nbrs: dict = {}
    for a, b in edges[counts == 1]:
        nbrs.setdefault(a, []).append(b)
        nbrs.setdefault(b, []).append(a)
    n, seen, out = vertex_normals(v, f), set(), []
    for start in nbrs:
        if start in seen or len(nbrs[start]) != 2:
            continue
        loop, prev, cur = [start], None, start
        while True:
            step = [x for x in nbrs[cur] if x != prev]
            if len(nbrs[cur]) != 2 or not step or step[0] == start:
                break
            prev, cur = cur, step[0]
            loop.append(cur)
        seen.update(loop)
        if len(loop) >= 8:
            out.append((v[loop], n[loop]))
    return out


def _boundary_turning(vertices, faces) -> list[float]:
    """Per boundary loop: the sum of |turning angles| between successive boundary edges within
    the surface's tangent plane, per metre of loop. A saw-tooth turns at every vertex; a smooth
    hem hardly at all."""
    out = []
    for p, nn in _boundary_loops(vertices, faces):
        flat = lambda d: d - (d * nn).sum(1, keepdims=True) * nn  # noqa: E731
        a, b = flat(p - np.roll(p, 1, 0)), flat(np.roll(p, -1, 0) - p)
        turn = np.abs(np.arctan2((np.cross(a, b) * nn).sum(1), (a * b).sum(1))).sum()
        out.append(turn / np.linalg.norm(np.roll(p, -1, 0) - p, axis=1).sum())
    return out


def _resampled(p: np.ndarray, nn: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """A closed loop's points (and normals) every ``step`` metres of its length."""
    closed = np.vstack([p, p[:1]])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    at = np.arange(0.0, s[-1], step)
    q = np.column_stack([np.interp(at, s, closed[:, k]) for k in range(3)])
    n = np.vstack([nn, nn[:1]])[np.clip(np.searchsorted(s, at), 0, len(p))]
    return q, n


def test_necklines_run_round_the_neck_without_a_step():
    """A t-shirt's neck opening (its highest loop, resampled every 3 mm: the cut leaves jogs of
    a few tenths of a millimetre that no render shows) turns by at most 120 degrees within any
    3 cm of it away from the front's dip, a U 2-3 cm wide by design (a level cut at the neck's
    height made a notch where the torso met the shoulders: 150-185 degrees on these subjects), stays off the neck (at least most of the ease out from
    the neck's axis, measured here from anny's neck ring) and is lowest at the front. Ungraded
    cuts: a top cut tight comes closer to the neck."""
    from synmitsuba.body.garments import NECK_EASE
    for seed in (3, 4):
        h = sm.build_subject(_ungraded(sm.sample_subject(np.random.default_rng(seed), {"outfit": ["tshirt", "trousers"],
                                                                                       "texture_size": 64})))
        g = next(g for g in h.garments if g.params.kind == "tshirt")
        p, nn = max(_boundary_loops(g.vertices, g.faces[:len(g.faces) - g.hem[0]]), key=lambda lp: lp[0][:, 1].mean())
        p, nn = _resampled(p, nn, 0.003)
        flat = lambda d: d - (d * nn).sum(1, keepdims=True) * nn  # noqa: E731
        a, b = flat(p - np.roll(p, 1, 0)), flat(np.roll(p, -1, 0) - p)
        turn = np.abs(np.arctan2((np.cross(a, b) * nn).sum(1), (a * b).sum(1)))
        neck = h.body.vertices[h.regions.group == "head"]
        axis = neck[np.abs(neck[:, 1] - h.regions.neck_y - 0.01) < 0.006][:, [0, 2]].mean(0)
        turn[(np.abs(p[:, 0] - axis[0]) < 0.03) & (p[:, 2] > axis[1])] = 0.0  # the front's dip is a U by design
        s = np.cumsum(np.linalg.norm(np.roll(p, -1, 0) - p, axis=1))
        twice, s2 = np.concatenate([turn, turn]), np.concatenate([s, s + s[-1]])
        worst = max(twice[i:np.searchsorted(s2, s2[i] + 0.03)].sum() for i in range(len(turn)))
        assert np.degrees(worst) < 120, (seed, np.degrees(worst))
        # the neck just above its base: 3 cm up, a short neck's ring takes in the jaw and chin
        ring = neck[np.abs(neck[:, 1] - h.regions.neck_y - 0.01) < 0.006][:, [0, 2]]
        centre = ring.mean(0)
        rho = np.linalg.norm(p[:, [0, 2]] - centre, axis=1)
        assert rho.min() > np.median(np.linalg.norm(ring - centre, axis=1)) + 0.5 * NECK_EASE
        assert p[np.argmin(p[:, 1]), 2] > centre[1]  # lowest in front of the neck's axis


def _edge_wobble(p: np.ndarray, nn: np.ndarray) -> np.ndarray:
    """Per point of a closed loop: how far it lies off the middle of its two neighbours across
    the loop, within the surface (metres): a smooth curve's points lie a fraction of a millimetre
    off; a saw-tooth's or a notch's, millimetres."""
    t = np.roll(p, -1, 0) - np.roll(p, 1, 0)
    across = np.cross(t, nn)
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    return np.abs(((p - 0.5 * (np.roll(p, 1, 0) + np.roll(p, -1, 0))) * across).sum(1))


def _turned_over_the_small_of_the_back(h, g) -> int:
    """Faces of garment ``g`` (its band left out) that face the body, over the back of the torso
    between the crotch's height (and 4 cm) and the waist's: their normal against the normal of
    the body vertex nearest their centre (trimesh's normals, a k-d tree)."""
    from scipy.spatial import cKDTree
    shell = trimesh.Trimesh(g.vertices, g.faces[:len(g.faces) - g.hem[0]], process=False)
    body = trimesh.Trimesh(h.body.vertices, h.body.faces, process=False)
    near = cKDTree(body.vertices).query(shell.triangles_center)[1]
    facing = (shell.face_normals * body.vertex_normals[near]).sum(1) < 0
    y = body.vertices[near, 1]
    back = (h.regions.group[near] == "torso") & (body.vertex_normals[near, 2] < 0)
    return int((facing & back & (y > h.regions.crotch_y + 0.04) & (y < h.regions.waist_y)).sum())


def test_a_loose_top_does_not_fold_over_itself_at_the_small_of_the_back():
    """A top stood off along the skin's own normals folds over itself where the spine's groove
    is narrower than its offset: seed 100's sweater (39 mm) showed a dark triangle there from
    behind. Tops now stand off along the normals averaged over neighbours there
    (``offset_directions``) and are bridged over hollows. Faces turned to the body there, on
    seed 100's sweater, seed 101's hoodie (30 mm) and seed 206's sweater (41 mm): 22, 12 and 27
    along the skin's normals, 3, 0 and 4 now."""
    for seed, kind in ((100, "sweater"), (101, "hoodie"), (206, "sweater")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        g = next(g for g in h.garments if g.params.kind == kind)
        assert g.offset > 0.025, (seed, kind, g.offset)
        assert _turned_over_the_small_of_the_back(h, g) <= 5, (seed, kind, _turned_over_the_small_of_the_back(h, g))


def _turned_under_the_chest(h, g) -> int:
    """Faces of garment ``g`` (its band left out) that face the body over the front of the
    torso, between the waist's height and 8 cm under the shoulder joints, within 0.7 of the
    shoulder joints' reach either side of the neck's axis (the armpits left out): their normal
    against the normal of the body vertex nearest their centre (trimesh's normals, a k-d tree)."""
    from scipy.spatial import cKDTree
    shell = trimesh.Trimesh(g.vertices, g.faces[:len(g.faces) - g.hem[0]], process=False)
    body = trimesh.Trimesh(h.body.vertices, h.body.faces, process=False)
    near = cKDTree(body.vertices).query(shell.triangles_center)[1]
    facing = (shell.face_normals * body.vertex_normals[near]).sum(1) < 0
    p, r = body.vertices[near], h.regions
    front = (r.group[near] == "torso") & (body.vertex_normals[near, 2] > 0)
    middle = np.abs(p[:, 0] - r.neck_xz[0]) < 0.7 * r.shoulder[0]
    return int((facing & front & middle & (p[:, 1] > r.waist_y) & (p[:, 1] < r.shoulder[1] - 0.08)).sum())


def test_a_loose_top_does_not_fold_over_itself_under_the_chest():
    """Offset along the skin's own normals, a top turned over itself where the body curves
    tighter than its offset: under the chest it rendered as a hard dark crease (seed 206's
    sweater, 41 mm off) and a black notch (seed 204's jacket, 67 mm). Tops now stand off along
    the averaged normals wherever a shell 5 cm off would turn over (``fold_prone``). Faces turned
    to the body under the chest: 14, 16, 28 and 60 along the skin's normals; now 0, 0, 0, 10."""
    for seed, kind, most in ((201, "tshirt", 3), (206, "sweater", 3), (224, "tshirt", 3), (204, "jacket", 20)):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        g = next(g for g in h.garments if g.params.kind == kind)
        assert _turned_under_the_chest(h, g) <= most, (seed, kind, _turned_under_the_chest(h, g))


def test_a_loose_top_hangs_straight_down_from_the_bust():
    """A loose top falls from the bust as cloth does, not round its underside: hung down the
    shell's edges, whose edges under the bust run sideways off it, a jacket kept a shelf there
    that rendered as a dark crescent under each breast (seed 219's jacket, 70 mm off). Seen
    from the front, down columns across the chest, how far each top lies behind a line falling
    in 1 cm for every 2 cm down from any point over it (``reference.hang_shelf``): 13.0, 18.6,
    11.8, 5.4, 12.7 and 13.7 mm hung down edges (``drape``, since removed); now under a millimetre
    (``hang_columns``, skinned tops). A sagging bust's underside and the crease under it, laid
    on that fall, fold flat there: faces crossing others within 0.3 m under the shoulder joints
    (``_crossing_beside_the_armpits``) 0, 0, 0, 0, 0 and 18 hung down edges; now 16, 12, 0, 0,
    0 and 30, none of them within 0.15 m."""
    for seed, kind in ((219, "jacket"), (204, "jacket"), (228, "longsleeve"), (206, "sweater"),
                       (210, "sweater"), (215, "blazer")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        g = next(g for g in h.garments if g.params.kind == kind)
        r = h.regions
        xs = r.neck_xz[0] + np.arange(-0.6, 0.61, 0.1) * r.shoulder[0]
        shelf = hang_shelf(g.vertices, g.faces[:len(g.faces) - g.hem[0]], xs, r.shoulder[1] - 0.08, r.waist_y, slope=0.5)
        assert g.offset > 0.03 and shelf < 0.003, (seed, kind, g.offset, shelf)
        assert _crossing_beside_the_armpits(h, g, below=0.3) <= 32, (seed, kind)


def test_a_simulated_tops_rest_shape_hangs_straight_down_from_the_bust():
    """The cloth stage's rest shapes hang as skinned tops do (``hang_columns``): a simulated
    top starts from them and kept their shelf under the bust as a crescent. The shelf (as in
    the test above) of a t-shirt, a sweater, a wrap dress's bodice and a blazer built
    ``cloth: simulated``: 14.5, 12.7, 10.8 and 8.3 mm hung down edges; now under a millimetre."""
    for seed, kind in ((224, "tshirt"), (210, "sweater"), (218, "wrap"), (215, "blazer")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64, "cloth": "simulated"}))
        g = next(g for g in h.garments if g.params.kind == kind)
        r = h.regions
        xs = r.neck_xz[0] + np.arange(-0.6, 0.61, 0.1) * r.shoulder[0]
        shelf = hang_shelf(g.vertices, g.faces[:len(g.faces) - g.hem[0]], xs, r.shoulder[1] - 0.08, r.waist_y, slope=0.5)
        assert g.offset > 0.03 and shelf < 0.003, (seed, kind, g.offset, shelf)


def _crossing_beside_the_armpits(h, g, below: float = 0.15) -> int:
    """Faces of garment ``g``'s shell (its band left out, merged by position: trimesh) within
    0.1 m of the shoulder joints' reach either side of the neck's axis and up to ``below``
    metres under them, that pass through another face of the shell there not touching them
    (``reference.self_crossing``)."""
    from reference import self_crossing
    mesh = trimesh.Trimesh(g.vertices, g.faces[:len(g.faces) - g.hem[0]], process=True)
    c, r = mesh.triangles_center, h.regions
    beside = np.abs(np.abs(c[:, 0] - r.neck_xz[0]) - r.shoulder[0]) < 0.1
    return int(self_crossing(mesh.vertices, mesh.faces, beside & (c[:, 1] > r.shoulder[1] - below)
                             & (c[:, 1] < r.shoulder[1])).sum())


def test_a_simulated_tops_rest_shape_takes_its_share_of_the_room_beside_the_armpits():
    """The cloth stage's rest shapes scale their offsets beside the armpits as a skinned top's
    do on the sleeves, by half that over the torso (``ROOM_SIMULATED``; in full, the t-shirt of
    tests/test_cloth_tops.py folded under its yoke in a walk), rising towards the arm's over the
    rings next to it (``_room_share``). Faces crossing the shell beside the armpits, up to 0.3 m
    under the shoulder joints, of two long sleeves, a shirt, a sweater and a third long sleeve
    built ``cloth: simulated``: the first four 60, 68, 104 and 78 unscaled; at half the scaling
    everywhere 0, 0, 0, 0 and 70; with the share stepping from the arm's to the torso's, 10 at the
    shirt's armpit apex and 6 at the sweater's; now 0 each."""
    for seed, kind in ((205, "longsleeve"), (211, "longsleeve"), (215, "shirt"), (226, "sweater"), (228, "longsleeve")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64, "cloth": "simulated"}))
        g = next(g for g in h.garments if g.params.kind == kind)
        assert _crossing_beside_the_armpits(h, g, below=0.3) <= 5, (seed, kind, _crossing_beside_the_armpits(h, g, 0.3))


def test_a_simulated_jackets_side_stops_short_of_its_sleeve_at_the_armpit():
    """A jacket or coat stands 6-7 cm off: at half its scaling (``ROOM_SIMULATED``) the cloth
    stage's rest shape stood its flank out past the middle of the gap to the arm and through its
    own sleeve's underside. The flank now stands off at most ``ROOM_CAP`` times the room there.
    Faces crossing the shell beside the armpits, up to 15 cm under the shoulder joints, of two
    jackets and a coat built ``cloth: simulated``: 92, 98 and 96 before; now 0, 0 and 4."""
    for seed, kind in ((219, "jacket"), (204, "jacket"), (211, "coat")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64, "cloth": "simulated"}))
        g = next(g for g in h.garments if g.params.kind == kind)
        assert g.offset > 0.06 and _crossing_beside_the_armpits(h, g) <= 5, (seed, kind, _crossing_beside_the_armpits(h, g))


def test_a_loose_tops_sleeve_and_side_meet_at_the_armpit_without_crossing():
    """Beside the armpit the arm's underside and the torso's flank face each other a few
    centimetres apart, and a top's shell stood off both by its whole offset: the sleeve's
    underside and the side went through each other (with an arm raised, a flat web over the
    armpit, hatched where the two surfaces fought, with a black notch). Tops now take only
    their share of the room there (``free_room``). Faces crossing the shell beside the armpits,
    up to 15 cm under the shoulder joints: landed 128, 108, 98 and 56; now 0. (Further down, a
    large bust's underside lies folded flat on the cloth's fall from it: see the next test.)"""
    for seed, kind in ((204, "jacket"), (219, "jacket"), (215, "blazer"), (205, "longsleeve")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        g = next(g for g in h.garments if g.params.kind == kind)
        assert _crossing_beside_the_armpits(h, g) <= 5, (seed, kind, _crossing_beside_the_armpits(h, g))


def test_a_long_top_hangs_straight_across_both_legs_under_the_crotch():
    """A top cut from the body past the crotch was a shell of each thigh: two tubes whose inner
    sides, offset towards each other, went through one another between the legs, and under the
    hem it read as a pair of shorts, notched at the front and back. It now hangs across both legs
    there (``hang_across``). Seen straight on at the middle between the legs (and a centimetre
    either side), under the crotch, the top lay up to 45, 59 and 45 mm behind its own front or
    back; now 3, 12 and 10 (``reference.middle_notch``)."""
    from reference import middle_notch
    for seed, kind in ((204, "jacket"), (222, "blazer"), (213, "longsleeve")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        g = next(g for g in h.garments if g.params.kind == kind)
        crotch = h.regions.crotch_y
        assert g.vertices[:, 1].min() < crotch - 0.04, (seed, kind)  # long: the case this is about
        legs = h.body.vertices[h.body.vertices[:, 1] < crotch - 0.05]
        layers = [(h.body.vertices, h.body.faces)] + [(m.vertices, m.faces) for m in h.garments]
        notch = middle_notch(layers, 1 + h.garments.index(g), float(legs[:, 0].mean()), crotch)
        assert notch < 0.015, (seed, kind, notch)


def test_a_simulated_long_top_is_one_tube_round_both_legs_under_the_crotch():
    """The cloth stage's rest shape of a top long enough to pass the crotch was two tubes, one
    round each thigh, whose inner sides went through each other between the legs (in a walk,
    a pair of shorts under the hem). It now hangs across both legs too (``hang_across``), and
    the two halves are sewn into one tube at the front and back (``close_middle``): hung across
    but not sewn, each thigh's inner side lay on the middle, a wall from front to back, and the
    cloth stage simulated culottes (seed 213's long sleeve tore by a walk's third frame). Under
    the crotch, its openings (merged by position) are one, round both legs, and faces crossing
    another of the shell there (``reference.self_crossing``) were 146, 135, 144 and 156 as two
    tubes, 68, 65, 57 and 84 hung across with the wall; now 6, 19, 6 and 23."""
    from reference import self_crossing
    for seed, kind in ((213, "longsleeve"), (205, "longsleeve"), (217, "shirt"), (222, "blazer")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64, "cloth": "simulated"}))
        g = next(g for g in h.garments if g.params.kind == kind)
        mesh = trimesh.Trimesh(g.vertices, g.faces[:len(g.faces) - g.hem[0]], process=True)
        open_ = mesh.edges_sorted[trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)]
        crotch, middle = h.regions.crotch_y, float(h.body.vertices[h.body.vertices[:, 1] < h.regions.crotch_y - 0.05, 0].mean())
        low = [np.unique(open_[np.isin(open_, c).all(1)]) for c in trimesh.graph.connected_components(open_)]
        low = [p for p in low if (mesh.vertices[p, 1] < crotch - 0.02).any()]
        assert len(low) == 1, (seed, kind, len(low))
        x = mesh.vertices[low[0], 0] - middle
        assert x.min() < -0.1 and x.max() > 0.1, (seed, kind)  # round both legs
        under = mesh.triangles_center[:, 1] < crotch + 0.04
        crossing = int(self_crossing(mesh.vertices, mesh.faces, under).sum())
        assert crossing <= 35, (seed, kind, crossing)


def test_a_loose_tops_neckline_is_smooth_and_turned_in_evenly():
    """Loose tops stand 3-5 cm off the body, and a neckline cut over the body's 1-1.5 cm
    triangles and offset that far zigzagged by 2-3 mm, with a notch at the centre front; its
    band, turned in towards the closest body point, jumped between neighbours over the neck's
    hollows and hung in teeth (seen at 0.35 m). Each neckline point now lies within 1.75 mm of
    the middle of its neighbours across the edge (landed: 3.1, 2.0 and 2.3 mm on these), and two
    neighbours' turn-in directions, on any opening, differ by under 30 degrees (landed: 105,
    178 and 78); but within a centimetre of the middle between the legs, under the crotch,
    where a top hanging across both legs meets itself out of sight (``hang_across``) and its
    band turns in along the middle, to the front on one side of the legs' centre and to the
    back on the other."""
    for seed, kind in ((5, "sweater"), (100, "sweater"), (101, "hoodie")):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}))
        g = next(g for g in h.garments if g.params.kind == kind)
        assert g.offset > 0.025, (seed, kind, g.offset)  # loose: the case this is about
        shell = g.faces[:len(g.faces) - g.hem[0]]
        p, nn = max(_boundary_loops(g.vertices, shell), key=lambda lp: lp[0][:, 1].mean())
        assert _edge_wobble(p, nn).max() < 0.00175, (seed, kind, _edge_wobble(p, nn).max())
        (edges, inv), start = _openings(g.vertices, shell), len(g.vertices) - g.hem[1]
        rim = np.full(inv.max() + 1, -1)
        rim[inv[hem_sources(g)]] = np.arange(start, len(g.vertices))  # each edge point's turned-in copy
        d = g.vertices[rim[edges]] - g.vertices[edges]  # (welded indices are vertices' own)
        d /= np.linalg.norm(d, axis=2, keepdims=True)
        y = h.body.vertices[:, 1] - h.regions.crotch_y
        legs = h.body.vertices[(y < -0.05) & (y > -0.25)][:, [0, 2]].mean(0)  # between the thighs
        p = g.vertices[edges]
        between = ((np.abs(p[:, :, 0] - legs[0]) < 0.01) & (p[:, :, 1] < h.regions.crotch_y)).all(1)
        worst = np.degrees(np.arccos(np.clip((d[:, 0] * d[:, 1]).sum(1), -1, 1)))[~between].max()
        assert worst < 30, (seed, kind, worst)


def test_a_tank_top_is_one_piece():
    """A tank's arms are cut by its armholes, and under each armpit the arm's field came back
    over zero: on 5 of 16 subjects (seeds 0, 6, 7, 13, 15) a patch of 13-29 points rode on each
    arm, apart from the top (simulated, it fell away as a ribbon). Pieces counted by trimesh,
    the mesh merged by position."""
    for seed in (0, 6, 7):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {"outfit": ["tank", "shorts"],
                                                                              "texture_size": 64}))
        g = next(g for g in h.garments if g.params.kind == "tank")
        mesh = trimesh.Trimesh(g.vertices, g.faces, process=False)
        mesh.merge_vertices(digits_vertex=6)
        assert len(mesh.split(only_watertight=False)) == 1, seed


def test_garment_edges_follow_smooth_curves():
    """Hems, cuffs and necklines are cut along their region's level set: their loops turn less
    than half as much per metre as the same regions cut along the body's triangle edges; each
    opening is turned in by the cloth's thickness (its edge lies that much nearer the body).
    Unstyled: an open front's V (a blazer's) has corners by design."""
    from synmitsuba.body.garments import GARMENTS
    cut, edge = [], []
    for seed in range(4):
        h = sm.build_subject(_unstyled(sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64})))
        for g in h.garments:
            kind = GARMENTS[g.params.kind]
            if kind.shape != "shell":
                continue
            band_faces, band_vertices = g.hem
            shell = g.faces[:len(g.faces) - band_faces]
            cut += _boundary_turning(g.vertices, shell)
            assert band_faces == 2 * len(_openings(g.vertices, shell)[0])  # the band: two triangles per opening edge
            d = signed_distance(h.body.vertices, h.body.faces, g.vertices)
            rim = np.arange(len(g.vertices)) >= len(g.vertices) - band_vertices  # the band's turned-in edge
            assert np.median(d[~rim]) - np.median(d[rim]) == pytest.approx(g.params.thickness, abs=0.0015)
            phi = kind.region(g.params, h.regions, h.body.vertices)[h.split.source]
            faces = h.split.faces[(phi[h.split.faces] >= 0).all(1)]
            src = h.split.source
            edge += _boundary_turning(h.body.vertices[src] + h.regions.normals[src] * g.offset, faces)
    assert len(cut) >= 10 and len(edge) >= 10
    assert np.median(cut) < 0.5 * np.median(edge) and np.median(cut) < 12, (np.median(cut), np.median(edge))


def test_skinning_keeps_garment_vertices_near_their_bound_points(human):
    from synmitsuba.body.binding import bind
    body, sk = human.body, human.skeleton
    g = next(g for g in human.garments if g.params.kind == "tshirt")
    b = bind(body.vertices, body.faces, body.weights, g.vertices)
    rest_gap = np.linalg.norm(g.vertices - bound_points(b, body.vertices, body.faces), axis=1)
    for R in strong_poses(sk):
        T = bone_transforms(sk, R)
        posed_body = skin(body.vertices, body.weights, T)
        gap = np.linalg.norm(skin(g.vertices, b.weights, T) - bound_points(b, posed_body, body.faces), axis=1)
        assert np.percentile(gap - rest_gap, 99) < 0.02 and gap.max() < 0.08


def test_hair_roots_lie_on_the_scalp_in_their_regions(human):
    from synmitsuba.body.hair import HairParams, grow_hair
    scalp = human.scalp
    roots = human.hair.points[:, 0]
    tri = scalp.faces
    d = np.abs(signed_distance(scalp.vertices, tri, roots))
    assert np.percentile(d, 99) < 0.003
    from scipy.spatial import cKDTree
    _, near = cKDTree(scalp.vertices).query(roots)
    # a face on a region boundary belongs to two of its corners' region (no bald seam between
    # regions), so a root there may be nearest a corner of the neighbouring region: 0.90 measured
    assert (scalp.region[near] == human.hair.region).mean() > 0.85
    from synmitsuba.body.hair import BEARDS, STYLES
    counts = {}
    for style in STYLES:
        for beard in BEARDS:
            s = grow_hair(HairParams(style=style, beard=beard, seed=1), scalp)
            counts[(style, beard)] = len(s)
            assert np.isfinite(s.points).all()
    assert counts[("bald", "none")] == 0
    assert all(counts[(st, "none")] > 500 for st in STYLES if st != "bald")
    assert counts[("bald", "full")] > 0


def test_no_hair_hangs_over_the_eyes(human):
    """For every style, no strand point lies in front of either eye (anny's COCO eye keypoints)
    within 3 cm across the face: long hair falls beside the face, bangs stop above the eyes."""
    from synmitsuba.body.hair import STYLES, HairParams, grow_hair
    from synmitsuba.geometry import frame
    scalp = human.scalp
    B = frame(scalp.forward, scalp.up).T  # rows: right, up, forward
    eyes = (human.keypoints()[[1, 2]] - scalp.origin) @ B.T
    for style in STYLES:
        s = grow_hair(HairParams(style=style, length=1.3, density=0.4, seed=2), scalp)
        local = (s.points[s.region < 5].reshape(-1, 3) - scalp.origin) @ B.T
        for e in eyes:
            ahead = local[:, 2] > e[2] - 0.01
            across = np.hypot(local[:, 0] - e[0], local[:, 1] - e[1]) < 0.03
            assert not (ahead & across).any(), (style, int((ahead & across).sum()))


def test_hair_stays_outside_the_body(human):
    """Strand points (roots aside) lie outside anny's body (exact signed distance to its
    triangles): long hair rests on the shoulders instead of entering them (before: 2-12 % of
    the points inside, up to 108 mm deep)."""
    from synmitsuba.body.collide import Surface
    from synmitsuba.body.hair import HairParams, grow_hair
    body = human.body
    surface = Surface.of(body.vertices, body.faces, human._incidence)
    for style in ("short", "bob", "long", "afro"):
        s = grow_hair(HairParams(style=style, beard="full", seed=1), human.scalp, surface, human.head.ears)
        d = signed_distance(body.vertices, body.faces, s.points[:, 1:].reshape(-1, 3))
        assert (d < 0).mean() < 0.002, (style, (d < 0).mean())


def test_hair_falls_in_smooth_locks_from_a_part(human):
    """Guides and their interpolated children: straight styles bend smoothly (no kinks between
    control points), neighbouring strands stay together down to the tips (locks, not a random
    spray), strands taper, and with a centre part each top strand falls to its root's side."""
    from scipy.spatial import cKDTree
    from synmitsuba.body.hair import HairParams, grow_hair
    from synmitsuba.geometry import frame
    scalp = human.scalp
    B = frame(scalp.forward, scalp.up).T
    for style in ("long", "bob"):
        s = grow_hair(HairParams(style=style, curliness=0.0, seed=3), scalp)
        P = s.points[s.region < 5]
        u = np.diff(P, axis=1)
        u /= np.linalg.norm(u, axis=2, keepdims=True)
        turn = np.degrees(np.arccos(np.clip((u[:, 1:] * u[:, :-1]).sum(2), -1, 1)))
        # the first point, 0.5-1 cm from the root, is where a strand that left the scalp steeply
        # lies down over it (p95 50-73 deg); past it, measured 16 and 16 (24 and 24 with evenly
        # spaced points, whose 5 cm first chord ran inside the scalp and bared a strip at the part)
        assert np.percentile(turn[:, 0], 95) < 90, (style, np.percentile(turn[:, 0], 95))
        assert np.percentile(turn[:, 1:], 95) < 22, (style, np.percentile(turn[:, 1:], 95))
        _, j = cKDTree(P[:, 0]).query(P[:, 0], k=2)
        together = np.median(np.linalg.norm(P[:, -1] - P[j[:, 1], -1], axis=1))
        apart = np.median(np.linalg.norm(P[:, -1] - P[::-1, -1], axis=1))
        assert together < 0.15 * apart, (style, together, apart)  # measured 0.016 / 0.15, 0.007 / 0.12
        r = s.radius
        assert (np.diff(r, axis=1) < 0).all() and np.allclose(r[:, -1] / r[:, 0], 0.33)
    s = grow_hair(HairParams(style="long", curliness=0.0, seed=3), scalp)  # a centre part
    local = (s.points[s.region == 1] - scalp.origin) @ B.T
    root_x, tip_x = local[:, 0, 0], local[:, -1, 0]
    off_part = np.abs(root_x) > 0.01
    assert (np.sign(tip_x[off_part]) == np.sign(root_x[off_part])).mean() > 0.97


def _scalp_points(scalp, region: int) -> tuple[np.ndarray, np.ndarray]:
    """20 random points on each face of a scalp ``region`` and their (N, 3) head-frame coordinates."""
    from synmitsuba.geometry import frame
    tri = scalp.vertices[scalp.faces[(scalp.region[scalp.faces] == region).all(1)]]
    w = np.random.default_rng(0).dirichlet((1, 1, 1), (len(tri), 20))
    pts = np.einsum("fnk,fka->fna", w, tri).reshape(-1, 3)
    return pts, (pts - scalp.origin) @ frame(scalp.forward, scalp.up)


def _bare(scalp, style: str, pts: np.ndarray) -> float:
    """Share of ``pts`` on the scalp without a strand of ``style`` (outside the head) within 4 mm."""
    from scipy.spatial import cKDTree
    from synmitsuba.body.hair import HairParams, grow_hair
    s = grow_hair(HairParams(style=style, curliness=0.0, density=0.5, seed=3), scalp)
    P = s.points[s.region < 5]
    f = np.linspace(0, 1, 8, endpoint=False)[None, None, :, None]
    dense = (P[:, :-1, None] * (1 - f) + P[:, 1:, None] * f).reshape(-1, 3)
    near = dense[np.isfinite(cKDTree(pts).query(dense, distance_upper_bound=0.005)[0])]  # only these can count
    outside = near[signed_distance(scalp.vertices, scalp.faces, near) > 0]
    if not len(outside):
        return 1.0
    return float((cKDTree(outside).query(pts)[0] > 0.004).mean())


def test_a_part_is_a_thin_line(human):
    """Strands leave a part and lie over the scalp beside it: points of the top of the scalp 1-3
    cm from a centre part have a strand (outside the head) within 4 mm (all but 17 % for long hair,
    1 % for a bob; the rest lie under strands higher than that). Control points evenly
    spaced along a long strand put its first chord inside the head and bared a 3-4 cm strip
    (97 % of those points bare for long hair)."""
    pts, local = _scalp_points(human.scalp, 1)
    x, z = local[:, [0, 2]].T
    band = (np.abs(x) > 0.01) & (np.abs(x) < 0.03) & (z > -0.03)  # beside the part, ahead of the crown
    for style in ("long", "bob"):
        assert _bare(human.scalp, style, pts[band]) < 0.25, style


def test_a_part_stays_thin_down_to_the_hairline(human):
    """At the front of the scalp too (its front region, over the forehead), points 0.5-2 cm either
    side of a centre part (or of the middle of hair combed back) have a strand (outside the head)
    within 4 mm: the face's window, out of which hair is moved aside, starts at the hairline
    instead of 3 cm above it. Measured: no point bare (long, bob, crew); moving hair aside from
    the scalp above the hairline bared a wedge (5 %, 5 % and 4 % of those points bare on this
    head, 53 % and 10 % with long hair on two sampled ones)."""
    pts, local = _scalp_points(human.scalp, 0)
    band = (np.abs(local[:, 0]) > 0.005) & (np.abs(local[:, 0]) < 0.02)
    assert band.sum() > 50
    for style in ("long", "bob", "crew"):
        assert _bare(human.scalp, style, pts[band]) < 0.01, style


def test_curls_leave_the_forehead_without_straight_streaks(human):
    """Curls and afros over the top of the head wind in coils right from the root: no segment
    of a strand over the head's upper half runs 3 cm straight (their coil points lie 5-8 mm
    apart, median). Measured: 19 mm longest (curly and afro); before, curls rooted inside the
    face's window, which reached 3 cm above the hairline, were moved sideways out of it in one
    straight segment, streaks across the top of the head (136 and 101 mm, 68 and 64 strands)."""
    from synmitsuba.body.hair import HairParams, grow_hair
    from synmitsuba.geometry import frame
    scalp = human.scalp
    B = frame(scalp.forward, scalp.up).T
    for style in ("curly", "afro"):
        s = grow_hair(HairParams(style=style, length=1.3, curliness=0.8, density=0.4, seed=5), scalp)
        P = s.points[s.region < 5]
        up = ((P[:, :-1] - scalp.origin) @ B.T)[..., 1] > 0
        seg = np.linalg.norm(np.diff(P, axis=1), axis=2)[up]
        assert seg.max() < 0.03, (style, seg.max(), int((seg >= 0.03).sum()))


def test_hair_goes_under_a_collar_standing_off_the_nape_and_over_a_jacket():
    """A flat body (y = 0, normals up) under garments standing 6 cm over it for x > 0 (a collar
    well off the nape) or 2 cm (a jacket's back): strands lying 5 mm over the body and running
    into them from x < 0 stay 3 mm over the body under the collar, with no segment longer than
    it was (lifted over it, the first point past its edge jumped 6 cm: the tails of a crew cut
    over a loose collar), and are lifted over the jacket; posed strands walked again
    (``off_garments``) keep the same rule."""
    from synmitsuba.body.collide import Surface, incidence
    from synmitsuba.body.hair import BODY_MARGIN, HAIR_CLEARANCE, _off_body, off_garments
    x, z = np.meshgrid(np.linspace(-0.1, 0.1, 41), np.linspace(-0.1, 0.1, 41))
    verts = np.stack([x.ravel(), np.zeros(x.size), z.ravel()], 1)
    grid = np.arange(x.size).reshape(x.shape)
    quads = np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], -1).reshape(-1, 4)
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    bare = Surface.of(verts, faces, incidence(faces, len(verts)))
    assert bare.normals[:, 1].min() > 0.99
    xs = np.linspace(-0.03, 0.05, 17)
    strands = np.stack(np.broadcast_arrays(xs[None, :], 0.005, np.linspace(-0.05, 0.05, 11)[:, None]), -1)
    for lift, under in ((0.06, True), (0.02, False)):
        out = _off_body(strands, bare.lifted(np.where(verts[:, 0] > 0, lift, 0.0)))
        beyond = out[:, xs > 0.01, 1]
        if under:
            assert np.allclose(beyond, 0.005), beyond.max()
            assert np.linalg.norm(np.diff(out, axis=1), axis=2).max() <= 0.0051
        else:
            assert (beyond >= lift + BODY_MARGIN - 1e-9).all(), beyond.min()
        shell = bare.lifted(np.where(verts[:, 0] > 0, lift, 0.0))
        walked = off_garments(strands[:, xs > 0.01].reshape(-1, 3), shell, bare)[:, 1]
        assert np.allclose(walked, 0.005 if under else lift + HAIR_CLEARANCE), (lift, walked.min(), walked.max())


def test_hair_passes_over_an_ear_without_jumps():
    """Straight strands (points 5 mm apart) falling past an ear, from 1 cm inside it to 3 cm
    out, are moved out of the ear's clearance sphere smoothly: every point at least
    ``EAR_CLEARANCE`` from the ear, no segment longer than 15 mm (measured 13.7). Moved
    radially from the ear, points either side of it went to opposite sides of the sphere
    (35 mm segments), and a point on the ear stayed there."""
    from synmitsuba.body.hair import EAR_CLEARANCE, _over_ears
    ear = np.array([0.08, 0.0, 0.0])
    dx, dz = np.meshgrid(np.linspace(-0.01, 0.03, 9), np.linspace(-0.03, 0.03, 13))
    y = np.linspace(0.06, -0.06, 25)
    strands = np.stack(np.broadcast_arrays((ear[0] + dx.ravel())[:, None], y[None, :], dz.ravel()[:, None]), -1)
    out = _over_ears(strands, ear[None], np.zeros(3))
    assert np.linalg.norm(out[:, 1:] - ear, axis=2).min() >= EAR_CLEARANCE - 1e-9
    assert np.linalg.norm(np.diff(out, axis=1), axis=2).max() < 0.015


def test_an_afro_is_a_rounded_mass_of_coils(human):
    """Seen from the front, an afro's outline is round (the farthest strand point in each 5-deg
    sector varies little from sector to sector, and sideways it reaches no farther than it
    rises), and its strands wind in coils: the path through 4 consecutive control points (median)
    is 1.4 times the chord across them or more. Measured 0.040, sides 0.99-1.01 of the top, 1.78;
    strands grown straight out as far as they are long gave 0.096, 1.24-1.28, 1.10 (a starburst)."""
    from synmitsuba.body.hair import HairParams, grow_hair
    from synmitsuba.geometry import frame
    scalp = human.scalp
    B = frame(scalp.forward, scalp.up).T
    s = grow_hair(HairParams(style="afro", length=1.3, curliness=0.9, seed=4), scalp)
    P = s.points[s.region < 5]
    x, y = ((P.reshape(-1, 3) - scalp.origin) @ B.T)[:, :2].T
    angle, radius = np.degrees(np.arctan2(y, x)), np.hypot(x, y)
    top = (angle > 0) & (angle < 180)
    outline = np.array([radius[top & (angle >= a) & (angle < a + 5)].max() for a in range(0, 180, 5)])
    assert outline.std() / outline.mean() < 0.06, outline.std() / outline.mean()
    assert outline[:3].mean() < outline[17:19].mean() * 1.1 and outline[-3:].mean() < outline[17:19].mean() * 1.1
    path = np.linalg.norm(np.diff(P, axis=1), axis=2)
    window = np.lib.stride_tricks.sliding_window_view(path[:, 1:], 3, axis=1).sum(-1)
    chord = np.linalg.norm(P[:, 4:] - P[:, 1:-3], axis=2)
    assert np.median(window / np.maximum(chord, 1e-9)) > 1.4, np.median(window / np.maximum(chord, 1e-9))


def test_scalp_under_hair_takes_the_hair_colour(human):
    """``paint_uv`` blends a colour over a face's texture triangle (checked texel by texel
    against barycentric inside tests) and nowhere else; on a subject, the skin texels under the
    crown are near the hair's colour while the face keeps the skin tone."""
    from synmitsuba.body.hair import hair_colour
    from synmitsuba.body.subject import SCALP_TINT
    from synmitsuba.body.textures import lab_to_linear_rgb, paint_uv
    base = np.full((64, 64, 3), 0.5, np.float32)
    uv = np.array([[0.1, 0.9], [0.6, 0.9], [0.1, 0.4]])  # v up: rows 6.4 .. 38.4
    out = paint_uv(base, uv, np.array([[0, 1, 2]]), np.array([[1.0, 1.0, 1.0]]), (0.0, 0.0, 1.0), blur=0)
    c = (np.stack(np.meshgrid(np.arange(64), np.arange(64)), -1) + 0.5) / 64  # texel centres (u, 1 - v)
    u, v = c[..., 0], 1 - c[..., 1]  # the triangle: u >= 0.1, v <= 0.9, v - u >= 0.3
    inside = (u > 0.11) & (v < 0.89) & (v - u > 0.31)
    outside = (u < 0.09) | (v > 0.91) | (v - u < 0.29)
    assert np.allclose(out[inside], [0, 0, 1]) and np.allclose(out[outside], 0.5)
    body, tex = human.body, human.parts[0].material.texture
    size = tex.shape[0]

    def texels(vertices):
        corners = np.isin(body.faces, vertices)
        t = body.uv[body.face_uv[corners]]
        return tex[np.clip(((1 - t[:, 1]) * size).astype(int), 0, size - 1), np.clip((t[:, 0] * size).astype(int), 0, size - 1)]
    crown = np.flatnonzero(human.head.mask & (body.vertices[:, 1] > human.head.centre[1] + 0.07))
    skin = lab_to_linear_rgb(human.recipe.skin.lab())
    hair = (1 - SCALP_TINT) * skin + SCALP_TINT * hair_colour(human.recipe.hair)
    assert np.median(np.abs(texels(crown) - hair).max(1)) < 0.05
    nose = np.argmin(np.linalg.norm(body.vertices - human.head.nose, axis=1))
    assert np.abs(texels([nose]) - hair).max() > 0.1


def test_hair_and_accessories_follow_the_head(human):
    sk = human.skeleton
    R = np.broadcast_to(np.eye(3), (len(sk), 3, 3)).copy()
    R[sk.index("neck01")] = axis_rotation("y", np.radians(60))
    rest = {p.name: p for p in human.pose()}
    turned = {p.name: p for p in human.pose(R)}
    head = sk.rest_positions[sk.index("neck01")]  # the turn is about the neck joint
    for name in ("hair", "glasses"):
        a = rest[name].points if rest[name].is_curves else rest[name].vertices
        b = turned[name].points if turned[name].is_curves else turned[name].vertices
        a, b = a.reshape(-1, 3) - head, b.reshape(-1, 3) - head
        ang = np.degrees(np.arctan2(b[:, 0], b[:, 2]) - np.arctan2(a[:, 0], a[:, 2]))
        ang = (ang + 180) % 360 - 180
        far = np.hypot(a[:, 0], a[:, 2]) > 0.05
        assert abs(np.median(ang[far]) - 60) < 8, name
    assert np.allclose(rest["watch"].vertices, turned["watch"].vertices)


@pytest.fixture(scope="module")
def long_haired():
    return sm.build_subject(_unstyled(sm.sample_subject(np.random.default_rng(3), {"hair_style": "long", "accessories": [],
                                                                                 "jacket": True, "texture_size": 64})))


def _head_turns(sk):
    """The head tilted 35 deg sideways, bent 35 deg forward, turned 70 deg (over the neck joints)."""
    for axis, deg in (("z", 35.0), ("x", 35.0), ("y", 70.0)):
        R = np.broadcast_to(np.eye(3), (len(sk), 3, 3)).copy()
        for name in ("neck01", "neck02", "neck03", "head"):
            R[sk.index(name)] = axis_rotation(axis, np.radians(deg / 4))
        yield axis, R


def test_long_hair_rests_on_the_shoulders_when_the_head_moves(long_haired):
    """Strands follow the body below the neck: with the head tilted 35 deg sideways or bent 35
    deg forward or turned 70 deg, few strand points lie inside the posed body (2 mm or more),
    where hair rigid with the head (computed here from the head bone's transform) swings into
    the shoulder or chest; with the head turned, points 15 cm or more under the head joint stay
    within 1 cm of where they hung."""
    from synmitsuba.body.binding import signed_distance
    h = long_haired
    sk = h.skeleton
    rest = h.hair.points[h.hair.region < 5][::3]
    low = rest[..., 1] < sk.rest_positions[h.head_bone, 1] - 0.15  # the head joint: at the ears
    shares = {}
    for axis, R in _head_turns(sk):
        layers = h.pose(R, resolve=False)
        hair = next(x for x in layers if x.name == "hair").points[::3]
        A, b = bone_transforms(sk, R)
        rigid = rest @ A[h.head_bone].T + b[h.head_bone]
        body = np.empty_like(h.body.vertices)
        body[h.split.source] = layers[0].vertices
        for name, pts in (("follow", hair), ("rigid", rigid)):
            shares[axis, name] = (signed_distance(body, h.body.faces, pts[:, 1:].reshape(-1, 3)) < -0.002).mean()
        if axis == "y":
            assert low.sum() > 1000 and np.linalg.norm(hair[low] - rest[low], axis=1).max() < 0.01
    for axis in ("z", "x", "y"):  # measured: none following, 8.3 %, 1.9 %, 7.8 % rigid (0.7 cm the most a low point moved)
        assert shares[axis, "follow"] < 0.002 and shares[axis, "rigid"] > 0.005, shares


def test_strands_keep_their_length_and_stay_out_when_the_head_turns(long_haired):
    """Posed with garment resolution (as rendered), no scalp strand segment is longer than
    ``STRETCH`` times its rest length (a point pushed off the body may add a little), and no
    strand point lies 2 mm or more inside the posed body; following the body alone, strands
    crossing from the head to the shoulders stretch up to 2.5x."""
    from synmitsuba.body.binding import signed_distance
    from synmitsuba.body.hair import STRETCH
    h = long_haired
    scalp = h.hair.region < 5
    rest = np.linalg.norm(np.diff(h.hair.points[scalp], axis=1), axis=2)
    for axis, R in _head_turns(h.skeleton):
        stretch = {}
        for resolve in (False, True):
            layers = h.pose(R, resolve=resolve)
            pts = next(x for x in layers if x.name == "hair").points
            stretch[resolve] = (np.linalg.norm(np.diff(pts, axis=1), axis=2) / np.maximum(rest, 1e-9)).max()
        body = np.empty_like(h.body.vertices)
        body[h.split.source] = layers[0].vertices
        inside = (signed_distance(body, h.body.faces, pts[:, 1:].reshape(-1, 3)) < -0.002).mean()
        assert stretch[True] < STRETCH + 0.1 < 1.5 < stretch[False] and inside < 0.001, (axis, stretch, inside)


def test_a_walked_strand_keeps_its_length_its_directions_and_its_side():
    """``limit_stretch`` on strands against a floor at y = 0: segments longer than ``STRETCH``
    times their rest length are cut to it along their own direction, the points after them
    follow, no point ends under the floor, and a strand that did not stretch is untouched."""
    from synmitsuba.body.hair import STRETCH, limit_stretch
    rng = np.random.default_rng(0)
    rest_pts = np.cumsum(np.concatenate([np.zeros((2, 1, 3)), rng.normal(0, 0.01, (2, 9, 3)) + [0, -0.02, 0]], 1), 1)
    rest_pts += [0, 0.3, 0]
    posed = rest_pts.copy()
    posed[0, 4:] += [0.0, -0.25, 0.05]  # segment 3 of strand 0 pulled 25 cm down, below the floor
    rest = np.linalg.norm(np.diff(rest_pts, axis=1), axis=2)
    out = limit_stretch(posed, rest, clear=lambda q: np.where(q[:, 1:2] < 0.001, q * [1, 0, 1] + [0, 0.001, 0], q))
    seg, before = np.diff(out, axis=1), np.diff(posed, axis=1)
    assert np.array_equal(out[1], posed[1]) and np.array_equal(out[0, :4], posed[0, :4])
    assert (np.linalg.norm(seg, axis=2) <= STRETCH * rest + 1e-12).all() and out[..., 1].min() >= 0.001 - 1e-12
    cos = np.einsum("ki,ki->k", seg[0, :3], before[0, :3])  # untouched before the pull
    unit = lambda a: a / np.linalg.norm(a, axis=-1, keepdims=True)
    assert np.allclose(np.einsum("i,i->", unit(seg[0, 3]), unit(before[0, 3])), 1.0) and (cos > 0).all()


def test_cover_heights_read_a_garment_over_half_a_plane():
    """A flat body (y = 0, normals up) with a garment 2 cm over its x < 0 half: cover height
    2 cm under the garment, 0 beyond 3 cm past its edge (beside it, not over it)."""
    from synmitsuba.body.collide import cover_heights
    x, z = np.meshgrid(np.linspace(-0.2, 0.2, 41), np.linspace(-0.2, 0.2, 41))
    body = np.stack([x.ravel(), np.zeros(x.size), z.ravel()], 1)
    keep = body[:, 0] <= 0
    ids = -np.ones(len(body), np.int64)
    ids[keep] = np.arange(keep.sum())
    grid = np.arange(x.size).reshape(x.shape)
    quads = np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], -1).reshape(-1, 4)
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    faces = ids[faces[(ids[faces] >= 0).all(1)]]
    lift = cover_heights(body, np.tile([0.0, 1.0, 0.0], (len(body), 1)), [(body[keep] + [0, 0.02, 0], faces)])
    assert np.allclose(lift[body[:, 0] <= 0], 0.02) and (lift[body[:, 0] > 0.03] == 0).all()


def test_cover_heights_count_a_garment_over_the_body_it_lies_on():
    """A chest (y = 0, normals up) under a top 1 cm over it and a chin 12 cm above it (normals
    down): the chin's normals meet the top 11 cm on, but the top lies over the chest, so the
    chin's cover height is 0 and the chest's 1 cm (before: 11 cm under the chin, and hair near
    a jaw or the nape was pushed out that far, in straight strands fanning out to a collar)."""
    from synmitsuba.body.collide import cover_heights
    x, z = np.meshgrid(np.linspace(-0.1, 0.1, 21), np.linspace(-0.1, 0.1, 21))
    chest = np.stack([x.ravel(), np.zeros(x.size), z.ravel()], 1)
    chin = chest[np.abs(chest).max(1) <= 0.03] + [0.0, 0.12, 0.0]
    body = np.concatenate([chest, chin])
    normals = np.concatenate([np.tile([0.0, 1.0, 0.0], (len(chest), 1)), np.tile([0.0, -1.0, 0.0], (len(chin), 1))])
    grid = np.arange(x.size).reshape(x.shape)
    quads = np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], -1).reshape(-1, 4)
    top = (chest + [0.0, 0.01, 0.0], np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]))
    lift = cover_heights(body, normals, [top])
    assert np.allclose(lift[:len(chest)], 0.01) and (lift[len(chest):] == 0).all(), lift[len(chest):].max()


def test_long_hair_lies_over_the_garments(long_haired):
    """Strands are laid over the garments worn under them (``collide.cover_heights``): from
    almost no strand point does a ray along the outward normal of the nearest body vertex meet
    a garment within 10 cm (Mitsuba's ray casts on the garments alone; 1.7 % now, all but 0.2 %
    of the points hair beside the jaw, whose nearest vertex faces down and whose ray meets the
    collar below it, which lies over the neck, not the jaw). Laid 3 mm over the body, 27 % of this
    subject's points went under the long sleeve and 6.5 % under the jacket, and long hair came
    out below a jacket's back only at its tips."""
    from scipy.spatial import cKDTree
    from synmitsuba.engine.raycast import cast
    from synmitsuba.geometry import vertex_normals
    h = long_haired
    sm.set_variant()
    scene = sm.Scene()
    for k, part in enumerate(h.parts[1:]):
        if not GARMENTS.get(part.name) or not GARMENTS[part.name].footwear:
            scene.add_mesh(part.name, part.rest, part.faces, instance=k + 1)
    pts = h.hair.points[h.hair.region < 5][:, 1:].reshape(-1, 3)
    near = cKDTree(h.body.vertices).query(pts)[1]
    ids, _ = cast(scene, pts, vertex_normals(h.body.vertices, h.body.faces)[near], np.full(len(pts), 0.1))
    assert {"jacket", "longsleeve"} <= {p.name for p in h.parts} and (ids > 0).mean() < 0.03, (ids > 0).mean()


def test_every_texture_parameter_changes_the_texture():
    from synmitsuba.body.textures import GarmentTextureParams, render_garment_texture
    base = GarmentTextureParams(pattern="stripes", decal="star", bump="knit", bump_scale=6.0, seed=3)
    a0, h0 = render_garment_texture(base, 64)
    changes = {"base_lab": [70.0, 20.0, -30.0], "pattern": "dots", "pattern_lab": [80.0, 40.0, 0.0], "pattern_scale": 12.0,
               "pattern_width": 0.6, "pattern_alpha": 0.5, "decal": "circle", "decal_lab": [20.0, 0.0, 40.0],
               "decal_center": [0.3, 0.6], "decal_size": 0.3, "bump": "ribbed", "bump_amplitude": 0.9,
               "bump_scale": 10.0, "uv_scale": 1.7, "uv_rotation_deg": 30.0, "uv_offset": [0.25, 0.1], "uv_aspect": 1.6}
    for key, value in changes.items():
        a, h = render_garment_texture(GarmentTextureParams(**{**base.to_dict(), key: value}), 64)
        assert not (np.array_equal(a, a0) and np.array_equal(h, h0)), key
    cam = GarmentTextureParams(pattern="camouflage", seed=1)
    assert not np.array_equal(render_garment_texture(cam, 64)[0],
                              render_garment_texture(GarmentTextureParams(**{**cam.to_dict(), "seed": 2}), 64)[0])


@pytest.mark.parametrize("pattern,decal", [("stripes", "star"), ("dots", "number"), ("checks", "circle")])
def test_texture_edges_are_box_filtered(pattern, decal):
    """Pattern and decal edges cover each texel by the share of it inside them: against the
    hard-edged pattern sampled 8 x 8 times per texel and averaged, within 0.06 on average and
    0.3 at worst (whole-texel stair-steps were off by up to 1)."""
    from synmitsuba.body.textures import GarmentTextureParams, render_garment_texture
    p = GarmentTextureParams(pattern=pattern, decal=decal, base_lab=[90.0, 0.0, 0.0], pattern_lab=[0.0, 0.0, 0.0],
                             decal_lab=[0.0, 0.0, 0.0], pattern_scale=6.0, pattern_width=0.4, decal_size=0.3,
                             uv_rotation_deg=17.0, uv_offset=[0.1, 0.3], uv_aspect=1.3)
    n, k = 96, 8
    ours = render_garment_texture(p, n)[0][..., 1]
    u, v = np.meshgrid((np.arange(n * k) + 0.5) / (n * k), 1 - (np.arange(n * k) + 0.5) / (n * k))
    a = np.radians(p.uv_rotation_deg)
    x, y = np.cos(a) * 1.3 * u - np.sin(a) * v + 0.1, np.sin(a) * 1.3 * u + np.cos(a) * v + 0.3
    s, w = p.pattern_scale, p.pattern_width
    if pattern == "stripes":
        ink = (y * s) % 1 < w
    elif pattern == "dots":
        ink = np.hypot((x * s) % 1 - 0.5, (y * s) % 1 - 0.5) < w / 2
    else:
        ink = (np.floor(x * s) + np.floor(y * s)) % 2 == 1
    dx, dy = (u - 0.5) * 1.3 / 0.3, (v - 0.5) / 0.3
    r = np.hypot(dx, dy)
    if decal == "star":
        ink |= (r < 0.55 + 0.45 * np.cos(5 * np.arctan2(dy, dx))) & (r < 1)
    elif decal == "number":
        ink |= (((np.abs(dy - 0.6) < 0.15) | (np.abs(dy + 0.6) < 0.15)) & (np.abs(dx) < 0.5)) | \
            ((np.abs(dx - 0.35) < 0.15) & (np.abs(dy) < 0.75))
    else:
        ink |= ((r < 1) & (r > 0.6)) | (r < 0.35)
    share = ink.reshape(n, k, n, k).mean((1, 3))
    bright = render_garment_texture(GarmentTextureParams(base_lab=[90.0, 0.0, 0.0]), 4)[0][0, 0, 1]
    expected = bright * (1 - share)
    err = np.abs(ours - expected) / bright
    assert err.mean() < 0.06 and err.max() < 0.3, (err.mean(), err.max())


def test_a_print_lies_round_on_the_chest_and_other_kinds_take_none():
    """A sampled t-shirt's drawn decal is printed on the chest: its centre, looked up through
    the built mesh's uv, is on the front within 2 cm of the centre line and 8-24 cm under the
    neck's base; its circle's rim is as wide on the body as it is tall (within 15 %: the uv
    atlas is 1.47 times wider in metres than tall there). Trousers, skirts and jackets are drawn
    without a decal, whatever their texture drew."""
    from synmitsuba.body.garments import build_garment, lay_out, sample_garment
    h = sm.build_subject(sm.sample_subject(np.random.default_rng(13)))
    g = sample_garment("tshirt", np.random.default_rng(2))
    g.texture.decal, g.texture.decal_size = "circle", 0.15  # a chest print, not a logo
    g.texture = lay_out(g.texture, GARMENTS["tshirt"])
    m = build_garment(h.body, h.regions, h.split, g)
    t, r = g.texture, h.regions
    centre = uv_to_rest(m.vertices, m.faces, m.uv, np.array(t.decal_center))
    assert abs(centre[0] - r.neck_xz[0]) < 0.02 and centre[2] > r.neck_xz[1], centre
    assert 0.08 < r.neck_y - centre[1] < 0.24, r.neck_y - centre[1]
    ang = np.radians([0, 90, 180, 270])
    rim = [uv_to_rest(m.vertices, m.faces, m.uv, np.array(t.decal_center) + t.decal_size * d)
           for d in np.stack([np.cos(ang) / t.uv_aspect, np.sin(ang)], 1)]
    wide, tall = np.linalg.norm(rim[0] - rim[2]), np.linalg.norm(rim[1] - rim[3])
    assert abs(wide / tall - 1) < 0.15, (wide, tall)  # the chest's atlas: 1.47 wider than tall, uv_aspect 1.35
    assert 0.1 < tall < 0.26, tall  # 6-12 cm in radius for a drawn size of 0.08-0.2
    for kind in ("trousers", "skirt", "jacket", "dress"):
        drawn = sample_garment(kind, np.random.default_rng(2)).texture
        assert drawn.decal == "none" and drawn.uv_aspect != 1.0, (kind, drawn.decal)


def test_sampled_garments_lie_on_the_grain_at_their_own_kinds_aspect():
    """Over 60 sampled subjects: every garment's pattern runs at 0 or 90 degrees, its
    ``uv_aspect`` is its own kind's (also a kind a style made it into after the draw: a
    jumpsuit drawn as a dress), and a decal is only on the kinds that print; footwear keeps 1."""
    from synmitsuba.body.garments import sample_garment, sample_style, uv_aspect
    from synmitsuba.body.textures import on_grain
    assert [on_grain(a) for a in (-45.0, -29.9, 0.0, 29.9, 30.0, 45.0)] == [90.0, 0.0, 0.0, 0.0, 90.0, 90.0]
    kinds = set()
    for seed in range(60):
        for g in sm.sample_subject(np.random.default_rng(seed)).garments:
            k, t = GARMENTS[g.kind], g.texture
            kinds.add(g.kind)
            if k.footwear:
                continue
            assert t.uv_rotation_deg in (0.0, 90.0) and t.uv_aspect == uv_aspect(k), (seed, g.kind, t)
            assert t.decal == "none" or k.prints, (seed, g.kind, t.decal)
    assert {"hoodie", "jeans", "skirt", "tank"} <= kinds, kinds
    styled = [sample_style(sample_garment("dress", np.random.default_rng(seed)), ["dress"]) for seed in range(40)]
    assert {"jumpsuit", "shift", "wrap"} <= {g.kind for g in styled}
    assert all(g.texture.uv_aspect == uv_aspect(GARMENTS[g.kind]) for g in styled)


def test_each_printing_kinds_uv_aspect_is_its_mesh_s():
    """``uv_aspect`` (metres per unit u over per unit v), which places a chest print, against
    the built meshes of the kinds that print, on two bodies, over the torso's front; within 30 %
    (10 % in the median)."""
    from synmitsuba.body.garments import build_garment, metres_per_uv, sample_garment, uv_aspect
    off = {}
    for seed in (13, 40):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed)))
        r = h.regions
        for kind, k in GARMENTS.items():
            if not k.prints:
                continue
            m = build_garment(h.body, r, h.split, sample_garment(kind, np.random.default_rng(seed)))
            c = m.vertices[m.faces].mean(1)
            faces = m.faces[(np.abs(c[:, 0] - r.neck_xz[0]) < 0.1) & (c[:, 2] > r.neck_xz[1]) &
                            (c[:, 1] > r.waist_y) & (c[:, 1] < r.neck_y - 0.05)]
            mu, mv = metres_per_uv(m.vertices, faces, m.uv)
            off[(seed, kind)] = round(mu / mv / uv_aspect(k) - 1, 3)
    assert len(off) == 8 and max(abs(x) for x in off.values()) < 0.3, off
    assert abs(np.median(list(off.values()))) < 0.1, off


def test_separable_noise_equals_the_general_one():
    """The skin's noise by two matrix products is the per-texel value noise it stands for."""
    from synmitsuba.body.textures import _value_noise, grid_noise
    v, u = (np.mgrid[:80, :80] + 0.5) / 80
    assert np.abs(grid_noise(80, 24, 3) - _value_noise(u * 24, v * 24, 3)).max() < 1e-5


def test_skin_roughness_varies_by_region(sm):
    """Lips and face are glossier than the body, with a fine variation around each value, and
    Mitsuba's principled BSDF reads the map (a bitmap under its roughness)."""
    import mitsuba as mi

    from synmitsuba.body.textures import SKIN_ROUGHNESS, SkinParams, render_skin_roughness, skin_material
    from synmitsuba.engine.build import bsdf_dict
    masks = {"lips": np.zeros((64, 64)), "face": np.zeros((64, 64))}
    masks["lips"][40:48, 20:44], masks["face"][:16] = 1.0, 1.0
    r = render_skin_roughness(SkinParams(seed=5), masks, 64)
    for region, value in ((r[40:48, 20:44], SKIN_ROUGHNESS["lips"]), (r[:16], SKIN_ROUGHNESS["face"]),
                          (r[20:36], SKIN_ROUGHNESS["body"])):
        assert abs(region.mean() - value) < 0.02 and 0.01 < region.std() < 0.05
    sm.set_variant()
    params = mi.traverse(mi.load_dict(bsdf_dict(skin_material(SkinParams(), masks, 64))))
    assert any(k.endswith("roughness.data") for k in params.keys())


def test_colour_conversions_match_colour_science():
    """Our CIELAB / XYZ / linear sRGB formulas (written out to spare each worker colour-science's
    2-s import) against colour-science on random colours, the sRGB curves both ways."""
    from synmitsuba import _colour as c
    colour, rng = colour_science(), np.random.default_rng(0)
    lab = np.stack([rng.uniform(0, 100, 500), rng.uniform(-90, 90, 500), rng.uniform(-90, 90, 500)], -1)
    xyz = colour.Lab_to_XYZ(lab)
    assert np.allclose(c.lab_to_xyz(lab), xyz, atol=1e-12) and np.allclose(c.xyz_to_lab(xyz), lab, atol=1e-9)
    rgb = rng.uniform(0, 1, (500, 3))
    assert np.allclose(c.rgb_to_xyz(rgb), colour.RGB_to_XYZ(rgb, "sRGB", apply_cctf_decoding=False), atol=1e-12)
    assert np.allclose(c.xyz_to_rgb(xyz), colour.XYZ_to_RGB(xyz, "sRGB", apply_cctf_encoding=False), atol=1e-12)
    assert np.allclose(c.srgb_encode(rgb), colour.cctf_encoding(rgb, function="sRGB"), atol=1e-12)
    assert np.allclose(c.srgb_decode(rgb), colour.cctf_decoding(rgb, function="sRGB"), atol=1e-12)


def test_skin_tones_span_light_to_dark_by_ita():
    from synmitsuba.body.textures import ITA_RANGE, SkinParams, render_skin_texture
    colour = colour_science()
    L = []
    for ita in (ITA_RANGE[0], -30, 0, 30, ITA_RANGE[1]):
        albedo = render_skin_texture(SkinParams(ita_deg=ita, freckles=0, blush=0), {}, 8)[0, 0]
        lab = colour.XYZ_to_Lab(colour.RGB_to_XYZ(albedo.astype(float), "sRGB", apply_cctf_decoding=False))
        assert np.degrees(np.arctan((lab[0] - 50) / lab[2])) == pytest.approx(ita, abs=1.0)
        L.append(lab[0])
    assert L[0] < 30 and L[-1] > 70 and np.all(np.diff(L) > 0)
    masks = {"lips": np.zeros((8, 8), np.float32)}
    masks["lips"][2:4, 2:4] = 1
    img = render_skin_texture(SkinParams(lip_darkening=0.8, lip_redness=0.8), masks, 8)
    assert img[3, 3, 0] / img[3, 3, 1] > img[0, 0, 0] / img[0, 0, 1]


def _population_check(n: int, p_min: float) -> None:
    """Stature and body mass index measured on the built anny meshes of ``n`` random recipes
    against the population tables they are drawn from (Kolmogorov-Smirnov per sex)."""
    from scipy.stats import kstest, lognorm, norm

    from synmitsuba.body.anny_model import measures
    from synmitsuba.body.recipe import BMI, STATURE_M
    recipes = [sm.sample_subject(np.random.default_rng(seed), {"texture_size": 64}) for seed in range(n)]
    stature, mass = [], []
    for i in range(0, n, 40):
        s, m = measures([r.phenotypes for r in recipes[i:i + 40]])
        stature += s.tolist()
        mass += m.tolist()
    stature, bmi = np.array(stature), np.array(mass) / np.array(stature) ** 2
    female = np.array([r.phenotypes["gender"] >= 0.5 for r in recipes])
    for sex, sel in (("male", ~female), ("female", female)):
        assert sel.sum() >= 0.35 * n
        mean, sd = STATURE_M[sex]
        median, log_sd = BMI[sex]
        assert kstest(stature[sel], norm(mean, sd).cdf).pvalue > p_min, (sex, np.median(stature[sel]))
        assert kstest(bmi[sel], lognorm(s=log_sd, scale=median).cdf).pvalue > p_min, (sex, np.percentile(bmi[sel], [5, 50, 95]))
    assert stature.max() < 2.0 and stature.min() > 1.45 and bmi.min() > 15.5 and bmi.max() < 43
    return recipes


def test_sampled_adults_match_population_stature_and_bmi():
    """80 random recipes: a man or a woman each (anny: gender 0 male, 1 female), adults by
    anny's age calibration, stature and BMI distributed as the tables say; beards only on men,
    skirts rare on men; explicit phenotypes win."""
    recipes = _population_check(80, 0.01)
    skirted = 0
    for recipe in recipes:
        g = recipe.phenotypes["gender"]
        assert g <= 0.2 or g >= 0.8
        assert 0.76 <= recipe.phenotypes["age"] <= 0.9  # 18-80 years on anny's morphological-age anchors
        if g >= 0.5:
            assert recipe.hair.beard == "none"
        else:
            skirted += bool({"skirt", "dress"} & {k.kind for k in recipe.garments})
    assert skirted <= 4  # skirts and dresses: 3 % of men's outfits (equal odds would give about 17 here)
    fixed = sm.sample_subject(np.random.default_rng(0), {"phenotypes": {"height": 0.9, "gender": 0.5, "muscle": 0.3}})
    assert fixed.phenotypes["height"] == 0.9 and fixed.phenotypes["gender"] == 0.5 and fixed.phenotypes["muscle"] == 0.3
    child = sm.sample_subject(np.random.default_rng(1), {"age_years": [8, 10]})
    assert child.phenotypes["age"] < 0.6  # children only when asked for


@pytest.mark.slow
def test_a_thousand_recipes_match_the_population_tables():
    _population_check(1000, 0.001)


@pytest.mark.parametrize("seed", [0, 3])
def test_glasses_sit_on_the_eyes_and_the_cap_hugs_the_skull(seed):
    """Measured against anny's eye keypoints and the body surface (signed distance from the
    closest triangle): the rims are centred on the eyes, the frame touches nothing and floats
    nowhere (within 5 mm of the face), the cap is outside the head but within 15 mm of it, and no
    hair strand grows through the cap."""
    from synmitsuba.body.accessories import under_cap
    recipe = sm.sample_subject(np.random.default_rng(seed), {"accessories": ["glasses", "cap"],
                                                             "hair_style": "short", "texture_size": 64})
    h = sm.build_subject(recipe)
    eyes = h.keypoints()[[1, 2]]
    glasses, cap = (next(p.rest for p in h.parts if p.name == k) for k in ("glasses", "cap"))
    front = glasses[glasses[:, 2] > glasses[:, 2].max() - 0.006]  # the rims and the bridge
    for eye in eyes:
        rim = front[np.abs(front[:, 0] - eye[0]) < 0.03]
        assert abs(rim[:, 0].mean() - eye[0]) < 0.003 and abs(rim[:, 1].mean() - eye[1]) < 0.003
    d_glasses = signed_distance(h.body.vertices, h.body.faces, glasses)
    d_cap = signed_distance(h.body.vertices, h.body.faces, cap)
    assert d_glasses.min() > 0.0005 and d_glasses.min() < 0.005
    arms = glasses[:, 2] < front[:, 2].min() - 0.015  # the temples, behind the frame
    ears = h.keypoints()[[3, 4]]
    # along the side of the head, not standing off it (a temple never bends in: on a head that a face shape
    # narrowed behind the frame, 12.1 mm at the 90th percentile for seed 0)
    assert np.percentile(d_glasses[arms], 90) < 0.013
    assert glasses[arms, 2].min() < ears[:, 2].mean() + 0.01  # back to the ears
    assert d_cap.min() > -0.001 and np.median(d_cap) < 0.015
    assert len(h.hair) > 0 and not under_cap(h.head, h.hair.points[:, 0]).any()


def test_cap_crown_ends_on_its_edge_line_and_the_bill_is_a_peak():
    """The crown's open edge follows the cap's line (3 cm over the eyes at the front, 3 cm lower
    for every 10 cm back; written out here) within 4 mm, not the head's triangle edges (up to
    2 cm off); the bill is a peak over the brow: in front of the forehead, no wider than the
    head and 1 cm, 5-9 cm long, its sides lower than its middle."""
    from synmitsuba.geometry import frame
    h = sm.build_subject(sm.sample_subject(np.random.default_rng(3), {"accessories": ["cap"], "texture_size": 64}))
    part = next(p for p in h.parts if p.name == "cap")
    R, c = frame(h.head.forward, h.head.up), h.head.centre
    v = (part.rest - c) @ R
    eyes = ((h.head.eyes - c) @ R).mean(0)
    head = (h.body.vertices[h.head.mask] - c) @ R
    brow = head[np.abs(head[:, 1] - eyes[1] - 0.03) < 0.01]
    bill = v[:, 2] > brow[:, 2].max() + 0.012
    edges = np.sort(np.concatenate([part.faces[:, [0, 1]], part.faces[:, [1, 2]], part.faces[:, [2, 0]]]), 1)
    uniq, count = np.unique(edges, axis=0, return_counts=True)
    crown = np.zeros(len(v), bool)
    crown[_pieces(v, part.faces)[0]] = True
    rim = np.unique(uniq[count == 1])
    rim = rim[crown[rim] & (v[rim, 2] < brow[:, 2].max() - 0.03)]  # the crown's edge at the sides and back
    line = eyes[1] + 0.03 - 0.3 * (eyes[2] - v[rim, 2])
    assert len(rim) > 20 and np.abs(v[rim, 1] - line).max() < 0.004
    assert bill.sum() > 20 and np.abs(v[bill, 0]).max() < np.abs(brow[:, 0]).max() + 0.01
    assert 0.05 < v[bill, 2].max() - brow[:, 2].max() < 0.09
    mid, sides = bill & (np.abs(v[:, 0]) < 0.01), bill & (np.abs(v[:, 0]) > 0.05)
    assert v[sides, 1].mean() < v[mid, 1].mean()


def _pieces(v: np.ndarray, f: np.ndarray) -> list:
    """Vertex indices of each connected piece of a mesh, largest first."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    label = connected_components(coo_matrix((np.ones(len(e)), tuple(e.T)), shape=(len(v),) * 2))[1]
    return sorted((np.flatnonzero(label == k) for k in np.unique(label)), key=len, reverse=True)


@pytest.mark.parametrize("seed", [0, 3])
def test_mask_covers_nose_and_mouth_and_headphones_sit_on_the_ears(seed):
    """Against anny's keypoints: the mask's shell spans the nose keypoint's height, stays below
    the eyes and reaches under the chin (2.4 eye-to-nose drops under the nose; the chin's
    underside is 2.4-2.9 under it on seeds 0-4), off the skin; its two ear loops pass
    over and behind the ears and meet the shell; the headphones' cups are on the ears and the
    band passes over the crown, not in front of the face."""
    recipe = sm.sample_subject(np.random.default_rng(seed), {"accessories": ["mask", "headphones"],
                                                             "hair_style": "bald", "texture_size": 64})
    h = sm.build_subject(recipe)
    kp = h.keypoints()
    nose, eye_y, ears = kp[0], kp[[1, 2], 1].mean(), kp[[3, 4]]
    part, phones = (next(p for p in h.parts if p.name == k) for k in ("mask", "headphones"))
    phones = phones.rest
    pieces = _pieces(part.rest, part.faces)
    assert len(pieces) == 3  # the shell and two loops
    mask, loops = part.rest[pieces[0]], [part.rest[k] for k in pieces[1:]]
    drop = eye_y - nose[1]
    assert mask[:, 1].max() < eye_y - 0.3 * drop and mask[:, 1].min() < nose[1] - 2.4 * drop  # under the chin
    assert mask[:, 2].max() > nose[2]  # in front of the nose tip
    d = signed_distance(h.body.vertices, h.body.faces, mask)
    assert d.min() > 0.002 and np.median(d) > 0.004
    for ear in ears:
        loop = next(q for q in loops if np.sign(q[:, 0].mean()) == np.sign(ear[0]))
        assert signed_distance(h.body.vertices, h.body.faces, loop).min() > 0.001
        behind = loop[(np.abs(loop[:, 1] - ear[1]) < 0.015)]
        assert behind[:, 2].min() < ear[2] - 0.02  # round the back of the ear
        assert loop[np.abs(loop[:, 2] - ear[2]) < 0.02, 1].max() > ear[1] + 0.02  # over it
        assert np.linalg.norm(mask[:, None] - loop[[0, -1]][None], axis=2).min(0).max() < 0.005  # both ends meet the shell
    for ear in ears:
        side = phones[np.sign(phones[:, 0]) == np.sign(ear[0])]
        cup = side[np.abs(side[:, 1] - ear[1]) < 0.03]
        assert np.linalg.norm(cup.mean(0)[[1, 2]] - ear[[1, 2]]) < 0.03
    top = h.body.vertices[h.head.mask, 1].max()
    above = phones[phones[:, 1] > top]
    assert len(above) and np.abs(above[:, 2] - h.head.centre[2]).max() < 0.03  # over the crown
    assert phones[:, 2].max() < nose[2] - 0.02  # nothing in front of the face


def test_mask_is_taut_and_pleated():
    """Down the middle of the face, from the nose tip to the chin, the mask's front never dips
    under the straight line between them (cloth stretched over the nose and chin spans the
    hollow under the nose and the mouth instead of following them; the face itself dips there
    by millimetres), and it stands at least 8 mm off the face in that hollow; its profile's
    strongest ripple repeats every pleat (an FFT of the profile less a quadratic fit)."""
    from synmitsuba.body.accessories import MASK_PLEATS
    h = sm.build_subject(sm.sample_subject(np.random.default_rng(3), {"accessories": ["mask"], "hair_style": "bald",
                                                                       "texture_size": 64}))
    part = next(p for p in h.parts if p.name == "mask")
    nose = h.keypoints()[0]

    def profile(v, f, ys):  # the frontmost point of the mesh's cut by the midplane, at each height
        seg = trimesh.intersections.mesh_plane(trimesh.Trimesh(v, f, process=False), [1, 0, 0], nose)
        t = np.linspace(0, 1, 20)[None, :, None]
        p = (seg[:, :1] * (1 - t) + seg[:, 1:] * t).reshape(-1, 3)
        p = p[p[:, 2] > nose[2] - 0.08]  # the face, not the back of the head
        return np.array([p[np.abs(p[:, 1] - y) < 0.001, 2].max() for y in ys])
    body = h.body
    ys = np.arange(nose[1] - 0.004, nose[1] - 0.05, -0.002)
    front, face = profile(part.rest, part.faces, ys), profile(body.vertices, body.faces, ys)
    chord = front[0] + (front[-1] - front[0]) * (ys - ys[0]) / (ys[-1] - ys[0])
    assert (front - chord).min() > -0.0015
    face_chord = face[0] + (face[-1] - face[0]) * (ys - ys[0]) / (ys[-1] - ys[0])
    assert (face - face_chord).min() < -0.004 and (front - face).max() > 0.008
    period, _ = MASK_PLEATS
    ys = np.arange(nose[1] - 0.005, nose[1] - 0.05, -0.0005)
    z = profile(part.rest, part.faces, ys)
    z = z - np.polyval(np.polyfit(ys, z, 2), ys)
    freq = np.fft.rfftfreq(4096, 0.0005)  # zero-padded: bins of 0.5 cycles a metre
    peak = freq[1 + np.abs(np.fft.rfft(z * np.hanning(len(z)), 4096))[1:].argmax()]
    assert abs(peak * period - 1) < 0.1


def test_keypoints_are_anatomical(human):
    kp = human.keypoints()
    names = human.body.keypoint_labels
    k = {n: kp[i] for i, n in enumerate(names)}
    assert len(kp) == 23
    assert k["nose"][1] > k["left_shoulder"][1] > k["left_hip"][1] > k["left_knee"][1] > k["left_ankle"][1]
    assert k["left_shoulder"][0] > 0 > k["right_shoulder"][0]  # the subject's left is +x
    assert k["nose"][2] > k["left_ear"][2]  # facing +z
    assert 0 <= k["left_heel"][1] < 0.12


def test_foot_points_come_in_the_documented_order(human):
    """Rows 17-22 are left big toe, left small toe, left heel, then the right ones (FORMAT.md,
    COCO-WholeBody), checked on the rest pose's geometry, not on the labels."""
    foot = human.keypoints()[17:]
    assert list(np.sign(foot[:, 0])) == [1, 1, 1, -1, -1, -1]  # the subject's left is +x
    for big, small, heel in (foot[:3], foot[3:]):
        assert min(big[2], small[2]) > heel[2] + 0.08  # toes ahead (+z) of the heel
        assert abs(small[0]) > abs(big[0]) + 0.02  # the small toe on the outside
    assert human.body.keypoint_labels[17:] == ("left_big_toe", "left_small_toe", "left_heel",
                                               "right_big_toe", "right_small_toe", "right_heel")


def test_subject_renders_with_instance_and_layer_ids(human):
    scene = sm.Scene()
    human.add_to(scene, instance=7)
    scene.set_environment(sm.Constant(1.0))
    cam = sm.Camera.look_at(eye=(0.4, 1.1, 3.2), target=(0, 0.9, 0), fov_y_deg=40, width=48, height=64)
    s = sm.render(scene, cam, spp=2)
    assert set(np.unique(s.instance)) == {0, 7}
    seen = set(np.unique(s.layer))
    assert {int(sm.Layer.BODY), int(sm.Layer.TOP), int(sm.Layer.BOTTOM), int(sm.Layer.SHOES)} <= seen
    assert s.rgb[s.mask].mean() > 0.05


def test_walk_retargets_onto_the_subject(human):
    m = sm.retarget(sm.procedural_motion("walk", np.random.default_rng(0), seconds=1.0), human.skeleton)
    heels = []
    for f in range(0, m.n_frames, 5):
        k = human.keypoints(*m.frame(f))
        heels.append(min(k[human.body.keypoint_labels.index("left_heel"), 1],
                         k[human.body.keypoint_labels.index("right_heel"), 1]))
    assert max(heels) < 0.12 and min(heels) > -0.05  # a foot stays on the ground
    assert m.root_translation[-1, 2] > 0.5  # walks forward (+z)


def test_smplx_backend_with_a_synthetic_model(tmp_path, monkeypatch):
    from synmitsuba.body.smplx_model import smplx_body
    rng = np.random.default_rng(0)
    V, J = 10475, 55
    v = rng.normal(0, 0.2, (V, 3)) + [0, 0.9, 0]
    Jreg = np.zeros((J, V))
    Jreg[np.arange(J), rng.integers(0, V, J)] = 1.0
    parents = np.concatenate([[2 ** 32 - 1], np.arange(J - 1)])
    W = rng.random((V, J))
    np.savez(tmp_path / "SMPLX_NEUTRAL.npz", v_template=v, f=rng.integers(0, V, (20908, 3)),
             shapedirs=rng.normal(0, 0.01, (V, 3, 10)), J_regressor=Jreg, weights=W / W.sum(1, keepdims=True),
             kintree_table=np.stack([parents, np.arange(J)]))
    monkeypatch.delenv("SMPLX_MODEL_PATH", raising=False)
    with pytest.raises(ConfigError) as e:
        smplx_body()
    assert "SMPLX_MODEL_PATH" in str(e.value)
    monkeypatch.setenv("SMPLX_MODEL_PATH", str(tmp_path))
    b0 = smplx_body()
    b1 = smplx_body(betas=[1.0] + [0] * 9)
    assert b0.vertices.shape == (V, 3) and abs(b0.vertices[:, 1].min()) < 1e-12
    assert not np.allclose(b0.vertices, b1.vertices)
    assert b0.skeleton.names[0] == "pelvis" and len(b0.skeleton) == J
    T = bone_transforms(b0.skeleton)
    assert np.allclose(skin(b0.vertices, b0.weights, T), b0.vertices)
    R = np.broadcast_to(np.eye(3), (J, 3, 3)).copy()
    R[0] = axis_rotation("y", np.pi / 2)
    posed = skin(b0.vertices, b0.weights, bone_transforms(b0.skeleton, R))
    root = b0.skeleton.rest_positions[0]
    np.testing.assert_allclose(posed[:, 1], b0.vertices[:, 1], atol=1e-9)  # a yaw keeps heights
    assert np.allclose(np.linalg.norm((posed - root)[:, [0, 2]], axis=1), np.linalg.norm((b0.vertices - root)[:, [0, 2]], axis=1))
    with pytest.raises(ConfigError):
        sm.build_subject(sm.SubjectRecipe(model="smplx"))


@pytest.mark.slow
def test_a_few_dozen_random_subjects_build_without_degenerate_meshes():
    for seed in range(24):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(1000 + seed), {"texture_size": 64}))
        for layer in h.pose():
            if layer.is_curves:
                assert np.isfinite(layer.points).all() and (layer.radius > 0).all()
                continue
            v, f = layer.vertices, layer.faces
            assert len(f) > 0 and np.isfinite(v).all() and f.max() < len(v), layer.name
            area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
            assert (area > 0).mean() > 0.99, layer.name


def test_identity_pose_is_the_rest_mesh_and_a_shoulder_moves_only_its_arm(human):
    sk, body = human.skeleton, human.body
    rest = skin(body.vertices, body.weights, bone_transforms(sk))
    assert np.abs(rest - body.vertices).max() < 1e-6
    R = np.broadcast_to(np.eye(3), (len(sk), 3, 3)).copy()
    R[sk.index("upperarm01.L")] = axis_rotation("z", np.radians(60))
    moved = np.linalg.norm(skin(body.vertices, body.weights, bone_transforms(sk, R)) - body.vertices, axis=1) > 1e-4
    assert moved.any()
    assert not moved[body.vertices[:, 0] < -0.05].any()  # the subject's right side (-x) stays
    assert (body.vertices[moved, 0] > 0.15).mean() > 0.8  # what moves is mostly the left arm


def test_every_body_and_garment_parameter_changes_the_subject():
    base = sm.sample_subject(np.random.default_rng(2), {"outfit": ["tshirt", "trousers"], "shoes": False,
                                                        "jacket": False, "accessories": [], "texture_size": 64})
    ref = {p.name: p.vertices for p in sm.build_subject(base).pose() if not p.is_curves}
    d = base.to_dict()
    changes = [("phenotypes", k, v) for k, v in [("gender", 0.1), ("age", 0.9), ("muscle", 0.95), ("weight", 0.05),
                                                  ("height", 0.95), ("proportions", 0.05)]]
    grade = 1 if d["garments"][1]["grade"] != 1 else -1  # sampled garments are graded: size acts on ungraded ones
    changes += [("garments", k, v) for k, v in [("grade", grade), ("ease", 0.04), ("length", 0.3), ("thickness", 0.015)]]
    for section, key, value in changes:
        e = json.loads(json.dumps(d))
        if section == "phenotypes":
            e["phenotypes"][key] = value if abs(e["phenotypes"][key] - value) > 0.2 else 1 - value
            target = "body"
        else:
            e["garments"][1][key] = value  # the trousers: the innermost layer, no nesting floor
            target = e["garments"][1]["kind"]
        other = {p.name: p.vertices for p in sm.build_subject(sm.SubjectRecipe.from_dict(e)).pose() if not p.is_curves}
        assert other[target].shape != ref[target].shape or not np.allclose(other[target], ref[target]), (section, key)


def test_hair_styles_and_beards_follow_the_documented_table():
    """2,000 draws per person kind: style and beard frequencies match ``STYLE_ODDS`` and
    ``beard_odds`` (chi-square, p > 0.001); women and people under 18 never get a beard."""
    from scipy.stats import chisquare
    from synmitsuba.body.hair import BEARDS, STYLE_ODDS, STYLES, beard_odds, sample_hair
    rng = np.random.default_rng(5)
    for sex, years in (("male", 25.0), ("male", 60.0), ("female", 40.0), ("male", 12.0)):
        draws = [sample_hair(rng, sex, years) for _ in range(2000)]
        styles = np.array([list(STYLES).index(h.style) for h in draws])
        beards = np.array([list(BEARDS).index(h.beard) for h in draws])
        assert chisquare(np.bincount(styles, minlength=len(STYLES)), 2000 * np.array(STYLE_ODDS[sex])).pvalue > 1e-3
        odds = np.array(beard_odds(sex, years))
        if sex == "female" or years < 18:
            assert (beards == 0).all()
        else:
            assert chisquare(np.bincount(beards, minlength=len(BEARDS)), 2000 * odds).pvalue > 1e-3


def test_clearance_reads_the_side_of_a_coarse_torus_where_one_vertex_cannot():
    """``Surface.clearance`` (the collision pass against the body) against the pseudonormal
    signed distance on a coarse torus, whose inner half is a saddle: the same side for every
    point it looks at exactly, within a millimetre for 99 % of them; the nearest vertex's
    tangent plane alone misreads hundreds."""
    import trimesh
    from synmitsuba.body.binding import incident_faces
    from synmitsuba.body.collide import Surface, incidence
    m = trimesh.creation.torus(1.0, 0.3, major_sections=16, minor_sections=8)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    rng = np.random.default_rng(0)
    p = v[rng.integers(0, len(v), 4000)] + rng.normal(0, 0.1, (4000, 3))
    surface = Surface.of(v, f, incidence(f, len(v)), incident_faces(f, len(v)))
    h, _ = surface.clearance(p, 0.05)
    d = signed_distance(v, f, p, k=8)
    look = h < 0.05
    assert 0.3 < look.mean() < 0.9 and np.array_equal(h < 0, d < 0)
    assert np.percentile(np.abs(h - d)[look], 99) < 1e-3
    assert ((surface.depth(p)[0] < 0) != (d < 0)).sum() > 100


def test_clearance_on_more_vertices_finds_a_part_pressed_against_a_denser_one():
    """A point 3.5 mm inside a coarse ball (an arm) that hangs 4 mm over a dense sheet (the
    torso), under the ball's lowest face: its 4 nearest vertices are all on the sheet, whose
    planes read it 7.5 mm outside; over its 8 nearest (``k=8``, as garment vertices carried by
    a push are checked again) it reads the depth under the ball's nearest face plane, computed
    here from the convex ball's face planes."""
    from synmitsuba.body.binding import incident_faces
    from synmitsuba.body.collide import Surface, incidence
    x, z = np.meshgrid(np.linspace(-0.15, 0.15, 31), np.linspace(-0.15, 0.15, 31))
    sheet = np.stack([x.ravel(), np.zeros(x.size), z.ravel()], 1)
    g = np.arange(x.size).reshape(x.shape)
    quads = np.stack([g[:-1, :-1], g[:-1, 1:], g[1:, 1:], g[1:, :-1]], -1).reshape(-1, 4)
    sheet_faces = np.concatenate([quads[:, [0, 2, 1]], quads[:, [0, 3, 2]]])
    assert (trimesh.Trimesh(sheet, sheet_faces, process=False).face_normals[:, 1] > 0.99).all()
    ball = trimesh.creation.icosphere(subdivisions=1, radius=0.05)
    low = ball.triangles_center[:, 1].argmin()
    bv = ball.vertices @ trimesh.geometry.align_vectors(ball.face_normals[low], [0, -1, 0])[:3, :3].T
    bottom = bv[ball.faces[low]].mean(0)
    bv = bv - bottom + [0, 0.004, 0]
    v, f = np.concatenate([sheet, bv]), np.concatenate([sheet_faces, ball.faces + len(sheet)])
    surface = Surface.of(v, f, incidence(f, len(v)), incident_faces(f, len(v)))
    p = np.array([[0.005, 0.0075, 0.005]])
    normals = trimesh.Trimesh(bv, ball.faces, process=False).face_normals
    depth = -np.einsum("fi,fi->f", p - bv[ball.faces[:, 0]], normals).max()
    assert (surface.tree.query(p, k=4)[1] < len(sheet)).all() and 0.003 < depth < 0.004
    assert surface.clearance(p, 0.01)[0][0] > 0.005
    assert abs(surface.clearance(p, 0.01, k=8)[0][0] + depth) < 1e-9


def test_a_vertex_pushed_out_of_one_ball_into_the_next_settles_in_the_gap(monkeypatch):
    """Two balls 3 mm apart (two thighs in a squat) and a patch of cloth 2.5 mm inside one of
    them, bound to it: pushed by its 6 mm margin it goes into the other ball, and out of that
    one by the margin back into the first. The resolver then sets it 1 mm over the surface
    it is in (``collide.SETTLE``): every vertex ends outside both balls, by their winding
    numbers, in the gap; without that step most end inside one."""
    from synmitsuba.body import collide
    from synmitsuba.body.binding import MeshIndex, incident_faces
    ball = trimesh.creation.icosphere(subdivisions=4, radius=0.05)
    gap = 0.003
    v = np.concatenate([ball.vertices - [0.05 + gap / 2, 0, 0], ball.vertices + [0.05 + gap / 2, 0, 0]])
    f = np.concatenate([ball.faces, ball.faces + len(ball.vertices)])
    y, z = np.meshgrid(np.linspace(-0.004, 0.004, 5), np.linspace(-0.004, 0.004, 5))
    patch = np.stack([np.full(y.size, -gap / 2 - 0.0025), y.ravel(), z.ravel()], 1)
    g = np.arange(y.size).reshape(y.shape)
    quads = np.stack([g[:-1, :-1], g[:-1, 1:], g[1:, 1:], g[1:, :-1]], -1).reshape(-1, 4)
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    index = MeshIndex(v[: len(ball.vertices)], ball.faces)  # bound to the first ball
    _, tri, bary = index.closest(patch)
    surface = collide.Surface.of(v, f, collide.incidence(f, len(v)), incident_faces(f, len(v)))

    def resolved():
        c = collide.GarmentCollider(faces, len(patch), 0.006, ball.faces[tri], bary)
        c.resolve(patch + [0, 0, 0.2], surface, calibrate=True)  # at rest the cloth is clear
        return c.resolve(patch, surface)

    out = resolved()
    assert (winding_numbers(v, f, patch) > 0.5).all()
    assert (winding_numbers(v, f, out) < 0.5).all() and (np.abs(out[:, 0]) < gap / 2).all()
    monkeypatch.setattr(collide, "SETTLE_ROUNDS", 0)
    assert (winding_numbers(v, f, resolved()) > 0.5).mean() > 0.5


def _tube(radius, rings: int = 41, segments: int = 32):
    """A vertical open tube, y in [0, 1], radius(y), outward-wound."""
    y, a = np.linspace(0, 1, rings), np.linspace(0, 2 * np.pi, segments, endpoint=False)
    r = radius(y)
    v = np.stack([np.outer(r, np.sin(a)), np.repeat(y[:, None], segments, 1), np.outer(r, np.cos(a))], -1)
    i, j = np.meshgrid(np.arange(rings - 1) * segments, np.arange(segments), indexing="ij")
    p, q = (i + j).ravel(), (i + (j + 1) % segments).ravel()
    return v.reshape(-1, 3), np.concatenate([np.stack([p, q, p + segments], 1), np.stack([q, q + segments, p + segments], 1)])


def test_hang_columns_hangs_cloth_from_what_is_above_at_its_slope():
    """``garments.hang_columns`` on tubes with a 2 cm bulge and a 2 cm groove (columns 2.9 cm
    apart round them: each hangs from its own alone): every column that moves straight out
    (front and back, and 6 cm or more to the side) has the radius cloth hanging at the slope
    from the points above it would have, max(r(y), max over y' > y of r(y') - slope (y' - y)),
    written out here; no point moves in, up or down, and elsewhere none moves out past it."""
    from synmitsuba.body.garments import hang_columns
    slope = 0.1
    for sign in (1, -1):
        v, f = _tube(lambda y: 0.15 + sign * 0.02 * np.exp(-((y - 0.5) / 0.05) ** 2))
        out = hang_columns(v, f, np.ones(len(v), bool), slope)
        r0, r1, y = np.hypot(v[:, 0], v[:, 2]), np.hypot(out[:, 0], out[:, 2]), v[:, 1]
        assert np.allclose(out[:, 1], y)
        ys, ring = np.unique(y, return_inverse=True)
        r = np.array([r0[ring == k].mean() for k in range(len(ys))])
        hang = np.array([max(r[k], (r[k:] - slope * (ys[k:] - ys[k])).max()) for k in range(len(ys))])
        radial = (np.abs(v[:, 0]) < 1e-9) | (np.abs(v[:, 0]) >= 0.06)
        assert radial.sum() > len(v) / 3
        np.testing.assert_allclose(r1[radial], hang[ring][radial], atol=1e-5)  # to 10 um: it stops under that
        assert (hang - r).max() > 0.004  # it did hang somewhere
        assert (r1 >= r0 - 1e-12).all() and (r1 <= hang[ring] + 1e-5).all()


def test_a_top_over_a_skirt_is_tucked_at_the_waist(human):
    """With ``tuck`` (the outfit has a skirt) a long top ends TUCK under the waist, inside the
    skirt's band, instead of down in its flare; without it, where its length says."""
    from synmitsuba.body.garments import TUCK, GarmentParams, build_garment
    g = GarmentParams(kind="tshirt", length=0.7)
    r = human.regions
    low = {t: build_garment(human.body, r, human.split, g, tuck=t).vertices[:, 1].min() for t in (False, True)}
    assert low[True] == pytest.approx(r.waist_y - TUCK, abs=0.012) and low[False] < r.waist_y - TUCK - 0.05


def test_a_skirt_is_dressed_over_the_top_tucked_into_it():
    """Tucked in, a top is under its skirt all the way down: a horizontal ray from the body's
    axis out to any skirt vertex at the top's heights crosses the top's shell once (the skirt
    is outside it), and the skirt's waistband stands further out than the top. Before, the top
    was dressed over the skirt's band and its tucked end ran inside the flare: the two crossed."""
    from reference import crossings
    recipe = sm.sample_subject(np.random.default_rng(12), {"outfit": ["longsleeve", "skirt"], "jacket": False,
                                                           "shoes": False, "texture_size": 64})
    h = sm.build_subject(recipe)
    top, skirt = (next(m for m in h.garments if m.params.kind == k) for k in ("longsleeve", "skirt"))
    assert skirt.offset >= top.offset + 0.004
    tri = top.vertices[top.faces[:len(top.faces) - top.hem[0]]]  # its shell, not the turned-in hem band
    torso = h.body.vertices[h.regions.group == "torso"]
    low = top.vertices[:, 1].min() + 0.005
    checked = 0
    for p in skirt.vertices[skirt.vertices[:, 1] > low]:
        ring = torso[np.abs(torso[:, 1] - p[1]) < 0.01]
        origin = np.array([ring[:, 0].mean() + 0.001, p[1], ring[:, 2].mean()])  # off the mirror plane's seam
        d = p - origin
        n = crossings(origin, d[None] / np.linalg.norm(d), tri, np.array([np.linalg.norm(d)]))[0]
        assert n == 1, (p, n)
        checked += 1
    assert checked >= 48  # two rings of the band at least


def test_a_straight_cut_is_vented_up_the_centre_back_and_no_other_cut_opens(human):
    """A straight skirt's only openings besides its waist and hem run up its centre back from
    the hem for its cut's vent (to the ring at or above it); its two edges stand apart, so a
    weld (the cloth stage's) leaves it open. Unvented, a stride stretched a straight hem 9-15 cm."""
    from synmitsuba.body.garments import SKIRT_CUTS, GarmentParams, _flare, open_edges
    from synmitsuba.body.topology import weld
    r = human.regions
    for name, cut in SKIRT_CUTS.items():
        v, f, _ = _flare(human.body, r, GarmentParams(kind="skirt", ease=0.01, length=0.6, cut=name), 0.006, r.waist_y)
        ends = np.unique(open_edges(f, weld(v)))
        top, hem = v[:, 1].max(), v[:, 1].min()
        slit = ends[(v[ends, 1] > hem + 1e-9) & (v[ends, 1] < top - 1e-9)]
        if not cut.vent:
            assert not len(slit), name
            continue
        spacing = (top - hem) / 13
        assert cut.vent <= np.ptp(v[slit, 1]) + spacing < cut.vent + spacing + 1e-9, name  # up to the vent's ring
        centre = v[:, [0, 2]].mean(0)
        assert (v[slit, 2] < centre[1]).all() and (np.abs(v[slit, 0] - centre[0]) < 0.03).all(), name  # at the back
        edges = slit[v[slit, 1] < v[slit, 1].max() - 1e-9]  # under the point where the two edges meet
        sides = np.sign(v[edges, 0] - v[slit[np.argmax(v[slit, 1])], 0])
        assert (sides != 0).all() and sides.sum() == 0, name  # both edges, apart


@pytest.mark.parametrize("density", [1, 2])
def test_a_coats_skirt_is_parted_down_the_front_under_its_top_ring(human, density):
    """A coat's skirt (``shell+parted``) is open down the centre front from its hem to under its
    top ring, its two edges apart (so the cloth stage's weld leaves it open: closed, a run's
    stride bunched it at the hips), and besides its waist and hem open only at its back vent;
    built for the cloth stage (``SIMULATED_DENSITY``) it is that skirt cut twice as fine each
    way (at one density its simulated walk folded 3.5x the skinned coat's, at two 14.5x)."""
    from synmitsuba.body.garments import (GARMENTS, SIMULATED_DENSITY, VENT_GAP, GarmentParams, _flare,
                                          build_garment, open_edges)
    from synmitsuba.body.topology import weld
    d = SIMULATED_DENSITY if density > 1 else 1
    r = human.regions
    g = GarmentParams(kind="coat", ease=0.01, length=0.5, cut="straight", thickness=GARMENTS["coat"].thickness[0])
    mesh = build_garment(human.body, r, human.split, g, density=d)
    closed = _flare(human.body, r, g, mesh.offset, r.hip_y, d)[0]
    v, f, _ = _flare(human.body, r, g, mesh.offset, r.hip_y, d, parted=True)
    end = len(mesh.vertices) - mesh.hem[1]
    assert np.allclose(mesh.vertices[end - len(v):end], v, atol=1e-6)  # the coat's skirt is this one
    if d > 1:
        coarse = _flare(human.body, r, g, mesh.offset, r.hip_y, 1, parted=True)[0]
        n, m = 48, 13  # the skinned skirt's points round and ring gaps
        fine = v[:(m * d + 1) * n * d].reshape(m * d + 1, n * d, 3)
        assert np.abs(fine[::d, ::d] - coarse[:(m + 1) * n].reshape(m + 1, n, 3)).max() < 0.006  # the same cut
    ends = np.unique(open_edges(f, weld(v)))
    top, hem = v[:, 1].max(), v[:, 1].min()
    slit = ends[(v[ends, 1] > hem + 1e-9) & (v[ends, 1] < top - 1e-9)]
    back = np.unique(open_edges(f, weld(closed)))
    back = back[(closed[back, 1] > hem + 1e-9) & (closed[back, 1] < top - 1e-9)]
    centre = v[:, [0, 2]].mean(0)
    front = slit[v[slit, 2] > centre[1]]
    assert len(slit) == len(front) + len(back) and len(back)  # the vent's as before, the rest at the front
    assert (np.abs(v[front, 0] - centre[0]) < 0.01).all()
    rings = 13 * d - 1  # between the top ring and the hem
    assert abs(v[front, 1].max() - (top - (top - hem) / (13 * d))) < 1e-9  # up to the ring under the top one
    assert len(front) == 2 * rings
    pairs = v[front[np.lexsort((v[front, 0], v[front, 1]))]].reshape(rings, 2, 3)  # each ring's two edges
    assert np.allclose(pairs[:, 1, 0] - pairs[:, 0, 0], 2 * VENT_GAP) and np.allclose(pairs[:, 0, 1:], pairs[:, 1, 1:])


def test_every_skirt_cut_has_its_folds_and_flare(human):
    """Each cut's rest skirt ring by ring: round the hem, the radius's harmonic at the cut's
    fold count has the amplitude its wave gives (a zigzag's first harmonic is 8/pi^2 of its
    half depth, a sine's all of it) and stands over every other harmonic from the 5th to twice
    the fold count; the stitched top ring has no folds; hems stand out in the order of the cuts'
    flare; no cut is the first cut (a_line), which is what a garment without a cut gets."""
    import dataclasses

    from synmitsuba.body.garments import SKIRT_CUTS, GarmentParams, _flare
    from synmitsuba.cloth.fabrics import FABRICS
    assert all(c.fabric is None or c.fabric in FABRICS for c in SKIRT_CUTS.values())
    r = human.regions
    hem_radius = {}
    for name, cut in SKIRT_CUTS.items():
        g = GarmentParams(kind="skirt", ease=0.01, length=0.6, cut=name)
        v, _, _ = _flare(human.body, r, g, 0.006, r.waist_y)
        n = 6 * cut.folds or 48  # each ring's first point comes again after the rings (the uv seam's copies)
        rings = v[:14 * n].reshape(14, n, 3)
        assert np.array_equal(v[14 * n:14 * n + 14], rings[:, 0]) and (len(v) == 14 * n + 14) == (cut.vent == 0)
        assert np.allclose(rings[..., 1], rings[:, :1, 1])  # level rings
        radius = [np.hypot(*(ring[:, [0, 2]] - ring[:, [0, 2]].mean(0)).T) for ring in rings]
        hem_radius[name] = radius[-1].mean()
        if not cut.folds:
            continue
        amp = np.abs(np.fft.rfft(radius[-1])) * 2 / n
        expected = 0.5 * cut.depth * (8 / np.pi ** 2 if cut.sharp else 1.0)
        assert amp[cut.folds] == pytest.approx(expected, rel=0.25), name
        others = np.delete(amp[5:2 * cut.folds], cut.folds - 5)
        assert others.max() < 0.35 * amp[cut.folds], name
        assert np.abs(np.fft.rfft(radius[0]))[cut.folds] * 2 / n < 1e-3, name
    assert hem_radius["straight"] < hem_radius["a_line"] < hem_radius["circle"]
    plain = GarmentParams(kind="skirt", ease=0.01, length=0.6)
    assert np.array_equal(_flare(human.body, r, plain, 0.006, r.waist_y)[0],
                          _flare(human.body, r, dataclasses.replace(plain, cut="a_line"), 0.006, r.waist_y)[0])


def test_skirts_and_dresses_are_drawn_cuts_and_nothing_else_is():
    """300 sampled subjects: every skirt and dress has a cut, at least three cuts are drawn,
    no other garment has one; the cut comes from the garment's own texture seed, so fixing the
    outfit to a skirt draws the same person with or without cuts drawn; a cut that is no cut is
    an error naming it."""
    from synmitsuba.body.garments import GARMENTS, SKIRT_CUTS, GarmentParams, sample_skirt_cut
    seen = set()
    for i in range(300):
        for g in sm.sample_subject(np.random.default_rng(i)).garments:
            cut = GARMENTS[g.kind].skirted and not GARMENTS[g.kind].cut  # a shift has its own
            assert (g.cut in SKIRT_CUTS) if cut else g.cut is None, (i, g.kind, g.cut)
            seen.add(g.cut)
    assert len(seen - {None}) >= 3
    g = GarmentParams(kind="skirt")
    assert sample_skirt_cut(g).cut == sample_skirt_cut(g).cut and sample_skirt_cut(g).texture == g.texture
    with pytest.raises(ValueError, match=r"garments\[0\]\.cut.*'godet'"):
        sm.SubjectRecipe.from_dict({"garments": [{"kind": "skirt", "cut": "godet"}]})


def _dressed(outfit: list, seed: int = 3):
    recipe = sm.sample_subject(np.random.default_rng(seed), {"outfit": outfit, "jacket": False, "shoes": False,
                                                             "accessories": [], "texture_size": 64})
    h = sm.build_subject(recipe)
    return h, {p.name: p for p in h.parts}


def test_a_tank_top_leaves_the_arms_bare_but_for_a_strap_over_each_shoulder():
    """Measured on the built mesh: no tank vertex is closest to an arm vertex a third of the way
    down the arm (the inner arm lies against the chest under the armpit), and none lies out past
    the shoulder joint over the armpit; from 1 cm under the neck's base up the tank is one strap
    a side, at most 5 cm wide, between the neck and the shoulder joint, running (that wide) from
    the front over to the back; at the front and the back its top is a scoop 8 cm or more under the neck's
    base, and a U: the front's top edge rises from the centre towards the straps (it was one level
    cut, its corners at the straps stepped)."""
    from scipy.spatial import cKDTree
    from synmitsuba.body.garments import TANK_STRAP
    h, parts = _dressed(["tank", "shorts"])
    r, tank = h.regions, parts["tank"].rest
    _, near = cKDTree(h.body.vertices).query(tank)
    assert r.arm_s[near].max() < 0.3
    ax, nz = np.abs(tank[:, 0] - r.neck_xz[0]), r.neck_xz[1]
    assert ax[tank[:, 1] > r.shoulder[1] - 0.05].max() < r.shoulder[0]
    over = tank[:, 1] > r.neck_y - 0.01
    for side in (1, -1):
        strap = tank[over & (np.sign(tank[:, 0] - r.neck_xz[0]) == side)]
        a = np.abs(strap[:, 0] - r.neck_xz[0])
        assert np.ptp(a) < 2 * TANK_STRAP + 0.015 and r.neck_radius < a.min() and a.max() < r.shoulder[0]
        down = tank[(tank[:, 1] > r.shoulder[1] - 0.03) & (np.sign(tank[:, 0] - r.neck_xz[0]) == side)
                    & (ax >= a.min()) & (ax <= a.max())]  # the strap's width, further down
        assert down[:, 2].min() < nz - 0.03 and down[:, 2].max() > nz + 0.03  # front to back
    centre = ax < 0.03
    for front in (True, False):
        mid = tank[centre & ((tank[:, 2] > nz) == front)]
        assert mid[:, 1].max() < r.neck_y - 0.08
    ahead = tank[:, 2] > nz + 0.03
    edge = [tank[ahead & (ax >= lo) & (ax < lo + 0.01), 1].max() for lo in (0.0, 0.02, 0.04, 0.06)]
    assert np.all(np.diff(edge) > 0) and edge[-1] - edge[0] > 0.02, edge


def _front_centre(r, v: np.ndarray, y: float) -> np.ndarray:
    """Vertices of ``v`` within 2 cm of the body's centre line in front, 1.5 cm either side of ``y``."""
    nx, nz = r.neck_xz
    return v[(np.abs(v[:, 1] - y) < 0.015) & (v[:, 2] > nz) & (np.abs(v[:, 0] - nx) < 0.02)]


def test_a_coat_opens_in_a_v_over_the_top_and_hangs_to_the_knees():
    """The coat's front: nothing within 2 cm of the centre line at mid-chest (the V shows the top
    under it, which is there), closed again 35 cm under the neck; its hem 30 cm or more under
    the hips; every coat vertex outside the t-shirt's and the trousers' surfaces' reach from the
    body (the layers nest)."""
    h, parts = _dressed(["tshirt", "trousers", "coat"])
    r, coat, shirt = h.regions, parts["coat"].rest, parts["tshirt"].rest
    assert len(_front_centre(r, coat, r.neck_y - 0.12)) == 0 and len(_front_centre(r, shirt, r.neck_y - 0.12)) > 0
    assert len(_front_centre(r, coat, r.neck_y - 0.35)) > 0
    assert coat[:, 1].min() < r.hip_y - 0.3
    d = {k: signed_distance(h.body.vertices, h.body.faces, parts[k].rest) for k in ("tshirt", "trousers", "coat")}
    assert np.median(d["coat"]) > np.median(d["tshirt"]) and np.median(d["coat"]) > np.median(d["trousers"])


def test_a_blazer_opens_in_a_v_to_its_buttons_and_ends_at_the_hips_and_joggers_above_the_ankles():
    """The blazer's front: nothing within 2 cm of the centre line 24 cm under the neck (the top
    under it shows there), closed 42 cm under it; its hem between the crotch and the waist; its
    median distance from the body past the long sleeve's under it. Joggers end above the ankle
    joint, where trousers on the same body reach past it."""
    h, parts = _dressed(["longsleeve", "joggers", "blazer"])
    r, blazer, shirt = h.regions, parts["blazer"].rest, parts["longsleeve"].rest
    assert len(_front_centre(r, blazer, r.neck_y - 0.24)) == 0 and len(_front_centre(r, shirt, r.neck_y - 0.24)) > 0
    assert len(_front_centre(r, blazer, r.neck_y - 0.42)) > 0
    assert r.crotch_y - 0.15 < blazer[:, 1].min() < r.waist_y
    d = {k: signed_distance(h.body.vertices, h.body.faces, parts[k].rest) for k in ("longsleeve", "blazer")}
    assert np.median(d["blazer"]) > np.median(d["longsleeve"])
    ankle = h.skeleton.rest_positions[h.skeleton.index("foot.L"), 1]
    assert parts["joggers"].rest[:, 1].min() > ankle
    _, trousers = _dressed(["longsleeve", "trousers"])
    assert trousers["trousers"].rest[:, 1].min() < ankle


def test_a_shirt_has_a_collar_standing_round_the_neck_and_open_at_the_front():
    """Measured on the built mesh against the body's own neck: behind the neck (more than 150
    degrees from straight ahead round its axis) the shirt rises 2.5 cm or more over a t-shirt's
    crew neckline on the same body; every shirt vertex over the neck's base is outside the body
    (positive signed distance) and none is within the front's opening (less than 20 degrees
    either side of straight ahead)."""
    h, parts = _dressed(["shirt", "trousers"])
    r, shirt = h.regions, parts["shirt"].rest
    nx, nz = r.neck_xz
    dx, dz = shirt[:, 0] - nx, shirt[:, 2] - nz
    up = shirt[:, 1] > r.neck_y
    assert signed_distance(h.body.vertices, h.body.faces, shirt[up]).min() > 0
    assert not (up & (np.abs(np.degrees(np.arctan2(dx, dz))) < 20)).any()
    _, tee = _dressed(["tshirt", "trousers"])

    def behind(v):
        return v[np.abs(np.degrees(np.arctan2(v[:, 0] - nx, v[:, 2] - nz))) > 150, 1].max()
    assert behind(shirt) > behind(tee["tshirt"].rest) + 0.025


def test_a_hoodie_has_a_hood_lying_down_the_back_outside_its_own_body():
    """Measured against a long sleeve on the same body: behind the neck (more than 150 degrees
    from straight ahead round its axis), 10 to 20 cm under the neck's base, the hoodie reaches
    1 cm or more farther from the body (the hood lies over its own back); it rises 2 cm or more
    higher there (the hood rolls up round the neck); nothing above the neck's base is inside
    the body or within 25 degrees of straight ahead (the hood's front edges come down flat to
    the neckline where they meet)."""
    h, parts = _dressed(["hoodie", "jeans"])
    _, plain = _dressed(["longsleeve", "jeans"])
    r = h.regions
    nx, nz = r.neck_xz

    def behind(v):
        return v[np.abs(np.degrees(np.arctan2(v[:, 0] - nx, v[:, 2] - nz))) > 150]
    hood, shell = behind(parts["hoodie"].rest), behind(plain["longsleeve"].rest)

    def reach(v):
        band = v[(v[:, 1] < r.neck_y - 0.1) & (v[:, 1] > r.neck_y - 0.2)]
        return signed_distance(h.body.vertices, h.body.faces, band).max()
    assert reach(hood) > reach(shell) + 0.01
    assert hood[:, 1].max() > shell[:, 1].max() + 0.02
    v = parts["hoodie"].rest
    up = v[:, 1] > r.neck_y
    assert signed_distance(h.body.vertices, h.body.faces, v[up]).min() > 0
    assert not (up & (np.abs(np.degrees(np.arctan2(v[:, 0] - nx, v[:, 2] - nz))) < 25)).any()


def _neck_strip(h, kind: str, rings: int, n_seg: int = 40) -> np.ndarray:
    """The collar's or hood's band of garment ``kind``: (rings, n_seg, 3), the last vertices
    its shape builds before the hem (``garments._strip`` lays them ring after ring)."""
    g = next(m for m in h.garments if m.params.kind == kind)
    n = len(g.vertices) - g.hem[1]
    return g.vertices[n - rings * n_seg:n].reshape(rings, n_seg, 3)


def _ends_and_back(h, band: np.ndarray, within: float) -> int:
    """Checks that the band's two ends leave its base within ``within`` degrees of straight
    ahead round the neck's axis and that one column lies behind the neck; returns that column."""
    nx, nz = h.regions.neck_xz
    turn = np.degrees(np.arctan2(band[0, :, 0] - nx, band[0, :, 2] - nz))
    back = int(np.argmax(np.abs(turn)))
    assert np.abs(turn[[0, -1]]).max() < within and abs(turn[back]) > 170
    return back


def test_a_shirt_collars_points_reach_down_onto_the_chest():
    """The collar's fall edge (its last ring) at the two points, either side of the opening,
    lies 3 cm or more lower under its base than it does behind the neck, and within 1 cm of the
    shirt's own shell there (lying on it, not standing off the neck as a funnel)."""
    from scipy.spatial import cKDTree
    h, _ = _dressed(["shirt", "trousers"])
    band = _neck_strip(h, "shirt", 5)
    points, back = [0, -1], _ends_and_back(h, band, 35)
    drop = band[-1, :, 1] - band[0, :, 1]
    assert (drop[points] < drop[back] - 0.03).all()
    g = next(m for m in h.garments if m.params.kind == "shirt")
    shell = g.vertices[:len(g.vertices) - g.hem[1] - band.size // 3]
    assert (cKDTree(shell).query(band[-1, points])[0] < 0.01).all()


def test_a_hoods_edges_meet_flat_at_the_front():
    """The hood's two front edges (its band's first and last columns) leave the neckline
    within 10 degrees of straight ahead, and there rise under 1 cm over their base (the hood
    rolls 3 cm or more higher behind the neck): flat edges meeting in a V, not a cowl."""
    h, _ = _dressed(["hoodie", "jeans"])
    band = _neck_strip(h, "hoodie", 9)
    edges, back = [0, -1], _ends_and_back(h, band, 10)
    rise = (band[:, :, 1] - band[0, :, 1]).max(0)
    assert rise[edges].max() < 0.01 and rise[back] > 0.03


def test_a_shift_is_straight_and_sleeveless_a_wrap_opens_in_a_v_and_a_jumpsuit_is_one_piece():
    """A shift: no vertex nearest an arm past the shoulder (arm_s > 0.3), its skirt's radius at
    the hem within 6 cm of its radius at the hips (an A-line of the same length flares more); a
    wrap: nothing within 2 cm of the front centre 10 cm under the neck, cloth there at the back;
    a jumpsuit: one connected surface covering the chest, both thighs and both shins."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree
    for kind in ("shift", "wrap"):
        h, parts = _dressed([kind])
        r, v = h.regions, parts[kind].rest
        if kind == "shift":
            _, near = cKDTree(h.body.vertices).query(v)
            assert r.arm_s[near].max() < 0.3
            def spread(y):
                ring = v[np.abs(v[:, 1] - y) < 0.02]
                return np.ptp(ring[:, 0]) / 2
            low = v[:, 1].min() + 0.03
            assert spread(low) - spread(r.hip_y - 0.05) < 0.06
        else:
            y = r.neck_y - 0.1
            band = v[np.abs(v[:, 1] - y) < 0.015]
            ax = np.abs(band[:, 0] - r.neck_xz[0])
            assert not ((ax < 0.02) & (band[:, 2] > r.neck_xz[1])).any()
            assert ((ax < 0.02) & (band[:, 2] < r.neck_xz[1])).any()
    h, parts = _dressed(["jumpsuit"])
    p = parts["jumpsuit"]
    from synmitsuba.body.topology import weld
    ids = weld(p.rest)[p.faces]
    n = len(p.rest)
    adj = sp.coo_matrix((np.ones(ids.size), (ids.ravel(), np.roll(ids, 1, 1).ravel())), shape=(n, n))
    _, label = connected_components(adj, directed=False)
    used = np.unique(ids)
    assert len(np.unique(label[used])) == 1
    from scipy.spatial import Delaunay
    r, b = h.regions, h.body.vertices
    for group, s in (("torso", None), ("upperleg", (0.2, 0.6)), ("lowerleg", (0.3, 0.6))):
        mask = r.group == group
        if s:
            mask &= (r.leg_s > s[0]) & (r.leg_s < s[1])
        else:
            mask &= np.abs(b[:, 1] - (r.neck_y - 0.25)) < 0.05
        for side in (1, -1):  # covered: inside the outline of the jumpsuit's own points round it at its height
            rows = np.flatnonzero(mask & (np.sign(b[:, 0]) == side))[::7]
            own = p.rest[np.sign(p.rest[:, 0]) == side]
            rings = [own[np.abs(own[:, 1] - b[k, 1]) < 0.01][:, [0, 2]] for k in rows]
            covered = [len(ring) > 3 and Delaunay(ring).find_simplex(b[k, [0, 2]]) >= 0 for k, ring in zip(rows, rings)]
            assert np.mean(covered) > 0.95, (group, side, np.mean(covered))


def test_drawn_outfits_come_in_styles_and_named_ones_as_named():
    """300 sampled subjects: each style is drawn near its share of its kind's garments; jeans
    are denim, chinos, joggers, coats and blazers in their palettes, sweaters knitted; a coat only over trousers (its skirt would cut
    through a skirt); a style changes a garment's kind and texture, nothing else; an outfit
    named in the config is worn as named."""
    import dataclasses
    from synmitsuba.body.garments import CHINO, DENIM, GARMENT_STYLES, HEATHER, SHIRTING, SUITING, WOOL, sample_style
    palettes = {"jeans": DENIM, "coat": WOOL, "chinos": CHINO, "joggers": HEATHER, "blazer": SUITING, "shirt": SHIRTING}
    hoodies = []
    counts: dict = {}
    for i in range(300):
        r = sm.sample_subject(np.random.default_rng(i))
        kinds = [g.kind for g in r.garments]
        for g in r.garments:
            counts[g.kind] = counts.get(g.kind, 0) + 1
            if g.kind in palettes:
                assert list(g.texture.base_lab) in [list(map(float, c)) for c in palettes[g.kind]]
            if g.kind == "coat":
                assert {"jeans", "trousers", "chinos", "joggers"} & set(kinds)
            if g.kind == "sweater":
                assert g.texture.bump == "knit"
            if g.kind == "hoodie":
                hoodies.append(list(g.texture.base_lab) in [list(map(float, c)) for c in HEATHER])
    for base, styles in GARMENT_STYLES.items():
        for st in styles:
            total = counts.get(base, 0) + sum(counts.get(x.kind, 0) for x in styles)
            if st.kind != "coat":  # a coat's share is of jackets over trousers only
                sigma = np.sqrt(st.share * (1 - st.share) / total)  # a binomial share's spread
                assert abs(counts.get(st.kind, 0) / total - st.share) < 3 * sigma + 0.02, (st.kind, counts)
            assert counts.get(st.kind, 0) > 0
    assert 0.3 < np.mean(hoodies) < 0.9  # heathered fleece, or the garment's own colour
    g = sm.sample_subject(np.random.default_rng(0)).garments[0]
    for kind in ("tshirt", "longsleeve", "trousers"):
        styled = [sample_style(dataclasses.replace(g, kind=kind, texture=dataclasses.replace(g.texture, seed=s)),
                               [kind]) for s in range(40)]
        assert {x.kind for x in styled} == {kind} | {st.kind for st in GARMENT_STYLES[kind]}
        for x in styled:
            assert (x.size, x.ease, x.length, x.thickness, x.texture.seed) == (g.size, g.ease, g.length, g.thickness,
                                                                               x.texture.seed)
    for i in range(20):
        r = sm.sample_subject(np.random.default_rng(i), {"outfit": ["tshirt", "trousers", "longsleeve"]})
        assert [x.kind for x in r.garments][:3] == ["tshirt", "trousers", "longsleeve"]


def test_a_skirt_hangs_from_both_legs_through_a_stride():
    """Below the hips a skirt's weights mix the left and right legs' by side: the front and back
    centre follow both legs half and half, the sides one leg each (bones named .L and .R here).
    Through a run, the 99.5th percentile of its edges' stretch stays under 8 (closest-point
    binding gave each point one leg: the front tore open between the legs, at 19-24 times)."""
    from synmitsuba.motion.retargeting import retarget
    from synmitsuba.motion.sources import load_motion
    h = sm.build_subject(sm.sample_subject(np.random.default_rng(2), {"outfit": ["tshirt", "skirt"],
                                                                      "texture_size": 64}))
    part = next(p for p in h.parts if p.name == "skirt")
    v, W, names = part.rest, part.weights, h.skeleton.names
    left = np.array([n.endswith(".L") for n in names])
    right = np.array([n.endswith(".R") for n in names])
    low = v[:, 1] < h.regions.hip_y - 0.15
    cx = v[low, 0].mean()
    centre = low & (np.abs(v[:, 0] - cx) < 0.01)
    sides = low & (np.abs(v[:, 0] - cx) > 0.9 * np.abs(v[low, 0] - cx).max())
    assert centre.sum() >= 4 and sides.sum() >= 4
    np.testing.assert_allclose(W[centre][:, left].sum(1), W[centre][:, right].sum(1), atol=0.1)
    assert (np.minimum(W[sides][:, left].sum(1), W[sides][:, right].sum(1)) < 0.02).all()
    f = part.faces
    e = np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), 1), axis=0)
    e = e[(v[e, 1] < h.regions.hip_y - 0.05).all(1)]
    rest = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    m = retarget(load_motion("run", np.random.default_rng(2), seconds=1.0), h.skeleton)
    k = [p.name for p in h.parts].index("skirt")
    for fr in range(0, m.n_frames, 2):
        p = h.pose(*m.frame(fr), resolve=False)[k].vertices
        assert np.percentile(np.linalg.norm(p[e[:, 0]] - p[e[:, 1]], axis=1) / rest, 99.5) < 8.0, fr


def test_fabric_normal_maps_tile_at_thread_scale(sm):
    """Each fabric's normal map decodes to unit normals leaning at most 60 degrees, tilted both
    ways on average to the flat normal, joins its own edges; rendered on a flat square under
    grazing light with the map repeated 16 and then 8 times, the shading's strongest
    frequencies across the image are multiples of the repeat (a flat map shades flat)."""
    from synmitsuba.body.textures import FABRICS, fabric_normal_map
    from synmitsuba.scene.materials import DirectionalLight, Material
    for fabric in FABRICS[1:]:
        n = 2 * fabric_normal_map(fabric).astype(np.float64) - 1
        assert np.allclose(np.linalg.norm(n, axis=-1), 1, atol=1e-5) and n[..., 2].min() > np.cos(np.radians(60)) - 1e-6
        assert np.abs(n[..., :2].mean((0, 1))).max() < 0.02
        jump = np.abs(np.roll(n, 1, 0) - n).max(-1)
        assert jump[0].max() <= jump.max() and jump[:, 0].max() <= np.abs(np.roll(n, 1, 1) - n).max()

    def render(normal_map, repeat):
        s = sm.Scene()
        v = np.array([[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]], float)
        s.add_mesh("cloth", v, np.array([[0, 2, 1], [0, 3, 2]]), uv=np.array([[0, 1], [1, 1], [1, 0], [0, 0]], float),
                   material=Material(base_color=(0.8, 0.8, 0.8), normal_map=normal_map, normal_map_repeat=repeat))
        s.add_light(DirectionalLight(direction=(-1.0, -0.6, 0.0)))
        cam = sm.Camera.look_at(eye=(0, 4, 0), target=(0, 0, 0), up=(0, 0, -1), width=64, height=64,
                                fov_y_deg=2 * np.degrees(np.arctan(0.5 / 4)))
        return sm.render(s, cam, spp=8, seed=0).rgb.mean(-1)
    for repeat in (16, 8):
        img = render(fabric_normal_map("plain"), (float(repeat), float(repeat)))
        for axis in (0, 1):
            spectrum = np.abs(np.fft.rfft(img - img.mean(axis=1 - axis, keepdims=True), axis=axis)).mean(1 - axis)
            assert (1 + np.argmax(spectrum[1:])) % repeat == 0
        assert img.std() > 0.05
    assert render(None, (16.0, 16.0)).std() < 1e-6


def test_duplicate_accessories_are_distinct_shapes_that_both_render(sm):
    recipe = sm.sample_subject(np.random.default_rng(3), {"texture_size": 64, "accessories": ["watch", "watch"]})
    human = sm.build_subject(recipe)
    scene = sm.Scene()
    human.add_to(scene, instance=1, prefix="s")
    watches = sorted(n for n in scene.meshes if "watch" in n)
    assert watches == ["s_watch", "s_watch_2"]
    cam = sm.Camera.look_at(eye=(0, 1, 3), target=(0, 1, 0), width=32, height=32)
    sm.render(scene, cam, spp=1)
    from synmitsuba.engine.build import cached_build
    loaded = {shape.id() for shape in cached_build(scene).mi_scene.shapes()}
    assert {"s_watch", "s_watch_2"} <= loaded  # before, the second overwrote the first's vertices
    assert len(scene.meshes["s_watch"].vertices) == len(scene.meshes["s_watch_2"].vertices) > 0


def test_accessories_are_worn_as_often_as_in_the_street():
    """300 random recipes: glasses on about a third of people, a face mask or headphones on few
    (each kind at 0.22 once put a mask on one in five), never a cap over headphones."""
    recipes = [sm.sample_subject(np.random.default_rng(5000 + seed)) for seed in range(300)]
    worn = [{a.kind for a in r.accessories} for r in recipes]
    share = {k: float(np.mean([k in w for w in worn])) for k in ("glasses", "mask", "headphones", "cap", "backpack")}
    assert 0.22 <= share["glasses"] <= 0.38, share  # 0.3 +- 3 binomial sd
    assert share["mask"] <= 0.06 and share["headphones"] <= 0.1 and 0.06 <= share["cap"] <= 0.18, share
    assert 0.13 <= share["backpack"] <= 0.27, share
    assert not any({"cap", "headphones"} <= w for w in worn)
    frames = [a.frame for r in recipes for a in r.accessories if a.kind == "glasses"]
    assert None not in frames and "round" not in frames and len(set(frames)) >= 4, frames  # the old loud ring is kept for old recipes only


def test_every_glasses_frame_leaves_the_eyes_open():
    """Each frame built on one head, measured in the head's frame: its rims are tubes of the
    frame's radius (front depth 2 x rim), centred on the eyes, and no rim vertex comes within
    10 mm of an eye centre in the lens plane (an iris, ~6 mm in radius, shows whole), so thin
    and thick frames alike leave the eyes to a detector."""
    from synmitsuba.body.accessories import GLASSES_FRAMES, AccessoryParams, build_accessory
    from synmitsuba.geometry import frame
    h = sm.build_subject(sm.sample_subject(np.random.default_rng(7), {"accessories": [], "texture_size": 64}))
    R = frame(h.head.forward, h.head.up)
    eyes = (h.keypoints()[[1, 2]] - h.head.centre) @ R
    for name, fr in GLASSES_FRAMES.items():
        v, _ = build_accessory(AccessoryParams("glasses", frame=name), h.body, h.head)
        local = (v - h.head.centre) @ R
        front = local[local[:, 2] > local[:, 2].max() - 2.2 * fr.rim]
        assert np.ptp(front[:, 2]) == pytest.approx(2 * fr.rim, rel=0.1), name
        for eye in eyes:
            rim = front[np.abs(front[:, 0] - eye[0]) < 0.03]
            assert abs(rim[:, 1].mean() - eye[1]) < 0.003, name
            assert np.hypot(*(front[:, :2] - eye[:2]).T).min() > 0.010, name
