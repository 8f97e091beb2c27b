"""Window functions of the FFTs (one definition for range, Doppler and metrics)."""

from __future__ import annotations

import numpy as np
from scipy.signal import get_window

__all__ = ["window"]


def window(name: str | None, n: int) -> np.ndarray:
    """Periodic (DFT-even) window of length ``n``; ``None`` or ``"rect"`` gives ones."""
    if name is None or name in ("rect", "boxcar", "none"):
        return np.ones(n)
    try:
        return get_window(name, n, fftbins=True)
    except ValueError as exc:
        raise ValueError(f"window {name!r} is not a scipy.signal window name: {exc}") from None
