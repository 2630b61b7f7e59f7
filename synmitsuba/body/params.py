"""Validation shared by the recipe parameter dataclasses (errors name the field and value)."""
from __future__ import annotations

from dataclasses import fields

from synmitsuba.errors import ConfigError


def from_dict(cls, d: dict, where: str):
    names = {f.name for f in fields(cls)}
    for k in d:
        if k not in names:
            raise ConfigError(f"{where}.{k}", d[k], f"unknown field; fields: {', '.join(sorted(names))}")
    obj = cls(**d)
    obj.validate(where)
    return obj


def check(where: str, name: str, value, low=None, high=None, choices=None):
    if choices is not None:
        if value not in choices:
            raise ConfigError(f"{where}.{name}", value, f"use one of {', '.join(choices)}")
        return
    if not isinstance(value, (int, float)) or not low <= value <= high:
        raise ConfigError(f"{where}.{name}", value, f"give a number in [{low}, {high}]")
