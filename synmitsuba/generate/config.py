"""Generation configs (``configs/tiny.yaml``, ``demo.yaml``, ``hps.yaml``, ``crowds.yaml``, ``nerf.yaml``): how many
sequences, which frames, how to render, and the composition of each sequence's scene. Every
value can be overridden with ``--set key.path=value`` (YAML syntax for the value)."""
from __future__ import annotations

import os
from dataclasses import dataclass

import yaml

from synmitsuba.annotate.smplx_fit import SMPLXOptions
from synmitsuba.compose.composition import ComposeConfig
from synmitsuba.engine.settings import DENOISERS, SAMPLERS
from synmitsuba.errors import ConfigError
from synmitsuba.resources import config_names, find_config
from synmitsuba.rendering.photo import PhotoOptions
from synmitsuba.schema import POSITIVE, Choice, Flag, Nested, Number, Params, Range, Text, optional, read_yaml, spec


@dataclass
class RenderOptions(Params):
    spp: int = spec(16, POSITIVE, doc="samples per pixel")
    max_depth: int = spec(6, POSITIVE)
    sampler: str = spec("auto", Choice(SAMPLERS))
    denoise: str = spec("none", Choice(DENOISERS), doc="oidn needs synmitsuba[denoise]")
    shutter_deg: list = spec(factory=lambda: [0.0, 0.0], check=Range(0, 360),
                             doc="shutter angle range drawn per sequence (180 = open half the frame interval); 0: no motion blur")
    subframes: int = spec(8, POSITIVE, doc="motion blur: renders across the exposure, spp shared among them")
    photo: PhotoOptions = spec(factory=PhotoOptions, check=Nested(PhotoOptions),
                               doc="exposure, white balance, sensor noise, JPEG (off by default)")


@dataclass
class GenerateConfig(Params):
    sequences: int = spec(2, POSITIVE, doc="sequences in the dataset (one task each)")
    seed: int = spec(0, Number(0, 2 ** 32 - 1, integer=True), doc="global seed: sequence i uses (seed, i) only")
    frames: int | None = spec(None, optional(POSITIVE), doc="frames rendered per sequence (default: the whole clip)")
    stride: int = spec(1, POSITIVE, doc="clip frames between rendered frames")
    annotate: bool = spec(True, Flag(), doc="subject labels, flow and body passes")
    flow: str = spec("rendered", Choice(("rendered", "adjacent")),
                     doc="rendered: flow to the previous/next rendered frame (f -/+ stride); adjacent: to clip frames f -/+ 1")
    render: RenderOptions = spec(factory=RenderOptions, check=Nested(RenderOptions))
    compose: ComposeConfig = spec(factory=ComposeConfig, check=Nested(ComposeConfig))
    scene: str | None = spec(None, optional(Text()), doc="a scene file whose objects, lights, cameras and subjects every "
                             "sequence uses instead of a composed scene (relative to the config file); compose is unused")
    smplx: SMPLXOptions = spec(factory=SMPLXOptions, check=Nested(SMPLXOptions),
                               doc="SMPL-X / SMPL fits of every subject (needs the user's model files)")


def _override(data: dict, assignment: str) -> None:
    """Apply ``key.path=value`` to nested dicts (the value read as YAML)."""
    if "=" not in assignment:
        raise ConfigError("--set", assignment, "give key.path=value, e.g. render.spp=16")
    path, value = assignment.split("=", 1)
    keys = path.strip().split(".")
    node = data
    for k in keys[:-1]:
        node = node.setdefault(k, {})
        if not isinstance(node, dict):
            raise ConfigError(f"--set {path}", value, f"{k} is not a section")
    node[keys[-1]] = yaml.safe_load(value)


def load_generate_config(path: str, overrides=()) -> GenerateConfig:
    """The config in ``path`` (or a shipped one by name: ``tiny``, ``demo``, ``hps``, ``crowds``, ``nerf``)
    with ``overrides`` applied, every key checked (errors name the key path); the compose
    section's motion paths start at the file's folder."""
    path = find_config(path)
    if not os.path.isfile(path):
        raise ConfigError("config file", path, f"no such file; give a path or a shipped config: {', '.join(config_names())}")
    data = read_yaml(path, "config file", "sequences, render, compose, ...")
    if isinstance(data.get("scene"), str):
        data["scene"] = os.path.join(os.path.dirname(os.path.abspath(path)), data["scene"])
    for assignment in overrides:
        _override(data, assignment)
    compose = data.setdefault("compose", {})
    if isinstance(compose, dict):
        compose.setdefault("base", os.path.dirname(os.path.abspath(path)))
    return GenerateConfig.from_dict(data, "")
