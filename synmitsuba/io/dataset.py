"""A PyTorch dataset over a folder of samples written by ``write_sample``.

Only complete samples are listed: a sample is complete when its JSON sidecar exists (it is
written last). Items are dicts of tensors plus the camera as ``K``, ``R``, ``t``.
"""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.io.exr import read_sample


def list_samples(root: str) -> list[str]:
    """Stems of the complete samples under ``root`` (recursively), sorted."""
    stems = []
    for folder, _, files in os.walk(os.fspath(root)):
        for f in files:
            if f.endswith(".json") and f[:-5] + ".exr" in files:
                stems.append(os.path.join(folder, f[:-5]))
    return sorted(stems)


class SampleDataset:
    """``torch.utils.data.Dataset`` of rendered samples: ``rgb`` (3, H, W), ``alpha``, ``depth``,
    ``mask``, ``normal`` (3, H, W), ``position``, ``uv``, ``instance``, ``layer``, ``K``, ``R``, ``t``."""

    def __init__(self, root: str, passes: tuple[str, ...] | None = None):
        self.stems = list_samples(root)
        self.passes = passes

    def __len__(self) -> int:
        return len(self.stems)

    def __getitem__(self, i: int) -> dict:
        import torch
        s = read_sample(self.stems[i])
        names = self.passes or tuple(s.passes)
        item = {}
        for name in names:
            arr = getattr(s, name)
            if arr.dtype == np.uint8:
                arr = arr.astype(np.int64)
            t = torch.from_numpy(np.ascontiguousarray(arr))
            item[name] = t.permute(2, 0, 1) if t.ndim == 3 else t
        item.update(K=torch.from_numpy(s.camera.K), R=torch.from_numpy(s.camera.R),
                    t=torch.from_numpy(s.camera.t), stem=self.stems[i])
        return item


def _as_torch_dataset():
    try:
        import torch.utils.data as tud
    except ImportError:  # torch is a dependency, but keep the reader usable without it
        return SampleDataset
    return type("SampleDataset", (SampleDataset, tud.Dataset), {"__doc__": SampleDataset.__doc__})


SampleDataset = _as_torch_dataset()
