"""Must-show: a simulated flight compensated with the unknowns estimated from the radar.

Oracle point targets (exact delays), 8 x 8 array, frames of 64 chirps 50 ms apart;
consumer MEMS IMU at 1 kHz with a 3 ms clock offset; hover jitter with rotor
vibration (80-160 Hz); the initial velocity unknown (hover guess, then radar).
The initial attitude and position are those of an aligned navigation solution
(the truth at the first chirp), as in :func:`raysim.pipeline.estimate.estimate_motion`.
"""

from __future__ import annotations

import numpy as np

from compensation import rigid_body_projection
from compensation.calibration import Scatterer, self_calibrate
from compensation.multiframe import integrate_record
from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.pipeline.self_calibration import calibrate_frames
from raysim.platform.imu import simulate_imu
from raysim.platform.motion import hover_jitter
from raysim.processing import metrics
from raysim.processing.maps import Map, range_compress
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Residual pseudo-velocity of the reference target, every frame [Doppler bins].
PV_TOL_BINS = 0.05
#: Doppler power outside bins -1..+1 relative to the total, every frame [dB].
LEAKAGE_MAX_DB = -35.0
#: Single-chirp angle error, every frame [deg].
ANGLE_TOL_DEG = 0.2
#: Clock-offset error [s].
OFFSET_TOL_S = 0.5e-3

OFFSET_S = 3e-3
#: Azimuth / elevation axis of the scatterer search [rad] (coarser than the default
#: to keep the test short; detection refines to a quarter step).
DETECT_AXIS = np.deg2rad(np.arange(-45.0, 45.5, 3.0))
CFG = RadarConfig(num_chirps=64, sample_rate=2.5e6, frame_period=0.05)
ARR = upa(8, 8, wavelength=CFG.wavelength)
LEVER = np.array([0.03, -0.02, 0.10])
#: (range [m], azimuth [deg], elevation [deg]); metrics on the first.
TARGETS = ((12.0, 20.0, -10.0), (9.0, -25.0, 15.0), (15.0, 5.0, 25.0))


def _flight(seed: int, frames: int, targets=TARGETS):
    traj = hover_jitter(seed)
    pts = [PointTarget.at(r, np.deg2rad(a), np.deg2rad(e), radar_origin=LEVER)
           for r, a, e in targets]
    fr = [simulate_point_targets(CFG, ARR, pts, traj, lever_arm=LEVER, frame=k)
          for k in range(frames)]
    imu = simulate_imu(traj, "consumer_mems", rate=1000.0, start=-0.6,
                       end=float(fr[-1].chirp_times[-1]) + 0.6, seed=seed, time_offset=OFFSET_S)
    return traj, fr, imu


def _worst(rcs, motions, target=TARGETS[0]):
    """Largest |pseudo-velocity| [bins], ridge leakage [dB] and angle error [deg] over frames."""
    r0, az0, el0 = target[0], np.deg2rad(target[1]), np.deg2rad(target[2])
    gate = int(np.argmin(np.abs(CFG.range_axis() - r0)))
    kw = dict(wavelength=CFG.center_wavelength, range_axis=CFG.range_axis(),
              range_gates=[gate], grid_shape=ARR.grid_shape, method="lattice")
    az = az0 + np.deg2rad(np.arange(-10, 10.01, 0.5))
    el = el0 + np.deg2rad(np.arange(-10, 10.01, 0.5))
    ch = CFG.num_chirps // 2 - 1
    pv, leak, ang = [], [], []
    for rc, m in zip(rcs, motions, strict=True):
        b = rigid_body_projection(rc, ARR.virtual_positions, m, azimuth=[az0], elevation=[el0],
                                  **kw)
        pv.append(abs(metrics.pseudo_velocity(b.data[:, 0, 0, 0], CFG.chirp_interval,
                                              CFG.center_wavelength)) / CFG.velocity_resolution)
        d = np.abs(b.doppler()[:, 0, 0, 0].astype(complex)) ** 2
        c = d.size // 2
        leak.append(10 * np.log10(max(d.sum() - d[c - 1:c + 2].sum(), 1e-30 * d.sum())
                                  / d.sum()))
        one = rigid_body_projection(rc[ch:ch + 1], ARR.virtual_positions,
                                    m.select(slice(ch, ch + 1)), azimuth=az, elevation=el, **kw)
        pk = Map(one.chirp_power(0)[0], ("azimuth", "elevation"),
                 {"azimuth": az, "elevation": el}).peak()
        ang.append(metrics.angle_error_deg(pk["azimuth"], pk["elevation"], az0, el0))
    return max(pv), max(leak), max(ang)


def test_flight_self_calibrated_through_the_pipeline():
    """Three scatterers, six frames: every metric within the Must-show limits, which the
    same IMU log without the radar estimates (hover velocity, offset 0) misses."""
    traj, frames, imu = _flight(seed=0, frames=6)
    cal = calibrate_frames(frames, imu.time, imu.gyro, imu.accel, trajectory=traj,
                           imu_grade="consumer_mems", detect_grid=(DETECT_AXIS, DETECT_AXIS))
    assert len(cal.result.scatterers) == len(TARGETS)          # found, no sidelobe taken
    rcs = [range_compress(fr.data) for fr in frames]
    pv, leak, ang = _worst(rcs, cal.result.motions)
    assert pv <= PV_TOL_BINS
    assert leak <= LEAKAGE_MAX_DB
    assert ang <= ANGLE_TOL_DEG
    assert abs(cal.report["time_offset_s"] - OFFSET_S) <= OFFSET_TOL_S
    assert 0 < cal.report["time_offset_sigma_s"] < OFFSET_TOL_S
    v0 = traj.velocity([0.0])[0]
    sig = np.asarray(cal.report["initial_velocity_sigma_mps"])
    assert np.all(np.abs(np.asarray(cal.report["initial_velocity_mps"]) - v0) <= 0.01)
    assert np.all(sig > 0)
    assert cal.motion.num_chirps == sum(fr.data.shape[0] for fr in frames)
    init = dict(lever_arm=LEVER, initial_attitude=traj.attitude([0.0]).as_matrix()[0],
                initial_position=traj.position([0.0])[0], reference_time=0.0)
    plain = integrate_record(imu.time, imu.gyro, imu.accel, [fr.chirp_times for fr in frames],
                             imu_grade="consumer_mems", **init)
    base = _worst(rcs, plain)
    assert base[0] > PV_TOL_BINS or base[1] > LEAKAGE_MAX_DB or base[2] > ANGLE_TOL_DEG


def test_single_point_target_offset_found_by_the_coarse_search():
    """One scatterer, four frames: the 3 ms offset is beyond the linearised fit's reach
    (about 1 ms) and is found by the coarse search; the metrics hold on that target."""
    target = ((12.0, 20.0, -10.0),)
    traj, frames, imu = _flight(seed=1, frames=4, targets=target)
    rcs = [range_compress(fr.data) for fr in frames]
    gate = int(np.argmin(np.abs(CFG.range_axis() - target[0][0])))
    res = self_calibrate(rcs, [fr.chirp_times for fr in frames], ARR.virtual_positions,
                         imu.time, imu.gyro, imu.accel, wavelength=CFG.center_wavelength,
                         range_axis=CFG.range_axis(), grid_shape=ARR.grid_shape,
                         scatterers=[Scatterer(gate, np.deg2rad(20.0), np.deg2rad(-10.0))],
                         lever_arm=LEVER, imu_grade="consumer_mems", reference_time=0.0,
                         initial_attitude=traj.attitude([0.0]).as_matrix()[0],
                         initial_position=traj.position([0.0])[0])
    pv, leak, ang = _worst(rcs, res.motions, target[0])
    assert pv <= PV_TOL_BINS
    assert leak <= LEAKAGE_MAX_DB
    assert ang <= ANGLE_TOL_DEG
    assert abs(res.time_offset - OFFSET_S) <= OFFSET_TOL_S


def test_the_clock_fits_warnings_reach_the_report():
    """A log said to average over a whole frame: no frame spans two of its intervals,
    so the clock is fitted per chirp, warned; the warning is in the report's
    ``warnings`` (the store's), not only on stderr."""
    import pytest

    from compensation.guards import CompensationWarning

    target = ((12.0, 20.0, -10.0),)
    traj, frames, imu = _flight(seed=1, frames=1, targets=target)
    gate = int(np.argmin(np.abs(CFG.range_axis() - target[0][0])))
    whole_frame = CFG.num_chirps * CFG.chirp_interval
    with pytest.warns(CompensationWarning, match="no frame spans two"):
        cal = calibrate_frames(frames, imu.time, imu.gyro, imu.accel, trajectory=traj,
                               estimate=("time_offset",), imu_grade="consumer_mems",
                               scatterers=[Scatterer(gate, np.deg2rad(20.0),
                                                     np.deg2rad(-10.0))],
                               lever_arm=LEVER, imu_interval=whole_frame, offset_search=0.0)
    assert any(w.startswith("clock: no frame spans two") for w in cal.report["warnings"])
