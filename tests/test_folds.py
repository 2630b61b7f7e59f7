"""Fold relief on skinned garments (body.folds): each zone's folds checked against the zone's
own geometry, and a built subject's garments carrying it in their bump and albedo."""
import numpy as np
import pytest

from synmitsuba.body.folds import FOLD_FANS, FOLD_ZONES, REACHES, FoldFan, FoldZone, crease_shade, fold_relief

ELBOW = FoldZone((0,), (1,), 0.0, 0.06, 0.085, 0.024, 0.034, (0.0, 0.0, 1.0))


def _keypoints():
    kp = np.zeros((2, 3))
    kp[1] = (0.0, -0.3, 0.0)  # the zone's axis runs down y from the origin
    return kp


def _zone_only(points, zone=ELBOW, seed=3):
    """The zone's part of the relief: the undulation is drawn first, so the same seed without
    the zone gives the same undulation."""
    kp = _keypoints()
    return (fold_relief(points, kp, np.random.default_rng(seed), zones={"z": zone}, fans={})
            - fold_relief(points, kp, np.random.default_rng(seed), zones={}, fans={}))


def _line(angle: float, radius: float = 0.05, n: int = 40001, half: float = 0.4):
    """Points along the axis at ``radius`` from it, ``angle`` from +x towards +z."""
    y = np.linspace(-half, half, n)
    return np.stack([np.full(n, radius * np.cos(angle)), y, np.full(n, radius * np.sin(angle))], 1), y


def test_a_zones_folds_lie_within_its_reach_and_radius_and_depth():
    pts, y = _line(np.pi / 2)  # on the gather side
    h = _zone_only(pts)
    assert h.max() <= ELBOW.depth and h.min() >= -2 / np.pi * ELBOW.depth  # crest to crease at most its depth
    assert h.max() - h.min() > 0.5 * ELBOW.depth  # folds there at all
    assert np.all(h[np.abs(y) >= REACHES * ELBOW.reach] == 0)
    far, _ = _line(np.pi / 2, radius=ELBOW.radius + 0.001)
    assert np.all(_zone_only(far) == 0)


def test_folds_are_spaced_about_a_wavelength_and_join_without_steps():
    """Creases (the relief's sharp minima) along lines near the zone's centre, over seeds and
    sides: the median gap between neighbours is the wavelength within a quarter (a fold whose arc
    misses a line leaves a double gap); and the relief is continuous where one fold meets the
    next (each is zero at the crease between them), its steps never far over its steepest slope."""
    gaps = []
    for seed in range(4):
        for angle in (np.pi / 2, np.pi / 3, 0.0):
            pts, y = _line(angle)
            h = _zone_only(pts, seed=seed)
            step = y[1] - y[0]
            assert np.abs(np.diff(h)).max() < 3 * np.pi * ELBOW.depth / ELBOW.wavelength * step
            dh = np.diff(h)
            minima = np.flatnonzero((dh[:-1] < 0) & (dh[1:] >= 0)) + 1
            gaps += list(np.diff(y[minima[np.abs(y[minima]) < 1.5 * ELBOW.reach]]))
    assert len(gaps) > 20 and abs(np.median(gaps) / ELBOW.wavelength - 1) < 0.25, np.round(gaps, 3)


def test_folds_crowd_on_the_gather_side():
    front, _ = _line(np.pi / 2)    # +z: the gather side
    back, _ = _line(-np.pi / 2)
    rms = [np.sqrt(np.mean(_zone_only(p, seed=s) ** 2)) for s in range(6) for p in (front, back)]
    assert np.mean(rms[0::2]) > 1.5 * np.mean(rms[1::2])


def test_the_relief_is_deterministic_and_every_zone_names_real_keypoints():
    pts = np.random.default_rng(0).uniform(-0.5, 0.5, (500, 3))
    kp = np.random.default_rng(1).uniform(-0.5, 0.5, (23, 3))
    a = fold_relief(pts, kp, np.random.default_rng(7))
    assert np.array_equal(a, fold_relief(pts, kp, np.random.default_rng(7)))
    assert not np.array_equal(a, fold_relief(pts, kp, np.random.default_rng(8)))
    assert all(max(z.at + z.toward) < 17 for z in FOLD_ZONES.values())  # COCO-17 body keypoints


def test_a_fans_ridges_radiate_within_its_spread_and_reach():
    """An armpit's fan at the origin aimed along +x in the frontal plane: on arcs round it the
    relief rises and falls once per ``spacing`` radians inside the spread (counted crossings of
    its arc's mean), is zero outside it and near the centre, and is continuous."""
    kp = np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])  # at, down (shift 0), toward
    fan = FoldFan((0,), (1,), 0.0, (2,), 0.6, 0.24, 0.1, 0.012)
    phi = np.linspace(-1.2, 1.2, 24001)
    gaps = []
    for radius, seed in ((0.06, 2), (0.09, 2), (0.06, 3), (0.09, 4)):
        pts = np.stack([radius * np.cos(phi), radius * np.sin(phi), np.full(len(phi), 0.05)], 1)
        h = (fold_relief(pts, kp, np.random.default_rng(seed), zones={}, fans={"f": fan})
             - fold_relief(pts, kp, np.random.default_rng(seed), zones={}, fans={}))
        assert np.all(h[np.abs(phi) >= fan.spread] == 0) and np.abs(h).max() <= fan.depth
        assert np.abs(np.diff(h)).max() < 0.05 * fan.depth  # 1e-4 rad a step: no jumps
        inside = np.abs(phi) < fan.spread - 0.2
        minima = np.flatnonzero((np.diff(h)[:-1] < 0) & (np.diff(h)[1:] >= 0)) + 1
        gaps += list(np.diff(phi[minima[inside[minima]]]))
    assert len(gaps) >= 6 and abs(np.median(gaps) / fan.spacing - 1) < 0.25, gaps
    near = np.stack([0.015 * np.cos(phi), 0.015 * np.sin(phi), np.zeros(len(phi))], 1)
    assert np.all(fold_relief(near, kp, np.random.default_rng(2), zones={}, fans={"f": fan})
                  == fold_relief(near, kp, np.random.default_rng(2), zones={}, fans={}))
    assert all(max(f.at + f.down + f.toward) < 17 for f in FOLD_FANS.values())


def test_folds_too_fine_for_the_map_fade_out_instead_of_aliasing():
    """On a map whose texels are 2 cm (a long sleeve on 128 texels) the elbow's 3.4 cm folds would be under
    two texels apart: gone; on 5 mm texels (a 512-texel one) they are whole; between, scaled."""
    pts, _ = _line(np.pi / 2)
    kp, zone = _keypoints(), {"z": ELBOW}

    def folds(texel):
        return (fold_relief(pts, kp, np.random.default_rng(3), zones=zone, fans={}, texel=texel)
                - fold_relief(pts, kp, np.random.default_rng(3), zones={}, fans={}, texel=texel))
    whole = _zone_only(pts)
    assert np.array_equal(folds(0.005), whole) and not folds(0.02).any()
    assert np.allclose(folds(ELBOW.wavelength / 4), 0.5 * whole)  # 4 texels a fold: halfway


def test_crease_shade_darkens_only_creases():
    h = np.array([0.004, 0.0, -0.003, -0.006, -0.02])
    assert np.allclose(crease_shade(h), [1.0, 1.0, 0.9, 0.8, 0.8])


@pytest.fixture(scope="module")
def folded(sm):
    recipe = sm.sample_subject(np.random.default_rng(3), {"outfit": ["longsleeve", "skirt"], "jacket": False,
                                                          "texture_size": 512})
    return sm.build_subject(recipe)


def _bare(h, m, size):
    """The garment's material as it was before folds: its pattern over its panels, nothing else."""
    from synmitsuba.body.garments import GARMENTS
    from synmitsuba.body.panels import PanelFrame, pattern_coords
    from synmitsuba.body.textures import garment_material
    kind = GARMENTS[m.params.kind]
    coords = None
    if kind.panels is not None:
        frame = PanelFrame.of(h.body.vertices, h.regions, h.body.skeleton)
        coords = pattern_coords(kind.panels, m.vertices, m.faces[:len(m.faces) - m.hem[0]], m.uv, frame, size)
    return garment_material(m.params.texture, size, fabric=kind.fabric, pattern_coords=coords)


def test_a_built_sleeve_carries_its_folds_and_a_skirt_none(folded):
    """The long sleeve's bump is its pattern's plus the fold map over its rest surface, and its
    albedo the pattern's darkened by ``crease_shade``; the skirt (simulated or hanging free)
    keeps its pattern's material."""
    from synmitsuba.body.textures import GARMENT_BUMP_SCALE
    parts = {p.name: p for p in folded.parts}
    garments = {g.params.kind: g for g in folded.garments}
    m = garments["longsleeve"]
    folds = folded._fold_heights(m, 512)
    assert np.abs(folds).max() > 0.003  # folds a few millimetres deep somewhere (elbow, cuff, waist)
    bare = _bare(folded, m, 512)
    top = parts["longsleeve"].material
    assert np.allclose(top.bump, folds / GARMENT_BUMP_SCALE + (bare.bump if bare.bump is not None else 0.0), atol=1e-4)
    assert np.allclose(top.texture, bare.texture * crease_shade(folds)[..., None], atol=1e-6)
    skirt, bare = parts["skirt"].material, _bare(folded, garments["skirt"], 512)
    assert np.array_equal(skirt.texture, bare.texture)
    assert (skirt.bump is None) == (bare.bump is None) and (skirt.bump is None or np.array_equal(skirt.bump, bare.bump))
