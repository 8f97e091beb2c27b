"""Key paths, TOML text and validation messages of scenario files.

``radar.num_chirps``-style key paths into nested scenario dicts
(:func:`get_key`, :func:`set_key`, :func:`parse_assignment` for ``--set``),
TOML output (:func:`dumps_toml`) and pydantic errors turned into one
:class:`ValueError` whose lines name the key, the value and what was expected
(:func:`format_validation_error`).
"""

from __future__ import annotations

import difflib
import json
import math
import re
import tomllib
from collections.abc import Callable, Iterable
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

__all__ = ["ClutterSection", "MoverSection", "RotorSection", "get_key", "set_key", "dumps_toml",
           "format_validation_error", "parse_value", "parse_assignment", "did_you_mean"]


def did_you_mean(word: Any, choices: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``choices`` (difflib), else ``""``.

    Appended to messages about unknown names (cases, scenes, presets, chains,
    maps, scenario keys).
    """
    if not isinstance(word, str):
        return ""
    close = difflib.get_close_matches(word, [str(c) for c in choices], n=2, cutoff=0.6)
    if not close:
        return ""
    return "; did you mean " + " or ".join(repr(c) for c in close) + "?"


# ------------------------------------------------------------------ key paths
def _split(path: str) -> list[str]:
    if not isinstance(path, str) or not re.fullmatch(r"[A-Za-z0-9_]+(\.[A-Za-z0-9_]+)*", path):
        raise ValueError(f"key path must look like 'section.key' or 'section.list.0.key', "
                         f"got {path!r}")
    return path.split(".")


def get_key(data: dict, path: str) -> Any:
    """Value at a dotted key path in nested dicts / lists (list items by index)."""
    cur: Any = data
    for part in _split(path):
        if isinstance(cur, list):
            if not part.isdigit() or int(part) >= len(cur):
                raise ValueError(f"{path}: list index {part!r} out of range "
                                 f"(list has {len(cur)} items)")
            cur = cur[int(part)]
        elif isinstance(cur, dict) and part in cur:
            cur = cur[part]
        elif isinstance(cur, dict):
            raise ValueError(f"{path}: no key {part!r}{did_you_mean(part, cur)}")
        else:
            raise ValueError(f"{path}: no key {part!r} (the value above it is "
                             f"{_fmt_value(cur)}, not a table)")
    return cur


def set_key(data: dict, path: str, value: Any) -> None:
    """Set a dotted key path in nested dicts / lists in place, creating tables."""
    parts = _split(path)
    cur: Any = data
    for i, part in enumerate(parts[:-1]):
        nxt_is_index = parts[i + 1].isdigit()
        if isinstance(cur, list):
            if not part.isdigit() or int(part) >= len(cur):
                raise ValueError(f"{path}: list index {part!r} out of range "
                                 f"(list has {len(cur)} items)")
            cur = cur[int(part)]
            continue
        if not isinstance(cur, dict):
            _not_a_table(path, parts[:i], cur)
        if cur.get(part) is None:
            cur[part] = [] if nxt_is_index else {}
        cur = cur[part]
    last = parts[-1]
    if isinstance(cur, list):
        if not last.isdigit() or int(last) > len(cur):
            raise ValueError(f"{path}: list index {last!r} out of range "
                             f"(list has {len(cur)} items)")
        if int(last) == len(cur):
            cur.append(value)
        else:
            cur[int(last)] = value
    elif isinstance(cur, dict):
        cur[last] = value
    else:
        _not_a_table(path, parts[:-1], cur)


def _not_a_table(path: str, parent: list[str], value: Any) -> None:
    raise ValueError(f"{path}: {'.'.join(parent)} is a value ({_fmt_value(value)}), not a "
                     f"table: nothing can be set under it; expected a key such as "
                     f"{'.'.join(parent)}=VALUE")


# ------------------------------------------------------------------- errors
def _num(v: Any) -> str:
    return f"{v:g}" if isinstance(v, (int, float)) else str(v)


def _expected(err: dict) -> str:
    t, ctx = err.get("type", ""), err.get("ctx") or {}
    simple = {
        "greater_than": lambda: f"> {_num(ctx.get('gt'))}",
        "greater_than_equal": lambda: f">= {_num(ctx.get('ge'))}",
        "less_than": lambda: f"< {_num(ctx.get('lt'))}",
        "less_than_equal": lambda: f"<= {_num(ctx.get('le'))}",
        "missing": lambda: "a value (required key is missing)",
        "extra_forbidden": lambda: "no such key (unknown keys are not allowed)",
        "literal_error": lambda: f"one of {ctx.get('expected')}",
        "int_type": lambda: "an integer",
        "int_parsing": lambda: "an integer",
        "int_from_float": lambda: "an integer",
        "float_type": lambda: "a number",
        "float_parsing": lambda: "a number",
        "finite_number": lambda: "a finite number",
        "bool_type": lambda: "true or false",
        "bool_parsing": lambda: "true or false",
        "string_type": lambda: "a string",
        "list_type": lambda: "a list",
        "tuple_type": lambda: "a list of 3 numbers",
        "too_long": lambda: f"at most {ctx.get('max_length')} items",
        "too_short": lambda: f"at least {ctx.get('min_length')} items",
        "model_type": lambda: "a table",
        "dict_type": lambda: "a table",
    }
    if t in simple:
        return simple[t]()
    msg = str(err.get("msg", "valid value"))
    return msg.removeprefix("Value error, ")


def _fmt_value(v: Any) -> str:
    if isinstance(v, dict):
        return "a table"
    text = json.dumps(v) if isinstance(v, (list, str, bool)) or v is None else repr(v)
    return text if len(text) <= 80 else text[:77] + "..."


def _literal_choices(err: dict) -> list[str]:
    return re.findall(r"'([^']*)'", str((err.get("ctx") or {}).get("expected", "")))


def format_validation_error(exc: ValidationError, source: str = "scenario",
                            known_keys: Callable[[tuple], Iterable[str]] | None = None,
                            extra_lines: Iterable[str] = ()) -> ValueError:
    """Turn a pydantic error into a ValueError listing ``key.path: got V, expected E``.

    Every error of ``exc`` is one line (a check of a whole table that found
    several problems raises them joined by newlines: one line each, under the
    table's key path), then ``extra_lines`` (problems found outside pydantic,
    e.g. the checks across sections). ``known_keys(loc)`` (optional) gives the
    valid keys of the table holding ``loc``; an unknown key is then followed by
    "did you mean" the closest one, as is a string outside a fixed set of names.
    """
    lines = []
    for err in exc.errors():
        loc = ".".join(str(p) for p in err.get("loc", ())) or "(top level)"
        hint = ""
        if err.get("type") == "extra_forbidden" and known_keys is not None:
            hint = did_you_mean(str(err["loc"][-1]), known_keys(tuple(err["loc"][:-1])))
        elif err.get("type") == "literal_error":
            hint = did_you_mean(err.get("input"), _literal_choices(err))
        if err.get("type") == "value_error" and isinstance(err.get("input"), dict):
            lines += [f"{loc}: {part}" if err.get("loc") else part
                      for part in _expected(err).splitlines() if part.strip()]
        elif err.get("type") == "missing":
            lines.append(f"{loc}: missing, expected {_expected(err)}")
        else:
            lines.append(f"{loc}: got {_fmt_value(err.get('input'))}, expected {_expected(err)}"
                         f"{hint}")
    lines += list(extra_lines)
    n = len(lines)
    head = f"{source}: {n} invalid value{'s' if n > 1 else ''}:\n  "
    return ValueError(head + "\n  ".join(lines))


# --------------------------------------------------------------------- TOML
def _toml_scalar(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        if math.isnan(v):
            return "nan"
        text = repr(v)
        if "e" not in text and abs(v) >= 1e5:
            for digits in range(1, 18):  # shortest exact exponent form: 77e9 -> 7.7e+10
                short = f"{v:.{digits}e}"
                if float(short) == v:
                    return short
        return text
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_scalar(x) for x in v) + "]"
    raise ValueError(f"cannot write {type(v).__name__} {v!r} to TOML")


def dumps_toml(data: dict, _prefix: str = "") -> str:
    """Write nested dicts / lists of scalars as TOML (tables and arrays of tables)."""
    lines: list[str] = []
    tables: list[tuple[str, dict]] = []
    arrays: list[tuple[str, list]] = []
    for k, v in data.items():
        if isinstance(v, dict):
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            arrays.append((k, v))
        else:
            lines.append(f"{k} = {_toml_scalar(v)}")
    out = "\n".join(lines)
    for k, v in tables:
        name = f"{_prefix}{k}"
        body = dumps_toml(v, name + ".")
        only_subtables = v and all(isinstance(x, dict) or (isinstance(x, list) and x and all(
            isinstance(y, dict) for y in x)) for x in v.values())
        out += ("\n\n" + body) if only_subtables else (f"\n\n[{name}]\n" + body)
    for k, items in arrays:
        name = f"{_prefix}{k}"
        for item in items:
            out += f"\n\n[[{name}]]\n" + dumps_toml(item, name + ".")
    return out.strip("\n") + ("\n" if not _prefix else "")


# ------------------------------------------------------------ command line
def parse_value(text: str) -> Any:
    """A command-line value read as a TOML value (``3``, ``1e-3``, ``true``, ``[1, 2]``),
    else as a plain string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_assignment(text: str) -> tuple[str, Any]:
    """Split ``key.path=value`` into the key path and the parsed value."""
    if "=" not in text:
        raise ValueError(f"expected KEY=VALUE such as radar.num_chirps=64, got {text!r}")
    key, value = text.split("=", 1)
    key = key.strip()
    _split(key)
    return key, parse_value(value.strip())


# ------------------------------------------------------------------ sections
class ClutterSection(BaseModel):
    """``[scene.clutter]``: ground clutter and multipath of ray-traced scenes (docs/clutter.md).

    ``mode``: the persistent clutter field (``"field"``), Sionna's own diffuse
    paths (``"sionna"``) or none; ``per_cell`` field scatterers per range x
    angle cell; ``reuse_m`` [m] the field is re-used while the radar stays this
    close to the pose it was built for; ``max_scatterers`` cost bound;
    ``ghosts`` target-ground-radar multipath (image method); ``wind_mps`` [m/s]
    wind moving the vegetation (internal clutter motion, Billingsley's model:
    0 = still, else 0.224 m/s (0.5 mph) to 27 m/s, the measured winds);
    ``vegetation`` the clutter materials that move in it (default the
    vegetation materials, ``["grass"]``); ``walls`` whether the field also
    covers walls and other faces steeper than 60 deg (default true; ``false``
    leaves the ground only).
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    mode: Literal["field", "sionna", "none"] = "field"
    per_cell: float = Field(10.0, gt=0, le=1000)
    reuse_m: float = Field(0.5, ge=0, le=100)
    max_scatterers: int = Field(200_000, ge=1, le=10_000_000)
    ghosts: bool = True
    wind_mps: float = Field(0.0, ge=0, le=27)
    vegetation: tuple[str, ...] | None = None
    #: None keeps the default (walls on) out of the scenario's canonical JSON.
    walls: bool | None = None


class MoverSection(BaseModel):
    """``[[scene.movers]]``: a car mesh driving through a ray-traced scene (docs/clutter.md).

    Traced by PO + SBR at every trace (:class:`raysim.echoes.moving.cars.CarMover`).
    ``start_m`` body origin on the ground at time 0 in W (NED) [m];
    ``heading_deg`` from north towards east; ``speed_mps`` ground speed;
    ``yaw_rate_dps`` turn rate (0 drives straight); ``length_m``, ``width_m``,
    ``height_m`` car size. Needs ``[scene.clutter] mode = "field"``.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    name: str = "car"
    start_m: tuple[float, float, float]
    heading_deg: float = Field(0.0, ge=-360, le=360)
    speed_mps: float = Field(10.0, gt=0, le=60)
    yaw_rate_dps: float = Field(0.0, ge=-90, le=90)
    length_m: float = Field(4.5, ge=3.5, le=5.5)
    width_m: float = Field(1.8, ge=1.5, le=2.1)
    height_m: float = Field(1.45, ge=1.2, le=1.9)


class RotorSection(BaseModel):
    """``[[scene.rotors]]``: a rotor or fan giving micro-Doppler (docs/clutter.md).

    :class:`raysim.echoes.moving.rotors.Rotor`: ``hub_m`` hub at time 0 in W
    (NED) [m], moving at ``speed_mps`` along ``heading_deg`` (default still);
    ``axis`` spin axis (W, or body FRD when moving); ``rate_rps`` [rev/s] or
    ``rate_radps`` [rad/s], one of them; ``blades``; ``blade_length_m`` hub to
    tip; ``root_m`` where the blade's scatterers begin; ``start_angle_deg``;
    ``scatterers_per_blade`` (default lambda / 4 apart); ``rcs_dbsm`` of a blade
    at its flash (``rcs_per = "blade"``) or of each scatterer. Needs
    ``[scene.clutter] mode = "field"``.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    name: str = "rotor"
    hub_m: tuple[float, float, float]
    heading_deg: float = Field(0.0, ge=-360, le=360)
    speed_mps: float = Field(0.0, ge=0, le=60)
    axis: tuple[float, float, float] = (0.0, 0.0, -1.0)
    rate_rps: float | None = Field(None, ge=-1000, le=1000)
    rate_radps: float | None = Field(None, ge=-6300, le=6300)
    blades: int = Field(2, ge=1, le=16)
    blade_length_m: float = Field(gt=0, le=10)
    root_m: float = Field(0.0, ge=0)
    start_angle_deg: float = Field(0.0, ge=-360, le=360)
    scatterers_per_blade: int | None = Field(None, ge=1, le=100_000)
    rcs_dbsm: float = Field(-20.0, ge=-100, le=40)
    rcs_per: Literal["blade", "scatterer"] = "blade"

    @model_validator(mode="after")
    def _check(self) -> RotorSection:
        problems = []               # every one, one line each
        if (self.rate_rps is None) == (self.rate_radps is None):
            problems.append(f"give one of rate_rps [rev/s] or rate_radps [rad/s], got "
                            f"rate_rps={self.rate_rps!r}, rate_radps={self.rate_radps!r}")
        if not any(self.axis):
            problems.append(f"axis must not be all zero, got {list(self.axis)}")
        if self.root_m >= self.blade_length_m:
            problems.append(f"root_m must be below blade_length_m = {self.blade_length_m} m, "
                            f"got {self.root_m}")
        if problems:
            raise ValueError("\n".join(problems))
        return self

    @property
    def rate(self) -> float:
        """Spin rate [rev/s]."""
        return self.rate_rps if self.rate_rps is not None else self.rate_radps / (2 * math.pi)
