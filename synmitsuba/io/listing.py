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


def dataset_samples(root: str, what: str = "dataset") -> list[str]:
    """``list_samples`` of a dataset folder, or one clear error (naming ``what``) when the folder
    is missing or holds no complete sample: an empty dataset is a mistake, not a length of 0."""
    from synmitsuba.errors import ConfigError
    if not os.path.isdir(os.fspath(root)):
        raise ConfigError(what, os.fspath(root), "no such folder; give a folder `synmitsuba generate` wrote")
    stems = list_samples(root)
    if not stems:
        raise ConfigError(what, os.fspath(root), "no complete samples here; give a folder `synmitsuba generate` wrote "
                          "(a run still going, or one that failed, has none yet)")
    return stems
