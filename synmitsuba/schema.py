"""One validation layer for recipes, scene files and configs.

Fields of a dataclass declare what they accept with ``spec(default, Check)``; ``from_dict``
turns a mapping (parsed YAML/JSON) into the dataclass. Every error is a ``ConfigError`` naming the full key path
(``subjects[2].motion``, ``recipe.garments[0].texture.pattern``), the value and the fix; an
unknown key lists the keys that exist.

We chose this over pydantic v2 after trying both on the scene file: pydantic's errors carry
the location but not our fix (an extra key says "Extra inputs are not permitted" without the
allowed keys; a 2-vector position says "Input should be a valid tuple"), and importing it
costs about 0.23 s, most of our 0.3 s budget for ``import synmitsuba``.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import MISSING
from typing import Any

import numpy as np

from synmitsuba.errors import ConfigError


class Check:
    """Validates and normalises one value; ``where`` is its key path."""

    def __call__(self, where: str, value):  # pragma: no cover - interface
        raise NotImplementedError


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


@dataclasses.dataclass(frozen=True)
class Number(Check):
    """A finite number in [low, high] (either bound optional); ``integer`` for whole numbers."""

    low: float | None = None
    high: float | None = None
    integer: bool = False

    def describe(self) -> str:
        what = "an integer" if self.integer else "a number"
        if self.low is not None and self.high is not None:
            return f"give {what} in [{self.low}, {self.high}]"
        if self.low is not None:
            return f"give {what} >= {self.low}"
        if self.high is not None:
            return f"give {what} <= {self.high}"
        return f"give {what}"

    def __call__(self, where: str, value):
        ok = _is_number(value) and math.isfinite(float(value))
        if ok and self.integer:
            ok = float(value) == int(value)
        if ok and self.low is not None:
            ok = value >= self.low
        if ok and self.high is not None:
            ok = value <= self.high
        if not ok:
            raise ConfigError(where, value, self.describe())
        return int(value) if self.integer else float(value)


@dataclasses.dataclass(frozen=True)
class Choice(Check):
    """One of ``options``: a tuple, or a registry dict read at check time (so kinds added to
    the registry later are accepted)."""

    options: Any  # a tuple or a registry dict

    def __call__(self, where: str, value):
        if value not in self.options:
            raise ConfigError(where, value, f"use one of {', '.join(map(str, self.options))}")
        return value


@dataclasses.dataclass(frozen=True)
class Vector(Check):
    """``n`` finite numbers (a list), each in [low, high] when given."""

    n: int
    low: float | None = None
    high: float | None = None
    what: str = ""

    def __call__(self, where: str, value):
        arr = np.asarray(value, dtype=object)
        ok = arr.shape == (self.n,) and all(_is_number(x) and math.isfinite(float(x)) for x in arr)
        if ok:
            arr = arr.astype(np.float64)
            ok = bool((self.low is None or (arr >= self.low).all()) and (self.high is None or (arr <= self.high).all()))
        if not ok:
            rng = f" in [{self.low}, {self.high}]" if self.low is not None and self.high is not None else ""
            raise ConfigError(where, value, f"give {self.n} numbers{rng}" + (f" ({self.what})" if self.what else ""))
        return [float(x) for x in arr]


POSITIVE = Number(1, integer=True)  # counts: spp, pixels, frames


class Range(Vector):
    """``[low, high]`` with low <= high, both within the bounds: a range to draw from."""

    def __init__(self, low: float | None = None, high: float | None = None, what: str = ""):
        super().__init__(2, low, high, what)

    def __call__(self, where: str, value):
        lo, hi = super().__call__(where, value)
        if lo > hi:
            raise ConfigError(where, value, "give [low, high] with low <= high" + (f" ({self.what})" if self.what else ""))
        return [lo, hi]


@dataclasses.dataclass(frozen=True)
class Text(Check):
    def __call__(self, where: str, value):
        if not isinstance(value, str) or not value:
            raise ConfigError(where, value, "give a non-empty string")
        return value


@dataclasses.dataclass(frozen=True)
class Flag(Check):
    def __call__(self, where: str, value):
        if not isinstance(value, bool):
            raise ConfigError(where, value, "give true or false")
        return value


@dataclasses.dataclass(frozen=True)
class Nested(Check):
    """A mapping read into dataclass ``cls`` with ``from_dict``."""

    cls: type

    def __call__(self, where: str, value):
        return value if isinstance(value, self.cls) else from_dict(self.cls, value, where)


@dataclasses.dataclass(frozen=True)
class ListOf(Check):
    """A list whose items pass ``item``; between ``min_len`` and ``max_len`` long."""

    item: Check
    min_len: int = 0
    max_len: int | None = None

    def __call__(self, where: str, value):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(where, value, "give a list")
        if len(value) < self.min_len or (self.max_len is not None and len(value) > self.max_len):
            most = f" and at most {self.max_len}" if self.max_len is not None else ""
            raise ConfigError(where, value, f"give at least {self.min_len}{most} entries")
        return [self.item(f"{where}[{i}]", v) for i, v in enumerate(value)]


@dataclasses.dataclass(frozen=True)
class MapOf(Check):
    """A mapping whose values pass ``value``; keys limited to ``keys`` when given."""

    value: Check
    keys: tuple | None = None

    def __call__(self, where: str, data):
        mapping(where, data, self.keys)
        return {k: self.value(f"{where}.{k}", v) for k, v in data.items()}


@dataclasses.dataclass(frozen=True)
class AnyOf(Check):
    """The first of ``checks`` that accepts the value; otherwise ``fix``."""

    checks: tuple
    fix: str

    def __call__(self, where: str, value):
        for check in self.checks:
            try:
                return check(where, value)
            except ConfigError:
                continue
        raise ConfigError(where, value, self.fix)


def optional(check: Check) -> Check:
    """``check``, or None."""
    return _Optional(check)


@dataclasses.dataclass(frozen=True)
class _Optional(Check):
    check: Check

    def __call__(self, where: str, value):
        return None if value is None else self.check(where, value)


def spec(default: Any = MISSING, check: Check | None = None, *, factory=MISSING, doc: str = ""):
    """A dataclass field with its check (and a one-line doc for generated help)."""
    return dataclasses.field(default=default, default_factory=factory, metadata={"check": check, "doc": doc})


def check_fields(obj, where: str) -> None:
    """Run each field's spec check on ``obj``'s own value (for a dataclass built in code, not
    read with ``from_dict``), storing the normalised value (frozen dataclasses too)."""
    for f in dataclasses.fields(obj):
        check = f.metadata.get("check")
        if check is not None:
            object.__setattr__(obj, f.name, check(f"{where}.{f.name}", getattr(obj, f.name)))


def mapping(where: str, data, allowed=None) -> dict:
    """``data`` must be a mapping with only ``allowed`` keys (when given)."""
    if not isinstance(data, dict):
        raise ConfigError(where, data, "give a mapping (key: value)")
    if allowed is not None:
        unknown = [k for k in data if k not in allowed]
        if unknown:
            k = unknown[0]
            raise ConfigError(f"{where}.{k}", data[k], f"unknown key; keys: {', '.join(sorted(map(str, allowed)))}")
    return data


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def from_dict(cls, data, where: str = ""):
    """An instance of dataclass ``cls`` from ``data``, every field checked by its spec;
    absent fields take their defaults. Errors name ``where.<key>``."""
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    mapping(where or cls.__name__, data, fields)
    values = {}
    for name, f in fields.items():
        if name in data:
            check = f.metadata.get("check")
            values[name] = check(_join(where, name), data[name]) if check else data[name]
        elif f.default is MISSING and f.default_factory is MISSING:
            doc = f.metadata.get("doc")
            raise ConfigError(_join(where, name), None, f"required{': ' + doc if doc else ''}")
    return construct(cls, values, where)


def construct(cls, values: dict, where: str):
    """``cls(**values)``, with a ConfigError from its ``__post_init__`` (which names fields
    relative to the object, e.g. ``material.roughness``) re-rooted at ``where``."""
    try:
        return cls(**values)
    except ConfigError as exc:  # a __post_init__ names the field relative to the object
        field = exc.field.split(".", 1)[-1] if "." in exc.field else exc.field
        raise ConfigError(_join(where, field) if where else exc.field, exc.value, exc.fix) from None


class Params:
    """Mixin for parameter dataclasses: ``from_dict`` / ``to_dict`` through the field specs, so
    a recipe part needs no hand-written validation."""

    @classmethod
    def from_dict(cls, data, where: str = ""):
        return from_dict(cls, data, where)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)  # type: ignore[call-overload]  # every Params is a dataclass


def read_yaml(path, what: str, keys: str) -> dict:
    """The top-level mapping of a YAML file; errors name ``what`` (e.g. "scene file"), the
    path and, for malformed YAML, the line and column; ``keys`` says what the top level holds."""
    import os

    import yaml
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ConfigError(what, path, "no such file")
    try:
        with open(path) as fh:
            data = yaml.safe_load(fh)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ConfigError(what, path, f"malformed YAML{at}: {getattr(exc, 'problem', exc)}") from None
    data = {} if data is None else data  # an empty file: every default
    if not isinstance(data, dict):
        raise ConfigError(what, path, f"the top level must be a mapping ({keys})")
    return data
