"""The hands' skin lines: the atlas rasteriser against a plane's analytic map, the lines
against the rest body's joints and nails, and what they do to the albedo and roughness."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.body.textures import render_skin_roughness, render_skin_texture, sample_skin, uv_surface


def test_uv_surface_puts_every_texel_where_the_plane_maps_it():
    """A tilted plane gridded into 4 x 4 cells, uv its (x, y) over its extent: every texel
    centre lands on the point that plane maps it to, its normal is the plane's, and a texel
    spans the plane's analytic metres per texel."""
    n, size = 4, 32
    u, v = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    uv = np.stack([u.ravel(), v.ravel()], 1)
    verts = np.stack([0.2 * uv[:, 0], 0.1 * uv[:, 1], 0.05 * uv[:, 0]], 1)
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    normal = np.cross([0.2, 0, 0.05], [0, 0.1, 0])
    normal /= np.linalg.norm(normal)
    s = uv_surface(verts, np.broadcast_to(normal, verts.shape), faces, uv, faces, size)
    assert s.covered.all()
    rows, cols = np.mgrid[0:size, 0:size]
    x, y = (cols + 0.5) / size, 1 - (rows + 0.5) / size
    np.testing.assert_allclose(s.position, np.stack([0.2 * x, 0.1 * y, 0.05 * x], -1), atol=1e-12)
    np.testing.assert_allclose(s.normal, np.broadcast_to(normal, s.normal.shape), atol=1e-12)
    assert s.texel == pytest.approx(np.sqrt(np.hypot(0.2, 0.05) * 0.1) / size, rel=1e-9)


@pytest.fixture(scope="module")
def lines():
    from synmitsuba.body.anny_model import anny_uv_masks, part_labels
    from synmitsuba.body.hand_skin import hand_lines
    from synmitsuba.geometry import vertex_normals
    h = sm.build_subject(sm.sample_subject(np.random.default_rng(6200), {"accessories": [], "texture_size": 64}))
    body, size = h.body, 1024  # the skin atlas of the default texture_size
    normals = vertex_normals(body.vertices, body.faces)
    hands = (part_labels(body) == 2)[body.faces].all(1)
    surface = uv_surface(body.vertices, normals, body.faces[hands], body.uv, body.face_uv[hands], size)
    nails = anny_uv_masks(size)["nails"]
    return h, surface, nails, hand_lines(h.skeleton, surface, nails)


def test_knuckle_wrinkles_lie_over_the_backs_of_the_finger_joints(lines):
    """Every texel of a knuckle pad lies within 9 mm along the finger of a PIP or DIP joint (or
    the thumb's MCP or IP), and on index .. pinky faces the side their nails face (found here
    from the nail mask's texels, not from the code's frames); each of those 16 joints has one."""
    h, surface, nails, out = lines
    sk = h.skeleton
    pad = out.knuckles > 0.5
    pos, nrm = surface.position[pad], surface.normal[pad]
    for s in "LR":
        for f in range(1, 6):
            heads = sk.rest_positions[[sk.index(f"finger{f}-{k}.{s}") for k in (1, 2, 3)]]
            axis = heads[2] - heads[1]
            axis /= np.linalg.norm(axis)
            on_nail = surface.covered & (nails > 0.5) & (np.linalg.norm(surface.position - heads[2], axis=-1) < 0.025)
            back = surface.normal[on_nail].mean(0)
            for j in (1, 2):
                along = (pos - heads[j]) @ axis
                mine = (np.abs(along) < 0.009) & (np.linalg.norm(pos - heads[j], axis=1) < 0.016)
                assert mine.sum() > 5, (s, f, j)
                if f > 1:
                    assert (nrm[mine] @ back > 0).mean() > 0.95, (s, f, j)
    every = np.zeros(len(pos), bool)
    for s in "LR":
        for f in range(1, 6):
            for j in (2, 3):
                head = sk.rest_positions[sk.index(f"finger{f}-{j}.{s}")]
                every |= np.linalg.norm(pos - head, axis=1) < 0.016
    assert every.all()


def test_palm_creases_lie_on_the_palm_side_only(lines):
    """Between the wrist and the knuckles, lines are drawn where the skin faces the palm's way
    and none where it faces the back of the hand."""
    from synmitsuba.body.hand_points import dorsal_axis
    h, surface, _, out = lines
    sk = h.skeleton
    for s in "LR":
        wrist, middle = (sk.rest_positions[sk.index(n)] for n in (f"wrist.{s}", f"finger3-1.{s}"))
        axis = middle - wrist
        t = (surface.position - wrist) @ axis / (axis @ axis)
        palm_part = surface.covered & (t > 0.2) & (t < 0.8) & (np.linalg.norm(surface.position - wrist - t[..., None] * axis, axis=-1) < 0.05)
        facing = surface.normal @ dorsal_axis(sk, s)
        assert (out.creases[palm_part & (facing < -0.7)] > 0.5).sum() > 20
        assert (out.creases[palm_part & (facing > 0.5)] < 0.05).all()


def test_creases_darken_the_albedo_and_nails_are_glossy():
    """Where a crease's mask is 1 the skin's CIELAB L* (colour-science's conversion) drops by
    more than 8 (70 % of the way to 16 darker, mixed in linear RGB); a nail is smoother (roughness within 0.06 of 0.2) than the body's skin."""
    from conftest import colour_science
    colour = colour_science()
    p = sample_skin(np.random.default_rng(3))
    mask = np.zeros((16, 16), np.float32)
    mask[4:8, 4:8] = 1.0
    img = render_skin_texture(p, {"creases": mask}, 16)
    lab = [colour.XYZ_to_Lab(colour.sRGB_to_XYZ(img[r, r], apply_cctf_decoding=False)) for r in (5, 12)]
    tone = p.lab()
    mix = [np.clip(colour.XYZ_to_sRGB(colour.Lab_to_XYZ(x), apply_cctf_encoding=False), 0, 1)  # in gamut
           for x in (tone, tone + [-16, 6, 2])]
    expect = colour.XYZ_to_Lab(colour.sRGB_to_XYZ(0.3 * mix[0] + 0.7 * mix[1], apply_cctf_decoding=False))
    np.testing.assert_allclose(lab[0], expect, atol=0.5)  # 70 % of the way to L* - 16, mixed as light mixes
    assert lab[1][0] - lab[0][0] > 8
    rough = render_skin_roughness(p, {"nails": mask}, 16)
    assert np.abs(rough[4:8, 4:8] - 0.2).max() < 0.065
    assert rough[12, 12] > 0.45
