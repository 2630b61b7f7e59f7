"""One multi-channel OpenEXR per sample (+ JSON sidecar + sRGB PNG preview), and reading back.

Channels: R G B A (float32), depth.Z, normal.X/Y/Z, position.X/Y/Z, uv.U/V (float32),
mask, instance, layer (uint32), coverage.<id> (half: soft mask of each instance). The camera (OpenCV K, R, t, size) and render settings are in
the EXR header (``synmitsuba`` attribute, JSON) and in ``<stem>.json``. Files are written under a
temporary name and renamed, so a crash never leaves a half-written sample that looks complete.
"""
from __future__ import annotations

import json
import os

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.io.preview import to_srgb8, write_png
from synmitsuba.render.sample import Sample
from synmitsuba.scene.camera import Camera

FORMAT_VERSION = 1
_VEC = {"normal": "XYZ", "position": "XYZ", "uv": "UV"}


def _channels(sample: Sample) -> dict[str, np.ndarray]:
    ch = {c: sample.rgb[..., i] for i, c in enumerate("RGB")}
    ch["A"] = sample.alpha
    ch["depth.Z"] = sample.depth
    for name, comps in _VEC.items():
        arr = getattr(sample, name)
        for i, c in enumerate(comps):
            ch[f"{name}.{c}"] = arr[..., i]
    ch = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in ch.items()}
    ch["mask"] = sample.mask.astype(np.uint32)
    ch["instance"] = sample.instance.astype(np.uint32)
    ch["layer"] = sample.layer.astype(np.uint32)
    for inst, frac in sample.coverage.items():  # k / samples: exact in half precision for samples <= 2048
        ch[f"coverage.{inst}"] = np.ascontiguousarray(frac, dtype=np.float16)
    return ch


def _sidecar(sample: Sample) -> dict:
    return {"format": "synmitsuba-sample", "format_version": FORMAT_VERSION,
            "camera": sample.camera.to_dict(), "instances": sample.instance_ids(),
            "width": sample.camera.width, "height": sample.camera.height, "meta": sample.meta}


def write_sample(sample: Sample, stem: str, preview: bool = True) -> dict[str, str]:
    """Write ``<stem>.exr``, ``<stem>.json`` and (``preview``) ``<stem>.png``; returns the paths."""
    import OpenEXR
    stem = os.fspath(stem)
    os.makedirs(os.path.dirname(os.path.abspath(stem)), exist_ok=True)
    side = _sidecar(sample)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "synmitsuba": json.dumps(side)}
    paths = {"exr": f"{stem}.exr", "json": f"{stem}.json"}
    tmp = f"{stem}.tmp-{os.getpid()}.exr"
    with OpenEXR.File(header, _channels(sample)) as f:
        f.write(tmp)
    os.replace(tmp, paths["exr"])
    if preview:
        paths["png"] = write_png(f"{stem}.png", to_srgb8(sample.rgb))
    tmp = f"{stem}.json.tmp-{os.getpid()}"
    with open(tmp, "w") as fh:
        json.dump(side, fh, indent=1)
    os.replace(tmp, paths["json"])  # the sidecar is written last: its presence marks the sample done
    return paths


def read_sample(stem: str) -> Sample:
    """Read a sample written by ``write_sample`` (``stem`` with or without ``.exr``)."""
    import OpenEXR
    stem = os.fspath(stem)
    stem = stem[:-4] if stem.endswith(".exr") else stem
    if not os.path.isfile(f"{stem}.exr"):
        raise ConfigError("sample path", f"{stem}.exr", "no such file; give the stem passed to write_sample")
    with OpenEXR.File(f"{stem}.exr", separate_channels=True) as f:
        ch = {k: v.pixels for k, v in f.channels().items()}
        side = json.loads(f.header()["synmitsuba"])
    vec = {name: np.stack([ch[f"{name}.{c}"] for c in comps], -1) for name, comps in _VEC.items()}
    cov = {int(k.split(".", 1)[1]): v.astype(np.float32) for k, v in ch.items() if k.startswith("coverage.")}
    return Sample(rgb=np.stack([ch["R"], ch["G"], ch["B"]], -1), alpha=ch["A"], depth=ch["depth.Z"],
                  coverage=dict(sorted(cov.items())),
                  mask=ch["mask"].astype(bool), instance=ch["instance"].astype(np.int32),
                  layer=ch["layer"].astype(np.uint8), camera=Camera.from_dict(side["camera"]),
                  meta=side.get("meta", {}), **vec)
