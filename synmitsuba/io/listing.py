"""The complete samples of a folder (``synmitsuba.data.SynDataset`` reads them into PyTorch).
A sample is complete when its JSON sidecar exists: it is written last."""
from __future__ import annotations

import os



def list_samples(root: str) -> list[str]:
    """Stems of the complete samples under ``root`` (recursively), sorted."""
    stems = []
    for folder, _, files in os.walk(os.fspath(root)):
        for f in files:
            if f.endswith(".json") and f[:-5] + ".exr" in files:
                stems.append(os.path.join(folder, f[:-5]))
    return sorted(stems)
