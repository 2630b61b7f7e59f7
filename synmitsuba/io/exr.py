"""One multi-channel OpenEXR per sample (+ JSON sidecar + sRGB PNG preview), and reading back.

Channels come from the pass registry (``synmitsuba.sample.PASSES``): R G B A, depth.Z,
normal.X/Y/Z, position.X/Y/Z, uv.U/V (float32); mask, uv.valid, instance, layer (uint32); plus
coverage.<id> (float32: soft mask of each instance) and amodal.<id> (uint32: each subject's
amodal mask, with its label record in the JSON's ``subjects``). The camera (OpenCV K, R, t, size) and render
settings are in the EXR header (``synmitsuba`` attribute, JSON) and in ``<stem>.json``. Files are written under a
temporary name and renamed, so a crash never leaves a half-written sample that looks complete.
"""
from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping

import numpy as np

from synmitsuba.annotate.labels import SubjectLabels
from synmitsuba.body.anny_model import KEYPOINTS
from synmitsuba.body.expressions import FACE_UNITS
from synmitsuba.body.face_points import face_keypoint_names
from synmitsuba.body.hand_points import hand_keypoint_names
from synmitsuba.errors import ConfigError
from synmitsuba.io.files import atomic_path
from synmitsuba.io.preview import to_srgb8, write_png
from synmitsuba.sample import PASSES, Sample
from synmitsuba.scene.camera import Camera

FORMAT_VERSION = 1
_EXR_DTYPE = {"float32": np.float32, "uint32": np.uint32, "half": np.float16}


def _channels(sample: Sample) -> dict[str, np.ndarray]:
    """EXR channels of every registered pass the sample holds (``PASSES`` order)."""
    ch = {}
    for name, spec in PASSES.items():
        if name not in sample.passes:
            continue
        arr = np.asarray(sample.passes[name])
        comps = [arr] if spec.components == 1 else [arr[..., i] for i in range(spec.components)]
        for cname, comp in zip(spec.channels, comps):
            ch[cname] = np.ascontiguousarray(comp, dtype=_EXR_DTYPE[spec.exr_type])
    for inst, frac in sample.coverage.items():  # float32: k / n is not exact in half precision for n = 9
        ch[f"coverage.{inst}"] = np.ascontiguousarray(frac, dtype=np.float32)
    for rec in sample.subjects:
        ch[f"amodal.{rec['instance']}"] = np.ascontiguousarray(rec["amodal_mask"], dtype=np.uint32)
    return ch


def _plain(value):
    """JSON-ready copy of a label record's value (arrays as lists)."""
    if isinstance(value, Mapping):  # dicts and label records (annotate.labels)
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _passes(ch: dict) -> dict[str, np.ndarray]:
    """Registered passes back from EXR channels (a pass missing any channel is skipped)."""
    out = {}
    for name, spec in PASSES.items():
        if all(c in ch for c in spec.channels):
            comps = [ch[c] for c in spec.channels]
            arr = comps[0] if spec.components == 1 else np.stack(comps, -1)
            out[name] = arr.astype(spec.dtype)
    return out


def _sidecar(sample: Sample) -> dict:
    side = {"format": "synmitsuba-sample", "format_version": FORMAT_VERSION,
            "camera": sample.camera.to_dict(), "instances": sample.instance_ids(),
            "width": sample.camera.width, "height": sample.camera.height, "meta": sample.meta,
            "subjects": [_plain({k: v for k, v in r.items() if k != "amodal_mask"}) for r in sample.subjects]}
    if sample.subjects:  # what each row of the keypoint arrays is
        side["keypoint_names"] = list(KEYPOINTS)
        side["hand_keypoint_names"] = [list(hand_keypoint_names(s)) for s in ("left", "right")]
        side["face_keypoint_names"] = list(face_keypoint_names())
        side["expression_names"] = list(FACE_UNITS)
    return side


def _use_threads(OpenEXR) -> None:
    """Compress EXR blocks on as many threads as drjit renders with (the process's share of the
    machine): the bytes are the same for any count, as each block is compressed on its own. The
    pool is shut down before any fork and started again at the next write."""
    from synmitsuba.engine.variant import thread_count
    n = thread_count() or os.cpu_count() or 1
    if OpenEXR.global_thread_count() != n:
        OpenEXR.set_global_thread_count(n)


def _stop_exr_pool() -> None:
    """A child forked with the pool's lock held but not its threads hangs (DataLoader workers)."""
    module = sys.modules.get("OpenEXR")
    if module is not None and module.global_thread_count():
        module.set_global_thread_count(0)


if hasattr(os, "register_at_fork"):  # not on Windows, which does not fork
    os.register_at_fork(before=_stop_exr_pool)


def write_sample(sample: Sample, stem: str, preview: bool = True) -> dict[str, str]:
    """Write ``<stem>.exr``, ``<stem>.json`` and (``preview``) ``<stem>.png``; returns the paths."""
    import OpenEXR
    stem = os.fspath(stem)
    os.makedirs(os.path.dirname(os.path.abspath(stem)), exist_ok=True)
    side = _sidecar(sample)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "synmitsuba": json.dumps(side)}
    paths = {"exr": f"{stem}.exr", "json": f"{stem}.json"}
    _use_threads(OpenEXR)
    with atomic_path(paths["exr"]) as tmp, OpenEXR.File(header, _channels(sample)) as f:
        f.write(tmp)
    if preview:  # a preview: fast zlib level (written once per sample, on the render's critical path)
        paths["png"] = write_png(f"{stem}.png", to_srgb8(sample.rgb), compress_level=1)
    with atomic_path(paths["json"]) as tmp, open(tmp, "w") as fh:  # written last: it marks the sample done
        json.dump(side, fh, indent=1)
    return paths


def update_subjects(stem: str, update) -> None:
    """Rewrite a written sample's subject records (EXR header and JSON sidecar) with
    ``update(records)``, which edits the JSON-ready records in place; pixels are unchanged.
    Both files are written under temporary names and renamed."""
    import OpenEXR
    stem = stem[:-4] if stem.endswith(".exr") else os.fspath(stem)
    with OpenEXR.File(f"{stem}.exr", separate_channels=True) as f:
        header, channels = dict(f.header()), {k: v.pixels for k, v in f.channels().items()}
    side = json.loads(header["synmitsuba"])
    update(side["subjects"])
    side["subjects"] = _plain(side["subjects"])
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, "synmitsuba": json.dumps(side)}
    _use_threads(OpenEXR)
    with atomic_path(f"{stem}.exr") as tmp, OpenEXR.File(header, channels) as f:
        f.write(tmp)
    with atomic_path(f"{stem}.json") as tmp, open(tmp, "w") as fh:
        json.dump(side, fh, indent=1)


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
    cov = {int(k.split(".", 1)[1]): v.astype(np.float32) for k, v in ch.items() if k.startswith("coverage.")}
    return Sample(camera=Camera.from_dict(side["camera"]), passes=_passes(ch), coverage=dict(sorted(cov.items())),
                  meta=side.get("meta", {}), subjects=[SubjectLabels.from_json(r, ch[f"amodal.{r['instance']}"].astype(bool))
                            for r in side.get("subjects", [])])
