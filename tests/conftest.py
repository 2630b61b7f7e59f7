"""Shared test setup: caches in the repository (reused across runs), the default variant."""
import os
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]
os.environ.setdefault("ANNY_CACHE_DIR", str(ROOT / ".cache" / "anny"))
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".cache" / "warp"))
os.environ.setdefault("DRJIT_CACHE_DIR", str(ROOT / ".cache" / "drjit"))

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def sm():
    import synmitsuba
    synmitsuba.set_variant()
    return synmitsuba
