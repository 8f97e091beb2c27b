"""The compensation chain of a forward-mounted radar, motion by motion.

One forward flight (consumer MEMS IMU, no clutter) compensated by ``raysim compensate``
with the motion of its frames replaced: the truth, the IMU's attitude with the true
translation, the truth with a known velocity error, and the IMU's own with the true
initial velocity. The mounting and the attitude chain restore the targets; what moves
them is a radar velocity error, by the azimuth shift of
:func:`compensation.azimuth_shift.azimuth_shift`, which a self-calibrated run measures
at its scatterers and warns of. Ground clutter in a target's range cell moves it too,
with the true motion.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import raysim.pipeline.compensate as stage
from compensation import PlatformMotion
from compensation.azimuth_shift import azimuth_shift
from compensation.geometry import direction
from raysim.cli import main
from raysim.io.mmwave_config import read_mmwave_config
from raysim.io.zarr_store import open_store
from raysim.measure.beams import beam_metrics
from raysim.pipeline.flight import TARGET_RANGE_HALF_WIDTH_CELLS, write_flight
from raysim.platform.motion import hover_jitter
from raysim.platform.mounting import mounting_matrix

#: Seed of the flight: the worst of seeds 1-4 with the true initial velocity given.
SEED = 3
#: Stationary targets (range [m], azimuth [deg], elevation [deg] in N).
TARGETS = [(6.0, -20.0, -6.0), (7.5, 18.0, 6.0), (9.0, 2.0, -12.0)]
#: The project's bound on a target's beam angle error [deg] and residual
#: pseudo-velocity [Doppler bins] (measured with the true motion: 0.056 deg, 0.002 bin;
#: with the IMU's attitude and the true translation 0.09 deg, 0.004 bin).
ANGLE_TOL_DEG = 0.2
PSEUDO_VELOCITY_BINS = 0.05
#: A velocity error put on the true motion [m/s]: along the forward boresight (W north).
VELOCITY_ERROR = np.array([0.01, 0.0, 0.0])
#: The azimuth shift it leaves, against the closed form, within this fraction of the
#: closed form (second order about the peak, the cross-range velocity averaged over the
#: frame: measured within 0.25) and this much [deg] (the peak's own interpolation on
#: the 0.5 deg grid: the true motion's error is 0.03-0.06 deg).
SHIFT_REL_TOL = 0.3
SHIFT_ABS_TOL_DEG = 0.03
#: Range cells, azimuth and elevation grid of the compensated beams.
GRID = ("--range-m", "5.5:9.5", "--az-deg", "-30:30:0.5", "--el-deg", "-12:6:6",
        "--no-progress")
#: Seed of a flight whose ground clutter shares the first target's range cell.
CLUTTER_SEED = 1
#: The stage's own motions (the IMU's), whatever a test put in their place.
IMU_MOTIONS = stage._motions


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    return write_flight(tmp_path_factory.mktemp("fwd") / "f", frames=2, targets=TARGETS,
                        mounting_deg="forward", time_offset=0.003, seed=SEED)


def _truth(times, lever, origin, seed=SEED):
    """The true motion at ``times`` [s], positions from ``origin`` [m]."""
    traj = hover_jitter(seed)
    pos, rot = traj.pose(times)
    return PlatformMotion(times, rot.as_matrix(), pos - origin, traj.velocity(times),
                          traj.angular_rate(times), np.asarray(lever, dtype=float))


def _measure(flight, out):
    """Signed azimuth error [target, frame] [deg] and pseudo-velocity [bins] of a store."""
    ds = open_store(out)
    cfg = read_mmwave_config(flight.radar_config).config
    ranges, els = ds["range"].values, ds["elevation"].values
    err, pv = [], []
    for j, (r, _, _) in enumerate(flight.targets):
        az, el = flight.apparent_direction(0, j)
        cells = np.flatnonzero(np.abs(ranges - r)
                               <= TARGET_RANGE_HALF_WIDTH_CELLS * cfg.range_resolution)
        rows = [beam_metrics(b, ds.azimuth.values, -1e3, chirp_interval=cfg.chirp_interval,
                             wavelength=cfg.center_wavelength,
                             velocity_resolution=cfg.velocity_resolution)
                for b in ds["beams"].values[..., int(np.argmin(np.abs(els - el)))][:, :, cells]]
        err.append([m["beam_angle_error_deg"] - 1e3 - az for m in rows])   # signed
        pv.append([m["beam_pseudo_velocity_bins"] for m in rows])
    return np.array(err), np.array(pv)


def _compensate(flight, out, monkeypatch, pick, seed=SEED):
    """Compensate ``flight`` with every frame's motion ``pick(imu_motion, truth)``;
    returns the signed azimuth error [target, frame] [deg], the pseudo-velocity
    [target, frame] [bins] and the stage's input."""
    seen = {}

    def motions(inp, imu, rcs, **kw):
        ms, cal, offset = IMU_MOTIONS(inp, imu, rcs, **kw)
        t0 = inp.slot_times[0].ravel()[0]
        origin = hover_jitter(seed).position(np.array([t0]))[0]
        seen["inp"] = inp
        return [pick(m, _truth(m.time, kw["lever_arm"], origin, seed)) for m in ms], cal, offset

    monkeypatch.setattr(stage, "_motions", motions)
    assert main(flight.command(out, *GRID)) == 0
    return (*_measure(flight, out), seen["inp"])


def _predicted(flight, inp, used, truth):
    """Closed-form azimuth shift [target, frame] [deg] of the velocity error ``truth`` minus
    ``used`` (lists of per-frame motions), averaged over each frame."""
    m = mounting_matrix(flight.mounting_deg)
    out = np.zeros((len(flight.targets), len(used)))
    for k, (mu, mt) in enumerate(zip(used, truth, strict=True)):
        dv = (mt.radar_velocity - mu.radar_velocity).mean(axis=0)            # W [m/s]
        times = inp.slot_times[k][:, inp.tx_slot]                             # [chirp, channel]
        for j, (_, az, el) in enumerate(flight.targets):
            a, e = np.deg2rad(az), np.deg2rad(el)
            u = m @ direction(a, e)
            across = m @ np.array([np.cos(a), 0.0, -np.sin(a)])      # increasing azimuth
            v = float(mt.radar_velocity.mean(axis=0) @ across)
            out[j, k] = np.rad2deg(azimuth_shift(u @ dv, v, inp.element_positions[:, 0],
                                                 times, e))
    return out


def test_true_motion_restores_the_forward_targets(flight, tmp_path, monkeypatch):
    """The mounting (``R_BA`` on the element positions, the motion in N, the targets'
    directions in N) with the true motion: every target within the bounds."""
    err, pv, _ = _compensate(flight, tmp_path / "t.zarr", monkeypatch, lambda m, t: t)
    assert np.all(np.abs(err) <= ANGLE_TOL_DEG), err
    assert np.all(np.abs(pv) <= PSEUDO_VELOCITY_BINS), pv


def test_imu_attitude_with_the_true_translation_restores_them(flight, tmp_path, monkeypatch):
    """The IMU's attitude (gyro bias and noise, heading drift included) with the true
    translation: within the bounds, so the gyro chain of the mounted radar is not what
    moves the targets."""
    def pick(m, t):
        return PlatformMotion(m.time, m.attitude, t.position, t.velocity, m.angular_rate,
                              m.lever_arm)

    err, pv, _ = _compensate(flight, tmp_path / "a.zarr", monkeypatch, pick)
    assert np.all(np.abs(err) <= ANGLE_TOL_DEG), err
    assert np.all(np.abs(pv) <= PSEUDO_VELOCITY_BINS), pv


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_velocity_error_moves_the_azimuth_by_the_closed_form(flight, tmp_path, monkeypatch,
                                                               sign):
    """The truth with a velocity error of 10 mm/s along the boresight: each target's
    azimuth moves by the closed form (:func:`azimuth_shift`) beyond the bound."""
    used, truth, dv = [], [], sign * VELOCITY_ERROR

    def pick(m, t):         # the position drifts with the error from the record's start
        t0 = truth[0].time[0] if truth else t.time[0]
        truth.append(t)
        used.append(PlatformMotion(t.time, t.attitude, t.position + dv * (t.time - t0)[:, None],
                                   t.velocity + dv, t.angular_rate, t.lever_arm))
        return used[-1]

    base, _, _ = _compensate(flight, tmp_path / "t.zarr", monkeypatch, lambda m, t: t)
    err, _, inp = _compensate(flight, tmp_path / "v.zarr", monkeypatch, pick)
    shift = _predicted(flight, inp, used, truth)
    assert np.max(np.abs(err)) > ANGLE_TOL_DEG                  # a miss, of this size
    assert np.all(np.abs(err - base - shift)
                  <= SHIFT_REL_TOL * np.abs(shift) + SHIFT_ABS_TOL_DEG), (err - base, shift)


def test_the_imu_translation_misses_by_its_velocity_error(flight, tmp_path, monkeypatch):
    """The IMU's own motion from the true initial velocity: the accelerometer's bias and
    scale errors (20 mg, 1 % of g) leave about 10 mm/s of velocity by the second frame,
    and the targets' azimuth misses by the closed form of that error."""
    used, truth = [], []

    def pick(m, t):
        used.append(m)
        truth.append(t)
        return m

    base, _, _ = _compensate(flight, tmp_path / "t.zarr", monkeypatch, lambda m, t: t)
    err, _, inp = _compensate(flight, tmp_path / "i.zarr", monkeypatch, pick)
    shift = _predicted(flight, inp, used, truth)
    assert np.max(np.abs(err)) > ANGLE_TOL_DEG
    assert np.all(np.abs(err - base - shift)
                  <= SHIFT_REL_TOL * np.abs(shift) + SHIFT_ABS_TOL_DEG), (err - base, shift)


def _warned(flight, text: str) -> tuple[int, int, float]:
    """The target an ``azimuth:`` warning names, its frame and the shift it states [deg]."""
    hit = re.search(r"azimuth (-?[0-9.]+) deg, elevation (-?[0-9.]+) deg a range rate of "
                    r"([-+][0-9.]+) mm/s in frame (\d+).* by ([-+][0-9.]+) deg", text)
    az, _, _, frame, shift = (float(g) for g in hit.groups())
    j = int(np.argmin([abs(flight.apparent_direction(0, i)[0] - az)
                       for i in range(len(TARGETS))]))
    return j, int(frame), shift


def test_a_self_calibration_warns_of_the_azimuth_its_doppler_residual_gives(flight, tmp_path,
                                                                            monkeypatch):
    """Self-calibrated (velocity and clock offset from the radar): three targets in a
    narrow cone leave the velocity across it uncertain; the stage measures the residual
    range rate the beams leave each scatterer and warns of the azimuth it gives, which is
    the miss of that target; without a warning no target misses the bound (with the
    velocity error common to each block modelled, this seed's miss of 0.46 deg is gone)."""
    out = tmp_path / "c.zarr"
    assert main(flight.calibrating_command(out, *GRID)) == 0
    cal = json.loads(open_store(out).attrs["self_calibration"])
    said = [w for w in cal["warnings"] if w.startswith("azimuth:")]
    if not said:
        err, _ = _measure(flight, out)
        assert np.all(np.abs(err) <= ANGLE_TOL_DEG), (err, cal["warnings"])
        return
    assert len(said) == 1, cal["warnings"]
    j, frame, shift = _warned(flight, said[0])
    err, _ = _measure(flight, out)
    base, _, _ = _compensate(flight, tmp_path / "t.zarr", monkeypatch, lambda m, t: t)
    miss = err[j, frame] - base[j, frame]
    assert abs(err[j, frame]) > ANGLE_TOL_DEG
    assert abs(miss - shift) <= SHIFT_REL_TOL * abs(shift) + SHIFT_ABS_TOL_DEG, (miss, said)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_self_calibration_off_by_a_velocity_warns_of_the_azimuth_it_misses(
        flight, tmp_path, monkeypatch, capsys, sign):
    """The self-calibrated motion with a velocity error of 10 mm/s added along the
    boresight (a velocity the scene left uncertain, made certain): the stage measures
    the residual range rate at its scatterers, warns of the azimuth it gives, and that
    is the miss of the target it names against the same run without the error."""
    import dataclasses

    from raysim.pipeline import self_calibration

    def calibrate(*args, **kw):
        cal = self_calibration.calibrate_record(*args, **kw)
        t0 = cal.result.motions[0].time[0]
        moved = tuple(dataclasses.replace(
            m, position=m.position + sign * VELOCITY_ERROR * (m.time - t0)[:, None],
            velocity=m.velocity + sign * VELOCITY_ERROR) for m in cal.result.motions)
        return dataclasses.replace(cal, result=dataclasses.replace(cal.result, motions=moved))

    base = tmp_path / "b.zarr"
    assert main(flight.calibrating_command(base, *GRID, "--autofocus", "off")) == 0
    monkeypatch.setattr(stage, "calibrate_record", calibrate)
    out = tmp_path / "v.zarr"
    assert main(flight.calibrating_command(out, *GRID, "--autofocus", "off")) == 0
    cal = json.loads(open_store(out).attrs["self_calibration"])
    said = [w for w in cal["warnings"] if w.startswith("azimuth:")]
    assert len(said) == 1, cal["warnings"]
    j, frame, shift = _warned(flight, said[0])
    err, _ = _measure(flight, out)
    miss = err[j, frame] - _measure(flight, base)[0][j, frame]
    assert abs(err[j, frame]) > ANGLE_TOL_DEG, (err, said)
    assert abs(miss - shift) <= SHIFT_REL_TOL * abs(shift) + SHIFT_ABS_TOL_DEG, (miss, said)
    # the note names the radar autofocus, which removes that Doppler frame by frame; by
    # default (--autofocus auto) the warning applies it
    assert "note: --autofocus displacement removes a Doppler" in capsys.readouterr().err
    focused = tmp_path / "a.zarr"
    assert main(flight.calibrating_command(focused, *GRID)) == 0
    assert "note: autofocus: displacement applied (the stationary scatterers keep a Doppler" \
        in capsys.readouterr().err
    assert np.all(np.abs(_measure(flight, focused)[0]) <= ANGLE_TOL_DEG)


def test_ground_clutter_in_a_target_cell_moves_it_with_the_true_motion(tmp_path, monkeypatch):
    """A forward radar 3 m over the ground sees it at the targets' ranges, 24-36 deg below
    them, where the array (one row raised by half a wavelength) hardly separates it: with
    the true motion the first target of this seed misses the bound in clutter and meets
    it without."""
    kw = dict(frames=2, targets=TARGETS, mounting_deg="forward", time_offset=0.003,
              seed=CLUTTER_SEED)
    clean = write_flight(tmp_path / "n", **kw)
    dirty = write_flight(tmp_path / "c", clutter_scene="flat_reflectors",
                         clutter_altitude=3.0, clutter_max_scatterers=300, **kw)
    truth = {}
    for name, f in (("clean", clean), ("clutter", dirty)):
        truth[name], _, _ = _compensate(f, tmp_path / f"{name}.zarr", monkeypatch,
                                        lambda m, t: t, seed=CLUTTER_SEED)
    assert np.all(np.abs(truth["clean"]) <= ANGLE_TOL_DEG), truth["clean"]
    assert np.max(np.abs(truth["clutter"][0])) > ANGLE_TOL_DEG, truth["clutter"]


#: Relative agreement of the closed form with its limits, and a shift that is zero but
#: for rounding [rad].
LIMIT_TOL = 1e-3
ZERO_SHIFT = 1e-12


def test_azimuth_shift_limits_and_bad_input():
    """Without motion across the beam and with every channel at once there is no shift;
    across a long synthetic aperture the real array no longer matters and the shift is
    a moving target's, ``dv_r / v`` (Raney 1971); TDM slots alone give ``2 c dv_r / s_x^2``;
    a channel table that does not match the elements is refused, named."""
    x = np.arange(8) * 2e-3                                  # elements along azimuth [m]
    at_once = np.repeat(np.arange(64)[:, None] * 2e-4, x.size, axis=1)
    assert abs(azimuth_shift(0.01, 0.0, x, at_once)) <= ZERO_SHIFT
    long = np.repeat(np.linspace(0.0, 10.0, 64)[:, None], x.size, axis=1)
    assert abs(azimuth_shift(0.01, 0.2, x, long) / (0.01 / 0.2) - 1) <= LIMIT_TOL
    slots = at_once + np.where(x < 8e-3, 0.0, 7e-5)          # the second half fires later
    cov = np.mean((x - x.mean()) * (slots[0] - slots[0].mean()))
    assert abs(azimuth_shift(0.01, 0.0, x, slots) / (2 * cov * 0.01 / x.var()) - 1) <= LIMIT_TOL
    assert abs(azimuth_shift(0.01, 0.0, x, slots, np.deg2rad(60.0))
               / azimuth_shift(0.01, 0.0, x, slots) - 2.0) <= LIMIT_TOL     # 1 / cos(el)
    with pytest.raises(ValueError, match="channel_time"):
        azimuth_shift(0.01, 0.2, x, at_once[:, :3])
