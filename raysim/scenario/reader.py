"""Reading scenario files: TOML text or a file to a validated :class:`Scenario`.

:func:`loads_scenario` parses TOML text (relative file paths taken from a
folder), :func:`load_scenario` reads a UTF-8 file, :func:`scenario_from_case`
builds the scenario of a paper case (:mod:`raysim.scenario.paper_cases`). Every
problem is one :class:`ValueError` naming the file, the key path and the value.
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path
from typing import Any

from raysim.scenario.keys import did_you_mean
from raysim.scenario.model import Scenario, validate_scenario
from raysim.scenario.paper_cases import PAPER_CASES, get_case

__all__ = ["loads_scenario", "load_scenario", "scenario_from_case"]


def loads_scenario(text: str, source: str = "scenario", base_dir: Path | None = None
                   ) -> Scenario:
    """Parse and validate TOML text; relative ``scene.path`` is taken from ``base_dir``."""
    text = text.removeprefix("\ufeff")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{source}: not valid TOML: {exc}") from None
    for sec, key in (("scene", "path"), ("radar", "element_pattern")):   # files: relative paths
        p = data[sec].get(key) if isinstance(data.get(sec), dict) else None
        if base_dir is not None and isinstance(p, str) and not Path(p).is_absolute() \
                and (key == "path" or p.lower().endswith(".csv")):
            data[sec][key] = str((Path(base_dir) / p).resolve())
    scene = data.get("scene") if isinstance(data.get("scene"), dict) else {}
    for m in scene.get("meshes") or [] if base_dir is not None else []:
        if isinstance(m, dict) and isinstance(m.get("file"), str):
            m["file"] = str((Path(base_dir) / m["file"]).resolve())
    return validate_scenario(data, source)


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file.

    Raises
    ------
    ValueError
        File missing or unreadable, invalid TOML, or invalid values (each
        offending key path named with its value and what was expected).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")      # a UTF-8 byte-order mark is fine
    except OSError as exc:
        raise ValueError(f"cannot read scenario file {str(path)!r}: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"scenario file {str(path)!r} is not UTF-8 text: byte "
                         f"{exc.object[exc.start:exc.start + 1]!r} at offset {exc.start}; "
                         f"save it as UTF-8") from None
    return loads_scenario(text, source=str(path), base_dir=path.parent)


def scenario_from_case(name: str, **overrides: Any) -> Scenario:
    """The scenario of a paper case (radar, 20 x 20 UPA, target, motion, frames, lever arm).

    Built from the case's scenario keys (``raysim.scenario.paper_cases.get_case(name)``)
    with ``motion.case = name`` standing for the case's motion sinusoids, so
    the TOML form reads like ``examples/case_<name>.toml``.

    Parameters
    ----------
    name : str
        Key of :data:`raysim.scenario.paper_cases.PAPER_CASES`.
    **overrides
        Not accepted; use :meth:`Scenario.with_values` for changes.
    """
    if overrides:
        raise ValueError(f"scenario_from_case takes no overrides, got {sorted(overrides)}; "
                         f"use Scenario.with_values")
    if not isinstance(name, str) or name not in PAPER_CASES:
        raise ValueError(f"unknown paper case {name!r}; expected one of {sorted(PAPER_CASES)}"
                         f"{did_you_mean(name, PAPER_CASES)}")
    case = get_case(name)
    data = case["scenario"]
    data.update(name=name, description=case["description"], motion={"case": name})
    return validate_scenario(copy.deepcopy(data), source=f"paper case {name!r}")


