"""Clock offset of a log of interval averages (compensation.clock_averaged).

A radar sees rotor vibration (124-171 Hz) the 250 Hz log holds only as the means
over its 4 ms intervals; the IMU's velocity is the cubic spline through those
means (:func:`compensation.strapdown.integrate_imu`). Closed forms: the mean of
``cos(w t + p)`` over ``[a, b]`` is ``(sin(w b + p) - sin(w a + p)) / (w (b - a))``;
the compensated phase is the spline's antiderivative.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from compensation.clock_averaged import (
    PER_CHIRP_SIGMA_FRACTION,
    PLACEMENT_SIGMA_FRACTION,
    Misfit,
    clock_misfit,
    coarse_offset,
    fit_clock,
    fit_time_shift_averaged,
    sample_rows,
)
from compensation.clock_offset import fit_time_shift, phase_misfit
from compensation.guards import CompensationWarning

#: Wavelength [m], averaging interval [s], true IMU-minus-radar offset [s].
WAVELENGTH, INTERVAL, OFFSET = 3.9e-3, 4e-3, 6.5e-3
#: Error allowed where the model is exact: the local cubic fits of the rate at the
#: interval ends and the quadrature of the phase [s].
EXACT_TOL_S = 2e-6
#: Least error of the per-chirp fit on the same tracks (the vibration the log misses
#: correlates with the spline's bending) [s]: what the interval fit removes.
PER_CHIRP_MIN_ERROR_S = 0.1e-3
#: Velocity tones per axis: sway, manoeuvre and rotor vibration through a lever arm.
FREQS_HZ = np.array([[2.1, 23.0, 131.0, 167.0], [1.3, 31.0, 143.0, 159.0],
                     [0.9, 17.0, 124.0, 171.0]])
AMPS_MPS = np.array([0.05, 0.01, 0.004, 0.003])
DIRECTIONS = np.array([[0.42, 0.0, 0.907], [-0.21, -0.08, 0.974], [0.14, 0.09, 0.987],
                       [0.0, 0.1, 0.995], [-0.4, 0.05, 0.915]])
FRAME_STARTS = 0.5 + 0.05 * np.arange(6)
CHIRPS, CHIRP_STEP = 64, 2.1e-4


def _phases(seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0, 2 * np.pi, FREQS_HZ.shape)


def _velocity(t, ph) -> np.ndarray:
    """``[time, 3]`` [m/s]."""
    w = 2 * np.pi * FREQS_HZ
    return np.stack([(AMPS_MPS * np.cos(w[i] * t[:, None] + ph[i])).sum(-1) for i in range(3)],
                    -1)


def _mean_velocity(a, b, ph) -> np.ndarray:
    """Mean over ``[a, b]`` ``[interval, 3]`` [m/s] (closed form)."""
    w = 2 * np.pi * FREQS_HZ
    return np.stack([(AMPS_MPS * (np.sin(w[i] * b[:, None] + ph[i]) - np.sin(w[i] * a[:, None]
                                                                           + ph[i]))
                      / (w[i] * (b - a)[:, None])).sum(-1) for i in range(3)], -1)


def _record(tau: float, ph, interval: float = INTERVAL, period: float | None = None):
    """IMU sample times [s, IMU clock] and the tracks compensated with the offset ``tau``:
    samples averaged over ``interval``, or with ``period`` instantaneous samples."""
    k = 4 * np.pi / WAVELENGTH
    imu_t = np.arange(0.45, 0.85, interval if period is None else period) + OFFSET
    logged = (_mean_velocity(imu_t - OFFSET - interval / 2, imu_t - OFFSET + interval / 2, ph)
              if period is None else _velocity(imu_t - OFFSET, ph))
    spline = CubicSpline(imu_t - tau, logged)
    anti = spline.antiderivative()
    u = DIRECTIONS / np.linalg.norm(DIRECTIONS, axis=1, keepdims=True)
    tracks = []
    for t0 in FRAME_STARTS:
        t = t0 + np.arange(CHIRPS) * CHIRP_STEP
        fine = np.linspace(t[0], t[-1], 8001)
        for d in u:
            rate = k * _velocity(fine, ph) @ d
            true = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1])
                                                    * np.diff(fine))])
            removed = k * (anti(t) - anti(t[0])) @ d
            tracks.append((t, np.interp(t, fine, true) - removed, k * spline(t) @ d,
                           np.ones_like(t)))
    return imu_t, tracks


def test_the_interval_fit_finds_the_offset_the_per_chirp_fit_misses():
    ph = _phases()
    imu_t, tracks = _record(OFFSET, ph)
    est = fit_time_shift_averaged(tracks, imu_t - OFFSET, INTERVAL)
    assert abs(est.offset) <= EXACT_TOL_S
    assert est.stamp_sigma == PLACEMENT_SIGMA_FRACTION * INTERVAL
    assert est.total_sigma >= est.stamp_sigma
    # the per-chirp fit on the same tracks: moved by the vibration the log misses
    assert abs(fit_time_shift(tracks).offset) >= PER_CHIRP_MIN_ERROR_S


@pytest.mark.parametrize("start_error", [-0.5e-3, 0.3e-3])
def test_two_passes_converge_from_half_a_millisecond(start_error):
    ph = _phases()
    tau = OFFSET + start_error
    for _ in range(2):
        imu_t, tracks = _record(tau, ph)
        est = fit_clock(tracks, imu_time=imu_t, time_offset=tau, interval=INTERVAL)
        tau += est.offset
        assert abs(tau - OFFSET) <= 3 * est.offset_sigma      # the fit's own spread covers it
    assert abs(tau - OFFSET) <= EXACT_TOL_S


def test_bad_input_is_named():
    ph = _phases()
    imu_t, tracks = _record(OFFSET, ph)
    with pytest.raises(ValueError, match="interval"):
        fit_clock(tracks, imu_time=imu_t, time_offset=OFFSET, interval=-1e-3)
    with pytest.raises(ValueError, match="interval"):
        fit_time_shift_averaged(tracks, imu_t - OFFSET, -1e-3)
    with pytest.raises(ValueError, match="two averaging intervals"):
        fit_time_shift_averaged(tracks, imu_t - OFFSET, 0.01)
    with pytest.raises(ValueError, match="tracks\\[0\\]"):
        fit_time_shift_averaged([(tracks[0][0], tracks[0][1][:3], tracks[0][2], None)],
                                imu_t - OFFSET, INTERVAL)


def test_instantaneous_samples_state_their_placement_over_the_sample_period():
    """A log of instantaneous samples keeps the per-chirp fit, and states the placement
    of its samples in time as the same share of its sample period (a 1 kHz log: 1/16 ms),
    apart from the fit's spread; the report's sigma holds both in quadrature."""
    ph = _phases()
    imu_t, tracks = _record(OFFSET, ph)
    period = 1e-3
    fine = np.arange(imu_t[0], imu_t[-1], period)
    est = fit_clock(tracks, imu_time=fine, time_offset=OFFSET, interval=0.0)
    ref = fit_time_shift(tracks)
    assert est.offset == ref.offset and est.offset_sigma == ref.offset_sigma
    assert est.stamp_sigma == pytest.approx(PLACEMENT_SIGMA_FRACTION * period, rel=1e-9)
    assert est.total_sigma == pytest.approx(np.hypot(ref.offset_sigma, est.stamp_sigma))


#: Averaging interval longer than half the frames (13.4 ms) [s]: no frame spans two.
LONG_INTERVAL = 8e-3
#: Stated spreads within which the fallback's offset must lie of the truth.
FALLBACK_SIGMAS = 3.0


@pytest.mark.parametrize("seed", range(4))
def test_frames_shorter_than_two_intervals_fall_back_to_the_per_chirp_fit(seed):
    """No frame spans two 8 ms intervals: the offset is the per-chirp fit's (it used to
    stop the command), warned, with 1/8 of the interval stated for the averaging's bias;
    the error lies within three of the stated spreads."""
    imu_t, tracks = _record(OFFSET, _phases(seed), LONG_INTERVAL)
    with pytest.warns(CompensationWarning, match="per chirp"):
        est = fit_clock(tracks, imu_time=imu_t, time_offset=OFFSET, interval=LONG_INTERVAL)
    assert est.stamp_sigma == PER_CHIRP_SIGMA_FRACTION * LONG_INTERVAL
    assert est.offset == fit_time_shift(tracks).offset
    assert abs(est.offset) <= FALLBACK_SIGMAS * est.total_sigma


#: A 200 Hz log's averaging interval [s]: a 13.2 ms frame spans two only at about two
#: thirds of the offsets (all frames 50 ms apart share that placement).
INTERVAL_200HZ = 5e-3
#: Start error at which no frame spans two 5 ms intervals [s].
UNSPANNED_START_S = -1.0e-3
#: Grid of the coarse offset search about the truth [s] (the calibration's step).
COARSE_GRID_S = np.arange(-6e-3, 6.1e-3, 0.5e-3)
#: Least error of the per-chirp misfit's minimum on the seed-2 tracks [s]: the aliased
#: vibration moves it by a whole vibration period.
PHASE_MISFIT_MIN_ERROR_S = 2e-3


@pytest.mark.parametrize("seed", range(4))
def test_a_frame_that_spans_two_intervals_only_at_a_nearby_offset_is_fitted_there(seed):
    """At the start offset no frame spans two 5 ms intervals (the per-chirp fallback
    moved it by 0.5-0.9 ms the wrong way): the intervals placed at the nearest offset
    where they fit give the offset to within the fit's three sigma, then exactly."""
    ph, tau = _phases(seed), OFFSET + UNSPANNED_START_S
    for one_pass in range(2):
        imu_t, tracks = _record(tau, ph, INTERVAL_200HZ)
        with warnings.catch_warnings():
            warnings.simplefilter("error", CompensationWarning)    # no per-chirp fallback
            est = fit_clock(tracks, imu_time=imu_t, time_offset=tau, interval=INTERVAL_200HZ)
        tau += est.offset
        assert abs(tau - OFFSET) <= 3 * est.offset_sigma + (EXACT_TOL_S if one_pass else 0.0)
    assert abs(tau - OFFSET) <= EXACT_TOL_S


def test_the_coarse_search_over_interval_means_is_not_moved_by_aliased_vibration():
    """The 124-171 Hz vibration through a 200 Hz log: the per-chirp phase misfit's
    minimum lies a vibration period off; the interval-mean misfit's at the truth, with
    no other minimum as good (no ambiguity warned, the fit unchanged)."""
    ph = _phases(2)
    interval_cost, phase_cost = [], []
    for d in COARSE_GRID_S:
        imu_t, tracks = _record(OFFSET + d, ph, INTERVAL_200HZ)
        interval_cost.append(clock_misfit(tracks, imu_t, OFFSET + d, INTERVAL_200HZ))
        phase_cost.append(phase_misfit(tracks))
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompensationWarning)
        found, fit = coarse_offset(OFFSET + COARSE_GRID_S, interval_cost, fit_clock)
    assert found == pytest.approx(OFFSET, abs=EXACT_TOL_S) and fit is fit_clock
    assert abs(COARSE_GRID_S[int(np.argmin(phase_cost))]) >= PHASE_MISFIT_MIN_ERROR_S
    # instantaneous samples keep the per-chirp misfit, its rows the log's samples
    m = clock_misfit(tracks, imu_t, OFFSET, 0.0)
    assert m.per_chirp and m.cost == phase_misfit(tracks)
    assert m.dof == sample_rows(tracks, imu_t - OFFSET)


#: Misfit ratios of a second minimum well inside and well outside Fisher's 95 % F
#: quantile for 15 and 15 degrees of freedom (2.40) [1].
RIVAL_RATIO_AMBIGUOUS, RIVAL_RATIO_CLEAR = 1.2, 4.0


@pytest.mark.parametrize("ratio", [RIVAL_RATIO_AMBIGUOUS, RIVAL_RATIO_CLEAR])
def test_a_second_minimum_as_good_as_the_best_is_warned_and_stated(ratio):
    """Misfit over the grid: a parabola about +3 ms and a second well at -2.5 ms whose
    floor is ``ratio`` times the best (15 degrees of freedom each): the best offset is
    kept; an ambiguous rival is warned and its distance, 5.5 ms, joins the stated
    spread in quadrature."""
    grid = np.arange(-10e-3, 10.01e-3, 0.5e-3)
    best, rival, floor = 3e-3, -2.5e-3, 6.0
    cost = np.minimum(floor + 1e7 * (grid - best) ** 2, ratio * floor + 1e7 * (grid - rival) ** 2)
    misfits = [Misfit(float(c), 15) for c in cost]
    ph = _phases()
    imu_t, tracks = _record(OFFSET, ph)
    plain = fit_clock(tracks, imu_time=imu_t, time_offset=OFFSET, interval=INTERVAL)
    if ratio == RIVAL_RATIO_CLEAR:
        with warnings.catch_warnings():
            warnings.simplefilter("error", CompensationWarning)
            found, fit = coarse_offset(grid, misfits, fit_clock)
        assert found == pytest.approx(best) and fit is fit_clock
        return
    with pytest.warns(CompensationWarning, match="ambiguous.*time sync"):
        found, fit = coarse_offset(grid, misfits, fit_clock)
    assert found == pytest.approx(best)
    est = fit(tracks, imu_time=imu_t, time_offset=OFFSET, interval=INTERVAL)
    assert est.offset == plain.offset
    assert est.stamp_sigma == pytest.approx(np.hypot(plain.stamp_sigma, best - rival))


def test_per_chirp_rows_are_the_log_samples_in_each_frame_less_its_line():
    """Two frames of three scatterers, chirps over 0-9.9 ms and 40-49.9 ms, a 1 kHz log:
    10 samples in each frame (the scatterers share them), less 2 for the line: 16 rows;
    a log of one sample per frame gives none."""
    t = np.arange(100) * 1e-4
    tracks = [(t0 + t, np.zeros(100), np.zeros(100), np.ones(100))
              for t0 in (0.0, 0.04) for _ in range(3)]
    assert sample_rows(tracks, np.arange(0.0, 0.06, 1e-3) + 0.5e-3) == 2 * (10 - 2)
    assert sample_rows(tracks, np.array([0.005, 0.045])) == 0


def test_per_chirp_minima_a_vibration_period_apart_are_warned_to_the_farthest():
    """A per-chirp misfit whose minima repeat every 7 ms (a 143 Hz vibration against a
    log that resolves it but a record too short to tell its periods apart), the three
    within 5 % of each other at 40 rows each: ambiguous, and the spread reaches the
    farthest minimum, 7 ms."""
    grid = np.arange(-10e-3, 10.01e-3, 0.5e-3)
    cost = 2.0 - np.cos(2 * np.pi * grid / 7e-3) + 0.05 * (grid / 10e-3) ** 2
    misfits = [Misfit(float(c), 40, per_chirp=True) for c in cost]
    ph = _phases()
    imu_t, tracks = _record(OFFSET, ph)
    plain = fit_clock(tracks, imu_time=imu_t, time_offset=OFFSET, interval=INTERVAL)
    with pytest.warns(CompensationWarning, match="vibration's period.*ambiguous.*7.00 ms"):
        found, fit = coarse_offset(grid, misfits, fit_clock)
    assert found == pytest.approx(0.0)
    est = fit(tracks, imu_time=imu_t, time_offset=OFFSET, interval=INTERVAL)
    assert est.stamp_sigma == pytest.approx(np.hypot(plain.stamp_sigma, 7e-3))


def test_minima_without_degrees_of_freedom_are_all_stated():
    """A 200 Hz log against 13 ms frames: no frame holds three samples, so the per-chirp
    misfit has no degrees of freedom and nothing tells its minima apart (a flight settled
    8.4 ms from the truth at a stated 0.75 ms). Minima at -10, 0 and +10 ms, the last
    the least: kept, warned, and the spread reaches the farthest, 20 ms."""
    grid = np.arange(-10e-3, 10.01e-3, 0.5e-3)
    cost = 2.0 - np.cos(2 * np.pi * grid / 10e-3) - 0.1 * grid / 10e-3
    misfits = [Misfit(float(c), 0, per_chirp=True) for c in cost]
    ph = _phases()
    imu_t, tracks = _record(OFFSET, ph)
    plain = fit_clock(tracks, imu_time=imu_t, time_offset=OFFSET, interval=INTERVAL)
    with pytest.warns(CompensationWarning, match=r"minima at -10.00, \+0.00, \+10.00 ms and no "
                      r"degrees of freedom.*\+10.00 ms is kept.*20.00 ms"):
        found, fit = coarse_offset(grid, misfits, fit_clock)
    assert found == pytest.approx(10e-3)
    est = fit(tracks, imu_time=imu_t, time_offset=OFFSET, interval=INTERVAL)
    assert est.stamp_sigma == pytest.approx(np.hypot(plain.stamp_sigma, 20e-3))


def test_a_spread_stated_already_is_kept_where_larger_than_the_rival():
    """Mixed cells state the search's half-width (10 ms): a rival 5.5 ms away does not
    narrow it; a 3 ms statement gives way to the rival's 5.5 ms."""
    grid = np.arange(-10e-3, 10.01e-3, 0.5e-3)
    best, rival, floor = 3e-3, -2.5e-3, 6.0
    cost = np.minimum(floor + 1e7 * (grid - best) ** 2,
                      RIVAL_RATIO_AMBIGUOUS * floor + 1e7 * (grid - rival) ** 2)
    misfits = [Misfit(float(c), 15) for c in cost]
    for stated, kept in ((10e-3, 10e-3), (3e-3, best - rival)):
        with pytest.warns(CompensationWarning, match="ambiguous"):
            _, fit = coarse_offset(grid, misfits, fit_clock, stated)
        assert fit.keywords["ambiguity"] == pytest.approx(kept)


def test_per_chirp_misfits_are_passed_over_where_interval_misfits_exist():
    """Misfits of the two kinds do not compare (rad^2 against rad^2/s^2): the offsets
    whose frames span two intervals alone are searched, those that do not are not."""
    grid = np.array([-1e-3, 0.0, 1e-3, 2e-3])
    misfits = [Misfit(1e-4, 9, True), Misfit(9.0, 15), Misfit(4.0, 15), Misfit(2e-4, 9, True)]
    assert coarse_offset(grid, misfits, fit_clock) == (1e-3, fit_clock)
    # per-chirp misfits alone: their least
    assert coarse_offset(grid, [Misfit(c, 0, True) for c in (3.0, 1.0, 2.0, 4.0)],
                         fit_clock)[0] == 0.0
    with pytest.raises(ValueError, match="one misfit per offset"):
        coarse_offset(grid, misfits[:3], fit_clock)


#: Period of a 250 Hz log of instantaneous samples [s]; the 124-171 Hz vibration folds.
POINT_PERIOD = 4e-3
#: Error allowed to the fit at the samples' instants [s]: its model is exact but for the
#: local cubic fits of the radar's rate and acceleration at each instant (12 chirps,
#: 2.5 ms, against a 171 Hz tone: 16 us measured), twenty times under the 0.5 ms bound.
POINT_TOL_S = 25e-6
#: Least distance of the per-chirp phase misfit's minimum from the truth on the point
#: samples [s] (1.0 ms measured): the folding moves it, not the misfit at the instants.
POINT_PHASE_MISFIT_MIN_ERROR_S = 0.5e-3


def test_instantaneous_samples_that_fold_the_vibration_are_fitted_at_their_instants():
    """A 250 Hz log of instantaneous samples: the spline through them misses the folded
    vibration; the radar's rate read at each sample's own instant against the sample
    does not (``z = phi'(x_k) = c + delta V'(x_k)``): the offset found, from the truth and
    from 0.4 ms off, and ``fit_clock(aliased=True)`` uses it, with the placement stated
    over the period."""
    ph = _phases()
    imu_t, tracks = _record(OFFSET, ph, period=POINT_PERIOD)
    est = fit_time_shift_averaged(tracks, imu_t - OFFSET, 0.0)
    assert abs(est.offset) <= POINT_TOL_S and abs(est.offset) <= 3 * est.offset_sigma
    fit = fit_clock(tracks, imu_time=imu_t, time_offset=OFFSET, aliased=True)
    assert fit.offset == est.offset
    assert fit.stamp_sigma == pytest.approx(PLACEMENT_SIGMA_FRACTION * POINT_PERIOD)
    tau = OFFSET + 0.4e-3                      # and from 0.4 ms off, in two passes
    for _ in range(2):
        imu_t, tracks = _record(tau, ph, period=POINT_PERIOD)
        tau += fit_clock(tracks, imu_time=imu_t, time_offset=tau, aliased=True).offset
    assert abs(tau - OFFSET) <= POINT_TOL_S


def test_the_coarse_search_at_the_samples_instants_is_not_moved_by_folding():
    """The same log over a coarse grid of offsets: the misfit at the samples' instants has
    its minimum at the truth, the per-chirp phase misfit's a vibration period off."""
    ph = _phases(2)
    point_cost, phase_cost = [], []
    for d in COARSE_GRID_S:
        imu_t, tracks = _record(OFFSET + d, ph, period=POINT_PERIOD)
        point_cost.append(clock_misfit(tracks, imu_t, OFFSET + d, 0.0, aliased=True))
        phase_cost.append(phase_misfit(tracks))
    assert all(m.dof > 0 for m in point_cost)
    found, _ = coarse_offset(OFFSET + COARSE_GRID_S, point_cost, fit_clock)
    assert found == pytest.approx(OFFSET, abs=EXACT_TOL_S)
    assert abs(COARSE_GRID_S[int(np.argmin(phase_cost))]) >= POINT_PHASE_MISFIT_MIN_ERROR_S


def test_the_interval_misfit_counts_a_frames_scatterers_once():
    """Tracks of one frame share the platform's error: five scatterers over the same
    intervals give the degrees of freedom of one."""
    from compensation.clock_averaged import interval_misfit

    rng = np.random.default_rng(0)
    t = np.arange(0.0, 0.0132, 1e-4)                          # a 13.2 ms frame
    knots = np.arange(-0.01, 0.03, 5e-3)                      # 5 ms averages
    one = [(t, rng.normal(size=t.size), rng.normal(size=t.size), 1.0)]
    five = one * 5
    two_frames = five + [(t + 0.04, *one[0][1:])] * 5
    k1 = interval_misfit(one, np.concatenate([knots, knots + 0.04]), 5e-3)
    k5 = interval_misfit(five, knots, 5e-3)
    k10 = interval_misfit(two_frames, np.concatenate([knots, knots + 0.04]), 5e-3)
    assert k5.dof == k1.dof and k10.dof == 2 * k1.dof
