"""Lazy exports for packages: names are imported on first use, so ``import synmitsuba`` loads
neither Mitsuba, torch nor anny until something needs them."""
from __future__ import annotations

import importlib
import sys


def lazy_exports(package: str, exports: dict[str, str]):
    """``(__getattr__, __dir__)`` for ``package`` whose public ``name`` is attribute ``name``
    of module ``exports[name]``; ``module:attr`` names another attribute, and ``module:``
    (nothing after the colon) the module itself."""

    def __getattr__(name: str):
        target = exports.get(name)
        if target is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module, colon, attr = target.partition(":")
        value = importlib.import_module(module)
        if not colon or attr:
            value = getattr(value, attr or name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
