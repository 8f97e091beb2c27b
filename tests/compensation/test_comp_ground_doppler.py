"""Ground clutter in the radar-inertial Doppler (compensation/ground_doppler.py).

Oracle point targets (exact delays) for the xWR18xx board (3 TX, TX1 raised half a
wavelength, x 4 RX, TDM): three targets in a narrow cone (azimuth 20-27 deg, elevation
-4..3 deg) inside the range window and eight ground scatterers 14 m below, beyond it,
at every 45 deg of bearing. The platform drifts at about 0.36 m/s with hover jitter.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest

from compensation.calibration import Scatterer, doppler_measurements, self_calibrate
from compensation.ground_doppler import ground_measurements, ground_scatterers
from compensation.strapdown import PlatformMotion, static_motion
from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.io.mmwave_config import ti_antenna_positions
from raysim.platform.imu import simulate_imu
from raysim.platform.kinematics import slot_times
from raysim.platform.motion import constant_velocity, hover_jitter
from raysim.processing.maps import range_compress
from raysim.radar.arrays import tdm_mimo
from raysim.radar.config import RadarConfig

CFG = RadarConfig(num_tx_slots=3, num_chirps=32, sample_rate=2.5e6, idle_time=10e-6,
                  frame_period=0.05)
LEVER = np.array([0.03, -0.02, 0.10])
#: Targets (range [m], azimuth [deg], elevation [deg]): one narrow cone.
TARGETS = ((6.0, 20.0, -4.0), (7.5, 24.0, 3.0), (9.0, 27.0, 0.0))
#: Ground 14 m below; eight scatterers 0.9 m apart in range (six cells: each its own).
HEIGHT, GROUND_RANGES = 14.0, 14.5 + 0.9 * np.arange(8)
#: Drift of the platform [m/s] and the first cell of the ground [m] (beyond the targets).
DRIFT, GROUND_FROM_M = (0.3, -0.2, 0.05), 12.0
#: Frames of the record.
FRAMES = 3
#: Every measured residual range rate lies within this many of its stated spread of
#: the closed form -u . v (Kellner et al., ITSC 2013, eq. 3-5).
SIGMAS = 3.0
#: Fewest ground scatterers the eight must give, and fewest bearing sectors (of 45 deg)
#: they span (measured: three, in three; the dense fit resolves three of the eight).
MIN_GROUND, MIN_SECTORS = 3, 3


@functools.cache
def _record():
    """(array, trajectory, range-compressed frames, slot times, IMU) of the scene."""
    tx, rx = ti_antenna_positions(CFG.center_wavelength)
    arr = tdm_mimo(tx[[0, 2, 1]], rx[[0, 1, 2, 3]], name="xWR18xx")
    traj = hover_jitter(0) + constant_velocity(list(DRIFT))
    pts = [PointTarget.at(r, np.deg2rad(a), np.deg2rad(e), radar_origin=LEVER)
           for r, a, e in TARGETS]
    bearing = (np.arange(GROUND_RANGES.size) + 0.3) * np.pi / 4
    hor = np.sqrt(GROUND_RANGES ** 2 - HEIGHT ** 2)
    ground = np.column_stack([hor * np.cos(bearing), hor * np.sin(bearing),
                              np.full(hor.size, HEIGHT)])
    pts += [PointTarget(LEVER + p, rcs_dbsm=0.0) for p in ground]
    frames = [simulate_point_targets(CFG, arr, pts, traj, lever_arm=LEVER, frame=k)
              for k in range(FRAMES)]
    imu = simulate_imu(traj, "consumer_mems", rate=1000.0, start=-0.6,
                       end=float(frames[-1].chirp_times[-1]) + 0.6, seed=0)
    rcs = [range_compress(fr.data) for fr in frames]
    times = [slot_times(fr.chirp_times, 3, CFG.slot_interval).ravel() for fr in frames]
    return arr, traj, rcs, times, imu


def _targets() -> list[Scatterer]:
    ra = CFG.range_axis()
    return [Scatterer(int(np.argmin(np.abs(ra - r))), np.deg2rad(a), np.deg2rad(e))
            for r, a, e in TARGETS]


def _ground_gates() -> np.ndarray:
    ra = CFG.range_axis()
    return np.arange(int(np.searchsorted(ra, GROUND_FROM_M)), ra.size)


def _held(traj, t) -> PlatformMotion:
    """The true attitude and angular rate at times ``t``, the body held at its first
    position: compensated with it, a stationary scatterer keeps -u . v of the body's
    true velocity ``v``."""
    return PlatformMotion(t, traj.attitude(t).as_matrix(), np.repeat(traj.position(t[:1]),
                                                                     t.size, axis=0),
                          np.zeros((t.size, 3)), traj.angular_rate(t), LEVER)


def test_ground_range_rate_is_the_velocity_along_its_direction():
    """Compensated with the body held still, every ground scatterer's residual range rate is
    -u . v of the body's true velocity, within its stated spread; the scatterers spread
    over the bearings."""
    arr, traj, rcs, times, _ = _record()
    rest = _held(traj, times[0])
    opts = dict(wavelength=CFG.center_wavelength, range_axis=CFG.range_axis())
    ground = ground_scatterers(rcs[0], arr.virtual_positions, rest, gates=_ground_gates(),
                               channel_slot=arr.tx_slot, **opts)
    assert len(ground) >= MIN_GROUND
    u = np.array([g.direction for g in ground])
    sectors = np.unique(np.floor((np.arctan2(u[:, 1], u[:, 0]) + np.pi) / (np.pi / 4)))
    assert sectors.size >= MIN_SECTORS
    meas = doppler_measurements(rcs[:1], arr.virtual_positions, [rest], _targets()[:1],
                                dict(opts, channel_slot=arr.tx_slot, method="direct"),
                                wavelength=CFG.center_wavelength)
    both = ground_measurements(meas, rcs[:1], arr.virtual_positions, [rest], ground,
                               wavelength=CFG.center_wavelength, channel_slot=arr.tx_slot)
    new = slice(meas.frame.size, None)
    assert both.frame[new].size == len(ground) * np.unique(meas.window, axis=0).shape[0]
    v = traj.velocity(both.window[new].mean(axis=1))
    truth = -np.einsum("mi,mi->m", both.directions[new], v)
    spread = np.sqrt(both.sigma[new] ** 2 + np.einsum("mi,mij,mj->m", v,
                                                      both.direction_cov[new], v))
    assert np.all(np.abs(both.range_rate[new] - truth) <= SIGMAS * spread), (
        both.range_rate[new] - truth, spread)


def _calibrate(ground_gates):
    arr, traj, rcs, times, imu = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = self_calibrate(rcs, times, arr.virtual_positions, imu.time, imu.gyro, imu.accel,
                             wavelength=CFG.center_wavelength, range_axis=CFG.range_axis(),
                             channel_slot=arr.tx_slot, scatterers=_targets(),
                             estimate=("velocity",), ground_gates=ground_gates,
                             lever_arm=LEVER, imu_grade="consumer_mems", reference_time=0.0,
                             initial_attitude=traj.attitude([0.0]).as_matrix()[0],
                             initial_position=traj.position([0.0])[0])
    rep = res.report()
    err = np.asarray(rep["initial_velocity_mps"]) - traj.velocity([0.0])[0]
    return rep, err, np.asarray(rep["initial_velocity_sigma_mps"])


def test_ground_constrains_the_velocity_across_a_narrow_cone():
    """The targets alone leave the horizontal velocity to the prior (warned); with the
    ground beyond the window every axis is constrained and within its stated spread."""
    alone, _, _ = _calibrate(None)
    assert any(w.startswith("geometry") for w in alone["warnings"])
    assert {"velocity_n", "velocity_e"} <= set(alone["unconstrained"])
    rep, err, sigma = _calibrate(_ground_gates())
    assert not any(w.startswith("geometry") for w in rep["warnings"]), rep["warnings"]
    assert not {"velocity_n", "velocity_e", "velocity_d"} & set(rep["unconstrained"])
    assert np.all(np.abs(err) <= SIGMAS * sigma), (err, sigma)
    assert any("ground scatterers" in n for n in rep["notes"])


def test_ground_scatterers_checks_its_input():
    arr, _, rcs, times, _ = _record()
    rest = static_motion(times[0], lever_arm=LEVER)
    kw = dict(wavelength=CFG.center_wavelength, range_axis=CFG.range_axis())
    assert ground_scatterers(rcs[0], arr.virtual_positions, rest, gates=None, **kw) == []
    with pytest.raises(ValueError, match="chanel_slot"):
        ground_scatterers(rcs[0], arr.virtual_positions, rest, gates=[3], chanel_slot=[0], **kw)
    with pytest.raises(ValueError, match="gates must lie"):
        ground_scatterers(rcs[0], arr.virtual_positions, rest, gates=[rcs[0].shape[2]], **kw)
    with pytest.raises(ValueError, match="count"):
        ground_scatterers(rcs[0], arr.virtual_positions, rest, gates=[3], count=-1, **kw)


def test_ground_doppler_needs_the_radar_velocity_and_the_window(tmp_path, capsys):
    """The CLI refuses --ground-doppler without --velocity radar (exit status 2, naming
    both); the stage refuses it without the compensated cells it lies beyond."""
    from raysim.cli import main
    from raysim.pipeline.self_calibration import calibrate_record

    args = ["compensate", str(tmp_path / "cube.npz"), "--imu", str(tmp_path / "imu.csv"),
            "--out", str(tmp_path / "o.zarr"), "--ground-doppler", "--velocity", "hover"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "--ground-doppler" in err and "--velocity radar" in err
    arr, _, rcs, times, imu = _record()
    with pytest.raises(ValueError, match="detect_gates"):
        calibrate_record(rcs, times, arr.virtual_positions, imu.time, imu.gyro, imu.accel,
                         wavelength=CFG.center_wavelength, range_axis=CFG.range_axis(),
                         ground_doppler=True)


def test_no_ground_beyond_the_window_is_reported():
    """With the window reaching the last cell there is no ground to add: the report says
    so instead of leaving the user to guess."""
    from raysim.pipeline.self_calibration import calibrate_record

    arr, traj, rcs, times, imu = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cal = calibrate_record(rcs, times, arr.virtual_positions, imu.time, imu.gyro,
                               imu.accel, wavelength=CFG.center_wavelength,
                               range_axis=CFG.range_axis(), estimate=("velocity",),
                               scatterers=_targets(), channel_slot=arr.tx_slot,
                               detect_gates=np.arange(CFG.range_axis().size),
                               ground_doppler=True, trajectory=traj, lever_arm=LEVER,
                               imu_grade="consumer_mems")
    assert any(n.startswith("velocity: Doppler of 0 ground scatterers")
               for n in cal.report["notes"]), cal.report["notes"]


def test_ground_measurements_stay_within_the_estimate_s_limit():
    """Where the detected scatterers' measurements leave room for fewer ground scatterers
    than found, the first ones only are added: the total stays within MAX_MEASUREMENTS."""
    from compensation.radar_inertial import MAX_MEASUREMENTS, DopplerMeasurements

    arr, traj, rcs, times, _ = _record()
    rest = _held(traj, times[0])
    opts = dict(wavelength=CFG.center_wavelength, range_axis=CFG.range_axis())
    ground = ground_scatterers(rcs[0], arr.virtual_positions, rest, gates=_ground_gates(),
                               channel_slot=arr.tx_slot, **opts)
    one = doppler_measurements(rcs[:1], arr.virtual_positions, [rest], _targets()[:1],
                               dict(opts, channel_slot=arr.tx_slot, method="direct"),
                               wavelength=CFG.center_wavelength)
    blocks = one.frame.size
    room = len(ground) - 1                     # room for all but one of them
    reps = (MAX_MEASUREMENTS - room * blocks) // blocks
    full = DopplerMeasurements(*(np.concatenate([a] * reps) for a in (
        one.directions, one.range_rate, one.sigma, one.frame, one.window,
        one.direction_cov)))
    both = ground_measurements(full, rcs[:1], arr.virtual_positions, [rest], ground,
                               wavelength=CFG.center_wavelength, channel_slot=arr.tx_slot)
    assert both.frame.size == full.frame.size + room * blocks <= MAX_MEASUREMENTS
