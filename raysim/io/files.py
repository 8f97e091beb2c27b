"""Atomic file output: a reader never sees a half-written file.

Every file raysim writes whole (tables, figures, JSON, NetCDF, captures) goes
through :func:`atomic_write`: the content is written to a temporary file in
the destination folder, flushed to disk, then renamed over the destination
with :func:`os.replace` (atomic on POSIX). If writing fails or is interrupted
the temporary file is removed and an existing destination is left untouched.

What raysim wrote is listed in a small manifest, ``.raysim-outputs`` (JSON), in
the folder of each file (name, size and modification time). A writer only
replaces a file that is absent or listed there unchanged
(:func:`check_replaceable_file`): a user's file given by mistake as an output
is refused with a :class:`ValueError` naming it, never overwritten.
:func:`check_output` also refuses an output that is one of the command's
inputs, before any computation.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path

#: Name of the manifest of raysim's outputs kept in each folder it writes files to.
MANIFEST = ".raysim-outputs"


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
    check_replaceable_file(path)
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
    record_output(path)
    return path


# ------------------------------------------------------------ what raysim wrote
@contextlib.contextmanager
def _folder_lock(folder: Path):
    """Exclusive lock on a folder (its directory descriptor) while its manifest changes."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        with contextlib.suppress(OSError):     # file systems without directory locks
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _read_manifest(folder: Path) -> dict:
    try:
        data = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
        files = data.get("files", {})
        return files if isinstance(files, dict) else {}
    except (OSError, ValueError, AttributeError):
        return {}


def _stamp(path: Path) -> list[int]:
    st = path.stat()
    return [int(st.st_size), int(st.st_mtime_ns)]


def record_output(path: str | os.PathLike) -> None:
    """List ``path`` (just written by raysim) in its folder's manifest :data:`MANIFEST`."""
    path = Path(path)
    folder = path.parent
    with _folder_lock(folder):
        files = {k: v for k, v in _read_manifest(folder).items() if (folder / k).exists()}
        files[path.name] = _stamp(path)
        text = json.dumps({"written_by": "raysim", "files": files}, indent=0, sort_keys=True)
        fd, tmp = tempfile.mkstemp(prefix=f"{MANIFEST}.", suffix=".tmp", dir=folder)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                fh.write(text + "\n")
            _default_mode(tmp)
            os.replace(tmp, folder / MANIFEST)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise


def written_by_raysim(path: str | os.PathLike) -> bool:
    """True when ``path`` is a file listed, unchanged, in its folder's manifest."""
    path = Path(path)
    if path.is_symlink() or not path.is_file():
        return False
    entry = _read_manifest(path.parent).get(path.name)
    return isinstance(entry, list) and entry == _stamp(path)


@contextlib.contextmanager
def written_together(folder: str | os.PathLike, names: Iterable[str]):
    """Create ``folder`` and write files that only make sense together inside the block.

    If the block fails or is interrupted after one of ``names`` was written, every one
    of them raysim wrote is removed (the earlier set's too: it no longer matches), and
    the folder when the block created it and nothing else is left in it; a failure
    before anything was written leaves the folder as it was.
    """
    folder = Path(folder)
    created = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / n for n in names]
    before = {p: _stamp(p) if p.is_file() else None for p in paths}
    try:
        yield folder
    except BaseException:
        if any((_stamp(p) if p.is_file() else None) != before[p] for p in paths):
            for p in paths:
                if written_by_raysim(p):
                    p.unlink(missing_ok=True)
        if created and {q.name for q in folder.iterdir()} <= {MANIFEST}:
            (folder / MANIFEST).unlink(missing_ok=True)
            folder.rmdir()
        raise


def check_replaceable_file(path: str | os.PathLike, option: str = "output") -> None:
    """Raise ValueError unless ``path`` is absent or a file raysim wrote (unchanged since).

    Parameters
    ----------
    path : path
        A file a writer is about to create or replace.
    option : str
        The option or key the path came from, named in the message.
    """
    p = Path(path)
    if not p.exists() and not p.is_symlink():
        return
    if p.is_symlink():
        raise ValueError(f"{option}: {str(p)!r} is a symbolic link; refusing to replace it "
                         f"(expected a new path or a file raysim wrote)")
    if p.is_dir():
        raise ValueError(f"{option}: cannot write {str(p)!r}: it is an existing directory "
                         f"(expected a file)")
    if not written_by_raysim(p):
        raise ValueError(f"{option}: {str(p)!r} is an existing file that raysim did not write "
                         f"(or that changed since; it is not listed in {MANIFEST}); refusing "
                         f"to replace it. Expected a new path or an output of raysim: choose "
                         f"another output or move the file away")


def _same_path(a: Path, b: Path) -> bool:
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def check_not_input(path: str | os.PathLike, inputs: Iterable, option: str = "--out") -> None:
    """Raise ValueError when the output ``path`` is an input or lies inside an input folder.

    Parameters
    ----------
    path : path
        The output file or folder.
    inputs : iterable of path or (label, path)
        The command's inputs (files or folders); ``None`` entries are skipped.
    option : str
        The option the output came from, named in the message.
    """
    p = Path(path)
    for item in inputs:
        label, src = item if isinstance(item, tuple) else ("input", item)
        if not isinstance(src, (str, os.PathLike)):
            continue                                   # None, or data given in memory
        q = Path(src)
        inside = False
        with contextlib.suppress(OSError, ValueError):
            pr, qr = p.resolve(), q.resolve()
            inside = qr in pr.parents
        if _same_path(p, q) or inside:
            raise ValueError(f"{option}: {str(p)!r} is one of the command's inputs ({label} "
                             f"{str(q)!r}); refusing to write over it. Expected an output path "
                             f"apart from every input")


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


def check_output(path: str | os.PathLike | None, kind: str = "file", option: str = "--out",
                 *, inputs: Iterable = (), names: Iterable[str] = ()) -> Path:
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
    inputs : iterable of path or (label, path)
        The command's inputs: the output may not be one of them.
    names : iterable of str
        With ``kind="dir"``: the files the command writes in the folder; each
        must be absent or a file raysim wrote.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        Naming ``option`` and ``path``: empty path, a file where a folder is
        expected or the reverse, a path under a file, a folder that cannot be
        written, one of the inputs, or an existing file raysim did not write.
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
    check_not_input(p, inputs, option)
    if kind == "file":
        check_replaceable_file(p, option)
    else:
        for name in names:
            check_replaceable_file(p / name, option)
    return p
