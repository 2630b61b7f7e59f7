"""EXR + JSON + PNG writing and reading back."""
import json

import numpy as np
import trimesh


def small_sample(sm, seed=0):
    scene = sm.Scene()
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.4)
    scene.add_mesh("ball", ball.vertices, ball.faces, instance=12, layer=sm.Layer.BODY,
                   material=sm.Material(base_color=(0.9, 0.3, 0.1)))
    scene.set_environment(sm.Constant(1.0))
    K = np.array([[40.0, 0, 14.0], [0, 44.0, 11.0], [0, 0, 1]])
    cam0 = sm.Camera.look_at(eye=(0, 0.2, 2), target=(0, 0, 0))
    return sm.render(scene, sm.Camera(K=K, R=cam0.R, t=cam0.t, width=30, height=20), spp=4, seed=seed)


def test_exr_round_trip_is_bit_exact(sm, tmp_path):
    s = small_sample(sm)
    paths = sm.write_sample(s, tmp_path / "0000")
    assert sorted(p.rsplit(".", 1)[1] for p in paths.values()) == ["exr", "json", "png"]
    r = sm.read_sample(tmp_path / "0000")
    for name in s.passes:
        a, b = getattr(s, name), getattr(r, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a, b), name
    assert sorted(r.coverage) == sorted(s.coverage) == [12]
    assert np.array_equal(r.coverage[12], s.coverage[12])
    np.testing.assert_array_equal(r.camera.K, s.camera.K)
    np.testing.assert_array_equal(r.camera.R, s.camera.R)
    assert r.camera.width == 30 and r.camera.height == 20
    assert not list(tmp_path.glob("*.tmp*"))


def test_exr_bytes_do_not_depend_on_the_thread_count(sm, tmp_path, monkeypatch):
    """write_sample compresses EXR blocks on drjit's thread count; the file must not change."""
    import OpenEXR

    from synmitsuba.engine import variant
    s = small_sample(sm)
    big = sm.Sample(camera=sm.Camera(K=s.camera.K, R=s.camera.R, t=s.camera.t, width=30, height=200),
                    passes={k: np.concatenate([v] * 10, axis=0) for k, v in s.passes.items()},
                    coverage={k: np.concatenate([v] * 10, axis=0) for k, v in s.coverage.items()}, meta=s.meta)
    files = []
    for n in (1, 3):
        monkeypatch.setitem(variant._state, "threads", n)
        sm.write_sample(big, tmp_path / f"t{n}", preview=False)
        assert OpenEXR.global_thread_count() == n
        files.append((tmp_path / f"t{n}.exr").read_bytes())
    assert files[0] == files[1] and len(files[0]) > 1000


def test_exr_has_named_channels_and_camera_header(sm, tmp_path):
    import OpenEXR
    sm.write_sample(small_sample(sm), tmp_path / "x")
    with OpenEXR.File(str(tmp_path / "x.exr"), separate_channels=True) as f:
        names = set(f.channels())
        header = json.loads(f.header()["synmitsuba"])
        assert f.channels()["depth.Z"].pixels.dtype == np.float32
        assert f.channels()["instance"].pixels.dtype == np.uint32
    expected = {"R", "G", "B", "A", "depth.Z", "normal.X", "normal.Y", "normal.Z", "position.X",
                "position.Y", "position.Z", "uv.U", "uv.V", "instance", "layer", "mask"}
    assert expected <= names
    side = json.loads((tmp_path / "x.json").read_text())
    assert header["camera"] == side["camera"] and side["instances"] == [12]
    assert side["camera"]["convention"] == "opencv_world_to_camera"


def test_png_preview_uses_srgb_encoding(sm, tmp_path):
    from PIL import Image
    s = small_sample(sm)
    sm.write_sample(s, tmp_path / "p")
    png = np.asarray(Image.open(tmp_path / "p.png"))
    lin = np.clip(s.rgb, 0, 1)
    # IEC 61966-2-1, written out independently of colour-science
    srgb = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    assert np.abs(png.astype(float) - np.round(srgb * 255)).max() <= 1


def test_to_srgb8_known_values(sm):
    out = sm.to_srgb8(np.array([[0.0, 0.0031308, 0.18, 1.0, 2.0]]).reshape(1, 5, 1).repeat(3, -1))
    assert out[0, :, 0].tolist() == [0, 10, 118, 255, 255]


def test_torch_dataset_lists_only_complete_samples(sm, tmp_path):
    import torch
    s = small_sample(sm)
    sm.write_sample(s, tmp_path / "a" / "0000")
    sm.write_sample(s, tmp_path / "a" / "0001")
    (tmp_path / "a" / "0002.exr").write_bytes(b"half-written")  # no sidecar: not done
    ds = sm.SampleDataset(tmp_path)
    assert len(ds) == 2 and isinstance(ds, torch.utils.data.Dataset)
    item = next(iter(torch.utils.data.DataLoader(ds, batch_size=2)))
    assert item["rgb"].shape == (2, 3, 20, 30) and item["depth"].shape == (2, 20, 30)
    assert item["instance"].dtype == torch.int32 and item["K"].shape == (2, 3, 3)
    assert torch.equal(item["depth"][0], torch.from_numpy(s.depth))


def test_subject_records_are_typed_and_write_back_the_same_bytes(sm, tiny, tmp_path):
    """Label records are dataclasses (read as mappings in the JSON's key order); a sample read
    and written again gives the same JSON, byte for byte, and arrays take their fields' dtypes."""
    from synmitsuba.annotate.labels import BodyParams, SubjectLabels
    stem = sorted((tiny / "seq_000000").glob("f*_cam0.json"))[-1].with_suffix("")  # the last frame: flow both ways
    s = sm.read_sample(stem)
    rec = s.subjects[0]
    assert isinstance(rec, SubjectLabels) and isinstance(rec.body_params_cam, BodyParams)
    assert rec.visibility.dtype == np.uint8 and rec.keypoints2d.dtype == np.float64 and rec.amodal_mask.dtype == bool
    assert rec["keypoints2d"] is rec.keypoints2d and rec["body_params_cam"]["rotations"] is rec.body_params_cam.rotations
    side = json.loads(stem.with_suffix(".json").read_text())
    assert [k for k in rec if k != "amodal_mask"] == list(side["subjects"][0])
    sm.write_sample(s, tmp_path / "again")
    assert (tmp_path / "again.json").read_bytes() == stem.with_suffix(".json").read_bytes()
