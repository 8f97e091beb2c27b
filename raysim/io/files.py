"""Atomic file output: a reader never sees a half-written file.

Every file raysim writes whole (tables, figures, JSON, NetCDF, captures) goes
through :func:`atomic_write`: the content is written to a temporary file in
the destination folder, flushed to disk, then renamed over the destination
with :func:`os.replace` (atomic on POSIX). If writing fails or is interrupted
the temporary file is removed and an existing destination is left untouched.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path


def _default_mode(path: str | Path) -> None:
    # mkstemp creates 0600; give the file the mode a plain open() would
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(path, 0o666 & ~umask)


def atomic_write(path: str | os.PathLike, write: Callable[[Path], object]) -> Path:
    """Create a file atomically: ``write(tmp)`` fills a temporary file, then rename.

    Parameters
    ----------
    path : str or path-like
        Final file; its folder is created if needed.
    write : callable
        ``write(tmp_path)`` writes the whole content to ``tmp_path`` (an empty
        file that already exists, named ``.<name>.<random>.tmp`` in the same folder).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        _default_mode(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    return atomic_write(path, lambda tmp: tmp.write_bytes(data))


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: str | os.PathLike, data, **kwargs) -> Path:
    """Write ``data`` as JSON (``json.dumps(data, **kwargs)``) to ``path`` atomically."""
    return atomic_write_text(path, json.dumps(data, **kwargs) + "\n")


def atomic_savefig(fig, path: str | os.PathLike, **kwargs) -> Path:
    """Save a Matplotlib figure atomically (format from the suffix of ``path``)."""
    fmt = kwargs.pop("format", Path(path).suffix.lstrip(".") or "png")
    return atomic_write(path, lambda tmp: fig.savefig(tmp, format=fmt, **kwargs))
