"""Procedural architecture and props: what each layout builds, at what size, from its seed."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.compose import architecture, environments


def _inside_convex(mesh, p) -> bool:
    """Inside a convex mesh: behind every face's plane (outward normals)."""
    v0 = mesh.vertices[mesh.faces[:, 0]]
    return bool((np.einsum("fk,fk->f", np.asarray(p, float) - v0, mesh.face_normals) < 0).all())


def test_chamfered_box_keeps_its_size_and_bevels_its_edges():
    m = architecture.chamfer_box(1.2, 0.8, 0.5, bevel=0.02)
    assert np.allclose(m.bounds, [[-0.6, 0.0, -0.25], [0.6, 0.8, 0.25]])
    assert m.is_watertight and len(m.vertices) == 24            # 8 corners, each cut into 3
    # a corner is cut: the box's corner point lies outside the solid
    assert not _inside_convex(m, [0.599, 0.799, 0.249]) and _inside_convex(m, [0.55, 0.75, 0.2])


def test_chamfered_boxes_of_any_size_are_the_hull_of_their_three_inset_boxes():
    """The faces are taken once from a template hull: for random sizes and bevels the box is
    closed, faces outwards and has the volume and area of qhull's hull of the same corners."""
    import trimesh
    rng = np.random.default_rng(0)
    for _ in range(50):
        w, h, d = rng.uniform(0.02, 5.0, 3)
        bevel = rng.uniform(0.001, 0.5)
        m = architecture.chamfer_box(w, h, d, bevel, *rng.normal(size=3))
        b = min(bevel, w / 3, h / 3, d / 3)
        corners = np.concatenate([trimesh.creation.box(extents=e).vertices
                                  for e in ((w, h - 2 * b, d - 2 * b), (w - 2 * b, h, d - 2 * b), (w - 2 * b, h - 2 * b, d))])
        hull = trimesh.convex.convex_hull(corners)
        assert m.is_watertight and m.is_winding_consistent and m.volume > 0
        assert m.volume == pytest.approx(hull.volume, rel=1e-9) and m.area == pytest.approx(hull.area, rel=1e-9)


@pytest.mark.parametrize("name, kinds, least_m", [
    ("city_street", {"building", "lamp", "bollard", "kerb", "bench"}, 30.0),
    ("city_park", {"tree2", "bush", "bench"}, 30.0),
    ("living_room", {"wall", "sofa", "table", "chair", "shelf"}, 8.0)])
def test_layouts_build_their_places(name, kinds, least_m):
    env = environments.load_environment(name)
    assert kinds <= {o.kind for o in env.objects}
    boxes = environments.object_boxes(env)
    span = boxes[:, [3, 5]].max(0) - boxes[:, [0, 2]].min(0)
    assert span.min() >= least_m, span
    again = environments.load_environment(name)
    assert [o.to_dict() for o in again.objects] == [o.to_dict() for o in env.objects]   # from the seed


def test_facades_have_windows_and_a_door_and_trees_have_branches_and_leaves():
    rng = np.random.default_rng(0)
    roles = [r for _, r in architecture.building(12.0, 9.6, 8.0, rng)]
    floors, cols = 3, 5
    assert roles.count("glass") == floors * cols - 1 and roles.count("door") == 1
    parts = architecture.tree(3.0, 6.0, 3.0, np.random.default_rng(1))
    assert sum(r == "trunk" for _, r in parts) >= 1 + 5 * 4           # trunk, branches, twigs
    leaves = sum(len(m.faces) for m, r in parts if r.startswith("leaf")) // 2
    assert leaves > 5000


def test_room_walls_leave_a_door_and_windows_open():
    env = environments.load_environment("living_room")
    walls = [o for o in env.objects if o.kind == "wall"]
    lifted = [o for o in walls if o.lift > 0]                         # pieces over the openings
    assert len(lifted) == 1 + 2 * 3                                   # one door, two windows on three walls
    door = [o for o in lifted if abs(o.lift - 2.1) < 1e-9]                # a 2.1 m door; windows reach 2.3 m
    assert len(door) == 1
    x, z = door[0].position
    # at the door's middle, 1 m up, no wall piece stands
    for o in walls:
        (mesh, _), = environments.object_parts(o)
        assert not _inside_convex(mesh, [x, 1.0, z])


def test_people_are_placed_on_a_street_clear_of_its_objects():
    cfg = {"environments": ["city_street"], "subjects": {"count": 3, "seconds": 0.5},
           "cameras": {"count": 2, "width": 64, "height": 48}}
    spec = sm.compose_scene(cfg, np.random.default_rng(1), seed=1)
    boxes = environments.object_boxes(environments.load_environment("city_street"))
    for s in spec.subjects:
        x, z = s.position[0], s.position[-1]
        assert not ((boxes[:, 0] < x) & (x < boxes[:, 3]) & (boxes[:, 2] < z) & (z < boxes[:, 5])).any()
    assert len(spec.views) == 2


def test_the_six_built_places_have_branched_trees_bushes_and_slatted_benches():
    """No sphere-on-a-stick trees or bare blocks left: every tree forks into branches with
    leaves, every planter grows a bush, every bench has three slats."""
    for name in ("plaza", "park", "street", "courtyard", "beach", "gallery"):
        env = environments.load_environment(name)
        for obj in env.objects:
            roles = [r for _, r in environments.object_parts(obj)]
            if obj.kind in ("tree", "tree2"):
                assert roles.count("trunk") >= 1 + 5 * 4 and {"leaf", "leaf2"} <= set(roles), (name, obj.kind)
            if obj.kind == "planter":
                assert {"leaf", "leaf2", "trunk"} <= set(roles), name
            if obj.kind == "bench":
                assert roles.count("main") == 3 and roles.count("metal") == 2, name


@pytest.mark.parametrize("name, lo, hi", [
    ("courtyard", (-5.05, -np.inf, -5.05), (np.inf, np.inf, np.inf)),
    ("gallery", (-5.35, -np.inf, -4.85), (5.35, 3.8, 4.85))])   # a closed hall under its ceiling
def test_cameras_stay_on_the_people_side_of_walls(name, lo, hi):
    """camera_keep_out: no view stands behind a wall looking over it, or over a ceiling."""
    cfg = {"environments": [name], "subjects": {"count": 2, "seconds": 0.5},
           "cameras": {"count": 4, "width": 64, "height": 48, "pitch_deg": [-5, 60]}}
    spec = sm.compose_scene(cfg, np.random.default_rng(3), seed=3)
    centres = np.array([c.center for v in spec.views for c in v.cameras])
    assert len(spec.views) == 4
    assert (centres > lo).all() and (centres < hi).all(), (centres.min(0), centres.max(0))


def test_a_built_place_loads_one_bsdf_per_look_and_keeps_every_triangle():
    """Parts of one object with one look are one mesh, and every look is one Mitsuba BSDF:
    drjit traces a call over every live BSDF, and a BSDF per part (1,094 on city_street) made
    a 160x120 frame cost 3.6 s instead of 0.7 s."""
    import drjit as dr
    import mitsuba as mi
    from synmitsuba.engine.build import load
    from synmitsuba.engine.variant import require_variant
    require_variant()
    env = environments.load_environment("city_street")
    scene = sm.Scene()
    environments.add_environment(scene, env, environments.sample_lighting(env, np.random.default_rng(0)),
                                 np.random.default_rng(0))
    parts = [p for o in env.objects for p in environments.object_parts(o)]
    objects = {n: m for n, m in scene.meshes.items() if n.startswith("object")}
    assert sum(len(m.faces) for m in objects.values()) == sum(len(p.faces) for p, _ in parts)
    assert len(objects) < len(parts) / 4
    # roles and textured looks across all objects, counted from the parts themselves
    looks = {r if r != "main" else (o.texture, tuple(o.color), None if o.texture else o.roughness)
             for o in env.objects for _, r in environments.object_parts(o)}
    mi_scene = load(scene).mi_scene
    bsdf_ids = dr.reinterpret_array(mi.UInt32, mi_scene.shapes_dr().bsdf()).numpy()
    assert len(set(bsdf_ids.tolist())) == len(looks) + 1          # and the ground's
