"""The label audit on `make demo`'s first sequence (configs/demo.yaml: stride 5, two people,
two moving views; its first 3 frames, so the middle one has flow both ways), against
computations of our own: every visible mask inside its amodal mask, and the flow to the next
rendered sample (f + 5) against the body's surface points moved by skinning the rebuilt
subjects and the ground's position pass, projected by hand."""
import json
import subprocess
import sys

import numpy as np
import pytest

STRIDE = 5
FRAMES = 3  # of the demo's 6: half the renders, and every case of flow_frames


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    run = subprocess.run([sys.executable, "-m", "synmitsuba", "generate", "demo", "--out", str(out), "--sequences", "1",
                          "--set", f"frames={FRAMES}", "--quiet"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return out / "seq_000000"


def _samples(sm, folder):
    return {p.stem: sm.read_sample(p.with_suffix("")) for p in sorted(folder.glob("f*.exr"))}


def test_every_visible_mask_lies_inside_its_amodal_mask(sm, demo):
    records = 0
    for name, s in _samples(sm, demo).items():
        for rec in s.subjects:
            visible = s.instance == rec["instance"]
            assert not (visible & ~rec["amodal_mask"]).any(), (name, rec["instance"])
            assert rec["visible_fraction"] <= 1.0
            records += 1
    assert records == FRAMES * 2 * 2  # frames x views x subjects


def _projected(cam, points):
    X = points @ cam.R.T + cam.t
    return (X @ cam.K.T)[:, :2] / X[:, 2:], X[:, 2]


def test_flow_goes_to_the_next_rendered_sample(sm, demo):
    samples = _samples(sm, demo)
    spec = sm.SceneSpec.from_json((demo / "scene.json").read_text())
    _, placed = spec.build()
    checked = 0
    for name, s in samples.items():
        f, view = int(name[1:5]), name.split("_")[1]
        after = samples.get(f"f{f + STRIDE:04d}_{view}")
        assert s.meta["flow_frames"] == {**({"fwd": f + STRIDE} if after else {}),
                                         **({"bwd": f - STRIDE} if f else {})}
        assert ("flow_fwd" in s.passes) == (after is not None)
        assert json.loads((demo / f"{name}.json").read_text())["meta"]["flow_frames"] == s.meta["flow_frames"]
        if after is None:
            continue
        cam, flow = after.camera, s.passes["flow_fwd"]
        ys, xs = np.mgrid[:s.camera.height, :s.camera.width] + 0.5
        centre = np.stack([xs, ys], -1)
        ground = s.instance == 1
        uv, z = _projected(cam, s.passes["position"][ground].astype(np.float64))
        ok = z > 0
        assert np.abs(flow[ground][ok] - (uv - centre[ground])[ok]).max() < 2e-3
        for p in placed:
            skin = (s.instance == p.instance) & (s.layer == int(sm.Layer.BODY)) & (s.body_face > 0)
            body = p.human.pose(*p.motion.frame(f + STRIDE), face=p.motion.face_at(f + STRIDE))[0].vertices
            tri = body[p.human.parts[0].faces[s.body_face[skin] - 1].astype(np.int64)]
            u, v = s.body_bary[skin, 0:1].astype(np.float64), s.body_bary[skin, 1:2].astype(np.float64)
            uv, z = _projected(cam, (1 - u - v) * tri[:, 0] + u * tri[:, 1] + v * tri[:, 2])
            assert (z > 0).all() and np.abs(flow[skin] - (uv - centre[skin])).max() < 2e-3, (name, p.instance)
            checked += int(skin.sum())
    assert checked > 100
