"""Files that ship with the package: bundled scenes, example scenarios, conventions.

* ``scenes/``: the canonical ray-tracing scenes (Mitsuba XML + PLY + JSON) and
  ``scenes/generate.py``, which writes them (:mod:`raysim.echoes.rt.scenes`).
* ``examples/``: scenario files of every paper case and bundled scene
  (``case_*.toml``, ``scene_*.toml``).
* ``conventions.md``: frames, signs and units (the same text as the
  repository's ``docs/conventions.md``; a test keeps them identical).

The repository's ``scenes/`` and ``examples/`` are links to the folders here.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["DATA_DIR", "data_path", "example_path", "conventions_text"]

#: Folder of the package data.
DATA_DIR = Path(__file__).resolve().parent


def data_path(name: str = "") -> Path:
    """Path of a shipped file or folder, e.g. ``data_path("scenes")``.

    Raises
    ------
    ValueError
        If nothing of that name ships with the package.
    """
    p = DATA_DIR / name
    if not p.exists():
        shipped = sorted(q.name for q in DATA_DIR.iterdir() if not q.name.startswith("_"))
        raise ValueError(f"package data {name!r} does not exist; expected one of {shipped}")
    return p


def example_path(name: str) -> Path:
    """Path of a shipped example scenario, e.g. ``example_path("case_yaw.toml")``.

    Raises
    ------
    ValueError
        Naming the examples that exist.
    """
    p = DATA_DIR / "examples" / name
    if not p.is_file():
        names = sorted(q.name for q in (DATA_DIR / "examples").glob("*.toml"))
        raise ValueError(f"example {name!r} does not exist; expected one of {names}")
    return p


def conventions_text() -> str:
    """The project's conventions (frames, signs, units), Markdown."""
    return (DATA_DIR / "conventions.md").read_text(encoding="utf-8")
