"""The ``raysim`` command line.

Subcommands live in modules ``raysim/cli/cmd_<name>.py``; each defines
``register(subparsers)`` which adds a parser and sets ``func(args) -> int``.
Exit codes: 0 success, 1 the work failed, 2 bad input (usage, files, values),
130 interrupted (Ctrl-C, or SIGTERM, which is handled the same way: the
writers remove their temporary files and keep what they finished).
Every parser is a :class:`raysim.cli.options.Parser` (option values such as
``-30:30:1`` are read as values); every command's ``--help`` ends with examples.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import pkgutil
import signal
import sys
import threading
import warnings
from pathlib import Path

from raysim import __version__
from raysim.cli.options import Parser


def build_parser() -> argparse.ArgumentParser:
    """Parser with every discovered subcommand registered."""
    parser = Parser(
        prog="raysim",
        description="Ray-traced FMCW MIMO radar simulation for hovering drones, "
        "and IMU-driven motion compensation.",
        epilog="examples:\n  raysim simulate --case rotation_y\n"
        "  raysim render examples/case_rotation_y.toml --out rotation_y.zarr\n"
        "  raysim report rotation_y.zarr --out rotation_y.html\n"
        "  raysim scenes list\n\nRun `raysim COMMAND --help` for a command's options and "
        "examples.", formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"raysim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("cmd_"):
            importlib.import_module(f"{__name__}.{info.name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``raysim`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        with _sigterm_as_interrupt(), _notes_as_lines(args.command):
            return int(args.func(args) or 0)
    except ValueError as exc:
        print(f"raysim {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:     # the reader left (`| head`): no error, nothing more to say
        with contextlib.suppress(OSError, ValueError, AttributeError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())   # exit flushes
        return PIPE_CLOSED
    except OSError as exc:      # a file or folder the checks could not foresee
        name = f" {exc.filename!r}" if exc.filename else ""
        print(f"raysim {args.command}: error:{name} {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        _quiet_shutdown()
        print(f"raysim {args.command}: interrupted; finished outputs were kept", file=sys.stderr)
        return 130


def _quiet_shutdown() -> None:
    """After an interrupt, the pending tasks of Dask's scheduler and of the event loop that
    die with the process report nothing: the one line above says what happened."""
    import logging
    import threading

    logging.disable(logging.CRITICAL)
    sys.unraisablehook = lambda _unraisable: None
    threading.excepthook = lambda _args: None


#: Exit status when the reader of the output closed the pipe early (128 + SIGPIPE, as a
#: shell reports a command killed by it).
PIPE_CLOSED = 141
#: Warnings the command line states as one line of its own (class names): they report a
#: choice the program made, not a fault of the user's input or of the code.
NOTE_WARNINGS = ("DecimationRefused",)
#: Packages whose warnings the command line states as one line each: they speak to the
#: user about the run, so the file, line and source of the ``warn`` call are noise there.
OWN_PACKAGES = ("raysim", "compensation")


def note_line(command: str, message) -> str:
    """The one line that states a :data:`NOTE_WARNINGS` warning (no file, line or source)."""
    text = " ".join(str(message).split())
    return f"raysim {command}: note: {text}"


def warning_line(command: str, message) -> str:
    """The one line that states a warning of :data:`OWN_PACKAGES`."""
    text = " ".join(str(message).split())
    return f"raysim {command}: warning: {text}"


def _own(category, filename) -> bool:
    """A warning class of ours, or a plain one raised from our code."""
    if category.__module__.split(".")[0] in OWN_PACKAGES:
        return True
    where = Path(str(filename)).resolve()
    return issubclass(category, UserWarning) and any(
        where.is_relative_to(d) for d in _package_dirs())


def _package_dirs() -> tuple:
    return tuple(Path(importlib.import_module(n).__file__).resolve().parent
                 for n in OWN_PACKAGES)


@contextlib.contextmanager
def _notes_as_lines(command: str):
    """While the block runs, :data:`NOTE_WARNINGS` and the other warnings of
    :data:`OWN_PACKAGES` go to stderr as one line each, through ``tqdm.write`` so that a
    progress bar is redrawn below them; other libraries' warnings as before."""
    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if category.__name__ in NOTE_WARNINGS:
            text = note_line(command, message)
        elif _own(category, filename):
            text = warning_line(command, message)
        else:
            return shown(message, category, filename, lineno, file, line)
        from tqdm import tqdm

        tqdm.write(text, file=sys.stderr)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = shown


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """While the block runs, SIGTERM raises KeyboardInterrupt (as Ctrl-C does)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, _frame):
        raise KeyboardInterrupt(f"signal {signum}")

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
