"""Memory estimates before allocating: refuse clearly what cannot fit, announce large outputs.

A frame, an IMU record or a store is sized from its dimensions before any
array is made; :func:`check_memory` raises a ValueError naming the size, what
is available and which setting to reduce, instead of a raw ``MemoryError``
deep in NumPy.
"""

from __future__ import annotations

import os

__all__ = ["LARGE_OUTPUT_BYTES", "available_memory", "format_bytes", "check_memory",
           "cube_bytes", "tree_bytes"]

#: Outputs above this size are announced before they are written [bytes].
LARGE_OUTPUT_BYTES = 1 << 30


def _read_int(path: str) -> int | None:
    try:
        with open(path, encoding="ascii") as fh:
            text = fh.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def _cgroup_room() -> int | None:
    """Memory left under this process's cgroup limit [bytes] (v2, else v1); None if none."""
    for limit, usage in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                         ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                          "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        lim = _read_int(limit)
        if lim is not None and lim < (1 << 60):
            return max(0, lim - (_read_int(usage) or 0))
    return None


def _address_space_room() -> int | None:
    """Address space left under ``ulimit -v`` (RLIMIT_AS) [bytes]; None if unlimited."""
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, ValueError, OSError):
        return None
    if soft == resource.RLIM_INFINITY or soft <= 0:
        return None
    used = 0
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmSize:"):
                    used = int(line.split()[1]) * 1024
    except OSError:
        pass
    return max(0, soft - used)


def available_memory() -> int:
    """Memory this process can still get now [bytes].

    The least of the system's ``MemAvailable``, the room under the process's
    cgroup memory limit (containers) and the room under ``ulimit -v``.
    """
    avail = None
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except OSError:
        pass
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError):
            avail = 1 << 62                              # unknown: do not refuse
    for room in (_cgroup_room(), _address_space_room()):
        if room is not None:
            avail = min(avail, room)
    return int(avail)


def format_bytes(n: float) -> str:
    """``1.5 GiB``-style size."""
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return f"{n:.3g} PiB"


def tree_bytes(path) -> int:
    """Bytes of the files under ``path`` (a file: its size; missing: 0)."""
    from pathlib import Path

    p = Path(path)
    if p.is_file():
        return p.stat().st_size
    return sum(f.stat().st_size for f in p.rglob("*") if f.is_file()) if p.is_dir() else 0


def cube_bytes(num_chirps: int, num_channels: int, num_samples: int, itemsize: int = 8) -> int:
    """Bytes of a ``[chirp, channel, sample]`` cube (complex64 by default)."""
    return int(num_chirps) * int(num_channels) * int(num_samples) * int(itemsize)


def check_memory(peak_bytes: float, what: str, hint: str) -> None:
    """Raise ValueError when ``peak_bytes`` exceed the memory available now.

    Parameters
    ----------
    peak_bytes : float
        Estimated peak memory of the step [bytes].
    what : str
        The step and its size, e.g. ``"a frame [256, 400, 600]"``.
    hint : str
        Which setting reduces it, e.g. ``"radar.num_chirps"``.
    """
    avail = available_memory()
    if peak_bytes > avail:
        raise ValueError(f"{what} needs about {format_bytes(peak_bytes)} of memory, "
                         f"{format_bytes(avail)} are available; expected a size that fits: "
                         f"reduce {hint}")


def free_disk(path) -> int:
    """Free bytes on the disk that holds ``path`` (or would: its nearest existing parent)."""
    import shutil
    from pathlib import Path

    parent = Path(os.path.abspath(path))
    while not parent.exists():
        parent = parent.parent
    return int(shutil.disk_usage(parent).free)
