"""Command line: ``synmitsuba <command> ...``. Each command lives in its own module here and
registers itself through ``add_parser(subparsers)``; the parser sets ``func`` to run it."""
from __future__ import annotations

import argparse
import importlib
import sys

# Modules providing commands, in the order they appear in --help. A module that fails to
# import (an optional extra missing) does not take the whole CLI down.
COMMAND_MODULES = ("render", "info", "subject", "motion")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="synmitsuba", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"synmitsuba.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"synmitsuba.cli.{name}":
                continue
            raise
        module.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    from synmitsuba.errors import SynMitsubaError
    try:
        return int(args.func(args) or 0)
    except SynMitsubaError as exc:
        print(f"synmitsuba {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
