"""The flight controller's IMU output: boxcar gain against its closed form, intervals, gaps."""

import numpy as np
import pytest

from raysim.platform.imu import Imu
from raysim.platform.imu_output import boxcar_gain, boxcar_output, drop_gaps
from raysim.platform.motion import sinusoid

#: Relative tolerance of a trapezoid mean against its hand sum [1] (float64 rounding).
GAIN_RTOL = 1e-9


def _fast(freq=150.0, rate=1000.0, end=0.5):
    traj = sinusoid("roll", 0.002, freq)
    return Imu("ideal", rate=rate)(traj, 0.0, end, seed=0)


def test_boxcar_gain_of_a_rotor_tone_is_the_trapezoid_closed_form():
    """PX4's integrator joins the fast samples by lines: the output of a tone is the
    discrete boxcar's Dirichlet gain times cos(x), x = pi f / f_fast (the mean of the two
    rectangle rules half a fast period apart), with no delay about the interval's middle."""
    fast, rate, freq = 1000.0, 250.0, 150.0
    s = _fast(freq, fast)
    out = boxcar_output(s, rate)
    m = round(fast / rate)
    # The roll rate is A w cos(w t): its mean is the tone times the trapezoid's gain.
    x = np.pi * freq / fast
    trapezoid = abs(np.sin(m * x) / (m * np.sin(x)) * np.cos(x))
    amp_in = np.max(np.abs(s.gyro[:, 0]))
    # least-squares amplitude and phase of the output tone at the interval middles
    tc = out.time - 0.5 / rate
    basis = np.stack([np.cos(2 * np.pi * freq * tc), np.sin(2 * np.pi * freq * tc)], axis=1)
    coef, *_ = np.linalg.lstsq(basis, out.gyro[:, 0], rcond=None)
    assert np.hypot(*coef) / amp_in == pytest.approx(trapezoid, rel=1e-3)
    # in phase with the input's cosine at the middles: no delay left to the clock offset
    ref, *_ = np.linalg.lstsq(np.stack([np.cos(2 * np.pi * freq * s.time),
                                        np.sin(2 * np.pi * freq * s.time)], axis=1),
                              s.gyro[:, 0], rcond=None)
    assert np.arctan2(coef[1], coef[0]) == pytest.approx(np.arctan2(ref[1], ref[0]), abs=1e-3)
    # the continuous boxcar approximates it at 4 samples per interval within 10 %
    assert boxcar_gain(freq, rate) == pytest.approx(trapezoid, rel=0.1)


def test_boxcar_intervals_end_on_output_ticks_and_take_the_trapezoid_of_m_periods():
    s = _fast()
    out = boxcar_output(s, 250.0)
    assert np.allclose(out.time * 250.0, np.round(out.time * 250.0), atol=1e-6)
    k = int(np.searchsorted(s.time, out.time[3]))
    w = np.array([0.5, 1.0, 1.0, 1.0, 0.5]) / 4
    assert np.allclose(out.accel[3], w @ s.accel[k - 4:k + 1], rtol=GAIN_RTOL)
    assert out.rate == 250.0 and out.truth.true_time.shape == out.time.shape


def test_drop_gaps_removes_exactly_the_samples_inside_each_gap():
    out = boxcar_output(_fast(), 250.0)
    kept = drop_gaps(out, [(0.101, 0.05), (0.301, 0.065)])  # not on a stamp
    dt = np.diff(kept.time)
    assert np.sort(dt)[-2:] == pytest.approx([0.052, 0.068], abs=1e-9)
    assert kept.num_samples == out.num_samples - 12 - 16


@pytest.mark.parametrize("rate", [300.0, 0.0, np.nan])
def test_boxcar_refuses_a_rate_that_does_not_divide(rate):
    with pytest.raises(ValueError, match="rate"):
        boxcar_output(_fast(), rate)


def test_drop_gaps_refuses_a_bad_gap():
    with pytest.raises(ValueError, match=r"gaps\[0\]"):
        drop_gaps(_fast(), [(0.1, -1.0)])
