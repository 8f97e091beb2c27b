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
``"imu window"``
    :func:`judge_imu_window`: gaps of the log outside the window the record
    is used over (the chirps on the IMU clock, plus a margin) are not judged:
    the log is cut before them.
``"imu gaps filled"``
    :func:`judge_imu_window`: gaps inside that window above
    :data:`GAP_LIMIT_FACTOR` times the median interval, up to ``max_gap``
    (default :data:`DEFAULT_MAX_GAP`), are filled by linear interpolation at
    the median interval; what the platform did inside them is not measured.
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
#: Largest gap [s] inside the window used that :func:`judge_imu_window` fills by
#: interpolation when no ``max_gap`` is given: a 50 ms logger dropout plus one
#: interval of a 100 Hz log. PX4 loggers drop 65-161 ms at times: give ``max_gap``.
DEFAULT_MAX_GAP = 0.06
#: Margin [s] of the window used on each side of the chirps (IMU clock): the
#: integration's spline support and the clock-offset search.
WINDOW_MARGIN = 0.5
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


def folds_vibration(imu_time, gyro, interval: float) -> bool:
    """Whether a log of instantaneous samples (``interval`` 0) is too slow for the vibration
    its gyro shows (:func:`imu_rate_warning`): the clock-offset fit then reads the radar
    at the samples' instants (:func:`compensation.clock_averaged.fit_clock`).
    ``imu_time [sample]`` [s, IMU clock], ``gyro [sample, 3]`` [rad/s], ``interval`` the
    averaging interval of each sample [s]."""
    return interval == 0 and bool(imu_rate_warning(np.asarray(imu_time, dtype=float),
                                                   np.asarray(gyro, dtype=float), None))


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


def judge_imu_window(t: np.ndarray, window: tuple[float, float], *,
                     max_gap: float | None = None, margin: float = WINDOW_MARGIN,
                     what: str = "the capture") -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Judge the gaps of an IMU log over the window it is used for, and plan their filling.

    A flight-controller log is judged where it is used: a logger dropout
    seconds away from the capture does not refuse the log (the record is cut
    before it); a gap inside the window up to ``max_gap`` is filled by linear
    interpolation at the median interval, with a warning; a larger gap there
    raises.

    Parameters
    ----------
    t : ndarray, shape ``[sample]``
        Strictly increasing IMU time stamps, IMU clock [s].
    window : (float, float)
        First and last time the record is needed at, IMU clock [s] (the
        chirps plus the clock offset).
    max_gap : float, optional
        Largest interval [s] inside the window that is filled; default
        :data:`DEFAULT_MAX_GAP` (or :data:`GAP_LIMIT_FACTOR` x the median
        interval when that is larger).
    margin : float
        Extent [s] of the window used beyond ``window`` on each side.
    what : str
        What the window is, for messages.

    Returns
    -------
    keep : ndarray, shape ``[sample_kept]``
        Indices of ``t`` kept (one contiguous run).
    fill_time : ndarray, shape ``[sample_new]``
        Times [s] to insert, inside the gaps filled (empty when none).
    warnings : tuple of str
        ``"imu window: ..."`` (record cut at far gaps) and ``"imu gaps filled:
        ..."`` entries.

    Raises
    ------
    ValueError
        The log does not cover the window (said as such, with both spans), or
        a gap inside the window is larger than ``max_gap``.
    """
    t = np.asarray(t, dtype=float)
    lo, hi = float(window[0]), float(window[1])
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi < lo:
        raise ValueError(f"window must be an increasing pair of finite times [s], got {window!r}")
    if max_gap is not None and not (np.isfinite(max_gap) and max_gap > 0):
        raise ValueError(f"max_gap must be a finite positive number of seconds, got {max_gap!r}")
    if t.size < 2:
        raise ValueError(f"the IMU log holds {t.size} sample(s); at least 2 are needed")
    if t[0] > lo or t[-1] < hi:
        raise ValueError(
            f"the IMU log does not cover {what}: the log spans {t[0]:.6f} .. {t[-1]:.6f} s on "
            f"its clock, {what} needs {lo:.6f} .. {hi:.6f} s (radar times plus the time "
            f"offset); check the time offset, the capture start and the log's time base "
            f"(time since boot or Unix epoch)")
    d = np.diff(t)
    med = float(np.median(d))
    big = np.flatnonzero(d > GAP_LIMIT_FACTOR * med)
    use_lo, use_hi = lo - margin, hi + margin
    first, last = 0, t.size - 1
    cut = []
    for k in big:
        if t[k + 1] <= use_lo:
            first = max(first, int(k) + 1)
            cut.append(int(k))
        elif t[k] >= use_hi:
            last = min(last, int(k))
            cut.append(int(k))
    out = []
    if cut:
        worst = max(cut, key=lambda k: d[k])
        out.append(f"imu window: the log is used over {t[first]:.4f} .. {t[last]:.4f} s (IMU "
                   f"clock) around {what}; {len(cut)} gap(s) outside it are not judged (the "
                   f"largest {d[worst]:.4g} s at {t[worst]:.6g} s)")
    inside = [int(k) for k in big if first <= k < last]
    limit = (max(DEFAULT_MAX_GAP, GAP_LIMIT_FACTOR * med) if max_gap is None
             else float(max_gap))
    fills = []
    if inside:
        k = max(inside, key=lambda j: d[j])
        if d[k] > limit:
            raise ValueError(
                f"the IMU log has a gap of {d[k]:.4g} s at {t[k]:.6g} s (IMU clock) inside the "
                f"window used for {what} ({use_lo:.6g} .. {use_hi:.6g} s; median interval "
                f"{med:.4g} s); largest gap filled by interpolation: {limit:.4g} s. Raise "
                f"max_gap (--max-gap SECONDS) to interpolate across it, or select frames away "
                f"from it")
        for j in inside:
            n = int(np.ceil(d[j] / med - 1e-9))
            fills.append(t[j] + d[j] * np.arange(1, n) / n)
        out.append(f"imu gaps filled: {len(inside)} gap(s) inside the window used for {what} "
                   f"filled by linear interpolation at the median interval {med:.4g} s (the "
                   f"largest {d[k]:.4g} s at {t[k]:.6g} s, IMU clock); the motion inside them "
                   f"is not measured (vibration and manoeuvres there are lost)")
    keep = np.arange(first, last + 1)
    fill = np.concatenate(fills) if fills else np.zeros(0)
    return keep, fill, tuple(out)


def frames_in_gaps(fill_time, spans, frames, step: float) -> tuple[str, ...]:
    """``("imu gaps: frame(s) ... lie in a filled gap ...",)`` for the frames
    :func:`gap_segments` places in a gap, else ``()``.

    ``fill_time [sample_new]`` [s, IMU clock] from :func:`judge_imu_window`; ``spans``
    each frame's first and last slot time on the IMU clock [s]; ``frames`` their
    numbers in the capture; ``step`` the median IMU interval [s], added on each side.
    """
    if len(frames) != len(spans):
        raise ValueError(f"frames: got {len(frames)} for {len(spans)} spans; expected one each")
    hit = [int(frames[k]) for idx, gap in gap_segments(fill_time, spans, step) if gap
           for k in idx]
    if not hit:
        return ()
    return (f"imu gaps: frame(s) {', '.join(map(str, hit))} lie in a filled gap: their "
            f"motion is interpolated, not measured, and what the platform did there is not "
            f"compensated",)


def gap_segments(fill_time, spans, step: float, slack: float = 0.0
                 ) -> list[tuple[list[int], bool]]:
    """The frames in runs the log's filled gaps do not cross, for estimating each apart.

    Across a filled gap the log's motion is interpolated, not measured: an
    estimate over the whole record fits the frames inside it to a motion the
    platform did not make, and carries what the gap left unmeasured into every
    frame after it. Each run is a record of its own.

    Parameters
    ----------
    fill_time : array_like, shape ``[sample_new]``
        Interpolated sample times [s, IMU clock] (:func:`judge_imu_window`).
    spans : sequence of (float, float)
        Each frame's first and last slot time on the IMU clock [s], in time order.
    step : float
        Median IMU interval [s]: a gap's extent beyond its first and last filled sample.
    slack : float
        How far the frames may lie from ``spans`` [s] (an offset still to be searched):
        a frame that near a gap counts as in it.

    Returns
    -------
    list of (list of int, bool)
        Frame indices into ``spans`` of each run, in order, and whether the run lies
        in a gap (its frames' motion interpolated); one run of every frame when no
        gap touches them.
    """
    fill = np.sort(np.asarray(fill_time, dtype=float))
    if fill.size == 0:
        return [(list(range(len(spans))), False)]
    cuts = np.flatnonzero(np.diff(fill) > 2 * step) + 1      # filled samples of one gap abut
    gaps = [(g[0] - step, g[-1] + step) for g in np.split(fill, cuts)]
    keys, near = [], step + abs(float(slack))
    for a, b in spans:
        inside = [i for i, (lo, hi) in enumerate(gaps) if lo <= b + near and hi >= a - near]
        keys.append(("in", inside[0]) if inside else
                    ("after", sum(hi < a - near for _, hi in gaps)))
    runs: list[tuple[list[int], bool]] = []
    for k, key in enumerate(keys):
        if k and key == keys[k - 1]:
            runs[-1][0].append(k)
        else:
            runs.append(([k], key[0] == "in"))
    return runs


def fill_imu_gaps(t: np.ndarray, values: np.ndarray, keep: np.ndarray,
                  fill_time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Apply the plan of :func:`judge_imu_window` to a record.

    Parameters
    ----------
    t : ndarray, shape ``[sample]``
        Time stamps [s].
    values : ndarray, shape ``[sample, n]``
        Samples (gyro and accel side by side, any units).
    keep, fill_time : ndarray
        From :func:`judge_imu_window`.

    Returns
    -------
    (ndarray, ndarray)
        ``time [sample_out]`` and ``values [sample_out, n]``: the kept samples
        with the interpolated ones inserted, in time order.
    """
    t = np.asarray(t, dtype=float)[keep]
    v = np.asarray(values, dtype=float)[keep]
    if fill_time.size == 0:
        return t, v
    new = np.column_stack([np.interp(fill_time, t, v[:, i]) for i in range(v.shape[1])])
    tt = np.concatenate([t, fill_time])
    order = np.argsort(tt, kind="stable")
    return tt[order], np.concatenate([v, new])[order]
