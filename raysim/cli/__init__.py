"""The ``raysim`` command line.

Subcommands live in modules ``raysim/cli/cmd_<name>.py``; each defines
``register(subparsers)`` which adds a parser and sets ``func(args) -> int``.
Exit codes: 0 success, 1 the work failed, 2 bad input (usage, files, values).
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from raysim import __version__


def build_parser() -> argparse.ArgumentParser:
    """Parser with every discovered subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="raysim",
        description="Ray-traced FMCW MIMO radar simulation for hovering drones, "
        "and IMU-driven motion compensation.",
    )
    parser.add_argument("--version", action="version", version=f"raysim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
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
        return int(args.func(args) or 0)
    except ValueError as exc:
        print(f"raysim {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"raysim {args.command}: interrupted; finished outputs were kept", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
