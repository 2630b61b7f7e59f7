"""Pack what a lent GPU machine needs to run our benches into ``.device/`` (git-ignored).

The device machine has Python 3.12, torch, numpy, scipy, PIL and yaml but no Mitsuba, and
carries at most 64 MiB. Mitsuba's wheel alone is 62 MB, so we keep only the RGB variants we run
(``cuda_ad_rgb``, ``llvm_ad_rgb``, ``scalar_rgb``) and the plugins the house uses, and zip them
with drjit, OpenEXR, trimesh and colour-science (no examples, tests or coverage pages) into ``.device/site.zip``. Subjects are built here (anny and
warp-lang do not fit) and carried as ``.device/subjects.pkl.xz`` by the benches'
``--subjects`` option. On the device, first:

    python3 -m zipfile -e .device/site.zip /tmp/site && export PYTHONPATH=/tmp/site:$PWD

    python bench/device_bundle.py      # needs network access to PyPI, here

``--cloth`` packs the cloth stage's solver instead (Warp, Newton, trimesh, pykdtree; their tests and
examples left out) as ``.device/cloth_site.tar.xz.NN``, parts of at most ``--part-mib`` (Warp's
library alone is 77 MiB compressed): each call carries one part and copies it to the machine's
/tmp, which lasts while the machine stays warm; the last one unpacks them all:

    cat /tmp/parts/cloth_site.tar.xz.* | tar xJ -C /tmp/site && export PYTHONPATH=/tmp/site:$PWD
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


def keep(name: str, variants: tuple[str, ...] = KEEP_VARIANTS) -> bool:
    """Whether a file of the wheels goes into the bundle (Mitsuba's ``variants`` only)."""
    base = os.path.basename(name)
    if name.startswith("mitsuba/") and ".cpython-" in base and name.count("/") == 1:
        module = base.split(".cpython-")[0]
        return module in variants or not module.startswith(("scalar_", "llvm_", "cuda_"))
    if name.startswith("mitsuba/plugins/"):
        return base.removesuffix(".so") not in DROP_PLUGINS
    if name.startswith("colour/") and ("/htmlcov/" in name or "/examples/" in name or "/resources/" in name):
        return False
    return not (".dist-info/" in name or "/tests/" in name)


CLOTH_WHEELS = ("warp-lang", "newton", "trimesh", "pykdtree")  # at the versions installed here; pykdtree
# (the closest-point queries of the cloth's projection) is the one built for the device's Python


def keep_cloth(name: str) -> bool:
    """Whether a file of the cloth wheels goes into the cloth bundle."""
    return not any(part in name for part in (".dist-info/", "/tests/", "/examples/", "__pycache__"))


def cloth_bundle(tmp: str, out: str, part_mib: int) -> list[str]:
    """The cloth wheels' kept files as one xz tar (here: ``tmp`` holds the wheels), split into
    parts of at most ``part_mib``; returns the parts' paths."""
    import io
    import tarfile
    raw = io.BytesIO()
    with tarfile.open(fileobj=raw, mode="w") as tar:
        for wheel in sorted(glob.glob(os.path.join(tmp, "*.whl"))):
            with zipfile.ZipFile(wheel) as src:
                for info in src.infolist():
                    if info.is_dir() or not keep_cloth(info.filename):
                        continue
                    member = tarfile.TarInfo(info.filename)
                    data = src.read(info.filename)
                    member.size, member.mode = len(data), 0o755 if info.filename.endswith(".so") else 0o644
                    tar.addfile(member, io.BytesIO(data))
    import lzma
    packed = lzma.compress(raw.getvalue(), preset=9 | lzma.PRESET_EXTREME)
    for old in glob.glob(out + ".*"):
        os.remove(old)
    size, paths = part_mib * 2 ** 20, []
    for k in range(0, len(packed), size):
        paths.append(f"{out}.{k // size:02d}")
        with open(paths[-1], "wb") as f:
            f.write(packed[k:k + size])
    return paths


def main(argv=None) -> int:
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--python-version", default="3.12", help="the device's Python (default 3.12)")
    ap.add_argument("--out", default=None, help="default .device/site.zip (--cloth: .device/cloth_site.tar.xz)")
    ap.add_argument("--variants", default=",".join(KEEP_VARIANTS),
                    help="Mitsuba's variants to keep (cuda_ad_rgb,scalar_rgb fits one call beside the working tree)")
    ap.add_argument("--cloth", action="store_true", help="the cloth stage's Warp, Newton, trimesh and pykdtree instead")
    ap.add_argument("--part-mib", type=int, default=40, help="--cloth: largest part (the working tree, 22 MiB, travels too)")
    args = ap.parse_args(argv)
    args.out = args.out or (".device/cloth_site.tar.xz" if args.cloth else ".device/site.zip")
    if args.cloth:
        from importlib.metadata import version
        wheels = tuple(f"{name}=={version(name)}" for name in CLOTH_WHEELS)
    else:
        wheels = WHEELS
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "pip", "download", "-q", "--no-deps", "--only-binary=:all:", "--python-version",
               args.python_version, "--implementation", "cp", "-d", tmp, *sum((["--platform", p] for p in PLATFORMS), []), *wheels]
        subprocess.run(cmd, check=True)
        if args.cloth:
            for path in cloth_bundle(tmp, args.out, args.part_mib):
                print(f"{path}: {os.path.getsize(path) / 2 ** 20:.1f} MiB")
            return 0
        out = args.out + ".part"
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as dst:
            for wheel in sorted(glob.glob(os.path.join(tmp, "*.whl"))):
                with zipfile.ZipFile(wheel) as src:
                    for info in src.infolist():
                        if keep(info.filename, tuple(args.variants.split(","))):
                            dst.writestr(info, src.read(info.filename))
        os.replace(out, args.out)
    print(f"{args.out}: {os.path.getsize(args.out) / 2 ** 20:.1f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
