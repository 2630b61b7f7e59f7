"""SMPL-X / SMPL fits of layered subjects, checked on synthetic model files made from anny (the
licensed files are never here): the torch model against numpy skinning, the fit against the
known shape and pose, camera-frame parameters against the world ones, the labels a generation
writes against those ``synmitsuba fit-smplx`` adds afterwards, and the errors without files."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from synmitsuba.errors import ConfigError

from conftest import generate_tiny


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    """SMPL-X in the published models' T-pose rest; SMPL resting in anny's own pose."""
    from synmitsuba.annotate.smplx_synthetic import write_anny_model
    folder = tmp_path_factory.mktemp("models")
    write_anny_model(str(folder), "smplx", rest="tpose")
    write_anny_model(str(folder), "smpl")
    return str(folder)


@pytest.fixture(scope="module")
def walker():
    import synmitsuba as sm
    from synmitsuba.motion.sources import load_motion
    human = sm.build_subject(sm.sample_subject(np.random.default_rng(3), {"texture_size": 64}))
    clip = sm.retarget(load_motion("walk", np.random.default_rng(1), seconds=1.0), human.skeleton)
    return human, clip


def _numpy_pose(model, betas, pose_aa, transl, expression=None):
    """The model posed with numpy only: blend shapes (and expression), correctives, our skinning
    (lbs.skin)."""
    from synmitsuba.body.lbs import bone_transforms, skin
    from synmitsuba.body.skeleton import Skeleton
    from synmitsuba.geometry import axis_angle_to_matrix
    v = model.v_template + model.shapedirs[:, :, :len(betas)] @ betas
    if expression is not None:
        v = v + model.exprdirs[:, :, :len(expression)] @ expression
    J = model.J_regressor @ v
    R = axis_angle_to_matrix(pose_aa)
    v = v + model.posedirs @ (R[1:] - np.eye(3)).reshape(-1)
    sk = Skeleton(model.joint_names, model.parents, J)
    A, b = bone_transforms(sk, R, transl)
    return skin(v, model.weights, (A, b)), b + np.einsum("jab,jb->ja", A, J)


def test_torch_model_matches_numpy_skinning(models):
    import dataclasses

    import torch

    from synmitsuba.annotate.smplx_layer import ModelLayer, rodrigues
    from synmitsuba.body.smplx_model import load_model
    rng = np.random.default_rng(0)
    m = load_model(models, kind="smplx")
    m = dataclasses.replace(m, posedirs=rng.normal(0, 1e-3, m.posedirs.shape))  # correctives exercised too
    betas, pose, transl = rng.normal(0, 1, 10), rng.normal(0, 0.3, (55, 3)), rng.normal(0, 0.5, 3)
    layer = ModelLayer(m, 10)
    t = lambda a: torch.as_tensor(a, dtype=torch.float32)  # noqa: E731
    verts, joints = layer(t(betas), rodrigues(t(pose[None])), t(transl[None]))
    ref_v, ref_j = _numpy_pose(m, betas, pose, transl)
    assert np.abs(verts[0].numpy() - ref_v).max() < 2e-5 and np.abs(joints[0].numpy() - ref_j).max() < 2e-5


def test_fit_recovers_the_known_shape_and_walking_pose(models, walker, sm):
    """The synthetic SMPL-X is anny's mesh: shape within 5 mm of the surface on every frame,
    pose within 5 degrees of the rotations that made it (each joint turns as its anny bone,
    from the T-pose rest), and the camera-frame parameters pose it where the camera sees it."""
    from synmitsuba.annotate.smplx_synthetic import true_pose
    from synmitsuba.body.smplx_model import load_model
    from synmitsuba.geometry import axis_angle_to_matrix, matrix_to_axis_angle
    human, clip = walker
    fit = sm.fit_smplx(human, clip, models, gender="neutral")
    assert fit.kind == "smplx" and len(fit.frames) == clip.n_frames == 30
    assert fit.surface_mean_mm.max() < 5.0 and fit.ok.all()
    assert fit.joint_mm.mean() < 10.0
    m = load_model(models)
    truth = true_pose(os.path.join(models, "SMPLX_NEUTRAL.npz"), human.body, clip)
    err = np.degrees(np.linalg.norm(matrix_to_axis_angle(np.swapaxes(truth, -1, -2) @ axis_angle_to_matrix(fit.pose)), axis=-1))
    assert err[:, :22].mean() < 5.0, err[:, :22].mean(0)
    # the model's own vertices at a frame against the posed anny body
    f = 17
    verts, _ = _numpy_pose(m, fit.betas, fit.pose[f], fit.transl[f])
    from synmitsuba.body.binding import closest_points
    from synmitsuba.body.lbs import bone_transforms, skin
    anny = skin(human.body.vertices, human.body.weights, bone_transforms(human.skeleton, *clip.frame(f)))
    d = np.linalg.norm(closest_points(anny, human.body.faces, verts)[0] - verts, axis=1) * 1000
    assert abs(d.mean() - fit.surface_mean_mm[f]) < 0.5
    cam = sm.Camera.look_at([2.0, 1.6, 3.0], [0, 1.0, 0], fov_y_deg=40, width=64, height=64)
    p = fit.params(f, cam)
    full = np.concatenate([p["global_orient"][None], p["body_pose"], p["jaw_pose"][None], p["leye_pose"][None],
                           p["reye_pose"][None], p["left_hand_pose"], p["right_hand_pose"]])
    in_cam, _ = _numpy_pose(m, p["betas"], full, p["transl"])
    assert np.abs(in_cam - (verts @ cam.R.T + cam.t)).max() < 1e-6  # micrometres: axis-angle round trips
    assert p["fit"]["ok"] and p["expression"].shape == (10,)


def test_fit_recovers_a_known_hand_pose_and_expression(models, walker, sm):
    """Fists on both hands and a held smile with the jaw open: the fingers within 5 degrees of
    the rotations that made them, the 10 expression coefficients near the least-squares
    projection of anny's face displacement onto the file's expression basis (computed here), the
    face and hands as close to the surface as the body; the model posed here with numpy from
    the camera-frame parameters lands on the fitted vertices."""
    import dataclasses

    from synmitsuba.annotate.smplx_fit import pca_hands
    from synmitsuba.annotate.smplx_synthetic import true_pose
    from synmitsuba.body.expressions import FACE_UNITS, face_units
    from synmitsuba.body.smplx_model import load_model
    from synmitsuba.geometry import axis_angle_to_matrix, matrix_to_axis_angle
    from synmitsuba.motion import hands as H
    human, clip = walker
    clip = H.with_hands(clip, H.HandTrack([H.HandKey(0.0, "fist", 1)], [H.HandKey(0.0, "fist", 2)], drift_deg=0.0))
    w = np.zeros(len(FACE_UNITS))
    w[[FACE_UNITS.index("jawOpen"), FACE_UNITS.index("mouthSmileLeft"), FACE_UNITS.index("mouthSmileRight")]] = 0.5, 0.7, 0.7
    clip = dataclasses.replace(clip, face=np.tile(w, (clip.n_frames, 1)))
    frames = [3, 4, 5]
    fit = sm.fit_smplx(human, clip, models, gender="neutral", frames=frames, hand_pca=12)
    truth = true_pose(os.path.join(models, "SMPLX_NEUTRAL.npz"), human.body, clip, frames)
    err = np.degrees(np.linalg.norm(matrix_to_axis_angle(np.swapaxes(truth, -1, -2) @ axis_angle_to_matrix(fit.pose)), axis=-1))
    assert err[:, 25:55].mean() < 5.0 and err[:, 25:55].max() < 15.0, err[:, 25:55].mean(0)
    m = load_model(models)
    units = face_units()
    d = np.zeros_like(m.v_template)
    d[units.vertices] = units.displacement(w)
    E = m.exprdirs.reshape(-1, m.exprdirs.shape[2])
    best = np.linalg.lstsq(E, d.ravel(), rcond=None)[0]
    assert fit.expression.shape == (3, 10)
    # compared as face geometry (the basis' later directions move the face little, so their
    # coefficients are loose): the fitted displacement's error against the smile, over the face
    moved = np.abs(d).sum(1) > 1e-4
    miss = lambda e: np.sqrt(((E @ e - d.ravel()).reshape(-1, 3)[moved] ** 2).sum(1).mean()) * 1000  # noqa: E731 (mm)
    floor, neutral = miss(best), miss(np.zeros(10))
    assert all(miss(e) < floor + 0.35 * (neutral - floor) for e in fit.expression)  # 1.7-2.0 mm; 0.6 best, 6.5 neutral
    assert fit.face_mm.max() < 3.0 and fit.hand_mm.max() < 5.0 and fit.ok.all()
    cam = sm.Camera.look_at([1.0, 1.6, 2.5], [0, 1.2, 0], fov_y_deg=40, width=64, height=64)
    p = fit.params(4, cam)
    assert np.array_equal(p["expression"], fit.expression[1]) and 0 <= p["fit"]["face_mm"] < 3.0
    full = np.concatenate([p["global_orient"][None], p["body_pose"], p["jaw_pose"][None], p["leye_pose"][None],
                           p["reye_pose"][None], p["left_hand_pose"], p["right_hand_pose"]])
    world, _ = _numpy_pose(m, fit.betas, fit.pose[1], fit.transl[1], fit.expression[1])
    in_cam, _ = _numpy_pose(m, p["betas"], full, p["transl"], p["expression"])
    assert np.abs(in_cam - (world @ cam.R.T + cam.t)).max() < 1e-6
    # the 12-component hand PCA: what it misses is orthogonal to the 12 components (least squares),
    # read here straight from the file; all 45 components give the fitted hands back
    with np.load(os.path.join(models, "SMPLX_NEUTRAL.npz")) as data:
        comps = {s: data[f"hands_components{s}"] for s in "lr"}
        mean = {s: data[f"hands_mean{s}"] for s in "lr"}
    assert fit.hand_pca.shape == (3, 2, 12) and p["left_hand_pca"].shape == (12,) and p["fit"]["hand_pca_deg"] > 0
    for k, s in enumerate("lr"):
        hand = fit.pose[:, 25 + 15 * k:40 + 15 * k].reshape(3, 45)
        miss = hand - mean[s] - fit.hand_pca[:, k] @ comps[s][:12]
        assert np.abs(miss @ comps[s][:12].T).max() < 1e-9 and np.abs(miss).max() > 1e-3
    coef, deg = pca_hands(fit.pose[:, 25:55].reshape(3, 2, 15, 3), np.stack([comps["l"], comps["r"]]),
                          np.stack([mean["l"], mean["r"]]), 45)
    assert deg.max() < 1e-6 and np.allclose(coef[:, 0], (fit.pose[:, 25:40].reshape(3, 45) - mean["l"]) @ comps["l"].T)


def test_hand_pca_without_components_in_the_file_is_one_line_before_any_fit(models, walker, tmp_path, sm):
    """A model file without the hand PCA arrays: asking for ``hand_pca`` names the field, the
    file and the fix when the options are read, before any work."""
    from synmitsuba.annotate.smplx_fit import SMPLXOptions
    with np.load(os.path.join(models, "SMPLX_NEUTRAL.npz")) as data:
        np.savez(tmp_path / "SMPLX_NEUTRAL.npz", **{k: data[k] for k in data.files if not k.startswith("hands_")})
    SMPLXOptions.from_dict({"enabled": True, "model_path": models, "gender": "neutral", "hand_pca": 12})
    with pytest.raises(ConfigError) as err:
        SMPLXOptions.from_dict({"enabled": True, "model_path": str(tmp_path), "gender": "neutral", "hand_pca": 12})
    assert err.value.field == "hand_pca" and "hand_pca: 0" in str(err.value)
    with pytest.raises(ConfigError):
        SMPLXOptions.from_dict({"enabled": True, "model_path": models, "hand_pca": 46})
    human, clip = walker  # the API says so too, from the loaded file, before the shape step
    with pytest.raises(ConfigError) as err:
        sm.fit_smplx(human, clip, str(tmp_path), gender="neutral", frames=[0], hand_pca=12)
    assert err.value.field == "hand_pca"


def test_smpl_fit_and_the_error_flag(models, walker, sm):
    human, clip = walker
    fit = sm.fit_smplx(human, clip, models, kind="smpl", frames=[4, 5, 6], threshold_mm=0.5)
    assert fit.pose.shape == (3, 24, 3) and fit.surface_mean_mm.max() < 5.0
    assert not fit.ok.any()  # above a 0.5 mm threshold: flagged, not written as good
    p = fit.params(5)
    assert p["body_pose"].shape == (23, 3) and p["fit"]["ok"] is False and "left_hand_pose" not in p
    with pytest.raises(ConfigError) as e:
        fit.params(7)
    assert "frame" in str(e.value)


def test_without_model_files_every_entry_point_says_where_to_get_them(walker, monkeypatch, tmp_path, sm):
    for var in ("SMPLX_MODEL_PATH", "SMPL_MODEL_PATH"):
        monkeypatch.delenv(var, raising=False)
    human, clip = walker
    with pytest.raises(ConfigError) as e:
        sm.fit_smplx(human, clip)
    assert "SMPLX_MODEL_PATH" in str(e.value) and "smpl-x.is.tue.mpg.de" in str(e.value)
    with pytest.raises(ConfigError) as e:
        sm.GenerateConfig.from_dict({"smplx": {"enabled": True}})
    assert e.value.field == "smplx.model_path" and "SMPLX_MODEL_PATH" in str(e.value)
    sm.GenerateConfig.from_dict({"smplx": {"enabled": False}})  # nothing asked, nothing needed
    with pytest.raises(ConfigError) as e:
        sm.fit_smplx(human, clip, str(tmp_path), kind="smpl")
    assert "SMPL_NEUTRAL.npz" in str(e.value)
    run = subprocess.run([sys.executable, "-m", "synmitsuba", "fit-smplx", str(tmp_path)], capture_output=True,
                         text=True, env={k: v for k, v in os.environ.items() if "MODEL_PATH" not in k})
    assert run.returncode == 2 and "SMPLX_MODEL_PATH" in run.stderr and "Traceback" not in run.stderr


def _cli(*args):
    run = subprocess.run([sys.executable, "-m", "synmitsuba", *args], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return run


@pytest.mark.slow  # 90 s on 2 cores (make bench runs it); make test keeps the fit itself and the missing-model errors
def test_generation_and_fit_smplx_write_the_same_labels(models, tiny, tmp_path, sm):
    """A generation with ``smplx: {enabled: true}`` and ``synmitsuba fit-smplx`` on a dataset
    generated without it write the same parameters; they pose the model where the sample's
    own joints are; HumanData carries them."""
    import shutil
    run = generate_tiny(tmp_path / "with", "--set", "sequences=1", "--set", "smplx.enabled=true",
                        "--set", f"smplx.model_path={models}")
    assert run.returncode == 0, run.stderr
    shutil.copytree(tiny, tmp_path / "after")
    shutil.rmtree(tmp_path / "after" / "seq_000001")
    _cli("fit-smplx", str(tmp_path / "after"), "--model-path", models, "--gender", "neutral", "--quiet")
    from synmitsuba.body.smplx_model import load_model
    m = load_model(models)
    transl = []
    for name in ("f0000_cam0", "f0002_cam0"):
        a = json.loads((tmp_path / "with" / "seq_000000" / f"{name}.json").read_text())["subjects"][0]
        b = json.loads((tmp_path / "after" / "seq_000000" / f"{name}.json").read_text())["subjects"][0]
        assert a["smplx_cam"] == b["smplx_cam"] and a["smplx_world"] == b["smplx_world"]
        rec = sm.read_sample(str(tmp_path / "after" / "seq_000000" / name)).subjects[0]
        p = rec["smplx_cam"]
        transl.append(p["transl"])
        full = np.concatenate([p["global_orient"][None], p["body_pose"], p["jaw_pose"][None], p["leye_pose"][None],
                               p["reye_pose"][None], p["left_hand_pose"], p["right_hand_pose"]])
        _, joints = _numpy_pose(m, p["betas"], full, p["transl"])
        # pelvis, knees, ankles, shoulders, elbows, wrists against anny's joints in the camera frame
        pairs = {0: "root", 4: "lowerleg01.L", 5: "lowerleg01.R", 7: "foot.L", 8: "foot.R", 16: "upperarm01.L",
                 17: "upperarm01.R", 18: "lowerarm01.L", 19: "lowerarm01.R", 20: "wrist.L", 21: "wrist.R"}
        from synmitsuba.body.anny_model import _static
        bones = _static()["bones"]
        gap = [np.linalg.norm(joints[j] - rec["joints3d_cam"][bones.index(n)]) for j, n in pairs.items()]
        assert max(gap) < 0.03, gap
    hd = tmp_path / "hd.npz"
    sm.export_humandata(str(tmp_path / "after"), str(hd))
    data = np.load(hd, allow_pickle=True)
    assert data["smplx"].item()["body_pose"].shape == (2, 21, 3) and data["has_smplx"].all()
    assert np.allclose(data["smplx"].item()["transl"], np.array(transl), atol=1e-6)
    import torch
    crops = sm.SynDataset(str(tmp_path / "after"), crop="person")  # the loader carries the fits too
    item = crops[0]
    fit = sm.read_sample(item["stem"]).subjects[0]["smplx_cam"]
    assert item["smplx_valid"] and item["smplx_body_pose"].shape == (21, 3) and "smpl_body_pose" not in item
    assert np.allclose(item["smplx_body_pose"].numpy(), fit["body_pose"], atol=1e-6)
    assert np.allclose(item["smplx_transl"].numpy(), fit["transl"], atol=1e-6)
    batch = next(iter(torch.utils.data.DataLoader(sm.SynDataset(str(tmp_path / "after")), batch_size=2, shuffle=True)))
    assert batch["smplx_body_pose"].shape == (2, 1, 21, 3) and batch["smplx_valid"].all()
