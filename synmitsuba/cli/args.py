"""Argument types and checks shared by the commands: each turns bad input into one line
naming the option, the value and the fix, before any heavy work starts."""
from __future__ import annotations

import argparse
import os
import tempfile

from synmitsuba.errors import ConfigError


def resolution(text: str) -> tuple[int, int]:
    """WIDTHxHEIGHT in pixels."""
    try:
        w, h = (int(x) for x in str(text).lower().split("x"))
        if w > 0 and h > 0:
            return w, h
    except ValueError:
        pass
    raise argparse.ArgumentTypeError(f"{text!r}: give WIDTHxHEIGHT in pixels, e.g. 640x480")


def _integer(low: int):
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < low:
            raise argparse.ArgumentTypeError(f"{text!r}: give a whole number >= {low}")
        return value
    parse.__name__ = f"integer >= {low}"
    return parse


positive_int = _integer(1)
natural_int = _integer(0)


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r}: give a positive number")
    return value


def output_dir(path: str, option: str = "--out") -> str:
    """Create ``path`` (a folder) and make sure files can be written in it, or raise."""
    try:
        os.makedirs(path, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path, prefix=".synmitsuba-write-test-"):
            pass
    except OSError as exc:
        raise ConfigError(option, path, f"cannot write there ({exc.strerror or exc}); give a writable folder") from None
    return path


def output_file(path: str, option: str = "--out", suffix: str = ".png") -> str:
    """Make sure a file can be written at ``path`` (its folder is created)."""
    output_dir(os.path.dirname(os.path.abspath(path)), option)
    if os.path.isdir(path):
        raise ConfigError(option, path, f"this is a folder; give a file name ending in {suffix}")
    return path


def add_variant_option(parser: argparse.ArgumentParser, what: str = "Mitsuba variant") -> None:
    """``--variant``, with the default every command shares."""
    parser.add_argument("--variant", help=f"{what} (default: auto = cuda_ad_rgb on a GPU, else llvm_ad_rgb; "
                                          "or $SYNMITSUBA_VARIANT)")
