"""The command line and scene files, end to end."""
import json
import pathlib
import textwrap

import numpy as np
import pytest

from synmitsuba.cli import main
from synmitsuba.errors import ConfigError
from synmitsuba.compose.scenefile_spec import load_scene_file

ROOT = pathlib.Path(__file__).resolve().parents[1]
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
    for name in ("f0000_front", "f0000_offaxis"):
        side = json.loads((out / f"{name}.json").read_text())
        assert side["width"] == 32 and side["height"] == 24 and side["meta"]["spp"] == 4
        s = sm.read_sample(out / name)
        assert s.rgb.shape == (24, 32, 3) and s.rgb.max() > 0.05
    front = sm.read_sample(out / "f0000_front")
    assert {4, 5} <= set(np.unique(front.instance))
    assert (front.layer[front.mask & (front.instance == 0)] == int(sm.Layer.GROUND)).all()
    assert "f0000_front.png" in capsys.readouterr().out
    assert sm.SceneSpec.from_json((out / "scene.json").read_text()).views[1].name == "offaxis"


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
    s = sm.read_sample(tmp_path / "o" / "f0000_cam")
    assert set(np.unique(s.instance)) == {0, 21}
    assert int(sm.Layer.BODY) in set(np.unique(s.layer))
    (tmp_path / "bad.yaml").write_text((tmp_path / "people.yaml").read_text().replace("motion: walk", "motion: moonwalk"))
    assert main(["render", str(tmp_path / "bad.yaml"), "--out", str(tmp_path / "o")]) == 2


def _run(*args, **kw):
    import subprocess
    import sys
    return subprocess.run([sys.executable, "-m", "synmitsuba", *args], capture_output=True, text=True,
                          timeout=300, **kw)


def test_version_and_help_with_defaults(capsys):
    from synmitsuba import __version__
    from synmitsuba.cli import build_parser
    assert main(["--version"]) == 0 and capsys.readouterr().out.strip() == f"synmitsuba {__version__}"
    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    assert {"render", "info", "subject", "motion"} <= set(commands)
    subs = dict(commands)
    subs["motion preview"] = commands["motion"]._subparsers._group_actions[0].choices["preview"]
    for name, sub in subs.items():
        assert sub.description, name
        for action in sub._actions:
            if action.dest not in ("help", "motion_command"):
                assert action.help, (name, action.dest)
        text = sub.format_help()
        assert "(default: None)" not in text
        for action in sub._actions:
            hidden = action.default is None or action.default is False or action.default == "==SUPPRESS=="
            if not hidden and action.option_strings:
                assert f"(default: {action.default})" in " ".join(text.split()), (name, action.dest)
            elif action.option_strings and not action.required and action.dest not in ("help", "quiet", "stick"):
                assert "default" in action.help, (name, action.dest)  # says what applies
    assert "Run 'synmitsuba COMMAND --help'" in parser.format_help()


@pytest.mark.parametrize("argv,names", [
    (["subject", "--res", "big", "--out", "o"], ["--res", "'big'", "WIDTHxHEIGHT"]),
    (["subject", "--views", "0", "--out", "o"], ["--views", "'0'"]),
    (["subject", "--seed", "-1", "--out", "o"], ["--seed", "'-1'"]),
    (["subject", "--env", "hdri_studio,moon", "--out", "o"], ["--env", "'moon'", "hdri_studio"]),
    (["motion", "preview", "walk", "--frames", "0", "--out", "o"], ["--frames", "'0'"]),
    (["motion", "preview", "walk", "--seconds", "-2", "--out", "o"], ["--seconds"]),
    (["motion", "preview", "moonwalk", "--out", "o"], ["CLIP = 'moonwalk'", "walk"]),
    (["motion", "preview", "walk", "--outfit", "tshirt,skort", "--out", "o"], ["--outfit = 'tshirt,skort'", "skirt"]),
    (["render", "nope.yaml", "--out", "o"], ["scene file", "nope.yaml", "no such file"]),
])
def test_bad_arguments_get_one_line_and_exit_2(argv, names, tmp_path, capsys):
    assert main(argv[:-1] + [str(tmp_path / argv[-1])]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    for n in names:
        assert n in err, (n, err)
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_unwritable_out_is_refused_before_any_work(scene_dir, capsys):
    (scene_dir / "file").write_text("not a folder")
    for argv in (["render", str(scene_dir / "s.yaml")], ["subject"], ["motion", "preview", "walk"]):
        assert main(argv + ["--out", str(scene_dir / "file" / "sub")]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.split(": error: ")[1].startswith("--out = "), err


def test_a_view_that_sees_nothing_warns_on_one_line(sm, scene_dir, capsys):
    text = SCENE.replace("{eye: [0, 1, 3], target: [0, 0.3, 0], fov_y_deg: 40}", "{eye: [0, 1, 3], target: [0, 5, 9]}")
    (scene_dir / "away.yaml").write_text(text.replace("      - {name: offaxis", "#"))
    assert main(["render", str(scene_dir / "away.yaml"), "--out", str(scene_dir / "o"), "--quiet"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["synmitsuba render: warning: the camera sees no geometry: every pixel is background; check the "
                   "camera's position, target and field of view"]


def test_no_third_party_banner_and_clean_stdout(tmp_path):
    r = _run("subject", "--sheet", "1", "--res", "24x32", "--spp", "1", "--closeup", "mouth", "--out",
             str(tmp_path / "s.png"))
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == str(tmp_path / "s.png")
    assert "Warp" not in r.stderr and "CUDA" not in r.stderr, r.stderr


def test_portraits_under_an_hdri_are_two_views_each(sm, tmp_path):
    """``--closeup portrait --env hdri_studio``: a frontal and a three-quarter tile per subject,
    in the studio panorama: behind the head its curtains, not the preview stage's sky (the same
    command without ``--env``); a ``.jpg`` sheet is a JPEG."""
    from PIL import Image
    tiles = {}
    for env in (["--env", "hdri_studio"], []):
        out = tmp_path / f"p{len(env)}.{'jpg' if env else 'png'}"
        assert main(["subject", "--sheet", "1", "--closeup", "portrait", "--res", "32x32", "--spp", "2",
                     "--out", str(out)] + env) == 0
        with Image.open(out) as im:
            assert im.format == ("JPEG" if env else "PNG")
            tiles[len(env)] = np.asarray(im.convert("RGB")).astype(float)
    assert tiles[2].shape == (32 + 4, 2 * 32 + 6, 3)
    for x in (2, 2 + 34):
        studio, sky = (tiles[k][2:8, x:x + 6].reshape(-1, 3).mean(0) for k in (2, 0))
        assert sky[2] - sky[0] > 30 and abs(studio[2] - studio[0]) < 25 and sky.mean() - studio.mean() > 30, (sky, studio)


@pytest.mark.parametrize("delay", [0.0, 1.0, 3.0])
def test_ctrl_c_is_one_line_and_leaves_nothing_half_written(delay, tmp_path):
    """Ctrl-C at any moment (building subjects, tracing a kernel, rendering) ends the command at
    once with one line and exit 130; a KeyboardInterrupt inside drjit used to hang or abort."""
    import signal
    import subprocess
    import sys
    import time
    out = tmp_path / "o"
    p = subprocess.Popen([sys.executable, "-m", "synmitsuba", "render", "scenes/demo.yaml", "--out", str(out),
                          "--res", "200x160", "--spp", "2048", "--quiet"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, cwd=str(ROOT))
    t0 = time.time()
    while not out.exists() and p.poll() is None and time.time() - t0 < 120:  # the command has started its work
        time.sleep(0.05)
    time.sleep(delay)
    p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        pytest.fail("the command did not end within 60 s of Ctrl-C")
    assert p.returncode == 130, err
    assert err.strip().splitlines() == ["synmitsuba render: interrupted; files already written are complete, "
                                        "nothing half-written was kept"]
    names = sorted(f.name for f in out.iterdir())
    assert not any(".tmp-" in n for n in names)
    stems = {n.rsplit(".", 1)[0] for n in names}
    assert all((out / f"{s}.exr").exists() for s in stems if (out / f"{s}.json").exists())


def test_stats_to_an_unwritable_place_is_one_line(tiny, capsys):
    """It ended in a FileNotFoundError traceback after computing everything."""
    assert main(["stats", str(tiny), "--out", "/proc/x.png"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("synmitsuba stats: error: --out = "), err
