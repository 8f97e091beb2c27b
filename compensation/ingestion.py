"""Checks of recorded IMU and chirp timing before integration.

Flight-controller logs drop samples and stamp them with jitter; a radar
records frames with idle time between them. What can be integrated safely is
accepted with a warning (``warnings.warn`` with
:class:`compensation.guards.CompensationWarning`, and the same text in
:attr:`compensation.PlatformMotion.warnings`), what cannot raises
``ValueError``. Warning keys:

``"imu gaps"``
    Sample intervals above :data:`compensation.guards.GAP_FACTOR` times the
    median, up to :data:`GAP_LIMIT_FACTOR` times (two dropped samples in a
    row); interpolation across them holds for motions well below the Nyquist
    rate of the gap. Larger gaps raise.
``"imu jitter"``
    Interval spread (median absolute deviation scaled to a standard
    deviation, blind to single gaps) above :data:`JITTER_WARN_FRACTION` of
    the median.
``"imu rate"``
    The sample rate is below :data:`VIBRATION_RATE_FACTOR` times the upper
    edge of the vibration band (stated, or found in the gyro spectrum): the
    spline cannot follow the vibration and the lever-arm phase is wrong.
"""

from __future__ import annotations

import warnings as _warnings

import numpy as np
from scipy.signal import welch

from ._checks import finite_array
from .guards import GAP_FACTOR, CompensationWarning

#: Largest default IMU interval, as a multiple of the median interval: two dropped
#: samples in a row (3 intervals) plus timestamp jitter.
GAP_LIMIT_FACTOR = 3.5
#: Interval spread (standard deviation over the median) above which jitter is reported.
JITTER_WARN_FRACTION = 0.1
#: Smallest IMU rate over the upper edge of the vibration band (Nyquist 2, plus a
#: margin for the cubic spline).
VIBRATION_RATE_FACTOR = 2.5
#: Spectral level above the noise floor that counts as motion in the gyro spectrum [dB].
VIBRATION_FLOOR_DB = 20.0
#: Dynamic range of the gyro spectrum searched for motion [dB] (below the peak).
VIBRATION_DYNAMIC_RANGE_DB = 50.0
#: Relative tolerance of the chirp spacing inside one frame [1].
CHIRP_UNIFORMITY_RTOL = 1e-3
#: Absolute tolerance of the chirp spacing [s] (float64 rounding of epoch seconds).
CHIRP_UNIFORMITY_ATOL = 1e-6
#: Default hover-window length per IMU grade [s] (``None``: the whole record). A
#: consumer MEMS accelerometer (20 mg bias, 1 % cross-axis) makes the velocity error
#: grow within seconds: a long window is worse than a short one (docs/self_calibration.md).
HOVER_WINDOW_BY_GRADE = {"ideal": None, "tactical": 8.0, "consumer_mems": 1.0}


def warn(texts) -> tuple[str, ...]:
    """Issue each text as a :class:`CompensationWarning` and return them."""
    texts = tuple(texts)
    for text in texts:
        _warnings.warn(text, CompensationWarning, stacklevel=3)
    return texts


def check_imu_timing(t: np.ndarray, max_gap: float | None = None) -> tuple[str, ...]:
    """Warnings on gaps and jitter of IMU time stamps; ``ValueError`` on larger gaps.

    Parameters
    ----------
    t : ndarray, shape ``[sample]``
        Strictly increasing time stamps [s].
    max_gap : float, optional
        Largest tolerated interval [s], tolerated without warning; default
        :data:`GAP_LIMIT_FACTOR` times the median interval, with a warning
        above :data:`~compensation.guards.GAP_FACTOR` times.

    Returns
    -------
    tuple of str
        ``"imu gaps: ..."`` and ``"imu jitter: ..."`` entries.
    """
    d = np.diff(t)
    if d.size < 2:
        return ()
    med = float(np.median(d))
    limit = GAP_LIMIT_FACTOR * med if max_gap is None else float(max_gap)
    if not np.isfinite(limit) or limit <= 0:
        raise ValueError(f"max_gap must be a finite positive number, got {max_gap!r}")
    k = int(np.argmax(d))
    if d[k] > limit:
        raise ValueError(
            f"imu_time has a gap of {d[k]:.6g} s at {t[k]:.6g} s (median interval {med:.6g} s, "
            f"largest tolerated {limit:.6g} s); interpolating across it would give a wrong "
            f"pose: fill or split the record, or raise max_gap")
    out = []
    if max_gap is None:
        big = d > GAP_FACTOR * med
        if np.any(big):
            out.append(f"imu gaps: {int(big.sum())} interval(s) above {GAP_FACTOR:g} x the "
                       f"median {med:.4g} s, the largest {d[k]:.4g} s at {t[k]:.6g} s; "
                       f"interpolated across (tolerated up to {GAP_LIMIT_FACTOR:g} x)")
    spread = 1.4826 * float(np.median(np.abs(d - med))) / med   # robust to single gaps
    if spread > JITTER_WARN_FRACTION:
        out.append(f"imu jitter: sample intervals spread by {100 * spread:.3g} % of the "
                   f"median {med:.4g} s; the samples are taken at their stamped times")
    return tuple(out)


def vibration_band_edge(t: np.ndarray, gyro: np.ndarray) -> float | None:
    """Highest frequency [Hz] where the gyro spectrum stands out of its noise floor.

    Welch spectrum of the three axes summed; the floor is the 10th percentile
    of the spectrum, motion is what exceeds it by :data:`VIBRATION_FLOOR_DB`
    and lies within :data:`VIBRATION_DYNAMIC_RANGE_DB` of the peak.
    Vibration above the Nyquist frequency folds below it and cannot be told
    from the data (state the band then). ``None`` when nothing stands out.
    """
    if t.size < 16:
        return None
    fs = 1.0 / float(np.median(np.diff(t)))
    f, p = welch(gyro - gyro.mean(axis=0), fs=fs, axis=0, nperseg=min(256, t.size))
    p = p.sum(axis=1)
    floor = float(np.percentile(p[1:], 10))
    # a noise-free record has no floor: the window's leakage below the dynamic range
    # of a spectrum estimate is not motion either
    level = max(floor * 10 ** (VIBRATION_FLOOR_DB / 10), float(p.max()) * 10 ** (
        -VIBRATION_DYNAMIC_RANGE_DB / 10))
    above = np.flatnonzero(p[1:] > level) + 1
    return float(f[above[-1]]) if above.size and p.max() > 0 else None


def imu_rate_warning(t: np.ndarray, gyro: np.ndarray, vibration_hz: float | None
                     ) -> tuple[str, ...]:
    """``("imu rate: ...",)`` when the IMU rate is below 2.5 x the vibration band edge."""
    fs = 1.0 / float(np.median(np.diff(t)))
    stated = vibration_hz is not None
    edge = float(finite_array("vibration_hz", vibration_hz, shape=())) if stated else \
        vibration_band_edge(t, gyro)
    if edge is None or fs >= VIBRATION_RATE_FACTOR * edge:
        return ()
    how = "stated" if stated else "found in the gyro spectrum"
    return (f"imu rate: {fs:.4g} Hz is below {VIBRATION_RATE_FACTOR:g} x the vibration band "
            f"edge {edge:.4g} Hz ({how}); the vibration is not resolved and its lever-arm "
            f"motion is compensated wrongly",)


def is_frame_list(times) -> bool:
    """True when ``times`` is a list or tuple of 1-D arrays (frames), not one array."""
    return isinstance(times, (list, tuple)) and len(times) > 0 and all(
        np.ndim(f) == 1 for f in times)


def check_frame_times(frame_times) -> list[np.ndarray]:
    """Frames of chirp times, each uniform, in order; ``ValueError`` otherwise.

    Parameters
    ----------
    frame_times : sequence of array_like ``[chirp]``, or array_like ``[chirp]``
        A sequence of frames, or one frame [s].

    Returns
    -------
    list of ndarray
    """
    if is_frame_list(frame_times):
        frames = [finite_array(f"chirp_times[{i}]", f, ndim=1) for i, f in
                  enumerate(frame_times)]
    else:
        frames = [finite_array("chirp_times", frame_times, ndim=1)]
    for i, f in enumerate(frames):
        name = f"chirp_times[{i}]" if len(frames) > 1 else "chirp_times"
        if f.size < 1:
            raise ValueError(f"{name} must hold at least one time")
        if f.size < 3:
            if f.size == 2 and f[1] < f[0]:
                raise ValueError(f"{name} must be sorted in increasing order")
            continue
        d = np.diff(f)
        if np.any(d < 0):
            raise ValueError(f"{name} must be sorted in increasing order")
        med = float(np.median(d))
        tol = max(CHIRP_UNIFORMITY_RTOL * med, CHIRP_UNIFORMITY_ATOL)
        k = int(np.argmax(np.abs(d - med)))
        if abs(d[k] - med) > tol:
            raise ValueError(
                f"{name} are not uniform within a frame: interval {k} is {d[k]:.6g} s against "
                f"the median {med:.6g} s (tolerance {tol:.3g} s); the Doppler axis would be "
                f"wrong. Give frames separated by idle time as a list of per-frame arrays")
        if i > 0 and f[0] <= frames[i - 1][-1]:
            raise ValueError(f"{name} starts at {f[0]!r} s, not after the previous frame's "
                             f"last chirp {frames[i - 1][-1]!r} s; frames must be in order")
    return frames


def grade_hover_window(grade: str, chirp_span: tuple[float, float],
                       imu_span: tuple[float, float]) -> tuple[float, float] | None:
    """Default hover window of an IMU grade on the radar clock [s], ``None`` for the record.

    The window of :data:`HOVER_WINDOW_BY_GRADE` is centred on the chirps and
    shifted (not shortened) to stay inside the IMU record ``imu_span`` (radar
    clock).
    """
    if grade not in HOVER_WINDOW_BY_GRADE:
        raise ValueError(f"imu_grade must be one of {sorted(HOVER_WINDOW_BY_GRADE)}, got "
                         f"{grade!r}")
    length = HOVER_WINDOW_BY_GRADE[grade]
    if length is None or length >= imu_span[1] - imu_span[0]:
        return None
    lo = 0.5 * (chirp_span[0] + chirp_span[1]) - 0.5 * length
    lo = min(max(lo, imu_span[0]), imu_span[1] - length)
    return (lo, lo + length)
