"""The command line and scene files, end to end."""
import json
import textwrap

import numpy as np
import pytest

from synmitsuba.cli import main
from synmitsuba.errors import ConfigError
from synmitsuba.compose.scenefile import load_scene_file

SCENE = textwrap.dedent("""
    render: {spp: 4, width: 40, height: 30}
    environment: {type: constant, radiance: 0.8}
    materials:
      red: {kind: principled, base_color: [0.8, 0.1, 0.1], roughness: 0.4}
    objects:
      - {name: ground, primitive: {type: box, extents: [10, 0.02, 10]}, position: [0, -0.01, 0], instance: 0, layer: ground}
      - {name: ball, primitive: {type: icosphere, radius: 0.3}, position: [0, 0.3, 0], material: red, instance: 4, smooth: true}
      - {name: tri, mesh: tri.obj, position: [0.8, 0, 0], instance: 5}
    cameras:
      - {name: front, look_at: {eye: [0, 1, 3], target: [0, 0.3, 0], fov_y_deg: 40}}
      - {name: offaxis, K: [[50, 0, 12], [0, 60, 20], [0, 0, 1]], t: [0, -0.3, 3]}
""")


@pytest.fixture
def scene_dir(tmp_path):
    (tmp_path / "tri.obj").write_text("v 0 0 0\nv 0.4 0 0\nv 0 0.6 0\nf 1 2 3\n")
    (tmp_path / "s.yaml").write_text(SCENE)
    return tmp_path


def test_render_command_writes_every_view(sm, scene_dir, capsys):
    out = scene_dir / "out"
    assert main(["render", str(scene_dir / "s.yaml"), "--out", str(out), "--res", "32x24", "--quiet"]) == 0
    for name in ("front", "offaxis"):
        side = json.loads((out / f"{name}.json").read_text())
        assert side["width"] == 32 and side["height"] == 24 and side["meta"]["spp"] == 4
        s = sm.read_sample(out / name)
        assert s.rgb.shape == (24, 32, 3) and s.rgb.max() > 0.05
    front = sm.read_sample(out / "front")
    assert {4, 5} <= set(np.unique(front.instance))
    assert (front.layer[front.mask & (front.instance == 0)] == int(sm.Layer.GROUND)).all()
    assert "front.png" in capsys.readouterr().out


def test_info_names_variant_and_llvm(sm, capsys):
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    assert "llvm_ad_rgb" in out and "libLLVM" in out and "mitsuba" in out


def test_missing_mesh_file(scene_dir):
    (scene_dir / "tri.obj").unlink()
    with pytest.raises(ConfigError) as e:
        load_scene_file(scene_dir / "s.yaml")
    assert "objects[2].mesh" in str(e.value) and "tri.obj" in str(e.value)


def test_malformed_yaml_names_the_line(scene_dir, capsys):
    (scene_dir / "bad.yaml").write_text("render: {spp: 4\ncameras: [\n")
    assert main(["render", str(scene_dir / "bad.yaml"), "--out", str(scene_dir / "o")]) == 2
    err = capsys.readouterr().err
    assert "malformed YAML" in err and "line" in err and "bad.yaml" in err


def test_unknown_keys_and_bad_values_are_named(scene_dir):
    (scene_dir / "u.yaml").write_text(SCENE.replace("instance: 4,", "instnce: 4,"))
    with pytest.raises(ConfigError) as e:
        load_scene_file(scene_dir / "u.yaml")
    assert "objects[1].instnce" in str(e.value)
    (scene_dir / "k.yaml").write_text(SCENE.replace("[[50, 0, 12], [0, 60, 20]", "[[0, 0, 12], [0, 60, 20]"))
    with pytest.raises(ConfigError) as e:
        load_scene_file(scene_dir / "k.yaml")
    assert "cameras[1].K" in str(e.value) and "fx = K[0][0]" in str(e.value)


def test_bad_spp_and_res_on_the_command_line(sm, scene_dir, capsys):
    assert main(["render", str(scene_dir / "s.yaml"), "--out", str(scene_dir / "o"), "--spp", "0"]) == 2
    err = capsys.readouterr().err
    assert "--spp" in err and "'0'" in err and len(err.strip().splitlines()) == 1
    assert main(["render", str(scene_dir / "s.yaml"), "--out", str(scene_dir / "o"), "--res", "big"]) == 2
    assert "--res" in capsys.readouterr().err


def test_demo_scene_file_parses():
    import pathlib
    sf = load_scene_file(pathlib.Path(__file__).parents[1] / "scenes" / "demo.yaml")
    assert len(sf.cameras) >= 2 and len(sf.scene.meshes) >= 4


def test_scene_file_with_a_posed_subject(sm, tmp_path):
    (tmp_path / "people.yaml").write_text(textwrap.dedent("""
        render: {spp: 2, width: 32, height: 48}
        environment: {type: constant, radiance: 1.0}
        objects:
          - {name: ground, primitive: {type: box, extents: [10, 0.02, 10]}, position: [0, -0.01, 0], instance: 0, layer: ground}
        subjects:
          - {seed: 4, position: [0.2, 0.0], yaw_deg: 90, motion: walk, frame: 10, instance: 21}
        cameras:
          - {name: cam, look_at: {eye: [0, 1.0, 4.0], target: [0, 0.9, 0], fov_y_deg: 40}}
    """))
    assert main(["render", str(tmp_path / "people.yaml"), "--out", str(tmp_path / "o"), "--quiet"]) == 0
    s = sm.read_sample(tmp_path / "o" / "cam")
    assert set(np.unique(s.instance)) == {0, 21}
    assert int(sm.Layer.BODY) in set(np.unique(s.layer))
    (tmp_path / "bad.yaml").write_text((tmp_path / "people.yaml").read_text().replace("motion: walk", "motion: moonwalk"))
    assert main(["render", str(tmp_path / "bad.yaml"), "--out", str(tmp_path / "o")]) == 2
