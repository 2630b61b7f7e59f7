"""Size grading (body/sizing.py): tape-measure girths, the chart, and garments cut a size small
or large on the same body."""
import dataclasses
import math

import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.body.garments import SNUG, GarmentParams, build_garment, garment_offset
from synmitsuba.body.sizing import CHARTS, GRADE_ODDS, SIZES, SizeChart, garment_fit, perimeter
from synmitsuba.scene.layers import Layer


@pytest.fixture(scope="module")
def human():
    recipe = sm.sample_subject(np.random.default_rng(7), {"outfit": ["tshirt", "trousers"], "jacket": False,
                                                          "shoes": False, "accessories": [], "texture_size": 64})
    return sm.build_subject(recipe)


def test_a_tape_round_an_ellipse_and_a_dented_outline_measures_their_hull():
    """Ramanujan's ellipse perimeter for points on an ellipse (and inside it); a dent a tape
    bridges does not shorten it."""
    a, b = 0.16, 0.11
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    ring = np.column_stack([a * np.cos(t), b * np.sin(t)])
    h = ((a - b) / (a + b)) ** 2
    exact = math.pi * (a + b) * (1 + 3 * h / (10 + math.sqrt(4 - 3 * h)))
    inside = np.random.default_rng(0).uniform(-0.5, 0.5, (200, 2)) * [a, b]
    assert perimeter(np.concatenate([ring, inside])) == pytest.approx(exact, rel=1e-4)
    dented = ring * np.where(np.abs(np.sin(t)) > 0.9, 0.8, 1.0)[:, None]  # front and back pushed in
    assert perimeter(dented) == pytest.approx(perimeter(ring[np.abs(np.sin(t)) <= 0.9]), rel=1e-9)


def test_the_wearers_size_is_the_smallest_that_goes_round_them():
    chart = SizeChart("chest", 0.80)
    for girth in np.linspace(0.6, 1.5, 181):
        s = chart.size_of(float(girth))
        assert chart.girth(s) >= girth - 1e-9 > chart.girth(s - 1)
    assert chart.size_of(0.96) == SIZES.index("M") and chart.name(2) == "M" and chart.name(-1) == "72 cm"


def test_hip_girth_matches_the_mesh_cut_by_planes(human):
    """The hips measured from vertices in 1-cm bands against the body mesh's exact cross-sections
    (trimesh's plane sections, largest loop, its hull) at the same heights: within 1 %."""
    import trimesh
    r, body = human.regions, human.body
    mesh = trimesh.Trimesh(body.vertices, body.faces, process=False)
    best = 0.0
    for y in np.arange(r.crotch_y, r.waist_y, 0.01):
        s = mesh.section(plane_origin=[0, y, 0], plane_normal=[0, 1, 0])
        if s is None:
            continue
        loops = [p[:, [0, 2]] for p in s.discrete]
        best = max(best, max(perimeter(p) for p in loops if len(p) > 8))
    assert r.girths.hip == pytest.approx(best, rel=0.01)
    assert 0.8 < r.girths.chest < 1.2 and 0.8 < r.girths.hip < 1.3


def test_heavier_bodies_measure_larger():
    from synmitsuba.body.anny_model import anny_body
    from synmitsuba.body.garments import body_regions
    pheno = {"gender": 0.5, "age": 0.8, "muscle": 0.5, "height": 0.5, "proportions": 0.5}
    light, heavy = (body_regions(anny_body({**pheno, "weight": w})).girths for w in (0.1, 0.9))
    assert heavy.chest > light.chest + 0.03 and heavy.hip > light.hip + 0.06


def test_a_size_up_stands_out_by_a_step_of_girth_and_hangs_longer(human):
    """A t-shirt cut a size small, true and large on the same body: the fit names the chart's
    size for the body's chest and the grade; a size up stands ``step / 2 pi`` further out (the
    built shell's girth at mid-chest grows by the step, within 10 %) and its hem and sleeves
    reach further down; a size small is tight, ``SNUG`` over its thickness at the least."""
    r = human.regions
    chart = CHARTS[Layer.TOP]
    own = chart.size_of(r.girths.chest)
    built = {}
    for grade in (-1, 0, 1):
        g = GarmentParams(kind="tshirt", length=0.5, ease=0.005, thickness=0.003, grade=grade)
        m = build_garment(human.body, r, human.split, g)
        assert m.fit.size == own + grade and m.fit.ease == pytest.approx(chart.girth(own + grade) - r.girths.chest)
        built[grade] = m
    assert built[1].offset - built[0].offset == pytest.approx(chart.step / (2 * np.pi), abs=1e-9)
    assert built[-1].offset >= 0.003 + SNUG - 1e-12 and built[-1].offset < built[0].offset
    from scipy.spatial import cKDTree
    y, tree = 0.5 * (r.waist_y + r.shoulder[1]), cKDTree(human.body.vertices)

    def round_chest(v):  # the shell round the torso, the sleeves left out
        keep = (r.group[tree.query(v)[1]] == "torso") & (np.abs(v[:, 1] - y) < 0.01)
        return perimeter(v[keep][:, [0, 2]])
    girth = {k: round_chest(m.vertices) for k, m in built.items()}
    assert girth[1] - girth[0] == pytest.approx(chart.step, rel=0.1)
    assert girth[0] - girth[-1] == pytest.approx(2 * np.pi * (built[0].offset - built[-1].offset), rel=0.1)
    lowest_arm = {k: m.vertices[np.abs(m.vertices[:, 0]) > r.shoulder[0] + 0.08][:, 1].min() for k, m in built.items()}
    assert lowest_arm[1] < lowest_arm[0] < lowest_arm[-1]
    assert built[1].vertices[:, 1].min() < built[0].vertices[:, 1].min() < built[-1].vertices[:, 1].min()


def test_trousers_cut_large_are_belted_at_the_waist_and_loose_round_the_legs(human):
    """Trousers a size up: their waist (and so the floor a top over them stands on) stays where
    a true size's would be without its slack; round the knees they stand further out by all of
    their room (the fit's ``radial``), within 1.5 mm (distances to the nearest body vertex)."""
    from scipy.spatial import cKDTree
    from synmitsuba.body.garments import GARMENTS
    r, tree = human.regions, cKDTree(human.body.vertices)
    m = {k: build_garment(human.body, r, human.split, GarmentParams(kind="trousers", ease=0.005, thickness=0.003,
                                                                    length=0.9, grade=k)) for k in (0, 1)}
    assert m[1].offset == pytest.approx(GARMENTS["trousers"].offset + 0.005 + 0.003)
    assert m[1].offset == pytest.approx(m[0].offset - min(m[0].fit.radial, 0.0))

    def standoff(v, y):
        near = v[np.abs(v[:, 1] - y) < 0.01]
        return float(np.median(tree.query(near)[0]))
    knee = r.crotch_y - 0.5 * (r.crotch_y - r.hip_y + r.leg_length) + 0.05
    waist = r.hip_y + 0.02
    assert standoff(m[1].vertices, waist) - standoff(m[0].vertices, waist) == pytest.approx(
        m[1].offset - m[0].offset, abs=0.0015)
    legs = {k: x.offset + max(x.fit.radial, 0.0) for k, x in m.items()}  # a bottom's room goes to its legs
    assert legs[1] - legs[0] == pytest.approx(chart_step_radial(), abs=1e-9) or m[0].fit.radial < 0
    assert standoff(m[1].vertices, knee) - standoff(m[0].vertices, knee) == pytest.approx(legs[1] - legs[0], abs=0.0015)


def chart_step_radial() -> float:
    return CHARTS[Layer.BOTTOM].step / (2 * np.pi)


def test_ungraded_garments_and_footwear_keep_their_old_fit(human):
    """A garment without a grade (recipes written before grading) is offset by its ``size`` as
    before; footwear has no chart."""
    g = GarmentParams(kind="tshirt", size=0.25, ease=0.01, thickness=0.003)
    m = build_garment(human.body, human.regions, human.split, g)
    assert m.fit is None and m.offset == pytest.approx(0.012 + 0.004 * 0.25 + 0.01 * (0.7 + 0.6 * 0.25) + 0.003)
    assert garment_fit(Layer.SHOES, 1, human.regions.girths) is None
    assert garment_offset(dataclasses.replace(g, grade=1)) == garment_offset(g)  # no fit given: ungraded


def test_sampled_grades_follow_their_odds_and_round_trip():
    from scipy.stats import chisquare
    rng = np.random.default_rng(3)
    grades, footwear = [], []
    for _ in range(300):
        recipe = sm.sample_subject(rng, {"accessories": [], "texture_size": 64})
        assert sm.SubjectRecipe.from_dict(recipe.to_dict()) == recipe
        for g in recipe.garments:
            (footwear if sm.body.garments.GARMENTS[g.kind].footwear else grades).append(g.grade)
    assert all(g is None for g in footwear) and len(footwear) > 100
    counts = [grades.count(k) for k in GRADE_ODDS]
    assert chisquare(counts, len(grades) * np.array(list(GRADE_ODDS.values()))).pvalue > 1e-3
