"""IMU simulation: truth sampling, strapdown consistency, error models, validation."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from raysim.platform.imu import (
    CONSUMER_MEMS,
    DEG,
    FOOT,
    HOUR,
    IDEAL,
    MICRO_G,
    PRESETS,
    SQRT_HOUR,
    STANDARD_GRAVITY,
    TACTICAL,
    Imu,
    ImuSamples,
    ImuSpec,
    SensorErrors,
    allan_deviation,
    get_preset,
    simulate_imu,
)
from raysim.platform.motion import Ramp, Sinusoid, Trajectory, hover_jitter, sinusoid, stationary

#: Ideal samples vs closed-form truth [rad/s], [m/s^2] (pure float round-off).
IDEAL_ATOL = 1e-12
#: Reference strapdown over one 256 x 60 us frame at 10 kHz: attitude error [rad]
#: (the 80-160 Hz rotor vibration of the hover jitter dominates; second-order
#: integration, so the tolerances scale with (10 kHz / rate)^2).
STRAPDOWN_ATT_TOL = 2e-6
#: ... velocity error [m/s].
STRAPDOWN_VEL_TOL = 1.5e-7
#: ... position error [m] (1e-9 m is 3e-7 wavelengths at 77 GHz).
STRAPDOWN_POS_TOL = 1e-9
#: Relative tolerance of the measured Allan deviation at tau = 1 s vs the spec.
ADEV_RTOL = 0.10
#: Relative tolerance of the bias-instability plateau vs the model.
PLATEAU_RTOL = 0.15
#: Relative tolerance of Monte-Carlo spreads of turn-on draws vs their sigma.
DRAW_RTOL = 0.15

G_W = np.array([0.0, 0.0, STANDARD_GRAVITY])
FRAME_DURATION = 256 * 60e-6


def dynamic_trajectory() -> Trajectory:
    """Hover jitter plus large, fast attitude and translation terms."""
    extra = Trajectory((
        Sinusoid("roll", 5 * DEG, 3.0, 0.3), Sinusoid("pitch", 4 * DEG, 2.0, 1.1),
        Sinusoid("yaw", 10 * DEG, 1.5, -0.4), Sinusoid("x", 0.2, 1.0, 0.2),
        Sinusoid("z", 0.05, 4.0), Ramp("y", 0.0, 1.5, 0.8),
    ))
    return hover_jitter(7) + extra


def ref_specific_force(traj: Trajectory, t: np.ndarray) -> np.ndarray:
    """``f_B = R_WB^T (a_W - g_W)`` with R_WB built from the Z-Y-X Euler matrices."""
    eul = traj.euler(t)  # yaw, pitch, roll
    out = np.empty((t.size, 3))
    for i, (psi, th, ph) in enumerate(eul):
        cz, sz, cy, sy, cx, sx = (np.cos(psi), np.sin(psi), np.cos(th), np.sin(th),
                                  np.cos(ph), np.sin(ph))
        rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
        ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
        out[i] = (rz @ ry @ rx).T @ (traj.acceleration(t[i:i + 1])[0] - G_W)
    return out


def ref_strapdown(t, gyro, accel, r0: Rotation, v0, p0):
    """Reference strapdown in W (NED, flat, non-rotating earth).

    Attitude: ``R_{k+1} = R_k exp(theta)``, ``theta`` the trapezoidal rotation
    vector plus the coning term ``(w_k x w_{k+1}) dt^2 / 12``. Velocity: trapezoid
    of ``R f + g``. Position: Simpson-like ``p += (v_k + v_{k+1}) dt / 2 +
    (a_k - a_{k+1}) dt^2 / 12`` (exact for cubic position).
    """
    rots = [r0]
    for k in range(t.size - 1):
        dt = t[k + 1] - t[k]
        theta = 0.5 * (gyro[k] + gyro[k + 1]) * dt + np.cross(gyro[k], gyro[k + 1]) * dt**2 / 12
        rots.append(rots[-1] * Rotation.from_rotvec(theta))
    rot = Rotation.concatenate(rots)
    acc_w = rot.apply(accel) + G_W
    v = np.empty_like(acc_w)
    p = np.empty_like(acc_w)
    v[0], p[0] = v0, p0
    for k in range(t.size - 1):
        dt = t[k + 1] - t[k]
        v[k + 1] = v[k] + 0.5 * (acc_w[k] + acc_w[k + 1]) * dt
        p[k + 1] = p[k] + 0.5 * (v[k] + v[k + 1]) * dt + (acc_w[k] - acc_w[k + 1]) * dt**2 / 12
    return rot, v, p


# ------------------------------------------------------------------ ideal / truth
def test_ideal_gyro_equals_trajectory_rate():
    traj = dynamic_trajectory()
    s = simulate_imu(traj, "ideal", rate=5000.0, start=0.0, end=FRAME_DURATION)
    np.testing.assert_allclose(s.gyro, traj.angular_rate(s.time), rtol=0, atol=IDEAL_ATOL)
    assert s.gyro.shape == (s.num_samples, 3) and s.accel.shape == (s.num_samples, 3)


def test_ideal_accel_equals_closed_form_specific_force():
    traj = dynamic_trajectory()
    s = simulate_imu(traj, IDEAL, rate=2000.0, start=0.0, end=FRAME_DURATION)
    np.testing.assert_allclose(s.accel, ref_specific_force(traj, s.time), rtol=0,
                               atol=IDEAL_ATOL)


def test_level_rest_reads_minus_g():
    s = simulate_imu(stationary(), "ideal", rate=100.0, start=0.0, end=0.1)
    np.testing.assert_array_equal(s.accel, np.tile([0.0, 0.0, -STANDARD_GRAVITY], (11, 1)))
    np.testing.assert_array_equal(s.gyro, 0.0)


@pytest.mark.parametrize("rate", [2000.0, 10000.0])
def test_ideal_strapdown_reproduces_truth_over_one_frame(rate):
    traj = dynamic_trajectory()
    s = simulate_imu(traj, "ideal", rate=rate, start=0.0, end=FRAME_DURATION)
    t = s.time
    rot, v, p = ref_strapdown(t, s.gyro, s.accel, traj.attitude(t[:1])[0],
                              traj.velocity(t[:1])[0], traj.position(t[:1])[0])
    att_err = (traj.attitude(t) * rot.inv()).magnitude()
    # second-order integration: global errors scale as dt^2
    scale = (10000.0 / rate) ** 2
    assert att_err.max() < STRAPDOWN_ATT_TOL * scale
    assert np.abs(v - traj.velocity(t)).max() < STRAPDOWN_VEL_TOL * scale
    assert np.abs(p - traj.position(t)).max() < STRAPDOWN_POS_TOL * scale
    # the motion is not trivial: the attitude changes by far more than the tolerance
    assert (traj.attitude(t[-1:]) * traj.attitude(t[:1]).inv()).magnitude()[0] > 1e-3


# ------------------------------------------------------------------------ clock
def test_samples_on_imu_clock_with_offset_and_drift():
    traj = dynamic_trajectory()
    imu = Imu("ideal", rate=1000.0, time_offset=0.0123, clock_drift_ppm=50.0)
    s = imu(traj, start=0.0, end=0.2)
    # time stamps are whole IMU-clock ticks
    np.testing.assert_allclose(s.time * 1000.0, np.round(s.time * 1000.0), atol=1e-9)
    t_true = (s.time - 0.0123) / (1 + 50e-6)
    np.testing.assert_allclose(s.truth.true_time, t_true, rtol=0, atol=1e-15)
    assert t_true[0] >= 0.0 and t_true[-1] <= 0.2
    assert t_true[0] < 1e-3 and t_true[-1] > 0.2 - 1e-3
    np.testing.assert_allclose(s.gyro, traj.angular_rate(t_true), rtol=0, atol=IDEAL_ATOL)
    np.testing.assert_allclose(imu.to_true_time(imu.to_imu_time(0.05)), 0.05, atol=1e-15)


def test_to_arrays_gives_plain_writable_copies():
    s = simulate_imu(sinusoid("pitch", 0.01, 2.0), "tactical", rate=500.0, start=0.0,
                     end=0.1, seed=3)
    t, w, f = s.to_arrays()
    assert all(type(a) is np.ndarray and a.flags.writeable for a in (t, w, f))
    t[0] = -1.0
    assert s.time[0] != -1.0
    np.testing.assert_allclose(s.mean_rate, 500.0)
    assert s.rate == 500.0


# ------------------------------------------------------------------ error models
def _stationary_record(spec: ImuSpec, rate: float, duration: float, seed: int) -> ImuSamples:
    return simulate_imu(stationary(), spec, rate=rate, start=0.0, end=duration, seed=seed)


def _pooled_adev(x: np.ndarray, rate: float, tau) -> np.ndarray:
    """Allan deviation pooled over the three axes (mean Allan variance)."""
    return np.sqrt(np.mean(allan_deviation(x, rate, tau) ** 2, axis=-1))


@pytest.mark.parametrize("name", ["tactical", "consumer_mems"])
def test_white_noise_matches_arw_vrw(name):
    spec = get_preset(name)
    rate = 200.0
    s = _stationary_record(spec, rate, 1800.0, seed=11)
    gyro_adev = _pooled_adev(s.gyro, rate, [1.0])[0]
    accel_adev = _pooled_adev(s.accel, rate, [1.0])[0]
    # datasheet ARW / VRW (white part dominates at tau = 1 s)
    assert gyro_adev == pytest.approx(spec.gyro.noise_density, rel=ADEV_RTOL)
    assert accel_adev == pytest.approx(spec.accel.noise_density, rel=ADEV_RTOL)
    # and the full model (white + bias instability + quantisation)
    assert gyro_adev == pytest.approx(spec.gyro.allan_deviation(1.0, rate), rel=ADEV_RTOL)
    assert accel_adev == pytest.approx(spec.accel.allan_deviation(1.0, rate), rel=ADEV_RTOL)


@pytest.mark.parametrize("name", ["tactical", "consumer_mems"])
def test_bias_instability_plateau(name):
    spec = get_preset(name)
    # quantisation switched off: at this low rate it would not be dithered by the noise
    gyro = dataclasses.replace(spec.gyro, resolution=0.0, full_scale=math.inf)
    accel = dataclasses.replace(spec.accel, resolution=0.0, full_scale=math.inf)
    spec = dataclasses.replace(spec, gyro=gyro, accel=accel)
    rate = 2.0
    tc = spec.gyro.bias_correlation_time
    tau_peak = 1.89 * tc
    s = _stationary_record(spec, rate, 120.0 * tau_peak, seed=5)
    for meas, err in ((s.gyro, spec.gyro), (s.accel, spec.accel)):
        got = _pooled_adev(meas, rate, [tau_peak])[0]
        assert got == pytest.approx(err.allan_deviation(tau_peak, rate)[()], rel=PLATEAU_RTOL)
        # with the white noise removed the plateau is the datasheet bias instability
    quiet = dataclasses.replace(spec.gyro, noise_density=0.0)
    s = _stationary_record(dataclasses.replace(spec, gyro=quiet), rate, 120.0 * tau_peak, 6)
    got = _pooled_adev(s.gyro, rate, [tau_peak])[0]
    assert got == pytest.approx(spec.gyro.bias_instability, rel=PLATEAU_RTOL)


def test_allan_deviation_matches_direct_definition():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(257)
    rate = 10.0
    for m in (1, 3, 17, 128):
        theta = np.concatenate([[0.0], np.cumsum(x)]) / rate
        terms = [(theta[k + 2 * m] - 2 * theta[k + m] + theta[k]) ** 2
                 for k in range(theta.size - 2 * m)]
        ref = math.sqrt(sum(terms) / len(terms) / (2 * (m / rate) ** 2))
        assert allan_deviation(x, rate, [m / rate])[0] == pytest.approx(ref, rel=1e-12)


def test_fixed_misalignment_and_scale_factor_on_known_rate():
    # constant yaw rate with level attitude: omega_B = (0, 0, 0.5) rad/s
    traj = Trajectory((Ramp("yaw", 0.0, 0.5),))
    m = np.array([[1.001, 2e-3, -1e-3],
                  [0.5e-3, 0.998, 3e-3],
                  [-2e-3, 1e-3, 1.0005]])
    s = Imu("ideal", rate=100.0)(traj, 0.0, 1.0, gyro_matrix=m, accel_matrix=m.T)
    np.testing.assert_allclose(s.gyro, np.tile(m[:, 2] * 0.5, (s.num_samples, 1)),
                               rtol=0, atol=IDEAL_ATOL)
    np.testing.assert_allclose(s.accel, np.tile(m.T[:, 2] * -STANDARD_GRAVITY,
                                                (s.num_samples, 1)), rtol=0, atol=IDEAL_ATOL)
    np.testing.assert_array_equal(s.truth.gyro_matrix, m)


def test_random_misalignment_and_scale_factor_statistics():
    err = SensorErrors(scale_factor_sigma=300 * 1e-6, misalignment_sigma=1e-3)
    spec = ImuSpec("sf_mis", gyro=err, accel=err)
    traj = Trajectory((Ramp("roll", 0.0, 0.2), Ramp("pitch", 0.0, -0.1), Ramp("yaw", 0.0, 0.3)))
    diag, off = [], []
    for seed in range(400):
        s = simulate_imu(traj, spec, rate=50.0, start=0.0, end=0.1, seed=seed)
        m = s.truth.gyro_matrix
        np.testing.assert_allclose(s.gyro, traj.angular_rate(s.time) @ m.T, rtol=0,
                                   atol=IDEAL_ATOL)
        diag.append(np.diag(m) - 1.0)
        off.append(m[~np.eye(3, dtype=bool)])
    assert np.std(diag) == pytest.approx(300e-6, rel=DRAW_RTOL)
    assert np.std(off) == pytest.approx(1e-3, rel=DRAW_RTOL)


def test_turn_on_bias_statistics_and_override():
    spec = ImuSpec("bias", gyro=SensorErrors(bias_sigma=0.01), accel=SensorErrors(bias_sigma=0.2))
    b = np.array([simulate_imu(stationary(), spec, rate=10.0, start=0.0, end=0.2,
                               seed=k).gyro[0] for k in range(400)])
    assert np.std(b) == pytest.approx(0.01, rel=DRAW_RTOL)
    s = Imu(spec, rate=10.0)(stationary(), 0.0, 1.0, gyro_turn_on_bias=[1e-3, -2e-3, 3e-3],
                             accel_turn_on_bias=[0.1, 0.0, 0.0])
    np.testing.assert_allclose(s.gyro, np.tile([1e-3, -2e-3, 3e-3], (11, 1)), atol=IDEAL_ATOL)
    np.testing.assert_allclose(s.accel[0], [0.1, 0.0, -STANDARD_GRAVITY], atol=IDEAL_ATOL)
    np.testing.assert_allclose(s.truth.gyro_bias, s.gyro, atol=IDEAL_ATOL)


def test_bias_random_walk_growth():
    k = 1e-4  # rad/s/sqrt(s)
    spec = ImuSpec("rw", gyro=SensorErrors(bias_random_walk=k))
    finals = np.array([simulate_imu(stationary(), spec, rate=100.0, start=0.0, end=100.0,
                                    seed=s).gyro[-1] for s in range(60)])
    assert np.std(finals) == pytest.approx(k * math.sqrt(100.0), rel=DRAW_RTOL)


def test_quantisation_and_saturation():
    traj = sinusoid("roll", 1.0, 5.0)  # peak rate 2 pi 5 = 31 rad/s
    err = SensorErrors(noise_density=1e-3, resolution=1e-2, full_scale=20.0)
    s = simulate_imu(traj, ImuSpec("q", gyro=err), rate=1000.0, start=0.0, end=0.5, seed=2)
    np.testing.assert_allclose(s.gyro / 1e-2, np.round(s.gyro / 1e-2), atol=1e-9)
    assert np.abs(s.gyro).max() == pytest.approx(20.0)


def test_seeded_runs_are_reproducible_and_independent():
    traj = dynamic_trajectory()
    a = simulate_imu(traj, "consumer_mems", rate=1000.0, start=0.0, end=0.05, seed=42)
    b = simulate_imu(traj, "consumer_mems", rate=1000.0, start=0.0, end=0.05, seed=42)
    c = simulate_imu(traj, "consumer_mems", rate=1000.0, start=0.0, end=0.05, seed=43)
    np.testing.assert_array_equal(a.gyro, b.gyro)
    np.testing.assert_array_equal(a.accel, b.accel)
    assert not np.array_equal(a.gyro, c.gyro)
    g = simulate_imu(traj, "consumer_mems", rate=1000.0, start=0.0, end=0.05,
                     seed=np.random.default_rng(1))
    assert g.truth.seed is None


# ------------------------------------------------------------------ presets
def test_presets_carry_datasheet_figures():
    assert set(PRESETS) >= {"ideal", "tactical", "consumer_mems"}
    assert IDEAL.gyro.is_ideal and IDEAL.accel.is_ideal
    # HG1700: 0.125 deg/sqrt(h) = 3.636e-5 rad/sqrt(s); 1 deg/h = 4.848e-6 rad/s
    assert TACTICAL.gyro.noise_density == pytest.approx(3.6361e-5, rel=1e-4)
    assert TACTICAL.gyro.bias_instability == pytest.approx(4.8481e-6, rel=1e-4)
    assert TACTICAL.accel.noise_density == pytest.approx(0.065 * FOOT / 60.0)
    # BMI088: 0.014 deg/s/sqrt(Hz); 160 ug/sqrt(Hz)
    assert CONSUMER_MEMS.gyro.noise_density == pytest.approx(2.4435e-4, rel=1e-4)
    assert CONSUMER_MEMS.accel.noise_density == pytest.approx(160 * MICRO_G)
    assert CONSUMER_MEMS.gyro.bias_instability == pytest.approx(2 * DEG / HOUR)
    assert SQRT_HOUR == 60.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        TACTICAL.gyro.noise_density = 0.0  # type: ignore[misc]


# ------------------------------------------------------------------ validation
@pytest.mark.parametrize("rate", [0.0, -10.0, float("nan"), float("inf")])
def test_bad_rate_raises(rate):
    with pytest.raises(ValueError, match="rate"):
        Imu("ideal", rate=rate)


def test_unknown_preset_names_value_and_options():
    with pytest.raises(ValueError, match=r"'navigation'.*consumer_mems.*ideal.*tactical"):
        Imu("navigation", rate=100.0)
    with pytest.raises(ValueError, match="valid presets"):
        get_preset("Tactical")


@pytest.mark.parametrize("kwargs, match", [
    ({"start": float("nan"), "end": 1.0}, "start"),
    ({"start": 0.0, "end": float("nan")}, "end"),
    ({"start": 1.0, "end": 0.0}, "precede"),
    ({"start": 0.0011, "end": 0.0012}, "no IMU sample"),
])
def test_bad_interval_raises(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Imu("ideal", rate=100.0)(stationary(), **kwargs)


@pytest.mark.parametrize("field, value", [
    ("noise_density", -1.0), ("bias_sigma", float("nan")), ("bias_correlation_time", 0.0),
    ("resolution", -1e-3), ("full_scale", 0.0),
])
def test_bad_sensor_errors_raise(field, value):
    with pytest.raises(ValueError, match=field):
        SensorErrors(**{field: value})


def test_bad_overrides_and_clock_raise():
    imu = Imu("ideal", rate=100.0)
    with pytest.raises(ValueError, match="gyro_matrix"):
        imu(stationary(), 0.0, 1.0, gyro_matrix=np.eye(2))
    with pytest.raises(ValueError, match="accel_turn_on_bias"):
        imu(stationary(), 0.0, 1.0, accel_turn_on_bias=[0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="clock_drift_ppm"):
        Imu("ideal", rate=100.0, clock_drift_ppm=float("nan"))
    with pytest.raises(ValueError, match="seed"):
        imu(stationary(), 0.0, 1.0, seed=-1)
    with pytest.raises(ValueError, match="strictly increasing"):
        ImuSamples(np.array([0.0, 0.0]), np.zeros((2, 3)), np.zeros((2, 3)))
