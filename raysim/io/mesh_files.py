"""Users' mesh files: trimesh's readers with errors naming the file; the unit a file declares.

Some formats state their length unit (3MF ``unit="millimeter"``, COLLADA
``<unit meter="0.01"/>``, glTF metres by its specification); STL, OBJ, PLY and
OFF do not. A declared unit is used as the file's scale, so a 3MF part drawn in
millimetres is not read as metres; an undeclared one is left to the caller's
check (a bounding box over 500 units is taken for millimetres).
"""

from __future__ import annotations

import contextlib
import logging
import math
from pathlib import Path

#: Suffixes of the mesh formats read (trimesh's loaders; COLLADA through pycollada).
MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".gltf", ".glb", ".3mf", ".dae")


def read_mesh_file(path, **options):
    """``trimesh.load`` of a user's file, every failure a ``ValueError`` naming the file.

    Parameters
    ----------
    path : path-like
        The file; its suffix must be one of :data:`MESH_SUFFIXES`.
    **options
        Passed to ``trimesh.load`` (``process``, ``split_object``, ...).

    Returns
    -------
    trimesh.Trimesh or trimesh.Scene or other trimesh geometry
        What trimesh read, in the file's own units.
    """
    import trimesh

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"mesh file {str(path)!r} does not exist")
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise ValueError(f"mesh file {str(path)!r}: expected one of "
                         f"{', '.join(MESH_SUFFIXES)}, got suffix {path.suffix!r}")
    try:
        with _appearance_logs_dropped():
            return trimesh.load(str(path), **options)
    except ImportError as exc:  # a soft dependency of trimesh's reader for this format
        raise ValueError(f"mesh file {str(path)!r}: its reader needs a package that is not "
                         f"installed ({exc}); or export the mesh as PLY, OBJ, STL or GLB"
                         ) from None
    except Exception as exc:  # trimesh raises many types for a malformed file
        raise ValueError(f"mesh file {str(path)!r} is not a readable mesh: "
                         f"{type(exc).__name__}: {exc}") from None


#: Words of trimesh's log records about a file's look (textures, images, colours), which
#: a radar does not use: a missing texture is logged with a traceback that reads as a crash.
APPEARANCE_WORDS = ("image", "texture", "shininess", "color", "colour")


class _Appearance(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage().lower()
        return not any(w in text for w in APPEARANCE_WORDS)


@contextlib.contextmanager
def _appearance_logs_dropped():
    """While trimesh reads, its log records about appearance are dropped; others pass."""
    # a logger's filter sees only the records logged to it: every trimesh module's logger
    logs = [logging.getLogger(n) for n in list(logging.root.manager.loggerDict)
            if n == "trimesh" or n.startswith("trimesh.")]
    drop = _Appearance()
    for log in logs:
        log.addFilter(drop)
    try:
        yield
    finally:
        for log in logs:
            log.removeFilter(drop)


def declared_scale(loaded, path) -> tuple[float | None, str | None]:
    """Metres per file unit as the file declares it, and the unit's name.

    Parameters
    ----------
    loaded : trimesh geometry or scene
        What :func:`read_mesh_file` returned.
    path : path-like
        The file (for the error message).

    Returns
    -------
    (float or None, str or None)
        ``(None, None)`` where the file declares no unit.
    """
    import trimesh

    units = getattr(loaded, "units", None)
    if not units:
        return None, None
    try:
        scale = float(trimesh.units.unit_conversion(str(units), "meters"))
    except Exception:  # noqa: BLE001 - trimesh's unit table raises on a name it lacks
        scale = math.nan
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"mesh file {str(path)!r} declares the unit {units!r}, which is not "
                         f"a length unit known here; give the scale (metres per file unit)")
    return scale, str(units)
