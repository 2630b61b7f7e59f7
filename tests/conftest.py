"""Shared test setup: kernel caches in the repository (reused across runs; anny's 790 MB model
stays in the user's cache, ``ANNY_CACHE_DIR`` or ``~/.cache/anny``, shared with ``make demo`` and
every checkout, as README says), idle OpenMP threads that sleep, the default variant, Warp's
kernels forward-only as the CLI has them."""
import dataclasses
import os
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".cache" / "warp"))
os.environ.setdefault("DRJIT_CACHE_DIR", str(ROOT / ".cache" / "drjit"))
# torch's OpenMP threads sleep when idle instead of spinning (before torch loads; thread counts,
# and so results, unchanged): with two test workers on two cores, spinning made sampling a
# recipe 4x slower (0.35 s against 0.09 s) and the suite 22 minutes long
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import pytest  # noqa: E402

from synmitsuba.process import SETTINGS  # noqa: E402

# the cloth stage's Warp kernels compiled forward-only, as the CLI and generation workers have them
# (process.configure_process): the cloth is the same to the bit, compiled in 52 s instead of 127 s
SETTINGS.forward_only_kernels = True


@pytest.fixture(autouse=True)
def _process_settings_restored():
    """Each test starts as a library user's process: a test that runs the CLI or a generation
    in this worker opts the process in (``configure_process``), and that stayed for the rest of
    the worker's tests (a full ``gc.collect()`` before every later scene load: 66 s of the
    suite's 1,900)."""
    saved = dataclasses.replace(SETTINGS)
    yield
    for f in dataclasses.fields(SETTINGS):
        setattr(SETTINGS, f.name, getattr(saved, f.name))


def colour_science():
    """colour-science (the independent reference for our colour conversions), without its
    warning that matplotlib is missing."""
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour
    return colour


@pytest.fixture(scope="session")
def sm():
    import synmitsuba
    synmitsuba.set_variant()
    return synmitsuba


TINY = str(ROOT / "configs" / "tiny.yaml")


def generate_tiny(out, *extra):
    """``synmitsuba generate configs/tiny.yaml`` (2 frames) in a subprocess."""
    import subprocess
    import sys
    return subprocess.run([sys.executable, "-m", "synmitsuba", "generate", TINY, "--out", str(out), "--quiet",
                           "--set", "frames=2", *extra], capture_output=True, text=True)


@pytest.fixture(scope="session")
def tiny(tmp_path_factory, request):
    """The tiny dataset (2 sequences, 2 frames each, one worker), shared by the tests that only
    read it: made once per run, by the first test worker that needs it, while the others wait
    for it (a file lock in the run's base folder; each worker made its own before, 40-60 s)."""
    from filelock import FileLock
    root = tmp_path_factory.getbasetemp()
    root = root.parent if hasattr(request.config, "workerinput") else root  # an xdist worker's is under the run's
    out, done = root / "tiny", root / "tiny.done"
    with FileLock(str(root / "tiny.lock")):
        if not done.exists():
            run = generate_tiny(out, "--workers", "1")
            assert run.returncode == 0, run.stderr
            done.touch()
    return out
