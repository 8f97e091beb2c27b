"""Shared pieces of the ``raysim`` commands: the parser class, name checks, output checks.

:class:`Parser` accepts option values that start with a minus sign and a
digit (``--az-deg -30:30:1``, ``--direction-deg -20,0``, ``--time-offset -1e-3``);
:func:`known_name` and :func:`chains_option` refuse unknown names with the
accepted ones and a "did you mean" suggestion; :func:`check_output` (from
:mod:`raysim.io.files`) checks an output path before any computation.
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Iterable

import numpy as np

from raysim.io.files import check_output
from raysim.scenario.keys import did_you_mean

__all__ = ["Parser", "NEGATIVE_VALUE", "known_name", "chains_option", "check_output",
           "did_you_mean", "span_option", "span_grid", "MAX_SPAN_VALUES",
           "add_decimation_options"]

#: Option values that are numbers, ranges or lists starting with a minus sign:
#: ``-30``, ``-1e-3``, ``-.5``, ``-30:30:1``, ``-30,0,30``, ``-0.1,0,0.2``.
NEGATIVE_VALUE = re.compile(r"^-\.?\d[\d.eE+\-:,]*$")


class Parser(argparse.ArgumentParser):
    """ArgumentParser that reads ``-30:30:1`` or ``-20,0`` as a value, not as an option.

    argparse treats an argument starting with ``-`` as an option unless it
    looks like a plain negative number; ranges and comma lists of the raysim
    options (:data:`NEGATIVE_VALUE`) are values too. No raysim option name
    starts with a digit, so nothing is lost.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_VALUE


class DefaultsHelpFormatter(argparse.ArgumentDefaultsHelpFormatter,
                            argparse.RawDescriptionHelpFormatter):
    """Option defaults in the help, once; the description and epilog as written.

    ``(default: VALUE)`` is appended to an option's help only where the help
    does not state its default itself (the word "default" or "left out:") and
    the option has a value to show: not ``None`` (the help says what happens
    without the option), not a flag's ``False``, not a positional argument.
    """

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if ("%(default)" in text or "default" in text.lower() or "left out" in text
                or action.default in (None, False, argparse.SUPPRESS)
                or not action.option_strings):
            return text
        return text + " (default: %(default)s)"


def known_name(value: str, choices: Iterable[str], option: str, what: str) -> str:
    """``value`` if it is one of ``choices``; else ValueError naming ``option``, the
    accepted names and the closest one."""
    choices = list(choices)
    if value not in choices:
        raise ValueError(f"{option}: unknown {what} {value!r}; expected one of "
                         f"{sorted(choices)}{did_you_mean(value, choices)}")
    return value


def chains_help(default: str) -> str:
    """Help text of a ``--chains`` option: every chain key of the vocabulary and the default."""
    from raysim.vocabulary import CHAIN_KEYS, CHAIN_NAMES

    names = list(dict.fromkeys([*CHAIN_KEYS, *CHAIN_NAMES]))
    return (f"comma-separated chains from {', '.join(names)} (dpca only when named; "
            f"default: {default})")


def chains_option(text: str, option: str = "--chains") -> list[str]:
    """Comma list of chain names -> chain keys (:func:`raysim.vocabulary.parse_chains`).

    Raises
    ------
    ValueError
        Naming ``option``, the value and the closest chain name.
    """
    from raysim.vocabulary import CHAIN_KEYS, CHAIN_NAMES, parse_chains

    names = list(dict.fromkeys([*CHAIN_KEYS, *CHAIN_NAMES]))
    try:
        return [s.key for s in parse_chains(text)]
    except ValueError as exc:
        bad = next((c.strip() for c in str(text).split(",")
                    if c.strip() and c.strip() not in names), None)
        hint = did_you_mean(bad, names) if bad else ""
        if bad == "uncompensated":
            hint = " (the uncompensated chain is called 'none')"
        raise ValueError(f"{option}: got {text!r}: {exc}{hint}") from None


def span_option(text: str, name: str, with_step: bool) -> tuple:
    """``LO:HI`` or ``LO:HI:STEP`` -> floats; errors name the option and the value."""
    parts = text.split(":")
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        raise ValueError(f"{name} must look like {'LO:HI:STEP' if with_step else 'LO:HI'}, "
                         f"got {text!r}") from None
    if not all(math.isfinite(v) for v in vals):
        raise ValueError(f"{name}: got {text!r}, expected finite numbers")
    if len(vals) != (3 if with_step else 2) or not vals[0] <= vals[1] or \
            (with_step and vals[2] <= 0):
        raise ValueError(f"{name} must look like {'LO:HI:STEP' if with_step else 'LO:HI'} "
                         f"with LO <= HI{' and STEP > 0' if with_step else ''}, got {text!r}")
    return vals


#: Most values a ``LO:HI:STEP`` option may expand to (checked before allocating).
MAX_SPAN_VALUES = 100_000


def span_grid(text: str, name: str, bound: float | None = None) -> np.ndarray:
    """``LO:HI:STEP`` -> ``LO, LO + STEP, ...`` up to ``HI`` included, shape ``[value]``;
    with ``bound``, LO and HI within ``+-bound`` (an angle option's unit and range)."""
    lo, hi, step = span_option(text, name, True)
    if bound is not None and not -bound <= lo <= hi <= bound:
        raise ValueError(f"{name}: got {text!r}, expected angles in degrees within "
                         f"+-{bound:g}")
    steps = (hi - lo) / step
    if not steps < MAX_SPAN_VALUES:         # also a step so small the count overflows
        raise ValueError(f"{name}: got {text!r}, {steps + 1:.3g} values (at most "
                         f"{MAX_SPAN_VALUES})")
    count = int(math.floor(steps + 1e-9)) + 1
    if count > MAX_SPAN_VALUES:
        raise ValueError(f"{name}: got {text!r}, {count} values (at most {MAX_SPAN_VALUES})")
    return lo + step * np.arange(count)


def add_decimation_options(parser: argparse.ArgumentParser, scenario: bool = True) -> None:
    """``--decimate {auto,off}`` and ``--decimate-tolerance TOL``: the scenario's
    ``synthesis.decimate`` and ``synthesis.decimate_tolerance`` (left out: the scenario's;
    ``scenario=False``: a command without a scenario, left out: ``auto`` and 0.1 x eps)."""
    from raysim.scenario.synthesis import DECIMATE_MODES

    mode = ("synthesis.decimate of the scenario, 'auto' unless set" if scenario else "'auto'")
    tol = ("synthesis.decimate_tolerance, else 0.1 x the synthesis eps" if scenario
           else "0.1 x the synthesis eps")
    parser.add_argument("--decimate", choices=DECIMATE_MODES, default=None,
                        help="slow-time decimation of the synthesis: 'auto' interpolates "
                        "chirps within the tolerance where the motion allows it (checked on "
                        "a few channels; refused with the reason otherwise), 'off' renders "
                        f"every chirp exactly (left out: {mode})")
    parser.add_argument("--decimate-tolerance", type=float, default=None, metavar="TOL",
                        help="relative error (l2 and worst chirp row) allowed to that "
                        f"interpolation against the undecimated render, in (0, 0.1] (left "
                        f"out: {tol})")
