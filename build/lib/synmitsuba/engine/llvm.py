"""Find a libLLVM that drjit's LLVM backend can use, and probe it safely.

drjit needs libLLVM >= 16: it refuses 14 and *aborts the process* inside the JIT with 15
("Cannot select: fminimum"). So we pick the newest libLLVM on the machine ourselves (setting
``DRJIT_LIBLLVM_PATH`` before drjit loads) and, when its version cannot be told from the file
name, run a tiny render in a subprocess first.  ``python -m synmitsuba.engine.llvm --probe``
exits 0 when the LLVM backend works (the Makefile uses it to decide whether to install one).
"""
from __future__ import annotations

import glob
import contextlib
import os
import re
import subprocess
import sys

from synmitsuba.errors import LLVMError

MIN_VERSION = 16
SEARCH_DIRS = ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64",
               "/usr/lib", "/usr/local/lib", "/opt/homebrew/opt/llvm/lib", "/usr/local/opt/llvm/lib")
INSTALL_HINT = ("drjit's LLVM backend needs libLLVM >= 16. On Debian/Ubuntu: "
                "`sudo apt-get install -y libllvm19` (or run `make setup`); if several are installed, "
                "point DRJIT_LIBLLVM_PATH at the newest, e.g. "
                "DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1. "
                "Or use another variant: synmitsuba.set_variant('cuda_ad_rgb') on an NVIDIA GPU.")

_PROBE = """
import mitsuba as mi, numpy as np
mi.set_variant('llvm_ad_rgb')
scene = mi.load_dict({'type': 'scene', 'i': {'type': 'path'}, 's': {'type': 'sphere'}, 'e': {'type': 'constant'},
    'sensor': {'type': 'perspective', 'film': {'type': 'hdrfilm', 'width': 8, 'height': 8}}})
img = np.array(mi.render(scene, spp=2))
assert np.isfinite(img).all()
import drjit as dr
print('.'.join(map(str, dr.detail.llvm_version())))
"""


def version_from_name(path: str) -> tuple[int, ...] | None:
    """libLLVM-19.so, libLLVM.so.19.1, libLLVM-15.so.1, libLLVM.19.dylib -> (19,), (19, 1), (15,), (19,)."""
    name = os.path.basename(path)
    m = re.match(r"libLLVM-(\d+)(?:\.(\d+))?", name) or re.match(r"libLLVM\.so\.(\d+)(?:\.(\d+))?", name) \
        or re.match(r"libLLVM\.(\d+)(?:\.(\d+))?\.dylib", name)
    if not m:
        return None
    return tuple(int(g) for g in m.groups() if g is not None)


def find_libllvm() -> list[tuple[tuple[int, ...] | None, str]]:
    """All libLLVM shared libraries in the usual places, newest first (unknown versions last)."""
    found: dict[str, tuple[int, ...] | None] = {}
    dirs = list(SEARCH_DIRS) + sorted(glob.glob("/usr/lib/llvm-*/lib"))
    for d in dirs:
        for p in glob.glob(os.path.join(d, "libLLVM*.so*")) + glob.glob(os.path.join(d, "libLLVM*.dylib")):
            real = os.path.realpath(p)
            found.setdefault(real, version_from_name(p) or version_from_name(real))
    return sorted(((v, p) for p, v in found.items()), key=lambda vp: (vp[0] is not None, vp[0] or ()), reverse=True)


def choose_libllvm() -> str | None:
    """The libLLVM drjit should load: the user's DRJIT_LIBLLVM_PATH, else the newest libLLVM
    >= 16 found (None: nothing found, or versions unknown). Raises LLVMError when only too-old
    ones exist. Reads the environment, never writes it: ``libllvm_path`` hands the choice to
    drjit only while its backend starts."""
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return os.environ["DRJIT_LIBLLVM_PATH"]
    libs = find_libllvm()
    good = [p for v, p in libs if v is not None and v[0] >= MIN_VERSION]
    if good:
        return good[0]
    known = [(v, p) for v, p in libs if v is not None]
    if known and len(known) == len(libs):
        have = ", ".join(f"{p} (LLVM {v[0]})" for v, p in known)
        raise LLVMError(f"only old libLLVM found: {have}. {INSTALL_HINT}")
    return None  # nothing found, or unknown versions: let the probe decide


@contextlib.contextmanager
def libllvm_path(path: str | None):
    """DRJIT_LIBLLVM_PATH set to ``path`` for the duration (drjit reads it when its LLVM
    backend starts, inside ``mi.set_variant``), then restored: the process keeps its
    environment."""
    before = os.environ.get("DRJIT_LIBLLVM_PATH")
    if path and not before:
        os.environ["DRJIT_LIBLLVM_PATH"] = path
    try:
        yield
    finally:
        if path and not before:
            os.environ.pop("DRJIT_LIBLLVM_PATH", None)


def probe(timeout: float = 120.0) -> tuple[bool, str]:
    """Render 8x8 pixels with llvm_ad_rgb in a subprocess. Returns (works, message)."""
    env = dict(os.environ)
    try:
        path = choose_libllvm()
    except LLVMError as exc:
        return False, str(exc)
    if path:
        env["DRJIT_LIBLLVM_PATH"] = path
    try:
        res = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True,
                             text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return False, f"the LLVM probe did not finish in {timeout:.0f} s. {INSTALL_HINT}"
    if res.returncode == 0:
        return True, f"LLVM {res.stdout.strip().splitlines()[-1]} ({path or 'drjit default'})"
    tail = (res.stderr or res.stdout).strip().splitlines()[-3:]
    pinned = " DRJIT_LIBLLVM_PATH is set: unset it to let synmitsuba pick the newest libLLVM." \
        if os.environ.get("DRJIT_LIBLLVM_PATH") else ""
    return False, (f"drjit's LLVM backend failed with {path or 'the default libLLVM'} "
                   f"(exit {res.returncode}: {' | '.join(tail)}). {INSTALL_HINT}{pinned}")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv != ["--probe"]:
        print("usage: python -m synmitsuba.engine.llvm --probe", file=sys.stderr)
        return 2
    ok, msg = probe()
    print(("ok: " if ok else "broken: ") + msg, file=sys.stdout if ok else sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
