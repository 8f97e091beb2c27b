"""Who may write a frame store, and what a writer may delete.

* A store belongs to raysim when its Zarr group carries the attribute
  ``raysim_format`` (:func:`is_raysim_store`). Only such a store (or an empty
  folder) is ever replaced or deleted (:func:`check_replaceable`): a user's
  folder given by mistake as ``--out`` is refused, never emptied, and so is a
  raysim store that holds anything Zarr did not write (:func:`foreign_files`:
  a user's notes, or the command's own inputs kept inside it).
* One writer at a time: :func:`writer_lock` takes an exclusive, non-blocking
  lock on the file ``.<store name>.lock`` beside the store for the whole
  render; a second writer gets a :class:`ValueError` naming the store and the
  process that holds it. The lock file is removed when the writer ends.
* Readers never write and take no lock (see
  :func:`raysim.io.storage.open_store`).
* Debris of a killed writer: the hidden ``.<store name>.<hex>.tmp`` folders
  of an unfinished :func:`~raysim.io.storage.write_store`, the hidden
  ``.<file name>.<random>.tmp`` files of an unfinished
  :func:`~raysim.io.files.atomic_write` and Zarr's ``*.partial`` files inside
  the store are removed by the next writer of the same output, under its lock
  (:func:`remove_debris`), and nothing else. The same lock and debris rules
  hold for every output that is written for a long time: ``render``,
  ``compensate`` and ``sweep``.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path

__all__ = ["STORE_MARKER", "is_raysim_store", "check_replaceable", "foreign_files", "remove_store",
           "lock_path", "writer_lock", "remove_debris", "tmp_siblings", "remove_tmp_files"]

#: Group attribute that marks a store written by raysim.
STORE_MARKER = "raysim_format"


def _group_attrs(path: Path) -> dict | None:
    import zarr

    if not ((path / "zarr.json").is_file() or (path / ".zgroup").is_file()):
        return None
    try:
        return dict(zarr.open_group(str(path), mode="r").attrs)
    except Exception:
        return None


def is_raysim_store(path: str | os.PathLike) -> bool:
    """True when ``path`` is a Zarr group written by raysim (attribute ``raysim_format``)."""
    attrs = _group_attrs(Path(path))
    return attrs is not None and STORE_MARKER in attrs


def check_replaceable(path: str | os.PathLike, what: str = "store") -> None:
    """Raise ValueError unless ``path`` is absent, an empty folder or a raysim store.

    Parameters
    ----------
    path : path
        What a writer is about to replace.
    what : str
        Name of the output in the message (``store``, ``--out`` ...).
    """
    p = Path(path)
    if not p.exists() and not p.is_symlink():
        return
    if p.is_symlink():
        raise ValueError(f"{what} {str(p)!r} is a symbolic link; refusing to replace it "
                         f"(expected a raysim Zarr store or a new path)")
    if p.is_dir() and not any(p.iterdir()):
        return
    if p.is_dir() and is_raysim_store(p):
        foreign = foreign_files(p)
        if foreign:
            more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
            raise ValueError(f"{what} {str(p)!r} is a raysim store that also holds "
                             f"{str(foreign[0].relative_to(p))!r}{more}, which raysim did not "
                             f"write; refusing to replace or delete it. Move those files out "
                             f"or choose another output")
        return
    kind = "folder" if p.is_dir() else "file"
    raise ValueError(f"{what} {str(p)!r} is a {kind} that raysim did not write (no Zarr group "
                     f"with attribute {STORE_MARKER!r}); refusing to replace or delete it. "
                     f"Expected a raysim store or a new path: choose another output")


#: Metadata files of a Zarr v2 or v3 hierarchy.
ZARR_METADATA = frozenset({"zarr.json", ".zgroup", ".zattrs", ".zarray", ".zmetadata"})
#: One component of a chunk key below its array: v3 ``c/0/1``, v2 ``0.1`` or ``0/1``.
_CHUNK_PART = re.compile(r"^(c|\d+(\.\d+)*)$")


def _is_array(folder: Path) -> bool:
    if (folder / ".zarray").is_file():
        return True
    meta = folder / "zarr.json"
    try:
        return meta.is_file() and json.loads(meta.read_text()).get("node_type") == "array"
    except (OSError, ValueError, AttributeError):
        return False


def foreign_files(store: str | os.PathLike) -> list[Path]:
    """Files below a store that Zarr did not write: anything but metadata files,
    chunk keys below an array and a killed writer's ``*.partial`` chunks (sorted).

    A user's notes, or the very inputs of the command, kept inside an output store
    would otherwise be deleted with it when it is replaced.
    """
    root = Path(store)
    foreign = []
    arrays: dict = {}          # folder -> whether it is an array, each read once

    def is_array(folder: Path) -> bool:
        if folder not in arrays:
            arrays[folder] = _is_array(folder)
        return arrays[folder]

    for dirpath, dirnames, filenames in os.walk(root):
        here = Path(dirpath)
        foreign += [here / d for d in dirnames if (here / d).is_symlink()]
        for name in filenames:
            f = here / name
            if f.is_symlink():
                foreign.append(f)
                continue
            if name in ZARR_METADATA or name.endswith(".partial"):
                continue
            rel = f.relative_to(root).parts
            # the nearest folder above the file that is an array: the rest is its chunk key
            ok = any(is_array(root.joinpath(*rel[:k]))
                     and all(_CHUNK_PART.match(x) for x in rel[k:])
                     for k in range(len(rel) - 1, 0, -1))
            if not ok:
                foreign.append(f)
    return sorted(foreign)


def remove_store(path: str | os.PathLike) -> None:
    """Delete a raysim store (or an empty folder); anything else raises ValueError."""
    p = Path(path)
    check_replaceable(p)
    if p.is_dir():
        shutil.rmtree(p)


def lock_path(store: str | os.PathLike) -> Path:
    """The writer's lock file of a store: ``.<name>.lock`` in the same folder."""
    p = Path(store)
    return p.parent / f".{p.name}.lock"


@contextlib.contextmanager
def writer_lock(store: str | os.PathLike) -> Iterator[Path]:
    """Hold the exclusive writer lock of a store for the duration of the block.

    Raises
    ------
    ValueError
        Another process writes the store; the message names the store and
        that process.
    """
    p = Path(store)
    p.parent.mkdir(parents=True, exist_ok=True)
    lock = lock_path(p)
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "unknown"
            raise ValueError(f"store {str(p)!r} is being written by another process (pid "
                             f"{holder}); expected one writer at a time: wait for it to "
                             f"finish or choose another output") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        try:
            yield lock
        finally:
            # unlink while still holding the lock: a writer that opened the old file
            # failed its non-blocking lock already, the next one creates a new file
            with contextlib.suppress(FileNotFoundError):
                lock.unlink()
    finally:
        os.close(fd)


def tmp_siblings(store: str | os.PathLike) -> list[Path]:
    """The hidden temporaries of a writer of this output, beside it.

    Folders of :func:`~raysim.io.storage.write_store` and files of
    :func:`~raysim.io.files.atomic_write`: ``.<name>.<random>.tmp``.
    """
    p = Path(store)
    if not p.parent.is_dir():
        return []
    return sorted(q for q in p.parent.glob(f".{p.name}.*.tmp")
                  if q.is_dir() or (q.is_file() and not q.is_symlink()))


def remove_debris(store: str | os.PathLike) -> list[Path]:
    """Remove what a killed writer of this store left; call it holding :func:`writer_lock`.

    Returns
    -------
    list of Path
        What was removed: temporary store folders beside it, ``*.partial``
        files inside it.
    """
    p = Path(store)
    removed = []
    for tmp in tmp_siblings(p):
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            tmp.unlink(missing_ok=True)
        removed.append(tmp)
    if p.is_dir() and is_raysim_store(p):
        for part in p.rglob("*.partial"):
            if part.is_file():
                part.unlink()
                removed.append(part)
    return removed


#: Name of a temporary file of :func:`raysim.io.files.atomic_write`: ``.<name>.<8 chars>.tmp``.
_ATOMIC_TMP = re.compile(r"^\..+\.[A-Za-z0-9_]{8}\.tmp$")


def remove_tmp_files(folder: str | os.PathLike) -> list[Path]:
    """Remove the temporary files a killed :func:`~raysim.io.files.atomic_write` left in
    ``folder`` (not below it); call it holding the folder's :func:`writer_lock`.

    Returns
    -------
    list of Path
        The files removed.
    """
    p = Path(folder)
    if not p.is_dir():
        return []
    removed = []
    for q in sorted(p.iterdir()):
        if _ATOMIC_TMP.match(q.name) and q.is_file() and not q.is_symlink():
            q.unlink(missing_ok=True)
            removed.append(q)
    return removed
