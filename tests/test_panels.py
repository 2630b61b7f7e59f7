"""A garment's pattern laid on its panels (body.panels), measured on the built rest garment:
each texel's rest position (rasterised through the garment's own uv, ``uv_surface``) against
its pattern coordinates, by finite differences between neighbouring texels."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.body.garments import GARMENTS
from synmitsuba.body.textures import rasterise_uv, uv_surface
from synmitsuba.geometry import vertex_normals
from reference import pattern_jacobians

SIZE = 256


@pytest.fixture(scope="module")
def dressed():
    """Subjects in a hoodie and trousers, in a jumpsuit, and in a t-shirt and a skirt."""
    out = {}
    for seed, outfit in ((40, ["hoodie", "trousers"]), (41, ["jumpsuit"]), (42, ["tshirt", "skirt"])):
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(seed), {
            "outfit": outfit, "shoes": False, "jacket": False, "texture_size": SIZE}))
        for part in h.parts:
            if part.name in outfit:
                out[part.name] = (h, part)
    return out


def texel_maps(h, part):
    """(rest positions (S, S, 3), metres of pattern (S, S, 2), covered (S, S)) of a garment's
    outer cloth (its hem's turned-in band left out)."""
    mesh = next(m for m in h.garments if m.params.kind == part.name)
    faces = mesh.faces[:len(mesh.faces) - mesh.hem[0]]
    surface = uv_surface(mesh.vertices, vertex_normals(mesh.vertices, mesh.faces), faces, mesh.uv, faces, SIZE)
    return surface.position, part.material.pattern_coords.astype(np.float64), surface.covered


@pytest.mark.parametrize("kind", ["tshirt", "trousers", "jumpsuit", "hoodie"])
def test_a_pattern_lies_square_and_true_to_size_on_its_panels(dressed, kind):
    """A square of the pattern is a square on the cloth, of its size in metres: the map from
    pattern to rest surface stretches one way over the other by under 10 % in the median texel
    and 30 % in nine in ten (the body's atlas: 36-75 % and 83-196 %; a hoodie, pinched under
    its arms and round its hood: 12 % and 80 %), and its scale is 1 within 5 % in the median,
    0.9-1.3 in eight in ten (the atlas: 0.1-1.1)."""
    J, _ = pattern_jacobians(*texel_maps(*dressed[kind]))
    s = np.linalg.svd(J, compute_uv=False)
    stretch, scale = s[:, 0] / s[:, 1], np.sqrt(s[:, 0] * s[:, 1])
    median, p90 = (1.12, 1.8) if kind == "hoodie" else (1.1, 1.3)
    assert np.median(stretch) < median and np.percentile(stretch, 90) < p90, np.percentile(stretch, [50, 90])
    assert abs(np.median(scale) - 1) < 0.05 and 0.9 < np.percentile(scale, 10) and np.percentile(scale, 90) < 1.3


def test_stripes_run_level_round_the_torso_and_round_the_sleeves(dressed):
    """A stripe (a line of constant pattern v, along u) runs level round the torso (between
    waist and armpits, away from the sleeves): within 6 degrees of horizontal in nine texels in
    ten; and round each sleeve, square to the arm within 10 degrees."""
    h, part = dressed["hoodie"]
    J, pos = pattern_jacobians(*texel_maps(h, part))
    along = J[:, :, 0] / np.linalg.norm(J[:, :, 0], axis=1, keepdims=True)
    r = h.regions
    torso = (pos[:, 1] > r.waist_y) & (pos[:, 1] < r.shoulder[1] - 0.12) & \
        (np.abs(pos[:, 0] - r.neck_xz[0]) < r.shoulder[0] - 0.03)
    tilt = np.degrees(np.arcsin(np.abs(along[torso, 1])))
    assert torso.sum() > 500 and np.percentile(tilt, 90) < 6, np.percentile(tilt, [50, 90])
    sk = h.body.skeleton
    for side, sign in (("L", 1), ("R", -1)):
        sh, wr = sk.rest_positions[sk.index(f"upperarm01.{side}")], sk.rest_positions[sk.index(f"wrist.{side}")]
        arm = (wr - sh) / np.linalg.norm(wr - sh)
        on = (pos[:, 0] - sh[0]) * sign > 0.12  # well down the arm
        off = np.degrees(np.arcsin(np.abs(along[on] @ arm)))
        assert on.sum() > 100 and np.percentile(off, 90) < 10, (side, np.percentile(off, [50, 90]))


def test_stripes_meet_at_the_side_seams(dressed):
    """Where the front and back panels meet at the torso's sides, the pattern jumps across
    (u starts again from each panel's centre line) but not up or down: a horizontal stripe
    meets itself, as a tailor matches it (height jumps under 1 cm in nine seam texels in ten)."""
    h, part = dressed["hoodie"]
    P, C, covered = texel_maps(h, part)
    r = h.regions
    jumps = []
    for a, b in (((slice(None), slice(1, None)), (slice(None), slice(None, -1))),
                 ((slice(1, None), slice(None)), (slice(None, -1), slice(None)))):
        both = covered[a] & covered[b]
        near = np.linalg.norm(P[a] - P[b], axis=-1) < 0.015  # neighbours on the cloth too (texels 0.9-1.1 cm apart here)
        side = (P[a][..., 1] > r.waist_y) & (P[a][..., 1] < r.shoulder[1] - 0.15)
        torso = (C[a][..., 1] > 0.5) & (C[b][..., 1] > 0.5)  # a sleeve's v is up its arm from the shoulder: under 0.1
        seam = both & near & side & torso & (np.abs(C[a][..., 0] - C[b][..., 0]) > 0.05)
        jumps.append(np.abs(C[a][..., 1] - C[b][..., 1])[seam])
    jumps = np.concatenate(jumps)
    assert len(jumps) > 20 and np.percentile(jumps, 90) < 0.01, (len(jumps), np.percentile(jumps, [50, 90]))


@pytest.mark.parametrize("kind", ["skirt", "dress", "coat", "shirt", "hoodie"])
def test_no_texel_is_drawn_in_two_places(kind):
    """Every garment kind but footwear lays its pattern on panels, so a texel must lie in one
    place on the cloth: the faces covering any texel (the hem's turned-in band left out) lie
    within 3 cm of each other at rest. A dress's or coat's skirt once took the whole uv square
    over its bodice's, and the face closing a skirt's ring ran its uv back across the square."""
    assert all(k.panels is not None or k.footwear for k in GARMENTS.values())
    h = sm.build_subject(sm.sample_subject(np.random.default_rng(44), {
        "outfit": [kind], "shoes": False, "jacket": False, "texture_size": 64}))
    mesh = next(m for m in h.garments if m.params.kind == kind)
    faces = mesh.faces[:len(mesh.faces) - mesh.hem[0]]
    span = mesh.uv[faces][..., 0]
    assert np.ptp(span, axis=1).max() < 0.1  # no face runs across the square
    rows, cols, f, w = rasterise_uv(mesh.uv, faces, SIZE)
    at = np.einsum("nk,nkd->nd", w, mesh.vertices[faces[f]])
    texel = rows * SIZE + cols
    lo, hi = np.full((SIZE * SIZE, 3), np.inf), np.full((SIZE * SIZE, 3), -np.inf)
    np.minimum.at(lo, texel, at)
    np.maximum.at(hi, texel, at)
    seen = np.isfinite(lo).all(1)
    assert np.linalg.norm(hi[seen] - lo[seen], axis=1).max() < 0.03


def test_a_face_with_no_area_in_the_atlas_covers_at_most_its_own_texel_box():
    """A face whose three uv corners coincide has weights (1, 0, 0) wherever it is tried: it
    may cover only texels within 1.5 of its point (its own box), never a larger search window."""
    p = 32.3 / 64  # the point, 32.3 texels in; a small face of 2-3 texels' reach beside it, a large one
    small = np.array([[10.2, 10.2], [12.0, 10.2], [10.2, 12.0]]) / 64
    uv = np.array([[0.1, 0.1], [0.9, 0.1], [0.1, 0.9], *small, [p, p], [p, p], [p, p]])
    rows, cols, f, w = rasterise_uv(uv, np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8]]), 64)
    point = f == 2
    assert 0 < point.sum() <= 9 and (np.abs(cols[point] + 0.5 - 32.3) <= 1.5).all()
    assert (np.abs(rows[point] + 0.5 - (64 - 32.3)) <= 1.5).all()
    big = f == 0  # the large face: texel centres inside its triangle, counted independently
    yy, xx = np.mgrid[0:64, 0:64] + 0.5
    u, v = xx / 64, 1 - yy / 64
    inside = (u >= 0.1) & (v >= 0.1) & (u + v <= 1.0)
    assert abs(int(big.sum()) - int(inside.sum())) <= 64 * 0.05 * 3  # edges within a few texels
