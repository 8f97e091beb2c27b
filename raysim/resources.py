"""Memory estimates before allocating: refuse clearly what cannot fit, announce large outputs.

A frame, an IMU record or a store is sized from its dimensions before any
array is made; :func:`check_memory` raises a ValueError naming the size, what
is available and which setting to reduce, instead of a raw ``MemoryError``
deep in NumPy.
"""

from __future__ import annotations

import os

__all__ = ["LARGE_OUTPUT_BYTES", "available_memory", "format_bytes", "check_memory",
           "cube_bytes"]

#: Outputs above this size are announced before they are written [bytes].
LARGE_OUTPUT_BYTES = 1 << 30


def available_memory() -> int:
    """Memory the system can give this process now [bytes] (``MemAvailable``)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError):
        return 1 << 62                               # unknown: do not refuse


def format_bytes(n: float) -> str:
    """``1.5 GiB``-style size."""
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return f"{n:.3g} PiB"


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
