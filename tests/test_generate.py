"""Dataset generation: byte-identical files whatever the worker count, resumable runs that
survive a killed worker, clear errors before any work, the PyTorch dataset over the result."""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from synmitsuba.errors import ConfigError

from conftest import TINY, generate_tiny as _generate


def _files(root) -> dict:
    """Every file's bytes by relative path, but the run log (timings and host names) and what
    `synmitsuba stats` adds to a dataset."""
    out = {}
    for folder, _, files in os.walk(root):
        for f in files:
            path = os.path.join(folder, f)
            if f not in ("run.log", "stats.json", "stats.png"):
                out[os.path.relpath(path, root)] = open(path, "rb").read()
    return out


def test_two_workers_write_the_same_bytes_as_one(tiny, tmp_path):
    run = _generate(tmp_path / "two", "--workers", "2")
    assert run.returncode == 0, run.stderr
    a, b = _files(tiny), _files(tmp_path / "two")
    assert sorted(a) == sorted(b) and len(a) > 10
    assert [k for k in a if a[k] != b[k] and k != "manifest.jsonl"] == []
    assert sorted(a["manifest.jsonl"].splitlines()) == sorted(b["manifest.jsonl"].splitlines())  # in finishing order
    lines = [json.loads(x) for x in (tiny / "manifest.jsonl").read_text().splitlines()]
    assert sorted(e["sequence"] for e in lines) == [0, 1] and all(len(e["samples"]) == 2 for e in lines)
    log = [json.loads(x) for x in (tiny / "run.log").read_text().splitlines()]
    assert all("seconds" in e and "host" in e for e in log)  # timings live in the log only
    assert "seconds" not in (tiny / "seq_000000" / "f0000_cam0.json").read_text()


def test_rerun_skips_complete_and_redoes_partial_sequences(tiny, tmp_path):
    import shutil
    out = tmp_path / "resume"
    shutil.copytree(tiny, out)
    lines = (out / "manifest.jsonl").read_text().splitlines()
    (out / "manifest.jsonl").write_text(lines[0] + "\n" + lines[1][:20])  # sequence 1 torn mid-line: not complete
    (out / "seq_000007.partial").mkdir()
    run = _generate(out)
    assert run.returncode == 0 and "1 done, 1 skipped" in run.stdout, run.stdout + run.stderr
    entries = [json.loads(x) for x in (out / "manifest.jsonl").read_text().splitlines() if x.startswith("{") and
               x.endswith("}")]
    assert sorted(e["sequence"] for e in entries) == [0, 1] and not (out / "seq_000007.partial").exists()
    assert _files(out)["seq_000001/f0000_cam0.exr"] == _files(tiny)["seq_000001/f0000_cam0.exr"]


def test_a_rerun_with_other_settings_is_refused_naming_them(tiny, tmp_path):
    """A rerun into a dataset made with other settings used to report "2 skipped" and then mix
    spp-4 and spp-16 sequences; now config.json names what differs and the run is refused
    (more sequences, or --allow-config-change, go on)."""
    import shutil
    out = tmp_path / "more"
    shutil.copytree(tiny, out)
    record = json.loads((out / "config.json").read_text())
    assert record["config"]["render"]["spp"] == json.loads((tiny / "config.json").read_text())["config"]["render"]["spp"]
    assert record["synmitsuba"] == __import__("synmitsuba").__version__
    run = _generate(out, "--set", "render.spp=16", "--set", "compose.cameras.width=200")
    err = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(err) == 1, run.stderr
    assert f"render.spp: {record['config']['render']['spp']!r} -> 16" in err[0] and "compose.cameras.width" in err[0]
    assert "--allow-config-change" in err[0] and sorted(p.name for p in out.iterdir()) == sorted(p.name for p in tiny.iterdir())
    run = _generate(out, "--set", "render.spp=16", "--allow-config-change", "--sequences", "3")
    assert run.returncode == 0 and "1 done, 2 skipped" in run.stdout, run.stderr
    log = [json.loads(x) for x in (out / "run.log").read_text().splitlines()]
    assert any("render.spp" in " ".join(e.get("config_changed", [])) for e in log)
    assert json.loads((out / "config.json").read_text()) == record  # the dataset's own settings stay recorded


def test_a_setting_added_since_counts_only_away_from_its_default():
    """A dataset recorded before a setting existed (``smplx.hand_pca`` here) is not "made with
    other settings" when the rerun leaves it at its default, which does what the old run did;
    set otherwise, or any recorded setting changed, it is named."""
    from synmitsuba.generate.config import GenerateConfig
    from synmitsuba.generate.run import config_changes, config_record
    new = json.loads(json.dumps(config_record(GenerateConfig(scene="scenes/demo.yaml"))))
    old = json.loads(json.dumps(new))
    del old["config"]["smplx"]["hand_pca"]
    assert config_changes(old, new) == []
    new["config"]["smplx"]["hand_pca"] = 12
    spp = old["config"]["render"]["spp"]
    new["config"]["render"]["spp"] = spp + 1
    assert config_changes(old, new) == [f"render.spp: {spp!r} -> {spp + 1!r}", "smplx.hand_pca: None -> 12"]


@pytest.mark.slow  # 42-52 s; make test keeps the stand-in pool's dying worker and the partial rerun below
def test_a_killed_worker_loses_and_duplicates_nothing(tmp_path):
    out = tmp_path / "kill"
    proc = subprocess.Popen([sys.executable, "-m", "synmitsuba", "generate", TINY, "--out", str(out), "--quiet",
                             "--set", "frames=2", "--sequences", "3", "--max-failures", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not list(out.glob("*.partial")) and time.time() < deadline:
        time.sleep(0.2)
    children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
    workers = [c for c in children if "spawn_main" in open(f"/proc/{c}/cmdline").read().replace("\0", " ")]
    assert workers, children
    os.kill(int(workers[0]), signal.SIGKILL)  # mid-sequence
    text, err = proc.communicate(timeout=300)
    assert proc.returncode == 1 and "a worker died" in text, text + err  # reported, not dropped
    done = [json.loads(x)["sequence"] for x in (out / "manifest.jsonl").read_text().splitlines()] \
        if (out / "manifest.jsonl").exists() else []
    run = _generate(out, "--sequences", "3")
    assert run.returncode == 0, run.stderr
    final = [json.loads(x)["sequence"] for x in (out / "manifest.jsonl").read_text().splitlines()]
    assert sorted(final) == [0, 1, 2] and len(final) == 3 and set(done) <= set(final)
    assert not list(out.glob("*.partial"))


def test_bad_output_and_config_fail_before_any_work(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    run = _generate(blocker / "out")
    assert run.returncode == 2 and "--out" in run.stderr and "cannot write there" in run.stderr
    run = _generate(tmp_path / "o", "--set", "render.spp=0")
    assert run.returncode == 2 and "render.spp = 0" in run.stderr
    run = _generate(tmp_path / "o", "--set", "compose.cameras.coutn=2")
    assert run.returncode == 2 and "compose.cameras.coutn" in run.stderr and not (tmp_path / "o" / "seq_000000").exists()


@pytest.mark.parametrize("setting, named", [
    ("compose.environments=[plaza, moon]", "compose.environments[1] = 'moon': no such environment"),
    ("compose.subjects.motions=[walk, moonwalk]", "compose.subjects.motions[1] = 'moonwalk'"),
    ("compose.subjects.motions=[no/such.bvh]", "compose.subjects.motions[0] = 'no/such.bvh': no such file"),
    ("scene=no_such.yaml", "scene = "),
    ("compose.cameras.distance_max=1.0", "compose.cameras.distance_max = 1.0: no view can frame one standing person"),
])
def test_names_and_files_a_worker_would_use_are_checked_before_any_work(tmp_path, setting, named):
    """A bad environment, motion or scene file is one line naming its key, exit 2, before the
    output folder exists (it used to fail in every worker: "a worker died", nothing logged)."""
    import time
    t0 = time.perf_counter()
    run = _generate(tmp_path / "o", "--set", setting)
    assert run.returncode == 2 and not (tmp_path / "o").exists(), run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], run.stderr
    assert time.perf_counter() - t0 < 20  # no subject was built


def test_dataset_reads_images_and_person_crops_with_workers(sm, tiny):
    import torch
    ds = sm.SynDataset(tiny, modalities=["rgb", "depth", "instance"])
    assert len(ds) == 4 and isinstance(ds, torch.utils.data.Dataset)
    batch = next(iter(torch.utils.data.DataLoader(ds, batch_size=4, num_workers=2)))
    assert batch["rgb"].shape == (4, 3, 72, 96) and batch["keypoints2d"].shape == (4, 1, 23, 3)
    crops = sm.SynDataset(tiny, crop="person", size=64)
    item = crops[0]
    s = sm.read_sample(item["stem"])
    rec = s.subjects[0]
    A = item["K"].numpy() @ np.linalg.inv(s.camera.K)  # the crop's K is the camera's, moved and scaled
    kp = rec["keypoints2d"] @ A[:2, :2].T + A[:2, 2]
    assert np.allclose(item["keypoints2d"][:, :2].numpy(), kp, atol=1e-4)
    assert item["image"].shape == (3, 64, 64) and item["mask"].float().mean() > 0.05
    batch = next(iter(torch.utils.data.DataLoader(crops, batch_size=2, num_workers=2)))
    assert batch["image"].shape == (2, 3, 64, 64) and batch["body_rotations_cam"].shape[1:] == (104, 3)
    with pytest.raises(ConfigError, match="crop"):
        sm.SynDataset(tiny, crop="face")


def test_shuffled_default_loader_batches_first_and_last_frames(sm, tiny, tmp_path):
    """Every pass by default, shuffled, with workers: a first frame (no backward flow) and a
    last frame (no forward flow) batch together (it raised KeyError: 'flow_bwd'); the missing
    side reads as zero flow with flag NO_TARGET, the present side as written."""
    import torch
    from synmitsuba.annotate.flow import NO_TARGET
    ds = sm.SynDataset(tiny)
    assert {"rgb", "depth", "flow_fwd", "flow_bwd", "flow_fwd_flag", "flow_bwd_flag", "body_part"} <= set(ds.modalities)
    seen = 0
    for batch in torch.utils.data.DataLoader(ds, batch_size=4, shuffle=True, num_workers=2):
        for k, stem in enumerate(batch["stem"]):
            meta = sm.read_sample(stem).meta["flow_frames"]
            for side in ("fwd", "bwd"):
                flag = batch[f"flow_{side}_flag"][k]
                if side in meta:
                    assert torch.equal(flag, torch.from_numpy(sm.read_sample(stem).passes[f"flow_{side}_flag"].astype(np.int64)))
                else:
                    assert (flag == NO_TARGET).all() and not batch[f"flow_{side}"][k].any()
                    seen += 1
    assert seen >= 4  # both sides were missing somewhere


def test_empty_or_missing_folders_are_errors_not_empty_datasets(sm, tmp_path):
    """A dataset folder with no complete sample (a failed run) used to give a length-0 dataset
    and a bare StopIteration later; the loader and the exports now say what is wrong."""
    (tmp_path / "empty" / "seq_000000.partial").mkdir(parents=True)
    for make in (lambda p: sm.SynDataset(p), lambda p: sm.export_coco(p, str(tmp_path / "c.json")),
                 lambda p: sm.export_humandata(p, str(tmp_path / "h.npz"))):
        with pytest.raises(ConfigError, match="no complete samples here"):
            make(tmp_path / "empty")
        with pytest.raises(ConfigError, match="no such folder"):
            make(tmp_path / "missing")


def test_stats_count_what_the_manifest_lists(tiny, tmp_path):
    import shutil
    tiny = shutil.copytree(tiny, tmp_path / "tiny")  # stats writes into the dataset; the shared one stays as made
    run = subprocess.run([sys.executable, "-m", "synmitsuba", "stats", str(tiny)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    stats = json.loads((tiny / "stats.json").read_text())
    manifest = [json.loads(x) for x in (tiny / "manifest.jsonl").read_text().splitlines()]
    assert stats["sequences"] == len(manifest) and stats["samples"] == sum(len(e["samples"]) for e in manifest)
    assert stats["subjects"] == sum(e["subjects"] for e in manifest)
    assert sum(stats["keypoint_visibility"].values()) == 23 * stats["visible_fraction"]["n"]
    assert stats["camera_pitch_deg"]["n"] == stats["samples"] and (tiny / "stats.png").stat().st_size > 10000
    # the partly hidden share and the cameras, recounted from the sample files
    sides = [json.loads(p.read_text()) for p in sorted(tiny.glob("seq_*/*.json")) if p.name != "scene.json"]
    vis = np.array([r["visible_fraction"] for s in sides for r in s["subjects"]])
    assert stats["occlusion"]["visible"] == [0.3, 0.8] and stats["occlusion"]["target_share"] == 0.0
    assert stats["occlusion"]["share"] == pytest.approx(((vis >= 0.3) & (vis <= 0.8)).mean())
    assert stats["occlusion"]["valid_share"] == pytest.approx(np.mean([r["valid"] for s in sides for r in s["subjects"]]))
    heights = sorted(float(-(np.array(s["camera"]["R"]).T @ s["camera"]["t"])[1]) for s in sides)
    assert stats["camera_height_m"]["n"] == len(sides) and stats["camera_height_m"]["mean"] == pytest.approx(np.mean(heights))
    assert sum(stats["cameras"].values()) == len(sides) and all(k.endswith("landscape") for k in stats["cameras"])
    run = subprocess.run([sys.executable, "-m", "synmitsuba", "stats", str(tiny / "nothing")], capture_output=True,
                         text=True)
    assert run.returncode == 2 and "no such folder" in run.stderr


@pytest.mark.slow  # 52-54 s, most of it Ray's start; make test keeps two local workers against one
def test_ray_writes_the_same_files_as_the_local_pool(tiny, tmp_path):
    run = _generate(tmp_path / "ray", "--executor", "ray", "--workers", "2")
    assert run.returncode == 0, run.stderr
    a, b = _files(tiny), _files(tmp_path / "ray")
    assert sorted(a) == sorted(b) and [k for k in a if a[k] != b[k] and k != "manifest.jsonl"] == []


def _quick_task(config, index, out):
    """A stand-in sequence (the orchestration is under test, not rendering): sequence 1 raises,
    sequence 2's cloth diverges, sequence 4 kills its worker process, the others finish after a
    short while."""
    from synmitsuba.cloth.simulate import ClothError
    time.sleep(0.3)
    if index == 1:
        raise ValueError(f"sequence {index} cannot be composed")
    if index == 2:
        raise ClothError("skirt", 16, "a vertex 1.08 m from the skinned garment")
    if index == 4:
        os._exit(3)
    name = f"seq_{index:06d}"
    os.makedirs(os.path.join(out, name), exist_ok=True)  # a rerun after a broken pool may find it (as run_sequence does)
    return {"sequence": index, "folder": name, "samples": [], "frames": 1, "views": 1, "seconds": 0.3,
            "pid": os.getpid(), "peak_rss_mb": 0.0, "rss_mb": 0.0}


def test_failures_are_logged_with_tracebacks_and_charged_to_their_own_sequence(tmp_path):
    """Two workers, six sequences: the one that raises and the one whose worker dies are each
    tried max_failures + 1 times with every traceback in run.log, the one whose cloth diverged
    once (a retry repeats it); a pool that broke under two running sequences charges neither
    until one breaks a pool alone; the rest complete once."""
    import synmitsuba as sm
    from synmitsuba.generate.run import generate
    cfg = sm.load_generate_config(TINY, ["sequences=6"])
    summary = generate(cfg, tmp_path, workers=2, max_failures=1, progress=False, task=_quick_task)
    assert sorted(summary.done) == [0, 3, 5] and sorted(summary.failed) == [1, 2, 4]
    assert summary.failed[1] == "ValueError: sequence 1 cannot be composed"
    assert summary.failed[2].startswith("ClothError: cloth simulation of the skirt diverged at clip frame 16")
    assert summary.failed[4].startswith("a worker died")
    log = [json.loads(x) for x in (tmp_path / "run.log").read_text().splitlines()]
    failures = [e for e in log if "failed" in e]
    assert sorted((e["sequence"], e["attempt"]) for e in failures) == [(1, 1), (1, 2), (2, 1), (4, 1), (4, 2)]
    assert [e["final"] for e in failures if e["sequence"] == 2] == [True]
    assert all('raise ValueError(f"sequence {index} cannot be composed")' in e["traceback"]
               for e in failures if e["sequence"] == 1)
    assert all(e["worker_died"] for e in failures if e["sequence"] == 4)
    assert sorted(e["sequence"] for e in log if "seconds" in e) == [0, 3, 5]  # each finished exactly once



def _children(pid: int) -> list[int]:
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open(f"/proc/{d}/stat") as fh:
                    if int(fh.read().rsplit(")", 1)[1].split()[1]) == pid:
                        out.append(int(d))
            except (OSError, IndexError, ValueError):
                pass
    return out


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")
def test_ctrl_c_stops_every_worker_and_keeps_only_complete_sequences(tmp_path):
    """SIGINT to `generate --workers 2` (as `timeout -s INT` sends it, to the parent alone): one
    line, exit 130, both workers gone within seconds, no .partial folder, every sequence folder
    in the manifest. Workers used to live on, write a sequence 15-22 s later, then block."""
    import signal
    import subprocess
    import sys
    import time
    out = tmp_path / "o"
    with open(tmp_path / "stdout", "w") as so, open(tmp_path / "stderr", "w") as se:
        p = subprocess.Popen([sys.executable, "-m", "synmitsuba", "generate", TINY, "--out", str(out), "--quiet",
                              "--workers", "2", "--sequences", "6", "--set", "frames=2"], stdout=so, stderr=se)
        t0, workers = time.time(), []
        while time.time() - t0 < 120 and len(workers) < 2:  # both workers started (and rendering soon)
            workers = [c for c in _children(p.pid) if "spawn_main" in open(f"/proc/{c}/cmdline").read()]
            time.sleep(0.2)
        time.sleep(4)
        p.send_signal(signal.SIGINT)
        assert p.wait(30) == 130
    time.sleep(3)
    assert workers and not [w for w in workers if os.path.exists(f"/proc/{w}")], "workers outlived the run"
    err = (tmp_path / "stderr").read_text().strip().splitlines()
    assert err == ["synmitsuba generate: interrupted; files already written are complete, nothing half-written was kept"]
    listed = {json.loads(x)["folder"] for x in (out / "manifest.jsonl").read_text().splitlines()} \
        if (out / "manifest.jsonl").exists() else set()
    seqs = {d.name for d in out.iterdir() if d.name.startswith("seq_")}
    assert seqs <= listed, seqs - listed


def test_loader_image_formats_and_visibility_codes_follow_one_table(sm, tiny):
    """sRGB uint8 and ImageNet-normalised images come from the same linear render (to_srgb8,
    computed apart here); COCO visibility flags in the loader equal the COCO export's."""
    import torch
    from synmitsuba.io.preview import to_srgb8
    lin = sm.SynDataset(tiny, crop="person", size=48)
    s8 = sm.SynDataset(tiny, crop="person", size=48, image="srgb8", visibility="coco")
    nrm = sm.SynDataset(tiny, crop="person", size=48, image="normalized", mean=(0.5, 0.5, 0.5), std=(0.25, 0.25, 0.25))
    a, b, c = lin[0], s8[0], nrm[0]
    assert b["image"].dtype == torch.uint8 and lin[0]["image"].dtype == torch.float32
    expect = to_srgb8(a["image"].numpy().transpose(1, 2, 0)).transpose(2, 0, 1)
    assert np.array_equal(b["image"].numpy(), expect)
    assert np.allclose(c["image"].numpy(), (expect / 255.0 - 0.5) / 0.25, atol=1e-6)
    classes, flags = a["keypoints2d"][:, 2].numpy().astype(int), b["keypoints2d"][:, 2].numpy().astype(int)
    assert np.array_equal(flags, np.where(classes == 0, 0, np.where(classes == 1, 2, 1)))  # COCO: 2 visible, 1 occluded
    whole = sm.SynDataset(tiny, modalities=["rgb"], image="srgb8", visibility="coco")[0]
    assert whole["rgb"].dtype == torch.uint8 and set(np.unique(whole["keypoints2d"][..., 2].numpy())) <= {0, 1, 2}
    with pytest.raises(ConfigError, match="image = 'jpeg'"):
        sm.SynDataset(tiny, image="jpeg")


def test_loader_carries_body_model_fits_where_records_have_them(sm, tiny, tmp_path):
    """Records with SMPL-X parameters (as fit-smplx writes them) reach crops and whole images
    under the smplx package's names; a record without them reads as zeros, valid False."""
    import torch
    rng = np.random.default_rng(0)
    stems = sorted(str(p.with_suffix("")) for p in (tiny / "seq_000000").glob("f*_cam0.json"))
    fits = []
    for k, stem in enumerate(stems):
        s = sm.read_sample(stem)
        fit = {"model": "smplx", "gender": "neutral", "betas": rng.normal(size=10), "global_orient": rng.normal(size=3),
               "body_pose": rng.normal(size=(21, 3)), "transl": rng.normal(size=3)}
        if k == 0:
            s.subjects[0].add_body_models({"smplx_cam": fit, "smplx_world": fit})
        fits.append(fit if k == 0 else None)
        sm.write_sample(s, tmp_path / "d" / f"{k:04d}")
    crops = sm.SynDataset(tmp_path / "d", crop="person")
    first = crops[0]
    assert first["smplx_valid"] and np.allclose(first["smplx_body_pose"].numpy(), fits[0]["body_pose"], atol=1e-6)
    assert set(first) >= {"smplx_betas", "smplx_global_orient", "smplx_transl"} and not crops[1]["smplx_valid"]
    assert not crops[1]["smplx_body_pose"].any()
    batch = next(iter(torch.utils.data.DataLoader(sm.SynDataset(tmp_path / "d"), batch_size=2)))
    assert batch["smplx_body_pose"].shape == (2, 1, 21, 3) and batch["smplx_valid"].tolist() == [[True], [False]]


def test_loader_keypoint_conventions(sm, tiny):
    """OpenPose-25, COCO-17 and COCO-WholeBody layouts from our 23 points: the neck is the
    shoulders' midpoint (occluded when either shoulder is), WholeBody keeps our 23 first, then
    the record's face and hands, cropped as the body's points are."""
    ours = sm.SynDataset(tiny, crop="person", size=64)[0]
    op = sm.SynDataset(tiny, crop="person", size=64, keypoints="openpose25")[0]
    wb = sm.SynDataset(tiny, crop="person", size=64, keypoints="coco_wholebody")[0]
    c17 = sm.SynDataset(tiny, crop="person", size=64, keypoints="coco17")[0]
    k, o = ours["keypoints2d"].numpy(), op["keypoints2d"].numpy()
    assert o.shape == (25, 3) and op["keypoints_mask"].tolist() == [1] * 25
    assert np.allclose(o[1, :2], (k[5, :2] + k[6, :2]) / 2, atol=1e-5)       # neck
    assert np.allclose(o[8, :2], (k[11, :2] + k[12, :2]) / 2, atol=1e-5)     # mid hip
    assert np.allclose(o[[2, 5, 19, 24], :2], k[[6, 5, 17, 22], :2])        # R/L shoulder, L big toe, R heel
    expect = k[5, 2] if k[5, 2] == k[6, 2] else (0 if 0 in (k[5, 2], k[6, 2]) else max(k[5, 2], k[6, 2]))
    assert o[1, 2] == expect
    assert np.allclose(op["keypoints3d_cam"].numpy()[1], (ours["keypoints3d_cam"].numpy()[5] + ours["keypoints3d_cam"].numpy()[6]) / 2, atol=1e-6)
    assert wb["keypoints2d"].shape == (133, 3) and int(wb["keypoints_mask"].sum()) == 133
    w = wb["keypoints2d"].numpy()
    assert np.array_equal(w[:23], k)
    rec = next(r for r in sm.read_sample(sm.SynDataset(tiny, crop="person", size=64)[0]["stem"]).subjects if r["valid"])
    for rows, pts, classes in ((slice(23, 91), rec["face2d"], rec["face_visibility"]),
                               (slice(91, 112), rec["hands2d"][0], rec["hands_visibility"][0])):
        assert np.array_equal(w[rows, 2], classes)
        # the crop maps image points as it maps the body's: a scale and a shift, fitted on those
        A = np.c_[np.asarray(rec["keypoints2d"]), np.ones(23)]
        fit = np.linalg.lstsq(A, k[:, :2], rcond=None)[0]
        assert np.allclose(np.c_[np.asarray(pts), np.ones(len(pts))] @ fit, w[rows, :2], atol=1e-3)
    assert np.array_equal(c17["keypoints2d"].numpy(), k[:17])
    whole = sm.SynDataset(tiny, modalities=["depth"], keypoints="openpose25")[0]
    assert whole["keypoints2d"].shape[1:] == (25, 3)
    with pytest.raises(ConfigError, match="keypoints = 'h36m'"):
        sm.SynDataset(tiny, keypoints="h36m")


def test_loader_smpl24_joints_project_like_the_camera(sm, tiny):
    """SMPL-24 joints: the anny joints SMPL's names pair with (pelvis = root, left hip =
    upperleg01.L, ...), their 2D the camera's own projection of the world joints."""
    from synmitsuba.annotate.conventions import smpl24_bones
    from synmitsuba.body.anny_model import _static
    bones = list(_static()["bones"])
    idx = list(smpl24_bones())
    assert [bones[i] for i in idx[:3]] == ["root", "upperleg01.L", "upperleg01.R"] and bones[idx[15]] == "head"
    item = sm.SynDataset(tiny, modalities=["depth"], keypoints="smpl24")[0]
    s = sm.read_sample(item["stem"])
    rec = s.subjects[0]
    uv, z = s.camera.project(np.asarray(rec["joints3d_world"])[idx])
    kp = item["keypoints2d"][0].numpy()
    assert kp.shape == (24, 3) and np.allclose(kp[:, :2], uv, atol=1e-3)
    inside = (z > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < s.camera.width) & (uv[:, 1] >= 0) & (uv[:, 1] < s.camera.height)
    assert np.array_equal(kp[:, 2], inside.astype(np.float32))
    assert np.allclose(item["keypoints3d_cam"][0].numpy(), np.asarray(rec["joints3d_cam"])[idx], atol=1e-5)
    crop = sm.SynDataset(tiny, crop="person", size=64, keypoints="smpl24")[0]
    assert crop["keypoints2d"].shape == (24, 3) and crop["keypoints_mask"].sum() == 24


def test_every_shipped_config_loads_and_frames_a_standing_person(sm):
    """Each shipped config parses with every key checked and passes the up-front framing check
    (a config whose cameras could not frame one person is refused before any work)."""
    from synmitsuba.compose.composition import check_framing, load_compose_config
    from synmitsuba.resources import config_names, find_config
    for name in config_names():
        cfg = load_compose_config(find_config(name)) if name == "compose" else sm.load_generate_config(name, []).compose
        check_framing(cfg.cameras, "compose.cameras")
