"""The package as a user installs it: a wheel (no editable install), run from another folder."""
import json
import pathlib
import shutil
import subprocess
import sys
import sysconfig

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_a_wheel_installed_in_a_fresh_venv_generates_a_shipped_config_and_lists_environments(tmp_path):
    src, wheels = tmp_path / "src", tmp_path / "wheels"  # built from a copy: no build/ left in the checkout
    shutil.copytree(ROOT / "synmitsuba", src / "synmitsuba", ignore=shutil.ignore_patterns("__pycache__"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation", "-w", str(wheels),
                    str(src)], check=True, capture_output=True)
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-deps", "--no-index", *map(str, wheels.glob("*.whl"))],
                   check=True, capture_output=True)
    # the dependencies come from the test environment; the editable synmitsuba there is not
    # seen (a .pth line adds a folder without running that folder's own .pth finders)
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          check=True, capture_output=True, text=True).stdout.strip()
    pathlib.Path(site, "_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    probe = subprocess.run([str(python), "-c", "import json, synmitsuba as sm; from synmitsuba.resources import "
                            "config_names; print(json.dumps([sm.__file__, sm.environment_names(), config_names()]))"],
                           cwd=elsewhere, check=True, capture_output=True, text=True)
    where, environments, configs = json.loads(probe.stdout)
    assert where.startswith(site)
    shipped = sorted(p.stem for p in (ROOT / "synmitsuba" / "assets" / "scenes" / "environments").glob("*.yaml"))
    assert environments == shipped and len(shipped) >= 6
    assert {"tiny", "demo", "hps", "crowds", "nerf"} <= set(configs)
    run = subprocess.run([str(python), "-m", "synmitsuba", "generate", "tiny", "--out", "data", "--quiet",
                          "--set", "frames=1", "--set", "sequences=1"], cwd=elsewhere, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    samples = sorted(p.name for p in (elsewhere / "data" / "seq_000000").glob("*.exr"))
    assert samples == ["f0000_cam0.exr"]
