"""Input validation shared by the public functions (ValueError naming the parameter)."""

from __future__ import annotations

import numpy as np


def _describe(value) -> str:
    arr = np.asarray(value)
    if arr.ndim == 0:
        return repr(value)
    return f"an array of shape {arr.shape}"


def finite_array(name: str, value, *, shape: tuple | None = None, ndim: int | None = None,
                 dtype=float, what: str = "") -> np.ndarray:
    """``value`` as an array of ``dtype``; checks finiteness and an optional shape.

    ``shape`` may contain ``None`` for free axes.
    """
    try:
        arr = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be numeric{what and ' ' + what}, got {value!r}") from None
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must have {ndim} axes{what and ' ' + what}, got "
                         f"{_describe(value)}")
    if shape is not None:
        ok = arr.ndim == len(shape) and all(s is None or s == n
                                             for s, n in zip(shape, arr.shape, strict=True))
        if not ok:
            want = "[" + ", ".join("any" if s is None else str(s) for s in shape) + "]"
            raise ValueError(f"{name} must have shape {want}{what and ' ' + what}, got "
                             f"{_describe(value)}")
    bad = ~np.isfinite(arr)
    if np.any(bad):
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name} must be finite{what and ' ' + what}; entry {idx} is "
                         f"{arr[idx]!r}")
    return arr


def strictly_increasing(name: str, t: np.ndarray) -> None:
    """Raise unless the 1-D array ``t`` is strictly increasing."""
    if t.size > 1:
        d = np.diff(t)
        if not np.all(d > 0):
            k = int(np.argmin(d > 0))
            raise ValueError(f"{name} must be strictly increasing; entry {k + 1} "
                             f"({t[k + 1]!r} s) does not follow entry {k} ({t[k]!r} s)")


def choice(name: str, value, options) -> str:
    """Raise unless ``value`` is one of ``options``."""
    if value not in options:
        raise ValueError(f"{name} must be one of {tuple(options)}, got {value!r}")
    return value


def positive(name: str, value) -> float:
    """A finite positive float."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {value!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise ValueError(f"{name} must be a finite positive number, got {value!r}")
    return v


def rotation_matrices(name: str, value, n: int | None = None) -> np.ndarray:
    """Rotation matrices ``[n, 3, 3]`` (a scipy Rotation or an array) checked for orthonormality."""
    if hasattr(value, "as_matrix"):
        value = value.as_matrix()
    m = finite_array(name, value)
    if m.shape == (3, 3):
        m = m[None]
    if m.ndim != 3 or m.shape[1:] != (3, 3) or (n is not None and m.shape[0] != n):
        want = f"[{n if n is not None else 'chirp'}, 3, 3]"
        raise ValueError(f"{name} must have shape {want} (rotation matrices), got "
                         f"{_describe(value)}")
    err = np.abs(np.einsum("nji,njk->nik", m, m) - np.eye(3)).max()
    if err > 1e-6 or np.any(np.linalg.det(m) < 0):
        raise ValueError(f"{name} must hold proper rotation matrices (R^T R = I, det +1); "
                         f"orthonormality error {err:.3g}")
    return m


def complex_cube(name: str, value) -> np.ndarray:
    """A complex ``[chirp, channel, range]`` cube with finite entries (NaN names its cell)."""
    x = np.asarray(value)
    if x.ndim != 3 or not np.iscomplexobj(x):
        raise ValueError(f"{name} must be a complex cube [chirp, channel, range], got "
                         f"{x.dtype} array of shape {x.shape}")
    if not np.all(np.isfinite(x)):
        idx = tuple(int(i) for i in np.argwhere(~np.isfinite(x))[0])
        count = int(np.count_nonzero(~np.isfinite(x)))
        raise ValueError(f"{name} must be finite; {count} entries are not, the first at "
                         f"[chirp, channel, range] = {list(idx)} is {x[idx]!r}")
    return x


#: Largest grid angle [rad]: directions beyond +-90 deg lie behind the array.
MAX_GRID_ANGLE = np.pi / 2


def angle_axis(name: str, value) -> np.ndarray:
    """A 1-D grid of angles in radians within +-pi/2 (a grid in degrees is named as such)."""
    a = finite_array(name, value, ndim=1, what="(radians)")
    if a.size and np.max(np.abs(a)) > MAX_GRID_ANGLE + 1e-9:
        worst = float(a[np.argmax(np.abs(a))])
        hint = " (degrees? convert with numpy.deg2rad)" if np.max(np.abs(a)) <= 360 else ""
        raise ValueError(f"{name} must be angles in radians within +-pi/2, got {worst!r}"
                         f"{hint}")
    return a


def channel_slots(value, n_channel: int) -> np.ndarray:
    """TDM slot of every channel: ``[channel]`` non-negative integers, else ``ValueError``."""
    slot = np.asarray(value)
    if slot.shape != (n_channel,) or not np.issubdtype(slot.dtype, np.integer) or \
            slot.min() < 0:
        raise ValueError(f"channel_slot must hold one non-negative integer slot per channel "
                         f"({n_channel}), got {value!r}")
    return slot
