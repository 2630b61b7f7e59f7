"""Command line: ``synmitsuba <command> ...``. Each command lives in its own module here and
registers itself through ``add_parser(subparsers)``; the parser sets ``func`` to run it.

Every command checks its arguments before heavy work; bad input is one line naming the
option or field, the value and the fix (exit 2); Ctrl-C is one line (exit 130), and
nothing half-written is left looking complete (files are written under temporary names).
"""
from __future__ import annotations

import argparse
import importlib
import sys
import warnings

# Modules providing commands, in the order they appear in --help. A module that fails to
# import (an optional extra missing) does not take the whole CLI down.
COMMAND_MODULES = ("render", "info", "subject", "motion")
DESCRIPTION = ("synthetic, exactly annotated images of clothed, animated people, rendered with Mitsuba 3. "
               "Run 'synmitsuba COMMAND --help' for a command's options.")


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Shows every option's default (options without one say what applies in their help);
    keeps descriptions as written."""

    def _get_help_string(self, action):
        text = action.help or ""
        shown = not any(action.default is x for x in (None, False, argparse.SUPPRESS))
        if shown and action.option_strings and "%(default)" not in text:
            text += " (default: %(default)s)"
        return text


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``synmitsuba CMD: error: argument --res: 'big': give ...``."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    from synmitsuba import __version__
    parser = Parser(prog="synmitsuba", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"synmitsuba {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"synmitsuba.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"synmitsuba.cli.{name}":
                continue
            raise
        module.add_parser(sub)
    return parser


def _interrupted(exc: BaseException) -> bool:
    """Ctrl-C, also when drjit re-raises it from inside a kernel as a RuntimeError."""
    while exc is not None:
        if isinstance(exc, KeyboardInterrupt) or "KeyboardInterrupt" in str(exc):
            return True
        exc = exc.__cause__ or exc.__context__
    return False


def _one_line_warnings(prog: str) -> None:
    def show(message, category, filename, lineno, file=None, line=None):
        print(f"{prog}: warning: {message}", file=sys.stderr)
    warnings.showwarning = show


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a bad argument (already reported on one line)
        return int(exc.code or 0)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    from synmitsuba.errors import SynMitsubaError
    prog = f"synmitsuba {args.command}"
    _one_line_warnings(prog)
    try:
        return int(args.func(args) or 0)
    except SynMitsubaError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, RuntimeError) as exc:
        if not _interrupted(exc):
            raise
        print(f"{prog}: interrupted; files already written are complete, nothing half-written was kept",
              file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
