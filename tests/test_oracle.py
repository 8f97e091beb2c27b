"""Point-target oracle against closed forms (docs/conventions.md signal model, radar equation).

Every expected value here is computed from geometry and textbook formulas, not
from the code under test.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from raysim.echoes.oracle import (
    PointTarget,
    direction,
    noise_power,
    point_target_delays,
    simulate_point_targets,
)
from raysim.platform.motion import Ramp, Trajectory, constant_velocity, sinusoid
from raysim.processing import maps as processing
from raysim.processing import metrics
from raysim.radar.arrays import ti_3tx4rx, upa
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.tones import synthesize_if, synthesize_if_direct

#: Tolerances named in the foundation acceptance criteria.
RANGE_TOL_BINS = 0.5
ANGLE_TOL_DEG = 0.2
TILT_TOL_DEG = 0.3
VELOCITY_TOL_BINS = 0.5
PLATFORM_VELOCITY_TOL_BINS = 0.25
HANN_WIDTH_BINS = 1.44
HANN_WIDTH_TOL_BINS = 0.02
#: complex64 synthesis against the complex128 reference.
SYNTH_RTOL = 2e-6
#: Radar equation amplitude at the range-FFT peak (on-bin target, window gain removed).
AMPLITUDE_TOL_DB = 0.01

AZ_GRID = np.deg2rad(np.arange(-60, 60.01, 0.25))


def peak_range_az(frame, chirp=0, el=0.0):
    rc = processing.range_compress(frame.data[chirp:chirp + 1])[0]
    m = processing.range_azimuth_map(rc, frame.array, frame.config, AZ_GRID, el=el)
    pk = m.peak()
    return pk["range"], np.rad2deg(pk["azimuth"])


def slow_time(frame, range_m, u):
    rc = processing.range_compress(frame.data)
    return processing.target_slow_time(rc, frame.array, frame.config, range_m, u)


def test_if_phase_equals_closed_form(paper_radar):
    """One chirp, one channel: s = A exp(+j 2 pi (mu tau t + f_c tau - mu tau^2 / 2))."""
    cfg = paper_radar.with_(num_chirps=2)
    arr = upa(2, 2, wavelength=cfg.wavelength)
    tgt = PointTarget.at(23.7, 0.3, -0.2, rcs_dbsm=5.0)
    frame = simulate_point_targets(cfg, arr, [tgt])
    m = 3
    q = arr.phase_centres[m]
    r = np.linalg.norm(tgt.position - q)
    tau = 2 * r / SPEED_OF_LIGHT
    mu, fc = 1e9 / 60e-6, 77e9
    t = np.arange(600) / 10e6
    pt = 10 ** (12 / 10) * 1e-3
    g = 10.0
    lam = SPEED_OF_LIGHT / fc
    amp = np.sqrt(pt * g * g * lam**2 * 10 ** 0.5 / ((4 * np.pi) ** 3 * r**4))
    expected = amp * np.exp(2j * np.pi * (mu * tau * t + fc * tau - mu * tau**2 / 2))
    np.testing.assert_allclose(frame.data[1, m], expected, rtol=SYNTH_RTOL, atol=amp * SYNTH_RTOL)


def test_fast_synthesis_equals_direct_sum(paper_radar, rng):
    cfg = paper_radar.with_(num_chirps=5)
    tau = rng.uniform(1e-8, 5e-7, size=(7, 5, 6))
    amp = rng.normal(size=(7, 5, 6)) + 1j * rng.normal(size=(7, 5, 6))
    fast = synthesize_if(tau, amp, cfg)
    ref = synthesize_if_direct(tau, amp, cfg)
    assert fast.dtype == np.complex64
    err = np.linalg.norm(fast - ref) / np.linalg.norm(ref)
    assert err < SYNTH_RTOL


def test_stationary_range_angle_velocity(paper_radar, paper_upa):
    cfg = paper_radar.with_(num_chirps=4)
    frame = simulate_point_targets(cfg, paper_upa, [PointTarget.at(15.0, np.deg2rad(20), 0.0)])
    r, az = peak_range_az(frame)
    assert abs(r - 15.0) < RANGE_TOL_BINS * cfg.range_resolution
    assert abs(az - 20.0) < ANGLE_TOL_DEG


def test_stationary_zero_velocity_and_hann_width(paper_radar, small_upa):
    frame = simulate_point_targets(paper_radar, small_upa,
                                   [PointTarget.at(15.0, np.deg2rad(20), 0.0)])
    s = slow_time(frame, 15.0, direction(np.deg2rad(20), 0.0))
    v = metrics.pseudo_velocity(s, paper_radar.chirp_interval, paper_radar.center_wavelength)
    assert abs(v) < 0.01 * paper_radar.velocity_resolution
    width_bins = metrics.doppler_mainlobe_width(s, paper_radar.chirp_interval) / (
        paper_radar.doppler_resolution)
    assert width_bins == pytest.approx(HANN_WIDTH_BINS, abs=HANN_WIDTH_TOL_BINS)


def test_moving_target_velocity(paper_radar, small_upa):
    u = direction(np.deg2rad(-15), np.deg2rad(10))
    v_radial = 3.3  # receding
    tgt = PointTarget.at(20.0, np.deg2rad(-15), np.deg2rad(10), velocity=v_radial * u)
    frame = simulate_point_targets(paper_radar, small_upa, [tgt])
    s = slow_time(frame, 20.0, u)
    v = metrics.pseudo_velocity(s, paper_radar.chirp_interval, paper_radar.center_wavelength)
    assert abs(v - v_radial) < VELOCITY_TOL_BINS * paper_radar.velocity_resolution
    # the range-Doppler map puts it in the same place
    rd = processing.range_doppler_map(processing.range_compress(frame.data), paper_radar)
    assert rd.peak()["doppler"] == pytest.approx(v_radial,
                                                 abs=VELOCITY_TOL_BINS *
                                                 paper_radar.velocity_resolution)


def test_platform_translation_gives_projected_pseudo_velocity(paper_radar, small_upa):
    az, el = np.deg2rad(10), np.deg2rad(35)
    u = direction(az, el)
    v_platform = np.array([0.4, -0.9, 0.6])
    frame = simulate_point_targets(paper_radar, small_upa, [PointTarget.at(15.0, az, el)],
                                   constant_velocity(v_platform))
    s = slow_time(frame, 15.0, u)
    v = metrics.pseudo_velocity(s, paper_radar.chirp_interval, paper_radar.center_wavelength)
    expected = -float(v_platform @ u)  # approaching the target shortens the range
    assert abs(v - expected) < PLATFORM_VELOCITY_TOL_BINS * paper_radar.velocity_resolution


@pytest.mark.parametrize("tilt_deg", [-7.0, 4.0, 12.0])
def test_tilt_about_y_shifts_azimuth(paper_radar, paper_upa, tilt_deg):
    cfg = paper_radar.with_(num_chirps=1)
    traj = Trajectory((Ramp("pitch", np.deg2rad(tilt_deg)),))
    frame = simulate_point_targets(cfg, paper_upa, [PointTarget.at(15.0, np.deg2rad(20), 0.0)],
                                   traj)
    _, az = peak_range_az(frame)
    # R_WB = Ry(tilt): the array frame sees the target at az - tilt
    assert abs(az - (20.0 - tilt_deg)) < TILT_TOL_DEG


def test_yaw_rotates_the_az_el_peak_about_boresight(paper_radar, paper_upa):
    cfg = paper_radar.with_(num_chirps=1)
    yaw = np.deg2rad(20.0)
    az0, el0 = np.deg2rad(25), np.deg2rad(25)
    frame = simulate_point_targets(cfg, paper_upa, [PointTarget.at(18.0, az0, el0)],
                                   Trajectory((Ramp("yaw", yaw),)))
    rc = processing.range_compress(frame.data)[0]
    idx = int(np.argmin(np.abs(cfg.range_axis() - 18.0)))
    grid = np.deg2rad(np.arange(0, 50.01, 0.25))
    m = processing.azimuth_elevation_map(rc[:, idx], paper_upa, cfg.center_wavelength, grid, grid)
    pk = m.peak()
    # independent prediction: u_A = Rz(yaw)^T u_W
    u_a = Rotation.from_euler("z", yaw).inv().apply(direction(az0, el0))
    az_p, el_p = np.arctan2(u_a[0], u_a[2]), np.arcsin(u_a[1])
    err = metrics.angle_error_deg(pk["azimuth"], pk["elevation"], az_p, el_p)
    assert err < TILT_TOL_DEG
    # the rotation is really visible: the peak moved far from the unrotated direction
    assert metrics.angle_error_deg(pk["azimuth"], pk["elevation"], az0, el0) > 10.0


def test_radar_equation_amplitude(paper_radar):
    cfg = paper_radar.with_(num_chirps=1)
    arr = upa(1, 1, wavelength=cfg.wavelength)
    r = 40 * cfg.range_resolution  # on a bin: no scalloping
    frame = simulate_point_targets(cfg, arr, [PointTarget.at(r, 0.0, 0.0, rcs_dbsm=0.0)])
    rc = processing.range_compress(frame.data)[0, 0]
    lam = cfg.wavelength
    pr = 10 ** (1.2 - 3) * 10 * 10 * lam**2 * 1.0 / ((4 * np.pi) ** 3 * r**4)
    got_db = 20 * np.log10(np.abs(rc[40]))
    assert got_db == pytest.approx(10 * np.log10(pr), abs=AMPLITUDE_TOL_DB)


def test_thermal_noise_power(paper_radar):
    cfg = paper_radar.with_(num_chirps=8)
    arr = upa(4, 4, wavelength=cfg.wavelength)
    tgt = PointTarget.at(10.0, 0, 0, rcs_dbsm=-200.0)  # signal far below the noise
    frame = simulate_point_targets(cfg, arr, [tgt], noise=True, seed=3)
    k_t0_f_fs = 1.380649e-23 * 290 * 10 ** 1.2 * 10e6
    measured = np.mean(np.abs(frame.data) ** 2)
    assert noise_power(cfg) == pytest.approx(k_t0_f_fs, rel=1e-12)
    assert measured == pytest.approx(k_t0_f_fs, rel=0.02)  # 76,800 samples: 0.4 % std


def test_intra_chirp_equals_stop_and_hop_without_motion(paper_radar, small_upa):
    cfg = paper_radar.with_(num_chirps=3)
    tgt = [PointTarget.at(12.0, 0.2, 0.1)]
    a = simulate_point_targets(cfg, small_upa, tgt).data
    b = simulate_point_targets(cfg, small_upa, tgt, intra_chirp=True).data
    np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-5 * np.abs(a).max())


def test_intra_chirp_range_migration_closed_form(paper_radar):
    """A target receding at v: the delay grows by 2 v t / c within the chirp."""
    cfg = paper_radar.with_(num_chirps=1)
    arr = upa(1, 1, wavelength=cfg.wavelength)
    v = 5.0
    tgt = PointTarget.at(12.0, 0.0, 0.0, velocity=(0.0, 0.0, v))
    tau, _ = point_target_delays(cfg, arr, sinusoid("x", 0.0, 1.0), [tgt], intra_chirp=True)
    t = cfg.fast_time()
    np.testing.assert_allclose(tau[0, 0, 0], 2 * (12.0 + v * t) / SPEED_OF_LIGHT, rtol=1e-12)


def test_tdm_mimo_angle_and_slot_timing():
    arr = ti_3tx4rx(RadarConfig().wavelength)
    cfg = RadarConfig(num_chirps=64, num_tx_slots=3)
    az = np.deg2rad(-12.0)
    v = 2.0
    u = direction(az, 0.0)
    frame = simulate_point_targets(cfg, arr, [PointTarget.at(9.0, az, 0.0, velocity=v * u)])
    # slot s fires s * (T_c + idle) later: its phase leads by 2 pi f_c (2 v s T_slot / c)
    tau, _ = point_target_delays(cfg, arr, Trajectory(), [PointTarget.at(9.0, az, 0.0,
                                                                         velocity=v * u)])
    dtau = tau[0, 0, 4] - tau[0, 0, 0]  # same rx, tx1 vs tx0
    p = arr.virtual_positions
    expected = (2 * v * cfg.slot_interval - u @ (p[4] - p[0])) / SPEED_OF_LIGHT
    assert dtau == pytest.approx(expected, rel=1e-6)
    # the 8-element azimuth row (tx0 and tx2) resolves the angle
    rc = processing.range_compress(frame.data)[0]
    row = np.r_[0:4, 8:12]
    sub = type(arr)(arr.tx_positions[row], arr.rx_positions[row], arr.tx_slot[row])
    idx = int(np.argmin(np.abs(cfg.range_axis() - 9.0)))
    # undo the slot-2 Doppler phase before beamforming (TDM-MIMO motion correction)
    x = rc[row, idx] * np.exp(-2j * np.pi * cfg.center_frequency * 2 * v * 2
                              * cfg.slot_interval / SPEED_OF_LIGHT * (arr.tx_slot[row] == 2))
    m = processing.azimuth_elevation_map(x, sub, cfg.center_wavelength, AZ_GRID, np.array([0.0]))
    assert abs(np.rad2deg(m.peak()["azimuth"]) + 12.0) < 1.0  # 8 elements: 14 deg beam


def test_tdm_array_requires_matching_slots():
    arr = ti_3tx4rx(RadarConfig().wavelength)
    with pytest.raises(ValueError, match="num_tx_slots"):
        simulate_point_targets(RadarConfig(num_chirps=4), arr, [PointTarget.at(9.0, 0, 0)])


def test_target_outside_range_window_is_refused(paper_radar, small_upa):
    with pytest.raises(ValueError, match="point-target range"):
        simulate_point_targets(paper_radar.with_(num_chirps=2), small_upa,
                               [PointTarget.at(95.0, 0, 0)])


def test_upa_angle_fft_peaks_at_the_direction_cosines(paper_radar, paper_upa):
    cfg = paper_radar.with_(num_chirps=1)
    az, el = np.deg2rad(25.0), np.deg2rad(-12.0)
    frame = simulate_point_targets(cfg, paper_upa, [PointTarget.at(18.0, az, el)])
    rc = processing.range_compress(frame.data)[0]
    idx = int(np.argmin(np.abs(cfg.range_axis() - 18.0)))
    power, ux, uy = processing.upa_angle_fft(rc[:, idx], paper_upa, cfg.center_wavelength,
                                             n_fft=256)
    i, j = np.unravel_index(np.argmax(power), power.shape)
    u = direction(az, el)
    # one FFT bin in direction cosine is lambda / (n_fft d) = 2 / 256
    assert abs(ux[i] - u[0]) <= 1.0 / 256 + 1e-12
    assert abs(uy[j] - u[1]) <= 1.0 / 256 + 1e-12
