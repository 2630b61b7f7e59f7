"""Command line: ``synmitsuba <command> ...``. Each command lives in its own module here and
registers itself through ``add_parser(subparsers)``; the parser sets ``func`` to run it.

Every command checks its arguments before heavy work; bad input is one line naming the
option or field, the value and the fix (exit 2); Ctrl-C is one line (exit 130), and
nothing half-written is left looking complete (files are written under temporary names).
"""
from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
import warnings
from typing import Callable

# Modules providing commands, in the order they appear in --help. A module that fails to
# import (an optional extra missing) does not take the whole CLI down.
COMMAND_MODULES = ("generate", "stats", "fit_smplx", "render", "compose", "show", "info", "subject", "motion",
                   "fit_texture", "view", "export", "warm")
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


def _stop_children() -> None:
    """Kill this process's worker processes (a generation's pool) and reap them."""
    import multiprocessing
    children = multiprocessing.active_children()
    for p in children:
        p.kill()
    for p in children:
        p.join(5)
    if children:  # their queues' named semaphores: unlinked now, as a normal exit would (else the tracker warns)
        from multiprocessing import util
        try:
            util._run_finalizers(0)  # type: ignore[attr-defined]  # what multiprocessing runs at exit
        except Exception:  # noqa: BLE001 - best effort on the way out
            pass


def _exit_on_interrupt(prog: str) -> Callable[[], None]:
    """Ctrl-C: remove the temporaries being written, say so on one line, exit 130 at once.

    A KeyboardInterrupt raised inside drjit (our Python sensor runs while a kernel is traced)
    can leave the renderer hung or abort the interpreter at exit, so the command never lets
    one reach it: the handler runs at the next point Python gets control and leaves."""
    from synmitsuba.io.files import remove_temporaries
    terminal = os.dup(2)  # the real stderr, also while a library's output is being caught
    message = f"{prog}: interrupted; files already written are complete, nothing half-written was kept\n"

    def handler(signum, frame):
        _stop_children()  # first: a worker left running would write on after we exit
        remove_temporaries()
        sys.stdout.flush()
        os.write(terminal, message.encode())
        os._exit(130)
    previous = signal.signal(signal.SIGINT, handler)

    def restore():
        signal.signal(signal.SIGINT, previous)
        os.close(terminal)
    return restore


def _one_line_warnings(prog: str) -> Callable:
    def show(message, category, filename, lineno, file=None, line=None):
        print(f"{prog}: warning: {message}", file=sys.stderr)
    previous, warnings.showwarning = warnings.showwarning, show
    return previous


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
    from synmitsuba.process import configure_process
    configure_process()  # the CLI owns its process: collector and thread settings (library code never sets them)
    prog = f"synmitsuba {args.command}"
    show_warning = _one_line_warnings(prog)
    main_thread = threading.current_thread() is threading.main_thread()
    restore = _exit_on_interrupt(prog) if main_thread else None
    try:
        return int(args.func(args) or 0)
    except SynMitsubaError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    finally:
        warnings.showwarning = show_warning
        if restore is not None:
            restore()


if __name__ == "__main__":
    sys.exit(main())
