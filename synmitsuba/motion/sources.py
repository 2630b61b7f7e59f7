"""Where a motion comes from, resolved in one place: a procedural kind, a BVH file or an
AMASS npz. Scene files, the CLI and the motion library all call ``load_motion``."""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.motion.motion import Motion


def motion_source_kind(source: str) -> str:
    """'procedural', 'bvh' or 'amass' for a motion source string; ConfigError otherwise."""
    from synmitsuba.motion.procedural import KINDS
    text = str(source)
    if text in KINDS:
        return "procedural"
    if text.lower().endswith(".bvh"):
        return "bvh"
    if text.lower().endswith(".npz"):
        return "amass"
    raise ConfigError("motion", source, f"give a .bvh or AMASS .npz file or one of {', '.join(KINDS)}")


MOTION_SUFFIXES = (".bvh", ".npz")


def motion_files(folder: str) -> list[str]:
    """Every .bvh / .npz file under ``folder`` (subfolders too), sorted by path: the same list
    on every machine and file system."""
    return sorted(os.path.join(root, f) for root, _, files in os.walk(folder) for f in files
                  if f.lower().endswith(MOTION_SUFFIXES))


def check_motion_source(source: str, base: str = "", field: str = "motion") -> tuple[str, str]:
    """(kind, path) of a motion source, or a ConfigError naming ``field`` for an unknown kind
    or a missing file (relative paths are taken from ``base``); cheap, so callers check every
    source before building anything."""
    try:
        kind = motion_source_kind(source)
    except ConfigError as exc:
        raise ConfigError(field, exc.value, exc.fix) from None
    path = "" if kind == "procedural" else os.path.join(base, os.fspath(source))
    if path and not os.path.isfile(path):
        where = "; relative paths start at the folder of the file that names them" if base else ""
        raise ConfigError(field, source, f"no such file ({path}){where}")
    return kind, path


def load_motion(source: str, rng: np.random.Generator, seconds: float = 2.0, base: str = "",
                labels=(), field: str = "motion", roll: float = 1.0) -> Motion:
    """The motion ``source`` names: a procedural kind (``seconds`` long, parameters from
    ``rng``, its feet's roll scaled by ``roll``), or a .bvh / AMASS .npz file (relative paths
    are taken from ``base``). ``field`` names the setting in errors (e.g. ``subjects[2].motion``)."""
    kind, path = check_motion_source(source, base, field)
    if kind == "procedural":
        from synmitsuba.motion.procedural import procedural_motion
        return procedural_motion(str(source), rng, seconds=seconds, roll=roll)
    if kind == "bvh":
        from synmitsuba.motion.bvh import load_bvh
        return load_bvh(path, labels=labels)
    from synmitsuba.motion.amass import load_amass
    return load_amass(path, labels=labels)
