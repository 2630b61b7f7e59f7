"""Data shipped inside the package (``synmitsuba/assets/``): generation configs, scene files,
environments and their HDRIs, found with ``importlib.resources`` so they work from a wheel as
from a checkout (where ``configs/`` and ``scenes/`` at the top are links to the same folders)."""
from __future__ import annotations

import os
from importlib import resources


def asset_path(*parts: str) -> str:
    """The path of a shipped file or folder, e.g. ``asset_path("scenes", "hdri")``."""
    return str(resources.files("synmitsuba").joinpath("assets", *parts))


def config_names() -> list[str]:
    """The shipped generation configs by name (``tiny``, ``demo``, ``hps``, ...)."""
    return sorted(os.path.splitext(n)[0] for n in os.listdir(asset_path("configs")) if n.endswith(".yaml"))


def find_config(name_or_path: str) -> str:
    """A config file: the path itself when it exists, else a shipped config named ``name`` (or
    ``name.yaml``); unchanged when neither (the reader then says what is missing)."""
    path = os.fspath(name_or_path)
    if os.path.exists(path) or os.sep in path:
        return path
    stem = path[:-5] if path.endswith(".yaml") else path
    shipped = asset_path("configs", f"{stem}.yaml")
    return shipped if os.path.isfile(shipped) else path
