"""The paper's experiments as named scenarios, read from the TOML files of ``cases/``.

A paper case is plain data, one file ``raysim/scenario/cases/<name>.toml``:
``description``, a ``[scenario]`` table (the TOML keys of
:class:`raysim.scenario.Scenario`: target, motion sinusoids, radar, array,
frames) and a ``[paper]`` table of the values the paper reports, in the words
of :mod:`raysim.vocabulary`. ``cases/_paper.toml`` lists the cases in the
order of the paper's tables and holds :data:`BASE`, the scenario keys every
case shares: the paper's Table 2 radar (the ``[radar]`` defaults), the
20 x 20 half-wavelength virtual UPA, the lever arm :data:`DEFAULT_LEVER_ARM`
and an ideal IMU. Motion phases are zero (every sinusoid starts at its rest
position at ``t = 0``, moving in the positive direction); the paper states
neither phases nor lever arm.

``paper`` maps a chain of :data:`raysim.vocabulary.CHAINS` to the metrics of
:data:`raysim.vocabulary.METRICS` the paper reports for it: ``none`` before
compensation, ``paper`` after (pseudo-velocities are magnitudes in the paper).

:func:`raysim.scenario.scenario_from_case` turns a case into a
:class:`~raysim.scenario.Scenario`; ``raysim simulate --case``,
``raysim report --case`` and ``raysim reproduce`` all render that scenario.
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np

__all__ = ["CASES_DIR", "DEFAULT_LEVER_ARM", "BASE", "PAPER_CASES", "get_case",
           "paper_values"]

#: Folder of the case files (package data).
CASES_DIR = Path(__file__).resolve().parent / "cases"
#: The keys of one case file.
_CASE_KEYS = {"description", "scenario", "paper"}


def _read(path: Path) -> dict:
    """One TOML file of ``cases/`` as a dict; a clear ValueError naming the file otherwise."""
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ValueError(f"cannot read paper case file {str(path)!r}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"paper case file {str(path)!r} is not valid TOML: {exc}") from None


def load_cases(folder: Path = CASES_DIR) -> tuple[dict, dict[str, dict]]:
    """Read the shared keys and every case of a cases folder.

    Parameters
    ----------
    folder : Path
        Holds ``_paper.toml`` (``cases = [...]`` and ``[scenario]``) and one
        ``<name>.toml`` per listed case.

    Returns
    -------
    base : dict
        Scenario keys shared by every case.
    cases : dict
        Case name -> ``{"description", "scenario", "paper"}``, in the listed order.

    Raises
    ------
    ValueError
        A file missing, not TOML, with unknown keys, or a case file not listed.
    """
    folder = Path(folder)
    index = _read(folder / "_paper.toml")
    names = index.get("cases")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ValueError(f"{folder / '_paper.toml'}: cases must be a list of case names, "
                         f"got {names!r}")
    files = sorted(p.stem for p in folder.glob("*.toml") if not p.stem.startswith("_"))
    if sorted(names) != files:
        raise ValueError(f"{folder / '_paper.toml'}: cases {sorted(names)} do not match the "
                         f"case files {files}")
    cases = {}
    for name in names:
        data = _read(folder / f"{name}.toml")
        extra = sorted(set(data) - _CASE_KEYS)
        if extra or not isinstance(data.get("description"), str):
            raise ValueError(f"paper case file {name}.toml: expected keys description, "
                             f"[scenario], [paper], got {sorted(data)}")
        cases[name] = {"description": data["description"],
                       "scenario": data.get("scenario", {}), "paper": data.get("paper", {})}
    return index.get("scenario", {}), cases


#: Scenario keys shared by every paper case (merged under each case's ``scenario``).
#: Case name -> ``{"description", "scenario", "paper"}``: ``scenario`` holds the
#: TOML keys of the case (over :data:`BASE`), ``paper`` chain -> metric -> value.
BASE, PAPER_CASES = load_cases()

#: Radar phase centre in the body frame [m], shape ``[3]``: 10 cm below the IMU (FRD, +Z down).
DEFAULT_LEVER_ARM = np.array(BASE["lever_arm_m"], dtype=float)


def _merged(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for k, v in over.items():
        out[k] = _merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) \
            else copy.deepcopy(v)
    return out


def get_case(name: str) -> dict:
    """A paper case by name: ``{"name", "description", "scenario", "paper"}`` (a copy).

    ``scenario`` is the full override (:data:`BASE` merged with the case's
    keys), ready for :func:`raysim.scenario.validate_scenario`.

    Raises
    ------
    ValueError
        Unknown name; the message lists the valid names.
    """
    if not isinstance(name, str) or name not in PAPER_CASES:
        raise ValueError(f"unknown paper case {name!r}; expected one of {sorted(PAPER_CASES)}")
    case = PAPER_CASES[name]
    return {"name": name, "description": case["description"],
            "scenario": _merged(BASE, case["scenario"]), "paper": copy.deepcopy(case["paper"])}


def paper_values(name: str) -> dict[str, float]:
    """The paper's values of a case, flat: ``"<metric> (<chain>)" -> value``, for display."""
    return {f"{metric} ({chain})": value
            for chain, values in get_case(name)["paper"].items()
            for metric, value in values.items()}
