"""Robust ingestion: IMU gaps and jitter, IMU rate against vibration, hover window by
grade, chirp times per frame; the multi-frame record API."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from compensation import CompensationWarning, integrate_imu
from compensation.ingestion import (
    GAP_LIMIT_FACTOR,
    HOVER_WINDOW_BY_GRADE,
    check_frame_times,
    vibration_band_edge,
)
from compensation.multiframe import accumulate, integrate_record, project_record
from raysim.platform.imu import simulate_imu
from raysim.platform.motion import hover_jitter, sinusoid

#: Pose agreement of a record with a dropped sample against the full record: the
#: cubic spline across a 2 ms gap on a 5 Hz motion [m] and [rad].
GAP_POSITION_TOL = 1e-6
GAP_ANGLE_TOL = 1e-6

TRAJ = sinusoid("pitch", np.deg2rad(3.0), 5.0) + sinusoid("z", 0.02, 3.0)
CHIRPS = 0.2 + np.arange(64) * 60e-6


def _imu(rate=1000.0, traj=TRAJ, end=0.5):
    s = simulate_imu(traj, "ideal", rate=rate, start=0.0, end=end)
    return s.time, s.gyro, s.accel


def _given(t, w, f, chirps=CHIRPS, **kw):
    return integrate_imu(t, w, f, chirps, velocity="given",
                         initial_velocity=TRAJ.velocity([chirps[0]])[0],
                         initial_attitude=TRAJ.attitude([chirps[0]]).as_matrix()[0],
                         initial_position=TRAJ.position([chirps[0]])[0], **kw)


def test_one_dropped_sample_is_tolerated_with_a_warning():
    t, w, f = _imu()
    full = _given(t, w, f)
    keep = np.ones(t.size, bool)
    keep[150] = False                                          # one sample lost
    with pytest.warns(CompensationWarning, match="imu gaps: 1 interval"):
        m = _given(t[keep], w[keep], f[keep])
    assert any(x.startswith("imu gaps:") for x in m.warnings)
    assert np.max(np.abs(m.position - full.position)) <= GAP_POSITION_TOL
    assert np.max(np.abs(m.euler() - full.euler())) <= GAP_ANGLE_TOL
    keep[151:153] = False                                      # now 4 intervals in a row
    with pytest.raises(ValueError, match=f"largest tolerated {GAP_LIMIT_FACTOR * 1e-3:g} s"):
        _given(t[keep], w[keep], f[keep])


def test_timestamp_jitter_is_tolerated_with_a_warning():
    """+-0.3 ms stamp jitter at 1 kHz (the spline follows the stamps) warns, no error."""
    t, w, f = _imu()
    tj = t + np.random.default_rng(0).uniform(-3e-4, 3e-4, t.size)
    with pytest.warns(CompensationWarning) as caught:
        m = _given(tj, w, f)
    assert any(str(c.message).startswith("imu jitter:") for c in caught)
    assert m.num_chirps == CHIRPS.size


def test_imu_rate_against_the_vibration_band():
    """Hover jitter with 80-160 Hz rotor vibration: 1 kHz is fine, 200 Hz is not (found in
    the data at 200 Hz, where the vibration folds onto the upper band); a stated band wins."""
    traj = hover_jitter(2)
    t, w, f = _imu(1000.0, traj)
    edge = vibration_band_edge(t, w)
    assert 80.0 <= edge <= 250.0
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompensationWarning)
        integrate_imu(t, w, f, CHIRPS)
    t2, w2, f2 = _imu(200.0, traj)
    with pytest.warns(CompensationWarning, match=r"imu rate: 200 Hz .* gyro spectrum"):
        integrate_imu(t2, w2, f2, CHIRPS)
    with pytest.warns(CompensationWarning, match=r"imu rate: 1000 Hz .*edge 500 Hz \(stated"):
        integrate_imu(t, w, f, CHIRPS, vibration_hz=500.0)


def test_hover_window_by_imu_grade():
    """Consumer MEMS: a 1 s window centred on the chirps (not the whole record)."""
    assert HOVER_WINDOW_BY_GRADE["consumer_mems"] == 1.0
    traj = sinusoid("x", 0.05, 0.3)                            # slow wander: mean velocity
    s = simulate_imu(traj, "ideal", rate=500.0, start=0.0, end=8.0)
    chirps = 4.0 + np.arange(64) * 60e-6
    whole = integrate_imu(s.time, s.gyro, s.accel, chirps)
    graded = integrate_imu(s.time, s.gyro, s.accel, chirps, imu_grade="consumer_mems")
    mid = 0.5 * (chirps[0] + chirps[-1])
    lo, hi = mid - 0.5, mid + 0.5                              # the window itself
    explicit = integrate_imu(s.time, s.gyro, s.accel, chirps, hover_window=(lo, hi))
    np.testing.assert_array_equal(graded.velocity, explicit.velocity)
    assert not np.array_equal(graded.velocity, whole.velocity)
    with pytest.raises(ValueError, match="imu_grade must be one of"):
        integrate_imu(s.time, s.gyro, s.accel, chirps, imu_grade="navigation")


def test_chirp_times_uniform_within_each_frame():
    f0 = np.arange(16) * 1e-4
    frames = check_frame_times([f0, f0 + 0.05])               # idle time between frames
    assert len(frames) == 2
    bad = f0.copy()
    bad[9:] += 3e-5
    with pytest.raises(ValueError, match=r"chirp_times\[1\] are not uniform within a frame: "
                                         r"interval 8"):
        check_frame_times([f0, bad + 0.05])
    with pytest.raises(ValueError, match="not after the previous frame"):
        check_frame_times([f0, f0])
    t, w, f = _imu()
    with pytest.raises(ValueError, match="not uniform within a frame"):
        integrate_imu(t, w, f, [bad + 0.1])


def test_record_is_one_integration_split_per_frame():
    """Frames given separately equal the same chirps integrated at once; accumulation adds
    the frames' zero-Doppler powers."""
    t, w, f = _imu()
    frames = [0.1 + np.arange(32) * 60e-6, 0.2 + np.arange(32) * 60e-6]
    per = integrate_record(t, w, f, frames, velocity="given", initial_velocity=np.zeros(3))
    one = integrate_imu(t, w, f, np.concatenate(frames), velocity="given",
                        initial_velocity=np.zeros(3))
    np.testing.assert_array_equal(np.concatenate([m.position for m in per]), one.position)
    rng = np.random.default_rng(0)
    pos = np.column_stack([np.arange(4) * 2e-3, np.zeros(4), np.zeros(4)])
    rcs = [rng.normal(size=(32, 4, 3)) + 1j * rng.normal(size=(32, 4, 3)) for _ in frames]
    beams = project_record(rcs, pos, per, wavelength=3.9e-3, range_axis=[1.0, 2.0, 3.0],
                           azimuth=[0.0, 0.1], elevation=[0.0], method="direct")
    acc = accumulate(beams, window=None)
    np.testing.assert_allclose(acc, beams[0].coherent_power() + beams[1].coherent_power(),
                               rtol=1e-12)


#: Six 13.2 ms frames every 50 ms from 0.5 s (IMU clock) and a 1 kHz log.
GAP_SPANS = [(0.5 + 0.05 * k, 0.5132 + 0.05 * k) for k in range(6)]
GAP_STEP = 1e-3


def test_gap_segments_split_the_frames_at_each_filled_gap():
    from compensation.ingestion import gap_segments

    # a gap over frames 3 and 4: before it, in it, after it
    over = np.arange(0.628, 0.716, GAP_STEP)
    assert gap_segments(over, GAP_SPANS, GAP_STEP) == [([0, 1, 2], False), ([3, 4], True),
                                                       ([5], False)]
    # a gap between frames 0 and 1 touches neither: two runs, none in a gap
    between = np.arange(0.521, 0.540, GAP_STEP)
    assert gap_segments(between, GAP_SPANS, GAP_STEP) == [([0], False), ([1, 2, 3, 4, 5], False)]
    # two gaps: each splits, frames in different gaps are different runs
    two = np.concatenate([np.arange(0.521, 0.540, GAP_STEP), np.arange(0.655, 0.66, GAP_STEP)])
    assert gap_segments(two, GAP_SPANS, GAP_STEP) == [([0], False), ([1, 2], False),
                                                      ([3], True), ([4, 5], False)]
    # none: one run of every frame; a frame within the slack of a gap counts as in it
    assert gap_segments([], GAP_SPANS, GAP_STEP) == [(list(range(6)), False)]
    near = np.arange(0.631, 0.6475, GAP_STEP)               # ends 1.5 ms before frame 3
    assert gap_segments(near, GAP_SPANS, GAP_STEP)[1] == ([3, 4, 5], False)
    assert gap_segments(near, GAP_SPANS, GAP_STEP, slack=2e-3)[1] == ([3], True)
