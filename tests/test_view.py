"""``synmitsuba view``: a sequence as a Rerun recording, read back with Rerun's own reader."""
import collections

import numpy as np
import pytest

from synmitsuba.cli import main

rerun = pytest.importorskip("rerun")


def _read(path) -> dict:
    """Per (entity, archetype column): the logged rows (arrow values), in frame order."""
    from rerun.chunk import RrdReader
    rows = collections.defaultdict(list)
    for chunk in RrdReader(str(path)).store().stream().to_chunks():
        rb = chunk.to_record_batch()
        frames = rb.column("frame").to_pylist() if "frame" in rb.schema.names else [None] * rb.num_rows
        for name in rb.schema.names:
            if ":" in name:
                rows[(chunk.entity_path, name)] += list(zip(frames, rb.column(name).to_pylist()))
    return {k: [v for _, v in sorted(r, key=lambda x: -1 if x[0] is None else x[0])] for k, r in rows.items()}


def test_view_writes_cameras_images_keypoints_and_meshes(sm, tiny, tmp_path, capsys):
    out = tmp_path / "seq.rrd"
    assert main(["view", str(tiny), "--sequence", "0", "--out", str(out), "--no-open"]) == 0
    assert "rerun " in capsys.readouterr().out  # how to open it, with no display here
    stems = sorted(str(p.with_suffix("")) for p in (tiny / "seq_000000").glob("f*_cam0.json"))
    samples = [sm.read_sample(s) for s in stems]
    rows = _read(out)
    assert len(rows[("/world/cam0", "Pinhole:image_from_camera")]) == len(samples)
    assert len(rows[("/world/cam0/image", "Image:buffer")]) == len(samples)
    assert len(rows[("/world/cam0/depth", "DepthImage:buffer")]) == len(samples)
    for s, t, K in zip(samples, rows[("/world/cam0", "Transform3D:translation")],
                       rows[("/world/cam0", "Pinhole:image_from_camera")]):
        assert np.allclose(np.ravel(t), s.camera.t, atol=1e-5)  # world -> camera, as our t
        assert np.allclose(np.reshape(K, (3, 3), order="F"), s.camera.K, atol=1e-4)  # Rerun stores it column-major
    rec = samples[0].subjects[0]
    inst = rec["instance"]
    kp3 = rows[(f"/world/subjects/{inst}/keypoints", "Points3D:positions")]
    assert len(kp3) == len(samples) and np.allclose(kp3[0], rec["keypoints3d_world"], atol=1e-5)
    kp2 = rows[(f"/world/cam0/image/keypoints/{inst}", "Points2D:positions")]
    assert len(kp2[0]) == int((rec["visibility"] > 0).sum())
    meshes = rows[(f"/world/subjects/{inst}/body", "Mesh3D:vertex_positions")]
    assert len(meshes) == len(samples) and len(meshes[0]) > 10000  # anny's body, posed per frame
    assert not np.allclose(meshes[0], meshes[-1])  # the subject moves
    assert main(["view", str(tiny), "--sequence", "9", "--out", str(tmp_path / "x.rrd")]) == 2
    assert "--sequence = 9" in capsys.readouterr().err
