"""Pack what a lent GPU machine needs to run our benches into ``.device/`` (git-ignored).

The device machine has Python 3.12, torch, numpy, scipy, PIL and yaml but no Mitsuba, and
carries at most 64 MiB. Mitsuba's wheel alone is 62 MB, so we keep only the RGB variants we run
(``cuda_ad_rgb``, ``llvm_ad_rgb``, ``scalar_rgb``) and the plugins the house uses, and zip them
with drjit, OpenEXR, trimesh and colour-science (no examples, tests or coverage pages) into ``.device/site.zip``. Subjects are built here (anny and
warp-lang do not fit) and carried as ``.device/subjects.pkl.xz`` by the benches'
``--subjects`` option. On the device, first:

    python3 -m zipfile -e .device/site.zip /tmp/site && export PYTHONPATH=/tmp/site:$PWD

    python bench/device_bundle.py      # needs network access to PyPI, here
"""
from __future__ import annotations

import glob
import os
import subprocess
import sys
import tempfile
import zipfile

WHEELS = ("mitsuba==3.9.1", "drjit==1.5.0", "OpenEXR==3.5.3", "trimesh==5.2.0", "colour-science==0.4.7")
KEEP_VARIANTS = ("cuda_ad_rgb", "llvm_ad_rgb", "scalar_rgb")
DROP_PLUGINS = {"volpath", "volpathmis", "ellipsoids", "ellipsoidsmesh", "sdfgrid", "timed_sunsky", "measured",
                "measured_polarized", "polarizer", "retarder", "pplastic", "stokes", "gridvolume", "heterogeneous",
                "homogeneous", "constvolume", "sggx", "tabphase", "rayleigh", "hg", "blendphase", "isotropic",
                "specfilm", "radiancemeter", "irradiancemeter", "projector", "ptracer", "blender", "catmullrom"}
PLATFORMS = ("manylinux_2_28_x86_64", "manylinux_2_27_x86_64", "manylinux_2_17_x86_64", "manylinux2014_x86_64")


def keep(name: str) -> bool:
    """Whether a file of the wheels goes into the bundle."""
    base = os.path.basename(name)
    if name.startswith("mitsuba/") and ".cpython-" in base and name.count("/") == 1:
        module = base.split(".cpython-")[0]
        return module in KEEP_VARIANTS or not module.startswith(("scalar_", "llvm_", "cuda_"))
    if name.startswith("mitsuba/plugins/"):
        return base.removesuffix(".so") not in DROP_PLUGINS
    if name.startswith("colour/") and ("/htmlcov/" in name or "/examples/" in name or "/resources/" in name):
        return False
    return not (".dist-info/" in name or "/tests/" in name)


def main(argv=None) -> int:
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--python-version", default="3.12", help="the device's Python (default 3.12)")
    ap.add_argument("--out", default=".device/site.zip", help="default .device/site.zip")
    args = ap.parse_args(argv)
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "pip", "download", "-q", "--no-deps", "--only-binary=:all:", "--python-version",
               args.python_version, "--implementation", "cp", "-d", tmp, *sum((["--platform", p] for p in PLATFORMS), []), *WHEELS]
        subprocess.run(cmd, check=True)
        out = args.out + ".part"
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as dst:
            for wheel in sorted(glob.glob(os.path.join(tmp, "*.whl"))):
                with zipfile.ZipFile(wheel) as src:
                    for info in src.infolist():
                        if keep(info.filename):
                            dst.writestr(info, src.read(info.filename))
        os.replace(out, args.out)
    print(f"{args.out}: {os.path.getsize(args.out) / 2 ** 20:.1f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
