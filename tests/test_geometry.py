"""The shared geometry helpers against formulas written out here."""
import numpy as np
import pytest

from synmitsuba.geometry import (align_vectors, axis_rotation, camera_ray_matrix, euler_to_matrix, frame,
                                 slerp_matrices, SmoothNormals, triangle_areas, unique_rows, vertex_normals)

from reference import winding_numbers


def _rodrigues_min(a, b):
    """Smallest rotation taking a to b: about a x b by the angle between them."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    v, c = np.cross(a, b), a @ b
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1 + c)


def test_align_vectors_is_the_smallest_rotation():
    rng = np.random.default_rng(0)
    for _ in range(50):
        a, b = rng.normal(size=3), rng.normal(size=3)
        np.testing.assert_allclose(align_vectors(a, b), _rodrigues_min(a, b), atol=1e-9)
    R = align_vectors([1.0, 0, 0], [-1.0, 0, 0])  # opposite: a half turn that takes a to b
    np.testing.assert_allclose(R @ [1, 0, 0], [-1, 0, 0], atol=1e-9)
    assert np.linalg.det(R) == pytest.approx(1.0)


def test_euler_is_intrinsic_in_bvh_order():
    a = np.radians([20.0, -35.0, 50.0])
    expect = axis_rotation("z", a[0]) @ axis_rotation("x", a[1]) @ axis_rotation("y", a[2])
    np.testing.assert_allclose(euler_to_matrix(a, "ZXY"), expect, atol=1e-12)
    c, s = np.cos(a[0]), np.sin(a[0])
    np.testing.assert_allclose(axis_rotation("z", a[0]), [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-12)


def test_slerp_halfway_is_half_the_angle():
    R = np.stack([np.eye(3), axis_rotation("y", np.pi / 2)])[:, None]  # (F=2, 1, 3, 3)
    mid = slerp_matrices(R, [0.5])[0, 0]
    np.testing.assert_allclose(mid, axis_rotation("y", np.pi / 4), atol=1e-12)


def test_frame_keeps_what_it_is_told_to():
    f = frame([0.2, 0.3, 1.0], [0, 1, 0], keep="up")
    np.testing.assert_allclose(f[:, 1], [0, 1, 0])
    g = frame([0.2, 0.3, 1.0], [0, 1, 0], keep="forward")
    np.testing.assert_allclose(g[:, 2], np.array([0.2, 0.3, 1.0]) / np.linalg.norm([0.2, 0.3, 1.0]))
    for m in (f, g):
        np.testing.assert_allclose(m.T @ m, np.eye(3), atol=1e-12)
        assert np.linalg.det(m) == pytest.approx(1.0)
    with pytest.raises(ValueError):
        frame([0, 2, 0], [0, 1, 0])


def test_normals_areas_and_camera_rays():
    v = np.array([[0, 0, 0], [2, 0, 0], [0, 1, 0], [0, 0, 3]], float)
    f = np.array([[0, 1, 2], [0, 3, 1]])
    np.testing.assert_allclose(triangle_areas(v[f]), [1.0, 3.0])
    n = vertex_normals(v, f)
    np.testing.assert_allclose(n[2], [0, 0, 1], atol=1e-12)  # only in the z-facing triangle
    # vertex 0 sums the unnormalised face normals: (0, 0, 2) (area 1) + (0, 6, 0) (area 3)
    np.testing.assert_allclose(n[0], np.array([0, 6.0, 2.0]) / np.linalg.norm([0, 6.0, 2.0]), atol=1e-12)
    K = np.array([[100.0, 0, 50], [0, 80, 40], [0, 0, 1]])
    R = axis_rotation("y", 0.3)
    d = camera_ray_matrix(K, R) @ [60.5, 30.5, 1]
    x_cam = R @ d
    np.testing.assert_allclose((K @ x_cam)[:2] / (K @ x_cam)[2], [60.5, 30.5])


def test_local_rotations_undo_forward_kinematics():
    from synmitsuba.body.skeleton import Skeleton, forward_kinematics, local_rotations
    from synmitsuba.geometry import axis_angle_to_matrix
    rng = np.random.default_rng(0)
    sk = Skeleton(("a", "b", "c", "d"), [-1, 0, 1, 1], rng.normal(size=(4, 3)))
    R = axis_angle_to_matrix(rng.normal(size=(5, 4, 3)))
    G = forward_kinematics(sk, R)[0]
    assert np.allclose(local_rotations(G, sk.parents), R, atol=1e-12)


def test_weld_joins_points_within_a_micrometre_whatever_the_grid():
    from synmitsuba.body.topology import weld
    base = np.array([[0.1234565, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 0.0, 0.0]])
    pts = np.concatenate([base, base + [4e-7, 0, 0], base + [3e-6, 0, 0]])  # straddles a 1e-6 rounding cell
    rep = weld(pts)
    d = np.linalg.norm(pts[:, None] - pts[None], axis=-1)  # brute force: same group iff within 1e-6
    assert ((rep[:, None] == rep[None]) == (d <= 1e-6)).all()
    assert (rep <= np.arange(len(pts))).all()  # the lowest index of its group


def test_smooth_normals_run_across_seams_and_keep_opposite_sheets_apart():
    """A sphere with every triangle cut loose (each vertex copied once per face, as uv seams
    copy vertices): welded, every copy gets the area-weighted normal of the whole sphere (trimesh's)
    (radial to within a degree); unwelded, each copy only its own face's normal. Two sheets
    through the same points facing away from each other keep their own normals."""
    import trimesh

    from synmitsuba.body.topology import weld
    ico = trimesh.creation.icosphere(subdivisions=3)
    v, f = ico.vertices[ico.faces].reshape(-1, 3), np.arange(3 * len(ico.faces)).reshape(-1, 3)
    n = SmoothNormals(f, weld(v), v)(v)
    expected = vertex_normals(ico.vertices, ico.faces)[ico.faces].reshape(-1, 3)
    assert np.abs(n - expected).max() < 1e-9
    assert np.degrees(np.arccos(np.clip((n * v).sum(1) / np.linalg.norm(v, axis=1), -1, 1))).max() < 1.0
    flat = SmoothNormals(f, np.arange(len(v)), v)(v)
    assert np.abs(flat - np.repeat(ico.face_normals, 3, axis=0)).max() < 1e-9
    quad = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    both = np.concatenate([quad, quad])
    faces = np.array([[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]])  # the copy is wound the other way
    sheets = SmoothNormals(faces, weld(both), both)(both)
    assert np.allclose(sheets[:4], [0, 0, 1]) and np.allclose(sheets[4:], [0, 0, -1])


def test_winding_numbers_and_signed_distance_agree_with_a_torus():
    """Winding numbers against the analytic torus (points off the polygonised surface); the
    pseudonormal sign of ``signed_distance`` against the winding numbers on coarse tori, where
    saddle vertices and edges make one face's normal point the wrong way; the pseudonormals
    computed from the faces around each feature alone (``local_pseudonormals``, for posed
    meshes) equal the whole mesh's."""
    import trimesh
    from synmitsuba.body.binding import MeshIndex, closest_points, incident_faces, local_pseudonormals, signed_distance
    from synmitsuba.geometry import face_normals
    rng = np.random.default_rng(0)
    p = rng.uniform([-1.5, -1.5, -0.5], [1.5, 1.5, 0.5], (3000, 3))
    fine = trimesh.creation.torus(1.0, 0.3, major_sections=48, minor_sections=24)
    true = np.hypot(np.hypot(p[:, 0], p[:, 1]) - 1.0, p[:, 2]) - 0.3  # exact distance to the smooth torus
    w = winding_numbers(fine.vertices, fine.faces, p)
    far = np.abs(true) > 0.01  # the 48 x 24 polygon lies within 4 mm of the torus
    assert np.array_equal((w > 0.5)[far], (true < 0)[far]) and np.abs(w - np.round(w)).max() < 1e-6
    for major, minor in ((6, 4), (5, 3)):
        m = trimesh.creation.torus(1.0, 0.4, major_sections=major, minor_sections=minor)
        inside = winding_numbers(m.vertices, m.faces, p) > 0.5
        d = signed_distance(m.vertices, m.faces, p, k=8)
        assert np.array_equal(d < 0, inside) and 0.05 < inside.mean() < 0.3
        c, tri, _ = closest_points(m.vertices, m.faces, p, k=8)  # one face's side: wrong at saddles
        assert ((np.einsum("ij,ij->i", p - c, face_normals(m.vertices[m.faces[tri]])) < 0) != inside).sum() >= 5
        np.testing.assert_allclose(np.abs(d), np.linalg.norm(p - c, axis=1))
        c, tri, bary = closest_points(m.vertices, m.faces, p, k=8)  # the same, from the faces around each feature
        local = local_pseudonormals(np.asarray(m.vertices), np.asarray(m.faces),
                                    incident_faces(np.asarray(m.faces), len(m.vertices)), tri, bary)
        assert np.array_equal(np.einsum("ij,ij->i", p - c, local) < 0, inside)
        whole = MeshIndex(m.vertices, m.faces).pseudonormals(tri, bary)
        np.testing.assert_allclose(local / np.linalg.norm(local, axis=1, keepdims=True),
                                   whole / np.linalg.norm(whole, axis=1, keepdims=True), atol=1e-9)


def test_unique_rows_is_numpys_unique_over_rows():
    """Same rows, order, first indices, inverse and counts as ``np.unique(axis=0)``: pairs and
    triples, negative values, int32 and int64, one row, and ranges too wide for one key."""
    import itertools
    rng = np.random.default_rng(4)
    arrays = [rng.integers(lo, hi, (n, k)).astype(dtype) for lo, hi, n, k, dtype in
              [(0, 3, 200, 2, np.int64), (-40, 40, 300, 2, np.int32), (0, 100000, 500, 2, np.int64),
               (0, 6, 300, 3, np.int64), (-5, 5, 1, 2, np.int64), (-2 ** 40, 2 ** 40, 50, 2, np.int64)]]
    arrays.append(np.repeat(arrays[0], 3, axis=0)[::-1].copy())  # every row several times, unsorted
    for a, flags in itertools.product(arrays, itertools.product([False, True], repeat=3)):
        kw = dict(zip(("return_index", "return_inverse", "return_counts"), flags))
        want, got = np.unique(a, axis=0, **kw), unique_rows(a, **kw)
        want, got = (want, got) if any(flags) else ((want,), (got,))
        assert len(got) == len(want)
        for w, g in zip(want, got):
            assert g.dtype == w.dtype and np.array_equal(g, w)
