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


def check_output(path: str | os.PathLike | None, kind: str = "file", option: str = "--out"
                 ) -> Path:
    """Check, before any computation, that an output path can be written.

    Nothing is created (a probe file in the nearest existing folder is made and
    removed again, to catch read-only file systems).

    Parameters
    ----------
    path : str or path-like
        The output: a file (``kind="file"``) or a folder such as a Zarr store
        or a result directory (``kind="dir"``); missing parent folders are fine
        (they are created by the writer).
    kind : {"file", "dir"}
        What ``path`` must be if it already exists.
    option : str
        The option or key the path came from, named in the message.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        Naming ``option`` and ``path``: empty path, a file where a folder is
        expected or the reverse, a path under a file, or a folder that cannot be
        written.
    """
    if kind not in ("file", "dir"):
        raise ValueError(f"kind must be 'file' or 'dir', got {kind!r}")
    if path is None or not str(path).strip():
        raise ValueError(f"{option}: got {path!r}, expected a "
                         f"{'file' if kind == 'file' else 'folder'} path")
    p = Path(path)
    what = "a file" if kind == "file" else "a folder"

    def fail(reason: str) -> ValueError:
        return ValueError(f"{option}: cannot write {str(p)!r}: {reason} (expected {what})")

    if p.exists():
        if kind == "file" and p.is_dir():
            raise fail("it is an existing directory")
        if kind == "dir" and not p.is_dir():
            raise fail("it is an existing file")
    # nearest existing ancestor: must be a folder we can create entries in
    anc = p if (kind == "dir" and p.is_dir()) else p.parent
    while not anc.exists() and anc != anc.parent:
        anc = anc.parent
    if not anc.is_dir():
        raise fail(f"{str(anc)!r} is a file, not a folder")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise fail(f"the folder {str(anc)!r} is not writable")
    try:
        fd, probe = tempfile.mkstemp(prefix=".raysim-probe.", suffix=".tmp", dir=anc)
    except OSError:
        raise fail(f"the folder {str(anc)!r} is not writable") from None
    os.close(fd)
    Path(probe).unlink(missing_ok=True)
    return p
