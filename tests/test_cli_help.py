"""Every option of every ``raysim`` subcommand has a clean help text.

The parsers are built by :func:`raysim.cli.build_parser` (one per
``raysim/cli/cmd_*.py``). Each argument's help is expanded the way
``--help`` prints it (the parser's formatter adds ``(default: ...)`` where it
does), then checked: present, at most one ``(default:``, and not ending in
``(default: None)`` (an option without a default says what happens without it).
"""

from __future__ import annotations

import argparse
import re

import pytest

from raysim.cli import build_parser


def _subparsers(parser: argparse.ArgumentParser, prefix: str = "") -> dict:
    """``{"scenes describe": parser, ...}``: every subcommand's parser, nested ones too."""
    out = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out[prefix + name] = sub
                out.update(_subparsers(sub, prefix + name + " "))
    return out


SUBPARSERS = _subparsers(build_parser())


def help_problems(parser: argparse.ArgumentParser) -> list[str]:
    """What is wrong with the help of each argument of ``parser`` (empty: nothing)."""
    problems = []
    formatter = parser._get_formatter()
    for action in parser._actions:
        if isinstance(action, (argparse._HelpAction, argparse._VersionAction,
                               argparse._SubParsersAction)) \
                or action.help == argparse.SUPPRESS:    # a subcommand: checked on its own
            continue
        name = "/".join(action.option_strings) or action.dest
        if not (action.help or "").strip():
            problems.append(f"{name}: no help")
            continue
        text = " ".join(formatter._expand_help(action).split())
        if text.count("(default:") > 1:
            problems.append(f"{name}: '(default:' twice: {text!r}")
        if text.endswith("(default: None)"):
            problems.append(f"{name}: ends in '(default: None)': {text!r}")
    return problems


def test_there_are_subcommands_to_check():
    assert {"simulate", "render", "report", "compensate", "rcs", "sweep"} <= set(SUBPARSERS)


@pytest.mark.parametrize("command", sorted(SUBPARSERS))
def test_every_option_has_clean_help(command):
    assert help_problems(SUBPARSERS[command]) == []


@pytest.mark.parametrize("command", sorted(SUBPARSERS))
def test_help_prints(command, capsys):
    with pytest.raises(SystemExit) as exc:
        SUBPARSERS[command].parse_args(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: raysim"), out[:200]


def test_the_checks_catch_each_glitch():
    p = argparse.ArgumentParser(formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--a")
    p.add_argument("--b", default=3, help="b (default: 3)")
    p.add_argument("--c", help="c")
    p.add_argument("--d", default=1, help="d")
    assert help_problems(p) == [
        "--a: no help", "--b: '(default:' twice: 'b (default: 3) (default: 3)'",
        "--c: ends in '(default: None)': 'c (default: None)'"]


def epilog_problems(parser: argparse.ArgumentParser) -> list[str]:
    """Example lines of ``parser``'s epilog where a continuation backslash was lost (an
    option glued to the previous line's end after a run of spaces)."""
    return [line for line in (parser.epilog or "").splitlines()
            if re.search(r"\S {3,}--", line.split("#")[0])]


@pytest.mark.parametrize("command", sorted(SUBPARSERS))
def test_every_example_line_is_whole(command):
    assert epilog_problems(SUBPARSERS[command]) == []


def test_the_example_check_catches_a_lost_continuation():
    p = argparse.ArgumentParser(epilog="  raysim x a.bin --board B       --imu f.ulg\n"
                                       "  raysim x a.bin --out b.npz     # comment\n")
    assert epilog_problems(p) == ["  raysim x a.bin --board B       --imu f.ulg"]
