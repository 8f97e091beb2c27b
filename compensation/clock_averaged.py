"""IMU-radar clock offset from a log of averaged samples (a flight controller's boxcar).

A flight controller logs its IMU at 200-250 Hz, each sample the average of the
rates over its interval ``[x_k - T/2, x_k + T/2]`` (``T`` the interval, ``x_k``
its middle). The log cannot resolve the 100-200 Hz rotor vibration; the radar
sees all of it. :func:`compensation.clock_offset.fit_time_shift` regresses the
residual phase on the predicted phase rate chirp by chirp, so the vibration the
log misses (mostly the rotation's, through the lever arm) is model error that
correlates with the regressor: on the 250 Hz flights it moved the offset by up
to 0.5 ms, with an offset and its sign that change from flight to flight.

What the log gives exactly is the mean of the rate over each interval. The
radar gives its phase-centre velocity along ``u`` at every chirp, so both are
compared over the same intervals, like with like. With the track's residual
phase ``phi(t)`` and predicted phase rate ``r(t)`` (the rate the IMU shows, a
spline through the averages, :func:`compensation.strapdown.integrate_imu`), the
radar's mean phase rate over an interval is ``(phi(b+) - phi(b-)) / T +
mean(r)`` and the log's average is the spline's value at the middle,
``r(x_k)``, so

    z_k = (phi(b+) - phi(b-)) / T + mean_k(r) - r(x_k) = c + delta g_k,

``g_k = (V(b+) - V(b-)) / T`` the mean phase acceleration the radar sees over the
interval (``V = phi' + r`` its phase rate, a local cubic fit of the track at
each end) and ``c`` a constant per track (its velocity error; the residual
Doppler removed when the track was unwrapped). Only intervals that lie within
the frame count. The vibration the log misses averages out of ``z`` the same
way it does out of the log, so the fit has no model error of that kind, and
``g`` is the full vibration, which makes the offset observable to tens of
microseconds.

Coarse search
-------------
The linearised fits reach about a quarter of the vibration period (1 ms); a grid
of misfits over +- 10 ms brings the offset within that reach first. The
per-chirp phase misfit (:func:`compensation.clock_offset.phase_misfit`) compares
the radar with the spline through the averages, and a 200 Hz log aliases the
80-160 Hz vibration (folded to 40-100 Hz): on the simulated 200 Hz flights its
minimum lay 6-10 ms from the truth. :func:`clock_misfit` compares interval means
instead (the mean square of the constant-free ``z``), whose minimum the aliasing
does not move. A 13.2 ms frame spans two 5 ms intervals at about two thirds of
the offsets; elsewhere the intervals are placed at the nearest offset where they
do (:func:`placement_lag`). Two intervals a track leave one constant-free row per
scatterer and frame, so a second minimum can fit about as well: over three frames
of one of six flights (seed 0) one 2.5 ms from the truth fitted better (6.05
against 6.91 rad^2/s^2, 15 degrees of freedom each), hence
:data:`SEARCH_FRAMES_AVERAGED`. Where another local minimum's misfit is
within the :data:`AMBIGUITY_LEVEL` quantile of Fisher's F distribution of the
best one's (both mean squares of residuals, with their degrees of freedom; the
scatterers' rows of one interval share the platform's error and count once: a
200 Hz boxcar log, seed 0, offset -4 ms, settled one interval off at 10 degrees
of freedom counted per scatterer, misfit ratio 5.8, stated 0.33 ms),
:func:`coarse_offset` keeps the best, states the distance to the other as a
spread of the offset and warns (a time sync, ``--time-offset``, removes it:
docs/recordings.md).

What it cannot observe
----------------------
* The placement of the averaging window within the interval: the log's stamp
  convention (the interval's middle, :mod:`raysim.io.flight_logs`) is taken as
  given; a log whose average is centred elsewhere (e.g. the plain mean of ``m``
  instantaneous samples, centred half an internal sample later) shifts the
  offset by that much, whatever estimates it from that log.
  :data:`PLACEMENT_SIGMA_FRACTION` of the interval is stated for it
  (``ClockOffset.stamp_sigma``), apart from the fit's own spread.
* Translational vibration within an interval: the log's velocity is exact only
  in the mean over an interval; the spline's value at the middle misses the
  curvature of the velocity within it (second order in ``f T``).
* An accelerometer-bias error tilts ``z`` over the intervals of a frame; with 2-3
  intervals a frame there is no room for a slope per track, so it is left in (on
  the 250 Hz test flights the refit after the radar-inertial estimate, biases
  corrected, moved the offset by at most 3 us, seeds 0 and 2).
* A track shorter than one interval gives nothing; a frame shorter than two gives
  no constant-free information (the per-track constant takes it). Where a frame
  spans two only at another placement (a 200 Hz log's 5 ms intervals against a
  13.2 ms frame) the fit is linearised about the nearest placement that does
  (:func:`placement_lag`); where none does at any placement (an 8 ms interval),
  :func:`fit_clock` falls back to the per-chirp fit, warned, and states
  :data:`PER_CHIRP_SIGMA_FRACTION` of the interval for the averaging's bias.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import replace
from functools import partial
from typing import NamedTuple

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.stats import f as fisher_f

from ._checks import finite_array, positive
from .clock_offset import ClockOffset, fit_time_shift, phase_misfit, track_arrays
from .guards import CompensationWarning

#: Share of the averaging interval stated for the placement when no frame spans two
#: intervals and the offset is fitted per chirp against the averages [1] (the per-chirp
#: fit on 250 Hz flights was off by 0.03-0.51 ms, up to 0.13 of the 4 ms interval).
PER_CHIRP_SIGMA_FRACTION = 1.0 / 8.0
#: Chirps each side of a boundary in the local cubic fit of the phase rate [1].
RATE_FIT_HALF_WIDTH = 6
#: Share of the averaging interval (of the sample period for instantaneous samples) added
#: in quadrature to the offset's spread for the placement of the samples in time, which
#: the log does not state [1] (the plain mean of 8 instantaneous samples is centred 1/16
#: of the interval late).
PLACEMENT_SIGMA_FRACTION = 1.0 / 16.0
#: Steps per half interval of the search for a placement spanning two intervals [1].
LAG_STEPS = 50
#: Frames of the coarse search over an averaged log (the first ones) [1]: each gives one
#: constant-free row per scatterer at 200 Hz (two 5 ms intervals a frame); with three a
#: second minimum fitted about as well on two of six simulated flights, with four on one.
SEARCH_FRAMES_AVERAGED = 4
#: Quantile of F below which another minimum's misfit ratio leaves the offset ambiguous [1].
AMBIGUITY_LEVEL = 0.95
#: Least distance of another minimum from the best one to count as a second offset [s]:
#: within it the linearised fits move the offset themselves (their reach).
AMBIGUITY_MIN_SEPARATION = 1e-3


def _rate(t: np.ndarray, phi: np.ndarray, tq: float, order: int = 1) -> float:
    """Derivative (first, or second with ``order`` 2) at ``tq`` of a local cubic fit of
    ``phi(t)`` [rad/s, rad/s^2]."""
    i = int(np.searchsorted(t, tq))
    lo = max(min(i - RATE_FIT_HALF_WIDTH, t.size - 2 * RATE_FIT_HALF_WIDTH), 0)
    hi = min(lo + 2 * RATE_FIT_HALF_WIDTH, t.size)
    c = np.polynomial.polynomial.polyfit(t[lo:hi] - tq, phi[lo:hi], 3)
    return float(c[order] * (1 if order == 1 else 2))


def _within(t: np.ndarray, knots: np.ndarray, interval: float, lag: float) -> np.ndarray:
    """Which intervals, placed ``lag`` earlier than ``knots``, lie within the chirp times
    ``t``, their middles' ``knots`` too [sample]."""
    x = knots - lag
    return ((x - interval / 2 >= t[0]) & (x + interval / 2 <= t[-1]) & (knots >= t[0])
            & (knots <= t[-1]))


def _intervals_within(t: np.ndarray, knots: np.ndarray, interval: float,
                      lag: float = 0.0) -> int:
    """How many whole averaging intervals lie within the chirp times ``t`` [1]."""
    if t.size < 2 * RATE_FIT_HALF_WIDTH:
        return 0
    return int(np.count_nonzero(_within(t, knots, interval, lag)))


def placement_lag(tracks, knots, interval: float) -> float | None:
    """Smallest shift [s] of the intervals' placement at which the most tracks span two,
    or None where none does at any shift.

    Where the frames span two intervals only at another offset than the one the
    tracks were compensated with (a 200 Hz log's 5 ms intervals against a 13 ms
    frame: about a third of the offsets), the radar's mean rate over the intervals
    so placed is compared with the log's averages (the predicted rate at the
    knots used): the fit is linearised about the shifted placement instead.
    """
    knots = np.sort(finite_array("knots", knots, ndim=1))
    times = [track_arrays(i, item)[0] for i, item in enumerate(tracks)]
    steps = np.arange(0.0, interval / 2 + interval / LAG_STEPS / 2, interval / LAG_STEPS)
    lags = np.ravel(np.column_stack([steps, -steps]))
    spanning = [sum(_intervals_within(t, knots, interval, lag) >= 2 for t in times)
                for lag in lags]
    # the most tracks (stamp jitter may leave a frame out), then the nearest placement
    return float(lags[int(np.argmax(spanning))]) if max(spanning) > 0 else None


def interval_rows(t, phi, r, knots, interval: float,
                  lag: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``z [k]`` [rad/s] and ``g [k]`` [rad/s^2] of one track over the log intervals within it.

    Parameters
    ----------
    t : ndarray, shape ``[chirp]``
        Chirp times [s, radar clock], increasing.
    phi : ndarray, shape ``[chirp]``
        Unwrapped residual phase [rad].
    r : ndarray, shape ``[chirp]``
        Predicted phase rate [rad/s].
    knots : ndarray, shape ``[sample]``
        Middles of the log's averaging intervals on the radar clock [s].
    interval : float
        Averaging interval ``T`` [s]; 0 for instantaneous samples, whose rows are the
        limit ``z = phi'(x_k)``, ``g = V'(x_k)`` (the radar's rate against the sample
        at its own instant, an aliased log's included).
    lag : float
        The radar's intervals are placed ``lag`` earlier than ``knots`` [s] (the
        log's values still read at ``knots``): ``z = c + (delta - lag) g``.
    """
    keep = _within(t, knots, interval, lag)
    if not keep.any() or t.size < 2 * RATE_FIT_HALF_WIDTH:
        return np.empty(0), np.empty(0)
    ps, rs = CubicSpline(t, phi), CubicSpline(t, r)
    if interval == 0:       # instantaneous samples: the limit of a vanishing interval
        x = knots[keep] - lag
        z = [_rate(t, phi, xk) for xk in x]
        g = [_rate(t, phi, xk, 2) + float(rs(xk, 1)) for xk in x]
        return np.asarray(z, dtype=float), np.asarray(g, dtype=float)
    z, g = [], []
    for xk in knots[keep]:
        bm, bp = xk - lag - interval / 2, xk - lag + interval / 2
        z.append((ps(bp) - ps(bm)) / interval + rs.integrate(bm, bp) / interval - rs(xk))
        vm, vp = _rate(t, phi, bm) + rs(bm), _rate(t, phi, bp) + rs(bp)
        g.append((vp - vm) / interval)
    return np.asarray(z, dtype=float), np.asarray(g, dtype=float)


def _constant_free_rows(tracks, knots, interval: float, lag: float):
    """``z`` and ``g`` of every track spanning two intervals, less each track's mean, and
    the frame (first chirp time) of each row; the number of tracks."""
    zs, gs, frame = [], [], []
    starts: dict = {}
    for i, item in enumerate(tracks):
        t, phi, r, _ = track_arrays(i, item)
        if phi.shape != t.shape or r.shape != t.shape or t.ndim != 1:
            raise ValueError(f"tracks[{i}]: phase and rate must have the shape of times "
                             f"{t.shape}, got {phi.shape} and {r.shape}")
        z, g = interval_rows(t, phi, r, knots, interval, lag)
        if z.size < 2:
            continue
        # remove the track's constant: its velocity error and unwrapping Doppler
        zs.append(z - z.mean())
        gs.append(g - g.mean())
        frame.append(np.full(z.size, starts.setdefault(round(float(t[0]), 9), len(starts))))
    if not zs:
        raise ValueError(f"tracks: no track spans two averaging intervals of {interval:g} s; "
                         "the clock offset is unobservable from these intervals")
    return np.concatenate(zs), np.concatenate(gs), np.concatenate(frame), len(zs)


class Misfit(NamedTuple):
    """Cost of one offset of the coarse search and its degrees of freedom."""

    #: Mean square [rad^2/s^2 for interval means, rad^2 per chirp].
    cost: float
    #: Independent rows less the constants fitted [1]: the scatterers' rows of one
    #: interval share the platform's error and count once; for the per-chirp phase
    #: misfit (its residuals correlate along a track) the log's samples within each
    #: frame less the line fitted (:func:`sample_rows`).
    dof: int
    #: Whether ``cost`` is the per-chirp phase misfit [rad^2] rather than interval
    #: means [rad^2/s^2]: the two kinds do not compare.
    per_chirp: bool = False


def interval_misfit(tracks, knots, interval: float, lag: float = 0.0) -> Misfit:
    """Mean square of the radar's mean phase rate over the log's intervals less the log's,
    about a constant per track [rad^2/s^2]: the cost of a coarse offset search.

    Unlike :func:`compensation.clock_offset.phase_misfit` it compares like with like
    (interval means), so the vibration a 200 Hz log aliases does not move its minimum.
    Arguments as for :func:`fit_time_shift_averaged`; ``lag`` as for
    :func:`interval_rows`. Raises a ValueError where no track spans two intervals.
    """
    z, _, frame, tracks_used = _constant_free_rows(
        tracks, np.sort(np.asarray(knots, dtype=float)), interval, lag)
    dof = z.size - tracks_used
    # the scatterers' rows of one interval carry the same platform error (the vibration
    # the log cannot resolve): count them once, a frame's scatterers as one track
    frames = np.unique(frame).size
    return Misfit(float(z @ z) / max(dof, 1), max(dof * frames // tracks_used, 1))


def clock_misfit(tracks, imu_time, time_offset: float, interval: float = 0.0,
                 aliased: bool = False) -> Misfit:
    """Cost of the coarse offset search at ``time_offset`` [s] (the tracks' offset).

    :func:`interval_misfit` for a log of averages (at the nearest placement spanning
    two intervals, :func:`placement_lag`) or of instantaneous samples that do not
    resolve the vibration (``aliased``: the radar's rate read at the samples'
    instants, which the folding does not move); the per-chirp
    :func:`compensation.clock_offset.phase_misfit` for other instantaneous samples or
    frames shorter than two intervals. Not comparable between the two kinds.
    """
    knots = np.asarray(imu_time, dtype=float) - float(time_offset)
    if interval > 0:
        lag = placement_lag(tracks, knots, interval)
        if lag is not None:
            return interval_misfit(tracks, knots, interval, lag)
    elif aliased and _spans_two(tracks, knots):
        return interval_misfit(tracks, knots, 0.0)
    return Misfit(phase_misfit(tracks), sample_rows(tracks, knots), per_chirp=True)


def sample_rows(tracks, knots) -> int:
    """Independent rows of the per-chirp phase misfit [1]: the log's samples within each
    frame's chirps (the instants at which a shifted log misplaces the motion; the residual
    phase between them is that motion, interpolated), a frame's scatterers counted once as
    they share the platform's error, less the line fitted to each frame's tracks; 0
    where no frame holds three samples."""
    knots = np.sort(np.asarray(knots, dtype=float))
    per_frame: dict = {}
    for i, item in enumerate(tracks):
        t = track_arrays(i, item)[0]
        if t.size < 4:
            continue
        n = int(np.count_nonzero((knots >= t[0]) & (knots <= t[-1])))
        key = round(float(t[0]), 9)
        per_frame[key] = max(per_frame.get(key, 0), n)
    return int(sum(n - 2 for n in per_frame.values() if n > 2))


def _spans_two(tracks, knots) -> bool:
    """Whether some track holds two instantaneous samples (constant-free information)."""
    knots = np.sort(knots)
    return any(_intervals_within(track_arrays(i, item)[0], knots, 0.0) >= 2
               for i, item in enumerate(tracks))


def fit_time_shift_averaged(tracks, knots, interval: float, lag: float = 0.0) -> ClockOffset:
    """Time shift of a log of interval averages, from the radar's mean rates over them.

    Parameters
    ----------
    tracks : sequence of (times, phase, rate, weight)
        As for :func:`compensation.clock_offset.fit_time_shift` (the weights
        are not used: the residuals are model error, not thermal noise).
    knots : array_like, shape ``[sample]``
        Middles of the log's averaging intervals on the radar clock (IMU
        sample times less the offset used) [s].
    interval : float
        Averaging interval of each sample ``T`` [s] (0: instantaneous samples, the
        radar's rate read at each sample's instant; ``stamp_sigma`` 0 then).
    lag : float
        Shift of the radar's intervals [s] (:func:`interval_rows`; the fit is
        linearised about the offset used plus ``lag``).

    Returns
    -------
    ClockOffset
        ``delta`` to add to the offset used; its spread the larger of the
        Gauss-Markov one and the cluster-robust sandwich over frames (tracks of
        one frame share the platform's error; Cameron & Miller, J. Human
        Resources 50(2), 2015, eq. 11); ``stamp_sigma``
        :data:`PLACEMENT_SIGMA_FRACTION` of ``T`` (``total_sigma`` both). No drift
        is fitted.

    Raises
    ------
    ValueError
        Bad knots or interval, or fewer than two intervals within a track
        anywhere (nothing left after each track's constant).
    """
    knots = np.sort(finite_array("knots", knots, ndim=1))
    interval = float(interval) if interval == 0 else positive("interval", interval)
    z, g, frame, tracks_used = _constant_free_rows(tracks, knots, interval, float(lag))
    gg = float(g @ g)
    if gg <= 0:
        raise ValueError("the radar's phase acceleration is the same over every interval: "
                         "the clock offset is unobservable")
    delta = float(g @ z) / gg
    res = z - delta * g
    dof = max(z.size - tracks_used - 1, 1)
    var = float(res @ res) / dof / gg
    clusters = np.unique(frame)
    if clusters.size > 1:
        score = np.array([g[frame == f] @ res[frame == f] for f in clusters])
        var = max(var, float(score @ score) / gg ** 2 * clusters.size / (clusters.size - 1))
    return ClockOffset(delta + float(lag), float(np.sqrt(var)),
                       stamp_sigma=PLACEMENT_SIGMA_FRACTION * interval)


def fit_clock(tracks, *, imu_time, time_offset: float, interval: float = 0.0,
              drift: bool = False, ambiguity: float = 0.0, aliased: bool = False
              ) -> ClockOffset:
    """The clock-offset fit for the log: over its intervals when averaged, else per chirp.

    ``imu_time [sample]`` [s, IMU clock] and ``time_offset`` [s] (the one the
    tracks were compensated with) place the intervals on the radar clock;
    ``interval`` is the averaging interval [s], 0 for instantaneous samples
    (:func:`compensation.clock_offset.fit_time_shift`, ``drift`` as there). The
    placement of the samples in time is stated apart (``stamp_sigma``):
    :data:`PLACEMENT_SIGMA_FRACTION` of the interval, or of the sample period (the
    median step of ``imu_time``) for instantaneous samples. ``ambiguity`` [s] joins it
    in quadrature: the distance to another offset the data fit about as well
    (:func:`coarse_offset`). Instantaneous samples that do not resolve the vibration
    (``aliased``) are fitted at their instants (:func:`fit_time_shift_averaged` with
    interval 0): per chirp, the folded vibration is model error that moved the offset
    of simulated 200-250 Hz logs by 0.7-7 ms.
    """
    interval = float(finite_array("interval", interval, shape=()))
    if interval < 0:
        raise ValueError(f"interval: got {interval!r} s, expected the averaging interval of "
                         "each IMU sample, >= 0 (0: instantaneous samples)")
    if interval > 0:
        knots = np.asarray(imu_time, dtype=float) - float(time_offset)
        lag = placement_lag(tracks, knots, interval)
        if lag is not None:
            fit = fit_time_shift_averaged(tracks, knots, interval, lag)
            return replace(fit, stamp_sigma=float(np.hypot(fit.stamp_sigma, ambiguity)))
        # Frames shorter than two intervals (an 8 ms interval against a 13 ms frame):
        # the per-chirp fit, its bias by the averaging stated as a share of the interval.
        warnings.warn(f"clock: no frame spans two of the log's {1e3 * interval:.3g} ms "
                      f"averaging intervals; the offset is fitted per chirp against the "
                      f"averages and its spread states {PER_CHIRP_SIGMA_FRACTION:g} of the "
                      f"interval for their bias (the offset from a time sync, --time-offset, "
                      f"docs/recordings.md, avoids it)", CompensationWarning, stacklevel=2)
        return replace(fit_time_shift(tracks, drift=drift),
                       stamp_sigma=float(np.hypot(PER_CHIRP_SIGMA_FRACTION * interval, ambiguity)))
    # Instantaneous samples: where within its sample period each was taken (the sensor's
    # filter delay, the driver's stamp) is not stated either; the same share of the period.
    t = np.asarray(imu_time, dtype=float)
    period = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    stamp = float(np.hypot(PLACEMENT_SIGMA_FRACTION * period, ambiguity))
    knots = t - float(time_offset)
    if aliased and _spans_two(tracks, knots):
        return replace(fit_time_shift_averaged(tracks, knots, 0.0), stamp_sigma=stamp)
    return replace(fit_time_shift(tracks, drift=drift), stamp_sigma=stamp)


def coarse_offset(grid, misfits: Sequence[Misfit], fit: Callable, stated: float = 0.0
                  ) -> tuple[float, Callable]:
    """The grid offset of least misfit, and the clock fit stating an ambiguity if any.

    Parameters
    ----------
    grid : array_like, shape ``[offset]``
        Offsets tried, increasing [s].
    misfits : sequence of Misfit, length ``offset``
        Cost of each (:func:`clock_misfit`). Per-chirp misfits are passed over
        where some offsets have interval misfits. Where the best has no degrees of
        freedom (no frame holds three of the log's samples) no test tells the local
        minima apart, and every other one counts as fitted about as well.
    fit : callable
        The clock fit (:func:`fit_clock` with its log).
    stated : float
        Spread [s] the fit states already (its ``ambiguity``; mixed cells,
        :mod:`compensation.point_tracks`): a rival's distance replaces it only if larger.

    Returns
    -------
    offset : float
        [s].
    fit : callable
        ``fit``, with ``ambiguity`` (the distance to the farthest other offset [s])
        where the misfits do not tell the best offset from other local minima (warned).
    """
    grid = np.asarray(grid, dtype=float)
    if grid.ndim != 1 or grid.size != len(misfits) or grid.size == 0:
        raise ValueError(f"grid of shape {grid.shape} and {len(misfits)} misfits: expected "
                         "one misfit per offset, at least one")
    dof = np.array([m.dof for m in misfits])
    per_chirp = np.array([m.per_chirp for m in misfits])
    # interval misfits [rad^2/s^2] and per-chirp ones [rad^2] do not compare: where the
    # frames span two intervals at some offsets only, those offsets alone
    cost = np.array([m.cost if not m.per_chirp or per_chirp.all() else np.inf
                     for m in misfits], dtype=float)
    best = int(np.argmin(cost))
    if grid.size < 3:
        return float(grid[best]), fit
    # without degrees of freedom no test tells the minima apart: every one is a rival
    untested = dof[best] <= 0
    padded = np.concatenate([[np.inf], cost, [np.inf]])
    local = ((cost <= padded[:-2]) & (cost <= padded[2:]) & ((dof > 0) | untested)
             & np.isfinite(cost))
    far = np.abs(grid - grid[best]) > AMBIGUITY_MIN_SEPARATION
    rivals = np.flatnonzero(local & far)
    limit = np.array([np.inf if untested else fisher_f.ppf(AMBIGUITY_LEVEL, dof[r], dof[best])
                      for r in rivals])
    rivals, limit = rivals[cost[rivals] / cost[best] < limit], limit[cost[rivals] / cost[best]
                                                                      < limit]
    if rivals.size == 0:
        return float(grid[best]), fit
    # the farthest of the minima fitted about as well: the spread must reach it
    k = int(np.argmax(np.abs(grid[rivals] - grid[best])))
    other, ratio = int(rivals[k]), float(cost[rivals[k]] / cost[best])
    gap = abs(float(grid[other] - grid[best]))
    if untested:
        found = ", ".join(f"{1e3 * g:+.2f}" for g in grid[np.sort(np.append(rivals, best))])
        why = (f"the misfit has minima at {found} ms and no degrees of freedom to tell them "
               f"apart (no frame holds three of the log's samples)")
    else:
        cause = ("a vibration's period repeats within the search" if misfits[best].per_chirp
                 else "the log's averages")
        why = (f"the radar fits offsets {1e3 * grid[best]:+.2f} ms and "
               f"{1e3 * grid[other]:+.2f} ms about as well (misfit ratio {ratio:.2f}, "
               f"below {limit[k]:.2f}, the {AMBIGUITY_LEVEL:g} quantile of F"
               f"{f'; {rivals.size} such minima' if rivals.size > 1 else ''}): {cause} "
               f"leaves the offset ambiguous")
    warnings.warn(f"clock: {why}; the one at {1e3 * grid[best]:+.2f} ms is kept and its spread "
                  f"states {1e3 * gap:.2f} ms; give the offset from a time sync "
                  f"(--time-offset, docs/recordings.md)", CompensationWarning, stacklevel=2)
    return float(grid[best]), partial(fit, ambiguity=max(gap, float(stated)))
