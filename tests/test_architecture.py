"""The seams later stages build on: lazy imports, the pass and garment registries, scene files
that bring their people, the per-index sequence function, in-place animation."""
import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import trimesh

import synmitsuba as sm
from synmitsuba.errors import ConfigError


def test_import_loads_neither_mitsuba_nor_torch():
    code = "import sys, synmitsuba as sm; sm.Camera; sm.Scene; print(sorted(m for m in ('mitsuba', 'drjit', " \
           "'torch', 'anny', 'trimesh', 'scipy') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_render_is_a_plain_function_with_a_real_signature(sm):
    import inspect
    import types

    import synmitsuba.rendering.passes as passes
    assert sm.render is passes.render and isinstance(sm.render, types.FunctionType)
    params = inspect.signature(sm.render).parameters
    assert list(params)[:4] == ["scene", "camera", "spp", "seed"] and params["spp"].default == 16


def _sky_box(sm):
    scene = sm.Scene()
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    scene.add_mesh("box", box.vertices, box.faces, material=sm.Material(base_color=(0.5, 0.5, 0.5)), instance=1)
    scene.set_environment(sm.SunSky(sun_direction=(0.3, 1.0, 0.2)))
    return scene, sm.Camera.look_at(eye=(0, 1, 4), target=(0, 0, 0), fov_y_deg=50, width=24, height=16)


def test_diffscene_after_a_render_and_render_after_diffscene(sm):
    """The engine keeps its builds off the Scene: a DiffScene of a rendered scene (soft sun:
    a copy with another environment) loads, and driving its variables never changes what a
    plain render of the user's unchanged scene returns."""
    scene, cam = _sky_box(sm)
    before = sm.render(scene, cam, spp=4, seed=1).rgb
    ds = sm.DiffScene(scene, soft_sun_deg=2)  # KeyError 'environment.data' when the build rode on the copy
    ds.set("environment.sun_scale", 0.0)
    ds.set("environment.sky_scale", 0.0)
    ds.apply()
    assert float(np.array(ds.render(cam, spp=2)).mean()) == 0.0
    assert np.array_equal(sm.render(scene, cam, spp=4, seed=1).rgb, before)
    scene.set_environment(sm.Constant(0.8))
    plain = sm.render(scene, cam, spp=4, seed=1).rgb
    ds2 = sm.DiffScene(scene)
    ds2.set("environment.radiance", 0.0)
    ds2.apply()
    assert float(np.array(ds2.render(cam, spp=2)).mean()) == 0.0
    again = sm.render(scene, cam, spp=4, seed=1).rgb
    assert again.mean() > 0.5 and np.array_equal(again, plain)


def test_scene_changes_bump_its_version_and_copies_carry_no_build(sm):
    import copy

    from synmitsuba.engine.build import cached_build
    scene, cam = _sky_box(sm)
    sm.render(scene, cam, spp=1)
    v = scene.structure_version
    scene.environment = sm.Constant(0.0)  # direct assignment counts as a change
    assert scene.structure_version == v + 1
    assert sm.render(scene, cam, spp=1).rgb.max() == 0.0
    dup = copy.copy(scene)
    assert cached_build(dup) is None and cached_build(scene) is not None
    dup.add_mesh("extra", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    assert "extra" not in scene.meshes


def test_a_new_pass_is_one_declaration_plus_its_computation(sm, tmp_path):
    from synmitsuba.rendering.passes import EXACT_PASSES, exact_pass
    from synmitsuba.sample import PASSES, register_pass
    register_pass("ray_t", ("ray.T",), "float32", doc="distance along the pixel-centre ray")

    @exact_pass("ray_t")
    def _ray_t(h):
        import drjit as dr
        return dr.select(h.hit, h.si.t, 0.0)
    try:
        scene = sm.Scene()
        scene.add_mesh("wall", np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], float),
                       np.array([[0, 1, 2], [0, 2, 3]]), instance=1)
        scene.set_environment(sm.Constant(1.0))
        cam = sm.Camera.look_at(eye=(0, 0, 2), target=(0, 0, 0), fov_y_deg=60, width=16, height=12)
        s = sm.render(scene, cam, spp=1)
        # distance along each ray to the plane z = 0 from z = 2, against the camera's own rays
        d = cam.pixel_rays()
        assert np.allclose(s.ray_t, 2.0 / -d[..., 2], rtol=1e-5)
        sm.write_sample(s, tmp_path / "x")
        assert np.array_equal(sm.read_sample(tmp_path / "x").ray_t, s.ray_t)
    finally:
        EXACT_PASSES.pop("ray_t")
        PASSES.pop("ray_t")


def test_a_new_garment_kind_is_one_table_entry(sm):
    from synmitsuba.body import garments
    from synmitsuba.scene.layers import Layer
    garments.GARMENTS["vest"] = garments.GarmentKind(Layer.TOP, 0.014, 2, "shell", garments._top(lambda L: 0.0),
                                                     (0.3, 0.6))
    try:
        recipe = sm.sample_subject(np.random.default_rng(1), {"outfit": ["vest", "trousers"], "texture_size": 64})
        assert [g.kind for g in recipe.garments][:2] == ["vest", "trousers"]
        human = sm.build_subject(sm.SubjectRecipe.from_json(recipe.to_json()))
        vest = next(p for p in human.parts if p.name == "vest")
        r = human.regions
        assert len(vest.rest) > 500 and vest.layer == int(Layer.TOP)
        chin_below = human.keypoints()[0, 1] - 0.06  # the nose, less a nose-to-chin height
        front = (vest.rest[:, 2] > r.neck_xz[1]) & (np.abs(vest.rest[:, 0]) < 0.05)  # under the chin
        assert r.crotch_y - 0.15 < vest.rest[:, 1].min() and vest.rest[front, 1].max() < chin_below  # the torso
        assert vest.rest[:, 1].max() < r.neck_y + 0.07  # over the trapezius: the collar, an offset above the neck's base
        assert np.abs(vest.rest[:, 0]).max() < 0.3  # sleeve length 0: no arms
    finally:
        del garments.GARMENTS["vest"]
    with pytest.raises(ConfigError, match=r"recipe.garments\[0\].kind"):
        sm.SubjectRecipe.from_dict({"garments": [{"kind": "vest"}]})


def test_recipe_refuses_a_layered_smplx_subject():
    with pytest.raises(ConfigError) as e:
        sm.SubjectRecipe.from_dict({"model": "smplx"})
    assert "recipe.model" in str(e.value) and "smplx_body" in str(e.value)


PEOPLE = textwrap.dedent("""
    render: {spp: 1, width: 40, height: 56}
    environment: {type: constant, radiance: 1.0}
    objects:
      - {name: ground, primitive: {type: box, extents: [10, 0.02, 10]}, position: [0, -0.01, 0], instance: 0, layer: ground}
    subjects:
      - {position: [0.0, 0.0], motion: walk, config: {texture_size: 64, hair_style: long}}
    cameras:
      - {name: cam, look_at: {eye: [0, 1.0, 4.0], target: [0, 0.9, 0], fov_y_deg: 40}}
""")


def test_load_scene_file_brings_the_people(sm, tmp_path):
    (tmp_path / "p.yaml").write_text(PEOPLE.replace("{position", "{seed: 5, instance: 7, position"))
    sf = sm.load_scene_file(tmp_path / "p.yaml")
    assert len(sf.subjects) == 1 and sf.subjects[0].instance == 7
    assert "subject0_body" in sf.scene.meshes and "subject0_hair" in sf.scene.curves
    s = sm.render(sf.scene, sf.cameras[0][1], spp=1)
    assert 7 in s.instance_ids()


def test_scene_file_errors_name_the_full_path_before_building(sm, tmp_path, monkeypatch):
    import synmitsuba.compose.subjects as subjects
    monkeypatch.setattr(subjects, "build_subject", lambda r: pytest.fail("built a subject before checking"))
    cases = {"spp: 1": ("spp: 0", "render.spp"), "width: 40": ("width: -4", "render.width"),
             "motion: walk": ("motion: moonwalk", "subjects[0].motion"),
             "fov_y_deg: 40": ("fov_y_deg: 40, zoom: 2", "cameras[0].look_at.zoom"),
             "hair_style: long": ("hair_style: mohawk", "subjects[0].config.hair_style")}
    for old, (new, field) in cases.items():
        (tmp_path / "bad.yaml").write_text(PEOPLE.replace(old, new))
        with pytest.raises(ConfigError) as e:
            sm.load_scene_file(tmp_path / "bad.yaml")
        assert str(e.value).startswith(field + " = "), (field, str(e.value))


def test_scene_file_subject_ids_never_meet_object_ids(sm, tmp_path, monkeypatch):
    import synmitsuba.compose.subjects as subjects
    from synmitsuba.compose.scenefile import read_scene_doc
    (tmp_path / "p.yaml").write_text(PEOPLE.replace("instance: 0, layer", "instance: 100, layer"))
    doc = read_scene_doc(tmp_path / "p.yaml")
    assert subjects.subject_instances(doc.subjects, set(doc.object_instances())) == [200]
    monkeypatch.setattr(subjects, "build_subject", lambda r: pytest.fail("built a subject before checking"))
    (tmp_path / "p.yaml").write_text(PEOPLE.replace("instance: 0, layer", "instance: 7, layer")
                                     .replace("{position", "{instance: 7, position"))
    with pytest.raises(ConfigError, match=r"^subjects\[0\]\.instance = 7: another subject or an object"):
        sm.load_scene_file(tmp_path / "p.yaml")


def _scene_config(sm, path, **kw):
    return sm.GenerateConfig(scene=str(path), frames=3, stride=4, render={"spp": 1}, **kw).to_dict()


def test_scene_file_sequence_is_reproducible_and_moves_everything_in_place(sm, tmp_path):
    """A scene file generates through the one per-task function, seeded from (seed, index)."""
    from synmitsuba.engine.build import STATS
    from synmitsuba.generate.run import run_sequence
    (tmp_path / "p.yaml").write_text(PEOPLE)
    cfg = _scene_config(sm, tmp_path / "p.yaml", flow="adjacent")  # flow copies built at frame 0 even for one frame
    loads = STATS["loads"]
    run_sequence({**cfg, "frames": 1}, 2, str(tmp_path / "one"))
    per_sequence, loads = STATS["loads"] - loads, STATS["loads"]
    entry = run_sequence(cfg, 2, str(tmp_path / "a"))
    assert STATS["loads"] - loads == per_sequence  # moved in place: no frame after the first loads a scene
    run_sequence(cfg, 2, str(tmp_path / "b"))
    stems = [str(tmp_path / "a" / entry["folder"] / s) for s in entry["samples"]]
    for x in stems:
        y = x.replace(str(tmp_path / "a"), str(tmp_path / "b"))
        for ext in (".exr", ".json"):
            assert open(x + ext, "rb").read() == open(y + ext, "rb").read()
    a = [sm.read_sample(s) for s in stems]
    assert not np.array_equal(a[0].mask, a[2].mask)  # the subject walks
    other = run_sequence(cfg, 3, str(tmp_path / "c"))
    first = sm.read_sample(tmp_path / "c" / other["folder"] / other["samples"][0])
    assert not np.array_equal(first.rgb, a[0].rgb)  # another sequence, another person
    side = json.load(open(stems[1] + ".json"))
    assert side["meta"]["sequence"] == 2 and side["meta"]["frame"] == 4 and "seconds" not in side["meta"]
    assert side["meta"]["camera_motion"] == "static" and side["meta"]["flow_frames"] == {"fwd": 5, "bwd": 3}
    assert side["subjects"][0]["instance"] == 100 and "keypoints2d" in side["subjects"][0]
    with pytest.raises(ConfigError, match=r"^frames = 0"):
        sm.GenerateConfig.from_dict({"scene": cfg["scene"], "frames": 0})


def test_scene_file_render_is_sequence_zero_of_generate(sm, tmp_path, tiny):
    """``synmitsuba render`` writes what ``generate`` writes for sequence 0 of a config naming
    the scene file, byte for byte, with the same label keys and passes as a composed scene."""
    from synmitsuba.cli import main
    from synmitsuba.generate.run import generate
    (tmp_path / "p.yaml").write_text(PEOPLE)
    assert main(["render", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "r"), "--frames", "3", "--stride", "4",
                 "--spp", "1", "--quiet"]) == 0
    generate(sm.GenerateConfig.from_dict({**_scene_config(sm, tmp_path / "p.yaml"), "sequences": 1}),
             str(tmp_path / "g"), progress=False)
    names = sorted(p.name for p in (tmp_path / "r").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "g" / "seq_000000").iterdir()) and len(names) == 10
    for n in names:
        assert (tmp_path / "r" / n).read_bytes() == (tmp_path / "g" / "seq_000000" / n).read_bytes(), n
    mine, composed = sm.read_sample(tmp_path / "r" / "f0000_cam"), sm.read_sample(tiny / "seq_000000" / "f0000_cam0")
    assert set(mine.subjects[0]) == set(composed.subjects[0])
    assert set(mine.passes) == set(composed.passes)
    assert set(mine.meta) == set(composed.meta)


def test_scene_file_spec_round_trips_and_rebuilds_the_same_scene(sm, tmp_path):
    """A scene file's SceneSpec, written and read back, builds the same meshes and curves; its
    subject shows the entry's ``frame`` first and stands on the ground."""
    from synmitsuba.compose.scenefile_spec import scene_spec
    (tmp_path / "p.yaml").write_text(PEOPLE.replace("motion: walk", "motion: walk, frame: 7"))
    spec = scene_spec(str(tmp_path / "p.yaml"), str(tmp_path / "p.yaml"), sm.sequence_rng(0, 0))
    again = sm.SceneSpec.from_json(spec.to_json())
    assert again.stage == "scene_file" and again.subjects[0].motion.start == 7 and len(again.views[0].cameras) == 60
    a, b = spec.build()[0], again.build()[0]
    assert set(a.meshes) == set(b.meshes) and set(a.curves) == set(b.curves)
    for name in a.meshes:
        assert np.array_equal(a.meshes[name].vertices, b.meshes[name].vertices), name
    placed = again.build()[1][0]
    lowest = min(lay.vertices[:, 1].min() for f in range(placed.motion.n_frames)
                 for lay in placed.human.pose(*placed.motion.frame(f), resolve=False) if not lay.is_curves)
    assert abs(lowest) < 1e-6  # the clip's lowest point over the clip is on the ground


def test_scene_keeps_the_previous_positions_for_flow(sm):
    scene = sm.Scene()
    box = trimesh.creation.box((1, 1, 1))
    scene.add_mesh("box", box.vertices, box.faces)
    scene.add_curves("c", np.zeros((2, 4, 3)) + np.arange(4)[None, :, None], radius=0.01)
    scene.update_mesh("box", box.vertices + 1)
    scene.update_curves("c", scene.curves["c"].points + 2)
    assert np.array_equal(scene.meshes["box"].previous_vertices, box.vertices)
    assert np.array_equal(scene.curves["c"].previous_points + 2, scene.curves["c"].points)


def test_hair_redness_reaches_the_bsdf(sm):
    """The same blond strands rendered with redness 0 and 1: red hair reflects more red than green
    (measured R/G 1.48 and 1.89 on linear curves; darker hair hides it under the white specular
    lobe)."""
    t = np.linspace(0, 1, 6)
    strands = np.array([[[x, 0.3 + 0.8 * s, 0.0] for s in t] for x in np.linspace(-0.3, 0.3, 25)])
    ratios = []
    for redness in (0.0, 1.0):
        scene = sm.Scene()
        scene.add_curves("hair", strands, radius=0.012,
                         material=sm.Material(kind="hair", melanin=0.1, redness=redness), instance=1)
        scene.set_environment(sm.Constant(1.0))
        cam = sm.Camera.look_at(eye=(0, 0.7, 1.5), target=(0, 0.7, 0), width=32, height=32)
        s = sm.render(scene, cam, spp=16)
        rgb = s.rgb[s.mask].mean(0)
        ratios.append(rgb[0] / rgb[1])
    assert ratios[1] > 1.2 * ratios[0]


def test_strands_take_their_own_melanin(sm):
    """Per-strand melanin: a comb of strands alternating blond (0.05) and black (0.95) in one
    curve shape renders the blond strands several times brighter (each strand's row of the
    sigma_a bitmap reaches its own segments), the same shape with one melanin renders even, and
    exactly as Mitsuba's own pigment parameters do. Only fully covered pixels count (alpha > 0.99): edge pixels mix in the bright sky."""
    t = np.linspace(0, 1, 10)
    xs = np.linspace(-0.3, 0.3, 8)
    strands = np.array([[[x, 0.3 + 0.8 * s, 0.0] for s in t] for x in xs])
    cam = sm.Camera.look_at(eye=(0, 0.7, 1.5), target=(0, 0.7, 0), width=128, height=128)
    means = {}
    for label, shade in (("mixed", np.tile([0.05, 0.95], 4)), ("even", np.full(8, 0.5))):
        scene = sm.Scene()
        scene.add_curves("hair", strands, radius=0.012,
                         material=sm.Material(kind="hair", melanin=0.5, strand_melanin=shade), instance=1)
        scene.set_environment(sm.Constant(1.0))
        s = sm.render(scene, cam, spp=16)
        full = s.alpha > 0.99
        strand = np.argmin(np.abs(s.position[..., 0][..., None] - xs), -1)  # the strand each pixel shows
        means[label] = np.array([s.rgb[full & (strand == i)].mean() for i in range(8)])
    blond, black = means["mixed"][0::2], means["mixed"][1::2]
    assert blond.min() > 3 * black.max(), (blond, black)
    assert means["even"].max() < 1.5 * means["even"].min(), means["even"]
    same = []  # one melanin for every strand renders as Mitsuba's own eumelanin/pheomelanin parameters
    for shade in (None, np.full(8, 0.3)):
        scene = sm.Scene()
        scene.add_curves("hair", strands, radius=0.012, instance=1,
                         material=sm.Material(kind="hair", melanin=0.3, redness=0.4, strand_melanin=shade))
        scene.set_environment(sm.Constant(1.0))
        same.append(sm.render(scene, cam, spp=4).rgb)
    assert np.abs(same[0] - same[1]).max() < 1e-4
    with pytest.raises(ConfigError, match="strand_melanin"):
        sm.Material(kind="hair", strand_melanin=[0.5, 1.5])
    with pytest.raises(ConfigError, match=r"hair\.material\.strand_melanin = '3 values'.*one melanin per strand: 8"):
        sm.Scene().add_curves("hair", strands, material=sm.Material(kind="hair", strand_melanin=[0.5] * 3))


def test_motion_sources_resolve_in_one_place(tmp_path):
    from synmitsuba.motion.sources import load_motion
    rng = np.random.default_rng(0)
    assert load_motion("walk", rng, seconds=1.0).n_frames == 30
    with pytest.raises(ConfigError, match=r"subjects\[3\].motion = 'fly'"):
        load_motion("fly", rng, field="subjects[3].motion")
    with pytest.raises(ConfigError, match="no such file"):
        load_motion("missing.bvh", rng, base=str(tmp_path))


def test_library_use_leaves_the_process_as_it_found_it(tmp_path):
    """Building a subject, rendering it and drawing the stats figure change no environment
    variable, torch thread count, collector state or matplotlib backend: only the CLI or a
    worker opts in (synmitsuba.process.configure_process)."""
    code = textwrap.dedent("""
        import gc, json, os
        import matplotlib, numpy as np, torch
        before = (dict(os.environ), torch.get_num_threads(), gc.get_freeze_count(), matplotlib.get_backend())
        import synmitsuba as sm
        from synmitsuba.data.stats import stats_figure
        h = sm.build_subject(sm.sample_subject(np.random.default_rng(1), {"texture_size": 64}))
        scene = sm.Scene(); h.add_to(scene, instance=1); scene.set_environment(sm.Constant(1.0))
        sm.render(scene, sm.Camera.look_at(eye=(0, 1, 3), target=(0, 1, 0), width=16, height=16), spp=1)
        stats_figure({k: [1.0, 2.0] for k in ("visible_fraction", "subject_height_m", "stature_m", "bmi",
                      "camera_distance_m", "camera_pitch_deg", "skin_ita_deg")} | {k: {"a": 1} for k in
                      ("keypoint_visibility", "garments", "motions")} | {"sequences": 1, "subjects": 1, "frames": 1,
                      "samples": 1}, os.path.join(%r, "s.png"))
        after = (dict(os.environ), torch.get_num_threads(), gc.get_freeze_count(), matplotlib.get_backend())
        changed = sorted(k for k, v in set(after[0].items()) ^ set(before[0].items())
                         if not k.startswith("TORCHINDUCTOR_"))  # torch's inductor sets its own cache folder
        print(changed)
        print(json.dumps([not changed, before[1:], after[1:]]))
    """ % str(tmp_path))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    same_env, before, after = json.loads(out.stdout.strip().splitlines()[-1])
    assert same_env, out.stdout.strip().splitlines()[-2]  # the variables that changed
    assert before == after


def test_format_document_lists_exactly_the_registered_passes():
    """docs/FORMAT.md's pass table names the passes ``sample.PASSES`` registers, no more (the
    coverage and amodal masks are per-instance channels, described below the table)."""
    import pathlib

    from synmitsuba.sample import PASSES
    text = (pathlib.Path(__file__).parents[1] / "docs" / "FORMAT.md").read_text()
    table = text.split("## Passes", 1)[1].split("\n\n", 2)[1]
    rows = [line.strip("|").split("|")[0] for line in table.splitlines() if line.startswith("| ")][1:]
    assert {n.strip() for row in rows for n in row.split(",")} == set(PASSES)


def test_new_kinds_are_one_registry_entry(monkeypatch):
    """A camera motion, a ground texture and a garment shape are added by one entry each; the
    config checks accept the new names and the builders use them (no if-chain to extend)."""
    from synmitsuba.body import garments
    from synmitsuba.compose import cameras, environments
    raise_eye = cameras.CameraMotion(lambda s, *args: setattr(s, "eye", s.eye + [0.0, 1.0, 0.0]))
    monkeypatch.setitem(cameras.CAMERA_MOTIONS, "crane", raise_eye)
    cfg = cameras.CameraConfig.from_dict({"motion": ["crane"]})
    F = 5
    group = cameras.Group(np.zeros((F, 3)) + [0, 1, 0], np.array([0.0, 1.0, 0.0]), np.zeros((1, 6)), np.zeros((F, 1, 6)))
    K = np.array([[300.0, 0, 160], [0, 300, 120], [0, 0, 1]])
    still = cameras.trajectory("static", group, 0.0, 0.0, 4.0, K, cfg, np.random.default_rng(0))
    crane = cameras.trajectory("crane", group, 0.0, 0.0, 4.0, K, cfg, np.random.default_rng(0))
    assert np.allclose(crane.eye - still.eye, [0.0, 1.0, 0.0]) and crane.kind == "crane"
    from synmitsuba.compose import grounds

    def snow(base, layout, tone, n, period):
        return grounds.GroundMaps(np.broadcast_to(base, (n, n, 3)).copy(), np.zeros((n, n)), np.full((n, n), 0.6), period)
    monkeypatch.setitem(grounds.GROUND_MATERIALS, "snow", grounds.GroundKind(snow, 5.0, (1.0, 1.0, 1.0)))
    ground = environments.Ground.from_dict({"texture": "snow", "color": [0.9, 0.8, 0.7]})
    mat, period = grounds.ground_material(ground.texture, ground.color, np.random.default_rng(0), ground.period_m, n=8)
    assert np.allclose(mat.a.texture, [0.9, 0.8, 0.7]) and np.allclose(mat.b.roughness_map, 0.6) and period == 5.0
    with pytest.raises(ConfigError, match="texture = 'lava'"):
        environments.Ground.from_dict({"texture": "lava"})
    assert set(g.shape for g in garments.GARMENTS.values()) <= set(garments.GARMENT_SHAPES)
