"""Your own environment: a glTF scene with a raised floor and a table. Subjects stand on the
floor, never inside the table; cameras are never inside the mesh; materials come through."""
import numpy as np
import pytest

import synmitsuba as sm
from synmitsuba.compose import environments

FLOOR_Y = 0.5                     # the slab's top, in the file's coordinates
TABLE = (1.2, 0.75, 0.8)          # width, height, depth; centred at x = 1.0, z = 0.5


def _scene_file(tmp_path) -> str:
    """A GLB: a 10 x 10 m slab whose top is at y = 0.5 (textured: red and blue halves) and a
    table on it (top and four legs)."""
    import trimesh
    from PIL import Image
    slab = trimesh.creation.box(extents=(10.0, 0.4, 10.0)).apply_translation((0, FLOOR_Y - 0.2, 0))
    tex = np.zeros((8, 8, 3), np.uint8)
    tex[:, :4], tex[:, 4:] = (200, 40, 40), (40, 40, 200)
    uv = (slab.vertices[:, [0, 2]] + 5.0) / 10.0
    slab.visual = trimesh.visual.TextureVisuals(uv=uv, material=trimesh.visual.material.PBRMaterial(
        baseColorTexture=Image.fromarray(tex), roughnessFactor=0.8))
    w, h, d = TABLE
    top = trimesh.creation.box(extents=(w, 0.05, d)).apply_translation((1.0, FLOOR_Y + h - 0.025, 0.5))
    legs = [trimesh.creation.box(extents=(0.06, h - 0.05, 0.06)).apply_translation(
        (1.0 + sx * (w / 2 - 0.05), FLOOR_Y + (h - 0.05) / 2, 0.5 + sz * (d / 2 - 0.05))) for sx in (-1, 1) for sz in (-1, 1)]
    scene = trimesh.Scene([slab, top, *legs])
    path = str(tmp_path / "room.glb")
    scene.export(path)
    return path


def test_floor_is_found_and_lifted_to_zero(tmp_path):
    path = _scene_file(tmp_path)
    env = environments.load_environment(path)
    parts, floor = environments.mesh_floor(env)
    assert floor.offset_y == pytest.approx(-FLOOR_Y, abs=1e-4)
    assert env.area == pytest.approx([-5.0, -5.0, 5.0, 5.0], abs=0.11)
    # the table's footprint is an obstacle, open floor is not
    boxes = environments.object_boxes(env)
    inside = lambda x, z: bool(((boxes[:, 0] <= x) & (x <= boxes[:, 3]) & (boxes[:, 2] <= z) & (z <= boxes[:, 5])).any())
    assert inside(1.0, 0.5) and inside(1.5, 0.8) and not inside(-2.0, -2.0) and not inside(3.0, 3.0)
    # the texture came through (sRGB 200 -> linear 0.578)
    tex = [p.material.texture for p in parts if p.material.texture is not None]
    assert tex and np.allclose(tex[0].max((0, 1)), [0.578, 0.021, 0.578], atol=0.01)


def test_subjects_stand_on_the_floor_clear_of_the_table_and_cameras_outside_the_mesh(tmp_path):
    import trimesh
    path = _scene_file(tmp_path)
    cfg = {"environments": [path], "subjects": {"count": 3, "seconds": 0.5},
           "cameras": {"count": 3, "width": 64, "height": 48}}
    spec = sm.compose_scene(cfg, np.random.default_rng(2), seed=2)
    scene, placed = spec.build()
    w, h, d = TABLE
    table = trimesh.creation.box(extents=(w, h, d)).apply_translation((1.0, h / 2, 0.5))   # floor at 0 now
    for frame in (0, 7, 14):                                            # a 0.5 s clip at 30 fps
        for subject in placed:
            subject.pose_in(scene, frame)
        for name, mesh in scene.meshes.items():
            if mesh.instance >= 100:
                v = mesh.vertices
                assert v[:, 1].min() > -0.03, (frame, name)              # on the floor (y = 0), not in the slab
                assert not table.contains(v[::20]).any(), (frame, name)  # never inside the table
    solids = [trimesh.creation.box(extents=(10.0, 0.4, 10.0)).apply_translation((0, -0.2, 0)), table]
    for view in spec.views:
        for cam in view.cameras:
            assert not any(s.contains(cam.center[None])[0] for s in solids)
            assert cam.center[1] > 0 and np.abs(cam.center[[0, 2]]).max() < 5.0
    floor = [m for n, m in scene.meshes.items() if n.endswith("_floor")]
    assert floor and all(m.layer == int(sm.Layer.GROUND) for m in floor)
    assert all(abs(m.vertices[:, 1]).max() < 1e-6 for m in floor)


def test_a_mesh_without_a_floor_is_refused(tmp_path):
    import trimesh
    path = str(tmp_path / "ball.ply")
    trimesh.creation.icosphere(radius=1.0).export(path)
    with pytest.raises(sm.ConfigError, match="floor"):
        environments.load_environment(path)
