"""Shoes (body/shoes.py): soles on the ground, the foot inside the shoe at rest and in motion,
styles sampled with the outfit, the sole's and the upper's colours where uv puts them."""
from __future__ import annotations

import numpy as np
import pytest
from reference import named_as, point_triangle_distances, winding_numbers

import synmitsuba as sm
from synmitsuba.body.garments import FOOTWEAR, GARMENTS
from synmitsuba.body.shoes import BACK, SHOE_STYLES, SOLE_V, UPPER_V

STYLES = tuple(SHOE_STYLES)


def test_a_walk_in_heels_rolls_its_feet_less():
    """Composition's walk (``retargeted_clip``) in heels bends the toes up against the foot no
    further than the same walk in flat shoes does at toe-off, within 2 degrees (the heel's
    pitch already bends them); with a bare foot's roll the heels bent them 16 degrees further. The foot's pitch
    against the ground swings over a smaller range (heel strike to toe-off)."""
    from synmitsuba.compose.subjects import MotionSpec, retargeted_clip

    def bend(human, clip, joint: str) -> np.ndarray:
        R = clip.rotations[:, human.skeleton.index(joint)]
        return np.degrees(np.arccos(np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1)))

    spec = MotionSpec("walk", 0, 1.0, 30.0)
    heeled, flat = _subject("heels"), _subject("sneakers")
    ours, theirs = retargeted_clip(heeled, spec), retargeted_clip(flat, spec)
    full = sm.retarget_to_subject(spec.clip(), heeled)
    toes = [bend(heeled, ours, "toe3-1.L").max(), bend(flat, theirs, "toe3-1.L").max(), bend(heeled, full, "toe3-1.L").max()]
    assert toes[0] <= toes[1] + 2.0 and toes[2] > toes[1] + 10.0, toes
    G = [c.global_rotations()[:, heeled.skeleton.index("foot.L")] for c in (ours, full)]
    pitch = [np.degrees(np.arcsin(np.clip(g[:, 1, 2], -1, 1))) for g in G]  # toe up > 0, as bench/feet.py
    assert np.ptp(pitch[0]) < 0.6 * np.ptp(pitch[1]), [np.ptp(p) for p in pitch]


def _subject(kind: str, seed: int = 4):
    recipe = sm.sample_subject(np.random.default_rng(seed), {"outfit": ["tshirt", "shorts", kind], "jacket": False,
                                                             "accessories": [], "texture_size": 64})
    return sm.build_subject(recipe)


@pytest.fixture(scope="module", params=STYLES)
def shod(request):
    return request.param, _subject(request.param)


def _shoe(human):
    return next(p for p in human.parts if p.name in GARMENTS and GARMENTS[p.name].footwear)


def _foot(human, side: float):
    """The rest body's foot vertices on one side, from the body's own skinning weights (not the
    garment code's regions): the vertices the foot and toe bones move most."""
    sk, body = human.skeleton, human.body
    bones = np.array([("foot" in n or "toe" in n) for n in sk.names])
    mask = bones[body.weights.argmax(1)] & (np.sign(body.vertices[:, 0]) == side)
    return np.flatnonzero(mask)


def _covered(foot: np.ndarray, kind: str) -> np.ndarray:
    """Which of a foot's vertices (rest) the closed vamp covers: the front 40 %, or a pump's
    toes (its opening reaches ``vamp`` further over the instep)."""
    style = SHOE_STYLES[kind]
    start = max(0.6, style.throat + style.vamp / np.ptp(foot[:, 2]) + 0.05)
    return foot[:, 2] > foot[:, 2].min() + start * np.ptp(foot[:, 2])


def test_the_body_stands_on_the_sole_and_the_sole_on_the_ground(shod):
    kind, h = shod
    g = next(m for m in h.garments if m.params.kind == kind)
    shoe = _shoe(h)
    standing = {lay.name: lay for lay in h.pose(*h.standing(), resolve=False)}  # at rest, but on heels if any
    assert standing[kind].vertices[:, 1].min() == pytest.approx(0.0, abs=1e-5)
    assert h.body.vertices[:, 1].min() == pytest.approx(g.params.thickness, abs=2e-3)
    sole = shoe.uv[:, 1] < (SOLE_V + UPPER_V) / 2
    flat = shoe.rest[sole & (np.abs(shoe.rest[:, 1]) < 1e-9)]  # the sole's bottom (a heel reaches below it)
    for side in (1.0, -1.0):  # the footprint spans the foot, from behind the heel to past the toes
        foot = h.body.vertices[_foot(h, side)]
        print_ = flat[np.sign(flat[:, 0]) == side]
        assert print_[:, 2].min() == pytest.approx(foot[:, 2].min() - BACK, abs=3e-3)
        assert print_[:, 2].max() == pytest.approx(foot[:, 2].max() + SHOE_STYLES[kind].toe, abs=3e-3)


def test_at_rest_every_shoe_vertex_is_outside_the_foot_and_the_forefoot_inside_the_shoe(shod):
    kind, h = shod
    shoe = _shoe(h)
    body = h.body
    for side in (1.0, -1.0):
        ids = _foot(h, side)
        near = np.isin(body.faces, ids).any(1)
        pts = shoe.rest[np.sign(shoe.rest[:, 0]) == side]
        tri = body.vertices[body.faces[near]]
        d = point_triangle_distances(pts[pts[:, 1] < body.vertices[ids, 1].max()], tri)
        assert d.min(1).min() > 1e-3
        if SHOE_STYLES[kind].straps:
            continue  # a sandal leaves the foot out between its straps
        foot = body.vertices[ids]
        front = foot[_covered(foot, kind)]
        assert winding_numbers(shoe.rest, shoe.faces, front).min() > 0.5


@pytest.mark.parametrize("motion", ["walk", "run"])
def test_in_motion_soles_meet_the_ground_and_the_toes_stay_in_the_shoe(motion, kind="sneakers", mocap=False):
    """Placed as composition places a clip (its lowest point over the clip on the ground), the
    lowest sole point is never under the ground; in a walk (one foot always planted, rolling
    from the heel to the ball) it is on it at every frame (the clip is planted on the shoes'
    soles: with the source's root height it floated 3-6 mm in most frames, 11-23 mm at worst);
    a sole point on the ground moves under 4 mm a frame while it stays there in a walk, 8 mm in
    a run (5.5-11 and 11-19 mm on the source's root path, whose stride is the humanoid's); the
    forefoot never leaves its shoe. ``mocap``: the clip's joints named as a CMU BVH names them, so
    its soles are estimated from its ankles and toes."""
    from synmitsuba.compose.subjects import clip_bounds
    h = _subject(kind)
    from synmitsuba.compose.subjects import heeled_roll
    source = sm.procedural_motion(motion, np.random.default_rng(0), seconds=1.0, roll=heeled_roll(h.heels))
    clip = sm.retarget_to_subject(named_as(source, "cmu") if mocap else source, h)
    _, _, lift = clip_bounds(h, clip)
    shoe = _shoe(h)
    front = [ids[_covered(h.body.vertices[ids], kind)] for ids in (_foot(h, 1.0), _foot(h, -1.0))]
    rows = np.isin(h.split.source, np.concatenate(front))  # the body layer is the seam-split render mesh
    rows = np.flatnonzero(rows)[::3]  # a third of them, spread over the forefoot: the reference's winding
    # numbers cost 2 s a frame for all (the suite's slowest test), and a toe through the shoe is many
    lowest, slide, before = [], [0.0], None
    for f in range(clip.n_frames):
        layers = {lay.name: lay for lay in h.pose(*clip.frame(f))}
        v = layers[shoe.name].vertices
        lowest.append(v[:, 1].min() + lift)
        if before is not None:
            down = (v[:, 1] + lift < 0.002) & (before[:, 1] + lift < 0.002)
            slide.append(np.linalg.norm((v - before)[down][:, [0, 2]], axis=1).max(initial=0.0))
        before = v
        inside = winding_numbers(v, layers[shoe.name].faces, layers["body"].vertices[rows])
        assert inside.min() > 0.5, (f, inside.min())
    lowest = np.array(lowest)
    assert lowest.min() >= -1e-9
    if motion == "walk":
        assert lowest.max() < 5e-4, lowest
    assert max(slide) < (0.004 if motion == "walk" else 0.008), slide  # a run: 11-19 mm without


def test_a_mocap_walk_is_planted_on_the_soles_too():
    """A walk that reaches retargeting as mocap (CMU joint names) is planted as the procedural one
    is: before its soles were estimated it kept its source's root path and floated 5-17 mm."""
    test_in_motion_soles_meet_the_ground_and_the_toes_stay_in_the_shoe("walk", mocap=True)


def test_styles_are_drawn_with_the_outfit_boots_never_under_trousers_heels_under_skirts():
    counts = dict.fromkeys(STYLES, 0)
    for seed in range(300):
        r = sm.sample_subject(np.random.default_rng(seed))
        kinds = [g.kind for g in r.garments]
        shoes = [k for k in kinds if k in GARMENTS and GARMENTS[k].footwear]
        assert len(shoes) <= 1 and not ("boots" in kinds and "trousers" in kinds)
        # heels with skirts and dresses (a drawn dress may be made as a jumpsuit)
        assert "heels" not in kinds or any(GARMENTS[k].skirted or k == "jumpsuit" for k in kinds)
        for k in shoes:
            counts[k] += 1
        assert sm.SubjectRecipe.from_json(r.to_json()).to_json() == r.to_json()
    total = sum(counts.values())
    assert 0.75 * 300 < total < 0.95 * 300  # 85 % shod
    skirted = 0.35  # about this share of outfits have a skirt or a dress, the only ones heels are drawn with
    for k, share in FOOTWEAR.items():
        assert counts[k] > 0.3 * share * total * (skirted if k == "heels" else 1.0), counts


def test_a_recipe_with_the_old_shoes_kind_still_builds_its_hull_shoes():
    recipe = sm.sample_subject(np.random.default_rng(4), {"outfit": ["tshirt", "shorts", "shoes"], "jacket": False,
                                                          "texture_size": 64})
    d = recipe.to_dict()
    d["garments"][-1]["kind"] = "shoes"
    d["garments"][-1]["thickness"] = 0.005
    h = sm.build_subject(sm.SubjectRecipe.from_dict(d))
    assert _shoe(h).name == "shoes" and h.body.vertices[:, 1].min() > 0.005


def test_the_sole_and_the_upper_render_in_their_own_colours():
    """A side view of white sneakers on a dark sole: a point half-way up the sole renders dark
    and a point on the upper's side renders light, both in the shoes' layer."""
    style = SHOE_STYLES["sneakers"]
    from synmitsuba.body.shoes import shoe_colours
    seed = next(s for s in range(1000) if shoe_colours(style, s)[1][0] < 20)  # a black sole
    recipe = sm.sample_subject(np.random.default_rng(4), {"outfit": ["tshirt", "shorts", "sneakers"], "jacket": False,
                                                          "accessories": [], "texture_size": 64})
    d = recipe.to_dict()
    d["garments"][-1]["texture"].update(base_lab=[93.0, 0.0, 2.0], seed=seed)
    h = sm.build_subject(sm.SubjectRecipe.from_dict(d))
    g = next(m for m in h.garments if m.params.kind == "sneakers")
    from synmitsuba.compose.stage import preview_stage
    sm.set_variant()
    scene = preview_stage()
    h.add_to(scene, instance=1)
    foot = h.body.vertices[_foot(h, 1.0)]
    mid_z = foot[:, 2].mean()
    side_x = _shoe(h).rest[:, 0].max()
    cam = sm.Camera.look_at(eye=(side_x + 0.6, 0.04, mid_z), target=(side_x, 0.04, mid_z), fov_y_deg=20,
                            width=96, height=64)
    sample = sm.render(scene, cam, spp=16, seed=0)
    sole_px, upper_px = (np.floor(cam.project(np.array([[side_x, y, mid_z]]))[0][0]).astype(int)
                         for y in (g.params.thickness / 2, g.params.thickness + 0.025))
    lum = sample.rgb[..., :3].mean(-1)
    layer = sample.layer
    for px in (sole_px, upper_px):
        assert layer[px[1], px[0]] == int(sm.Layer.SHOES)
    assert lum[upper_px[1], upper_px[0]] > 4 * lum[sole_px[1], sole_px[0]]


def test_laces_are_cords_over_the_throat_in_the_laces_colour(shod):
    """Laced styles get a cord across the throat every ``LACE_PITCH`` of u, lying on the upper
    (every point within 4 mm of its surface, the middles standing out 1.5 mm or more, the ends
    sunk into it) with uv on the bar ``shoe_texture`` paints in the laces' colour; the built
    shoe carries them; sandals have none."""
    from synmitsuba.body.shoes import LACE_PITCH, LACE_SPAN, foot_points, lace_mesh, shoe_colours, shoe_mesh, shoe_texture
    from synmitsuba.body.textures import GarmentTextureParams, lab_to_linear_rgb
    kind, h = shod
    style = SHOE_STYLES[kind]
    g = next(m for m in h.garments if m.params.kind == kind).params
    v, f, uv = shoe_mesh(foot_points(h.body, h.regions, 1.0), style, g.thickness, 0.004, g.length)
    cv, cf, cuv = lace_mesh(v, f, uv, style)
    if not style.laces:
        assert len(cv) == 0
        return
    cords = int(LACE_SPAN / LACE_PITCH)
    assert len(cv) % cords == 0 and len(cf) == cords * (len(cf) // cords)
    tri = v[f]
    tri = tri[np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) > 1e-12]  # no slivers
    d = point_triangle_distances(cv, tri).min(1)
    assert d.max() < 0.004
    per = cv.reshape(cords, -1, 3)
    mids = np.array([point_triangle_distances(c[len(c) // 2 - 4:len(c) // 2 + 4].mean(0)[None], tri).min() for c in per])
    assert mids.min() > 0.0015, mids
    albedo, _ = shoe_texture(style, GarmentTextureParams(base_lab=[40.0, 0.0, 0.0], seed=g.texture.seed), 256)
    lace = lab_to_linear_rgb(shoe_colours(style, g.texture.seed)[2])
    texels = albedo[((1 - cuv[:, 1]) * 256).astype(int), (cuv[:, 0] * 256).astype(int)]
    assert np.allclose(texels, lace, atol=1e-6)
    shoe = _shoe(h)
    assert (np.isin(shoe.uv[:, 0], np.unique(cuv[:, 0])) & (shoe.uv[:, 1] == cuv[0, 1])).sum() == 2 * len(cv)


def test_heels_pitch_the_foot_with_the_heel_tip_and_the_level_forefoot_on_the_ground():
    """Standing in heels: the heel's tip and the forefoot's sole are on the ground (the forefoot
    level, under 1 mm across), the body's heel is up by the style's heel height over its ball
    (measured on the posed body's own underside), and the forefoot stays in its shoe."""
    h = _subject("heels")
    g = next(m for m in h.garments if m.params.kind == "heels").params
    shoe = _shoe(h)
    layers = {lay.name: lay for lay in h.pose(*h.standing(), resolve=False)}
    v, body = layers["heels"].vertices, layers["body"].vertices
    heel_block = shoe.rest[:, 1] < -1e-6  # at rest only the heel reaches under the sole
    bottom = np.abs(shoe.rest[:, 1]) < 1e-9
    for side, pitch in zip((1.0, -1.0), h.heels):
        mine = np.sign(shoe.rest[:, 0]) == side
        assert v[heel_block & mine, 1].min() == pytest.approx(0.0, abs=1e-5)
        fore = bottom & mine & (pitch.ahead(shoe.rest) > 0.03)
        assert v[fore, 1].min() == pytest.approx(0.0, abs=1e-5) and np.ptp(v[fore, 1]) < 1e-3
        rows = np.isin(h.split.source, _foot(h, side))  # the body layer is the seam-split render mesh
        rest, posed = h.body.vertices[h.split.source[rows]], body[rows]
        back = rest[:, 2] < rest[:, 2].min() + 0.02  # the heel's back, its underside the lowest of it
        ball = rest[:, 2] > rest[:, 2].min() + 0.6 * np.ptp(rest[:, 2])
        rise = posed[back, 1].min() - posed[ball, 1].min()
        assert rise == pytest.approx(pitch.height, abs=0.012), (rise, pitch.height)
    assert h.heels[0].height == pytest.approx(0.05 + 0.04 * g.length)
    test_in_motion_soles_meet_the_ground_and_the_toes_stay_in_the_shoe("walk", kind="heels")
