"""Self-calibration of a record: the unknowns of the IMU estimated from the radar itself.

Over a record of frames and an IMU log, stationary scatterers give:

* the IMU-radar clock offset (and drift), from their residual slow-time
  phase against the IMU-predicted phase rate (:mod:`compensation.clock_offset`);
* the gyro bias, from their apparent angular drift over the frames
  (:mod:`compensation.gyro_bias`);
* the platform velocity, with the tilt, the IMU biases and the clock as one
  radar-inertial state over the record, from their residual range rates in
  blocks of chirps (:mod:`compensation.radar_inertial`): the integration is
  corrected as a whole, and what the scene does not constrain stays at the
  IMU's prior, named and warned about.

The clock offset and the gyro bias change the integration itself and are
iterated first (integrate, project, estimate, integrate again; a per-frame
velocity, :mod:`compensation.ego_velocity`, keeps the parallax of a
translation error out of the gyro-bias fit); the radar-inertial estimate then
starts from them, with their uncertainties as its priors. Every estimate
carries its uncertainty.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from ._checks import finite_array, positive
from .cell_directions import parabola_vertex
from .clock_averaged import SEARCH_FRAMES_AVERAGED, clock_misfit, coarse_offset, fit_clock
from .clock_offset import ClockOffset, phase_tracks
from .ego_velocity import EgoVelocity, fit_ego_velocity, slow_time_velocity
from .elevation import measure_elevation, vertical_baseline
from .exact import rigid_body_projection
from .geometry import direction
from .ground_doppler import ground_measurements, ground_scatterers
from .gyro_bias import GyroBias, fit_gyro_bias
from .ingestion import check_frame_times, folds_vibration
from .mounting import mounting_rotation, radar_frame_motion, world_directions
from .multiframe import apply_velocity, integrate_record
from .point_tracks import clock_scatterers
from .radar_inertial import (
    MAX_MEASUREMENTS,
    DopplerMeasurements,
    ImuErrors,
    RadarInertialResult,
    estimate_radar_inertial,
)
from .strapdown import PlatformMotion

__all__ = ["ESTIMATES", "CalibrationResult", "Scatterer", "apply_velocity", "detect_scatterers",
           "doppler_measurements", "self_calibrate"]

#: Quantities :func:`self_calibrate` can estimate.
ESTIMATES = ("time_offset", "gyro_bias", "velocity")
#: Half-width of the local angle grid that measures a scatterer's direction [rad].
DIRECTION_HALF_WIDTH = float(np.deg2rad(3.0))
#: Step of that grid [rad].
DIRECTION_STEP = float(np.deg2rad(0.5))
#: Smallest virtual-array extent along x (y) resolving azimuth (elevation) [wavelengths]:
#: four half-wavelength elements (the IWR6843AOP's grid), a 3 dB beam of about 25 deg.
MIN_APERTURE_WAVELENGTHS = 1.5
#: Smallest range-rate spread given to the ego-velocity fit [m/s] (a noise-free
#: simulation leaves only rounding in the phase).
MIN_RANGE_RATE_SIGMA = 1e-6
#: Half-width of the coarse clock-offset search around the first guess [s].
OFFSET_SEARCH_HALF_WIDTH = 10e-3
#: Step of that search [s]: within the reach of the linearised fit (a quarter of
#: the shortest vibration period of 1-2 ms).
OFFSET_SEARCH_STEP = 0.5e-3
#: Azimuth and elevation axis of the default scatterer search [rad] (-60..60 deg).
DETECT_AXIS = np.deg2rad(np.arange(-60.0, 60.5, 2.0))
#: Frames of the coarse search (the first ones; the fit then uses all).
SEARCH_FRAMES = 3
#: Default number of integrate-estimate passes for the clock offset and gyro bias.
ITERATIONS = 3
#: Default blocks of chirps per frame of the radar-inertial Doppler measurements (time
#: resolution of the velocity within a frame).
DOPPLER_BLOCKS = 4
#: Fewest chirp loops in a block (the slope of fewer is too noisy).
MIN_BLOCK_CHIRPS = 8
#: A detected maximum within this factor of a stronger one's sidelobe response there
#: (3 dB) is taken for that sidelobe, not for a scatterer.
SIDELOBE_MARGIN = 2.0
#: Spread of a detected direction along an axis the array resolves [rad] (the peak
#: refined to a quarter of the coarse step; multipath and the lever arm's parallax).
DIRECTION_SIGMA = float(np.deg2rad(0.5))
#: Spread along an axis it does not resolve [rad] (the scatterer may lie anywhere in a
#: wide fan; a line array's elevation).
UNRESOLVED_DIRECTION_SIGMA = float(np.deg2rad(10.0))
#: IMU figures used when none are given: a consumer MEMS class (BMI088 datasheet, one
#: sigma: accel 160 ug/sqrt(Hz), offset 20 mg, scale and cross-axis 1 %; gyro
#: 0.014 deg/s/sqrt(Hz), offset 0.5 deg/s), the widest of the grades, so its spreads
#: cover the better ones. The accelerometer bias spread adds the scale and cross-axis
#: errors on gravity (1 % of g each, constant in hover).
DEFAULT_IMU_ERRORS = ImuErrors(160e-6 * 9.80665, float(np.deg2rad(0.014)),
                               float(np.hypot.reduce([20e-3, 0.01, 0.01])) * 9.80665,
                               float(np.deg2rad(0.5)), 0.01)


@dataclass(frozen=True)
class Scatterer:
    """A stationary scatterer used for calibration: range gate and direction.

    Attributes
    ----------
    gate : int
        Range bin of the range-compressed cube.
    azimuth, elevation : float
        Direction [rad] in W, or for a mounted radar in its nominal frame N
        (:mod:`compensation.mounting`).
    elevation_sigma : float or None
        Spread of ``elevation`` [rad] by phase comparison across a vertical baseline too
        short for a beam (:func:`compensation.elevation.measure_elevation`); None otherwise.
    """

    gate: int
    azimuth: float
    elevation: float
    elevation_sigma: float | None = None

    @property
    def direction(self) -> np.ndarray:
        """Unit vector (W, or N of a mounted radar), shape ``[3]``."""
        return direction(self.azimuth, self.elevation)


@dataclass(frozen=True)
class CalibrationResult:
    """Corrected motion of a record and the estimates, each with its uncertainty.

    Attributes
    ----------
    motions : tuple of PlatformMotion
        Per-frame motion from the calibrated integration, velocity corrected.
    time_offset : float
        IMU clock minus radar clock used for the final integration [s].
    clock : ClockOffset or None
        Last clock-offset update (``offset`` is the remaining correction,
        ``total_sigma`` the uncertainty of ``time_offset``: the fit's and the log
        stamps'); ``None`` when not estimated.
    gyro_bias : ndarray, shape ``[3]``
        Gyro bias removed from the samples [rad/s] (body frame).
    gyro : GyroBias or None
        Last gyro-bias update (``covariance`` the uncertainty of ``gyro_bias``).
    velocity : tuple of EgoVelocity
        Per-frame velocity corrections [m/s] (W); empty when the velocity
        comes from the radar-inertial estimate (``radar_inertial``).
    initial_velocity : ndarray, shape ``[3]``
        Body velocity in W at the record's first chirp after correction [m/s].
    initial_velocity_covariance : ndarray, shape ``[3, 3]``
        Its covariance [m^2/s^2].
    scatterers : tuple of Scatterer
    notes : tuple of str
        Estimates asked for but not made, and why.
    radar_inertial : RadarInertialResult or None
        The radar-inertial estimate that gave ``motions``, ``time_offset``,
        ``gyro_bias`` and the initial velocity (``velocity`` estimated); its
        state, spreads and unconstrained components.
    """

    motions: tuple[PlatformMotion, ...]
    time_offset: float
    clock: ClockOffset | None
    gyro_bias: np.ndarray
    gyro: GyroBias | None
    velocity: tuple[EgoVelocity, ...]
    initial_velocity: np.ndarray
    initial_velocity_covariance: np.ndarray
    scatterers: tuple[Scatterer, ...] = field(default_factory=tuple)
    notes: tuple[str, ...] = ()
    radar_inertial: RadarInertialResult | None = None

    def report(self) -> dict:
        """Estimates with one-sigma uncertainties as plain numbers (SI units).

        With the radar-inertial estimate, the clock offset, gyro bias and initial velocity
        are its (those applied; the offset's spread no tighter than the clock fit's it
        started from, docs/self_calibration.md), ``radar_inertial`` holds its whole state,
        spreads and unconstrained components, and ``warnings`` its observability warnings.
        """
        ri = self.radar_inertial
        stamp, clock = (0.0, 0.0) if (c := self.clock) is None else (c.stamp_sigma, c.total_sigma)
        out = {"time_offset_s": self.time_offset,
               "time_offset_sigma_s": None if self.clock is None else self.clock.total_sigma,
               "gyro_bias_rad_s": self.gyro_bias.tolist(),
               "gyro_bias_sigma_rad_s": None if self.gyro is None else self.gyro.sigma.tolist(),
               "initial_velocity_mps": self.initial_velocity.tolist(),
               "initial_velocity_sigma_mps": np.sqrt(np.diag(
                   self.initial_velocity_covariance)).tolist(),
               "scatterers": len(self.scatterers), "notes": list(self.notes)}
        if self.velocity:
            out["frame_velocity_correction_mps"] = [v.velocity.tolist() for v in self.velocity]
            out["frame_velocity_sigma_mps"] = [v.sigma.tolist() for v in self.velocity]
        if self.clock is not None and np.isfinite(self.clock.drift_sigma):
            out["clock_drift"] = self.clock.drift
            out["clock_drift_sigma"] = self.clock.drift_sigma
        if ri is not None:
            out["time_offset_sigma_s"] = float(max(np.hypot(ri.sigma[12], stamp), clock))
            out["gyro_bias_sigma_rad_s"] = ri.sigma[9:12].tolist()
            out["clock_drift"], out["clock_drift_sigma"] = float(ri.state[13]), float(ri.sigma[13])
            out["radar_inertial"] = ri.report()
            out["unconstrained"] = list(ri.unconstrained)
            out["held_at"] = {n: self._prior_of(n) for n in ri.unconstrained}
            out["warnings"] = list(ri.warnings)
        return out

    def _prior_of(self, name: str) -> str:
        """Where the prior of a state component the Doppler leaves unconstrained came from."""
        if self.clock is not None and (name == "clock_offset" or name == "clock_drift"
                                       and np.isfinite(self.clock.drift_sigma)):
            return "clock fit"
        if name.startswith("gyro_bias") and self.gyro is not None and np.isfinite(
                self.gyro.sigma["xyz".index(name[-1])]):
            return "gyro-bias fit"
        return "IMU grade"


def detect_scatterers(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                      range_axis, azimuth, elevation, range_gates=None, count: int = 8,
                      dynamic_range_db: float = 25.0, chirps: int = 4,
                      **options) -> list[Scatterer]:
    """Strongest local maxima of a frame's compensated range-angle power.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        One range-compressed frame.
    element_positions, motion, wavelength, range_axis, azimuth, elevation, range_gates
        As for :func:`compensation.rigid_body_projection`; ``motion`` of this frame.
    count : int
        Most scatterers returned.
    dynamic_range_db : float
        Only maxima within this many dB of the strongest [dB]; the search
        beams are tapered (Hamming over the aperture) so that sidelobes stay
        below it. Each maximum is refined on a local grid of a quarter step.
    chirps : int
        Chirps (spread over the frame) whose powers are averaged.

    Returns
    -------
    list of Scatterer
        Strongest first. A maximum within :data:`SIDELOBE_MARGIN` of a stronger
        one's sidelobe response (same or neighbouring range cell) is left out.
        Where the array resolves no elevation but has a short vertical baseline
        (the raised TX), each elevation is measured by phase comparison
        (:func:`compensation.elevation.measure_elevation`, its spread in
        ``elevation_sigma``) and the azimuth refined again at it.
    """
    from scipy.ndimage import maximum_filter

    has_az, has_el = _apertures(element_positions, wavelength)
    azimuth = azimuth if has_az else np.zeros(1)            # a line array sees one angle
    elevation = elevation if has_el else np.zeros(1)
    n = rc.shape[0]
    pick = np.unique(np.linspace(0, n - 1, min(int(chirps), n)).round().astype(int))
    sel = motion.num_chirps // n
    mo = motion.select(np.concatenate([np.arange(k * sel, (k + 1) * sel) for k in pick]))
    taper = options.pop("weights", None)
    taper = _taper(element_positions) if taper is None else taper
    beams = rigid_body_projection(rc[pick], element_positions, mo, wavelength=wavelength,
                                  range_axis=range_axis, azimuth=azimuth, elevation=elevation,
                                  range_gates=range_gates, weights=taper, **options)
    power = np.mean(np.abs(beams.data) ** 2, axis=0)          # [range, az, el]
    peak = maximum_filter(power, size=3, mode="nearest") == power
    level = power.max() * 10 ** (-positive("dynamic_range_db", dynamic_range_db) / 10)
    idx = np.argwhere(peak & (power >= level))
    order = np.argsort(power[tuple(idx.T)])[::-1][:int(count)]
    gates = np.arange(len(range_axis)) if range_gates is None else np.asarray(range_gates)
    az, el = np.asarray(azimuth, dtype=float), np.asarray(elevation, dtype=float)
    step = float(np.median(np.abs(np.diff(az)))) if az.size > 1 else DIRECTION_STEP
    proj = dict(options, wavelength=wavelength, range_axis=range_axis)
    found, kept = [], []
    for i in order:
        s = Scatterer(int(gates[idx[i, 0]]), float(az[idx[i, 1]]), float(el[idx[i, 2]]))
        if _sidelobe(idx[i], kept, power, az, el, element_positions, taper, wavelength):
            continue
        kept.append(idx[i])
        pk = _peak(rc, element_positions, motion, s, proj, 2 * step, step / 4)
        if pk is None:
            continue
        s = Scatterer(s.gate, *pk)            # refined to a fraction of the coarse step
        if not has_el and vertical_baseline(element_positions, wavelength,
                                            MIN_APERTURE_WAVELENGTHS):
            x, opts = _gate(rc, s, proj)
            measured = measure_elevation(x, element_positions, motion, s.azimuth, opts)
            if measured is not None:   # else left at 0 in the unresolved fan
                e0, sig = measured
                # the azimuth row sees cos(el) sin(az): refined again at that elevation
                pk = _peak(rc, element_positions, motion, Scatterer(s.gate, s.azimuth, e0),
                           proj, 2 * step, step / 4)
                if pk is not None:
                    s = Scatterer(s.gate, pk[0], e0, sig)
        found.append(s)
    return found


def _sidelobe(cell, kept, power, az, el, positions, taper, wavelength: float) -> bool:
    """Whether the maximum at ``cell`` (range, az, el indices of ``power``) is a sidelobe of
    a stronger one kept in the same or a neighbouring range cell: its power is within
    :data:`SIDELOBE_MARGIN` of the tapered array factor's response there to the
    stronger one (the array's axes taken along the grid's, a small tilt aside)."""
    p = np.asarray(positions, dtype=float)
    k = 2 * np.pi / wavelength
    for c in kept:
        if abs(int(c[0]) - int(cell[0])) > 1:
            continue
        du = direction(az[cell[1]], el[cell[2]]) - direction(az[c[1]], el[c[2]])
        af = abs(np.sum(taper * np.exp(1j * k * (p @ du)))) ** 2 / np.sum(taper) ** 2
        if power[tuple(cell)] <= SIDELOBE_MARGIN * af * power[tuple(c)]:
            return True
    return False


def _taper(positions) -> np.ndarray:
    """Hamming taper over the aperture along x and y, ``[channel]`` (sidelobes about -40 dB).

    Detection on a tapered beam keeps a scatterer's sidelobes (-13 dB untapered)
    from being taken for scatterers of their own.
    """
    p = np.asarray(positions, dtype=float)
    w = np.ones(p.shape[0])
    for axis in (0, 1):
        span = np.ptp(p[:, axis])
        if span > 0:
            x = (p[:, axis] - p[:, axis].min()) / span
            w = w * (0.54 - 0.46 * np.cos(2 * np.pi * x))
    return w


def _gate(rc, s: Scatterer, options) -> tuple[np.ndarray, dict]:
    """The scatterer's range gate alone (the projection then checks and reads no more)."""
    opts = dict(options, range_axis=np.asarray(options["range_axis"])[s.gate:s.gate + 1])
    return np.ascontiguousarray(rc[:, :, s.gate:s.gate + 1]), opts


def _beams(rcs, positions, motions, scatterers, options) -> np.ndarray:
    """Slow-time beam of every scatterer in every frame, ``[frame, scatterer, chirp]``."""
    def beam(rc, m, s):
        x, opts = _gate(rc, s, options)
        return rigid_body_projection(x, positions, m, azimuth=[s.azimuth],
                                     elevation=[s.elevation], **opts).data[:, 0, 0, 0]
    return np.asarray([[beam(rc, m, s) for s in scatterers]
                       for rc, m in zip(rcs, motions, strict=True)], dtype=complex)


def _loop_motion(m: PlatformMotion, n_chirps: int) -> PlatformMotion:
    """One pose per chirp loop (the first slot) of a per-slot motion."""
    return m.select(slice(0, None, m.num_chirps // n_chirps))


def _peak(rc, positions, m: PlatformMotion, s: Scatterer, options, half: float, step: float
          ) -> tuple[float, float] | None:
    """Interpolated (az, el) [rad] of the power peak on a local grid around ``s``.

    ``None`` when the peak lies on the grid's edge (another scatterer's lobe).
    """
    offs = np.arange(-half, half + step / 2, step)
    has_az, has_el = _apertures(positions, options["wavelength"])
    az = s.azimuth + offs if has_az else np.array([s.azimuth])
    el = s.elevation + offs if has_el else np.array([s.elevation])
    x, opts = _gate(rc, s, options)
    b = rigid_body_projection(x, positions, m, azimuth=az, elevation=el, **opts)
    p = np.mean(np.abs(b.data[:, 0]) ** 2, axis=0)             # [az, el]
    i, e = np.unravel_index(int(np.argmax(p)), p.shape)
    if (has_az and not 0 < i < az.size - 1) or (has_el and not 0 < e < el.size - 1):
        return None
    db = 10 * np.log10(p)        # the peak's vertex, within half a step of the grid's best
    fa = parabola_vertex(db[i - 1, e], db[i, e], db[i + 1, e]) if has_az else 0.0
    fe = parabola_vertex(db[i, e - 1], db[i, e], db[i, e + 1]) if has_el else 0.0
    fa, fe = np.clip([fa, fe], -0.5, 0.5)
    return float(az[i] + fa * step), float(el[e] + fe * step)


def _apertures(positions, wavelength: float) -> tuple[bool, bool]:
    """Whether the array resolves azimuth (extent along x) and elevation (along y): an
    extent below :data:`MIN_APERTURE_WAVELENGTHS` wavelengths gives a beam too wide."""
    p = np.asarray(positions, dtype=float)
    lim = MIN_APERTURE_WAVELENGTHS * wavelength
    return bool(np.ptp(p[:, 0]) >= lim), bool(np.ptp(p[:, 1]) >= lim)


def _directions(rcs, positions, motions, scatterers, options) -> np.ndarray:
    """Apparent direction of each scatterer in each frame, ``[frame, scatterer, 3]``."""
    out = np.full((len(rcs), len(scatterers), 3), np.nan)
    for k, (rc, m) in enumerate(zip(rcs, motions, strict=True)):
        for j, s in enumerate(scatterers):
            pk = _peak(rc, positions, m, s, options, DIRECTION_HALF_WIDTH, DIRECTION_STEP)
            if pk is not None:
                out[k, j] = direction(*pk)
    return out


def _with_prior(estimate: np.ndarray, cov: np.ndarray, prior_sigma: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """Fitted gyro bias ``[3]`` (covariance ``C [3, 3]``; few scatterers: looser than the IMU)
    and the IMU's zero-mean prior ``s`` [rad/s] (0 floored to 1e-6): mean, ``(C^-1 + I/s^2)^-1``."""
    info = np.linalg.inv(cov)
    post = np.linalg.inv(info + np.eye(3) / max(prior_sigma, 1e-6) ** 2)
    return post @ (info @ estimate), 0.5 * (post + post.T)


#: Options of :func:`compensation.integrate_imu` the radar-inertial integration keeps (the
#: initial state, velocity mode and hover window are its own).
_INTEGRATION_KEYS = ("lever_arm", "gravity", "max_gap", "vibration_hz")


def doppler_measurements(rcs, positions, motions, scatterers, options, *, wavelength: float,
                         blocks: int = DOPPLER_BLOCKS, mounting=None) -> DopplerMeasurements:
    """Residual range rate of every scatterer in every block of chirps of every frame.

    Parameters
    ----------
    rcs : sequence of ndarray, each shape ``[chirp, channel, range]``
    positions : array_like, shape ``[channel, 3]``
        Virtual element positions in A [m].
    motions : sequence of PlatformMotion
        Motion of each frame the beams are compensated with.
    scatterers : sequence of Scatterer
    options : dict
        For :func:`compensation.rigid_body_projection` (``range_axis`` included).
    wavelength : float
        [m].
    blocks : int
        Blocks per frame (fewer when a block would hold under
        :data:`MIN_BLOCK_CHIRPS` chirp loops, or the record would give more
        than :data:`compensation.radar_inertial.MAX_MEASUREMENTS`).
    mounting : array_like, shape ``[3, 3]``, optional
        ``R_BA`` of a mounted radar: the scatterers' directions are in its nominal
        frame N, the beams formed there (:mod:`compensation.mounting`); default
        down-looking (N is W).

    Returns
    -------
    DopplerMeasurements
        One per scatterer, block and frame: the slow-time slope of its beam
        (:func:`compensation.ego_velocity.slow_time_velocity`), its spread
        (at least :data:`MIN_RANGE_RATE_SIGMA`), the block's first and last
        chirp time, and the direction and its covariance turned into W.
    """
    if int(blocks) != blocks or blocks < 1:
        raise ValueError(f"blocks: got {blocks!r}, expected a whole number of chirp blocks "
                         f"per frame, at least 1")
    y = _beams(rcs, positions, [radar_frame_motion(m, mounting) for m in motions], scatterers,
               options)                                             # [frame, scatterer, chirp]
    nb = max(1, min(int(blocks), y.shape[2] // MIN_BLOCK_CHIRPS,
                    MAX_MEASUREMENTS // max(y.shape[0] * y.shape[1], 1)))
    u = np.stack([sc.direction for sc in scatterers])
    dcov = np.stack([_direction_cov(sc, positions, wavelength) for sc in scatterers])
    u, dcov = world_directions(u, mounting, dcov)     # the Doppler model's frame
    rs, win, n = [], [], len(scatterers)
    for k, m in enumerate(motions):
        t = _loop_motion(m, y.shape[2]).time
        for blk in np.array_split(np.arange(t.size), nb):
            rs.extend(slow_time_velocity(y[k, j, blk], t[blk], wavelength) for j in range(n))
            win.extend([(t[blk][0], t[blk][-1])] * n)
    per = np.tile(np.arange(n), len(motions) * nb)            # scatterer of each measurement
    r, s = np.reshape(rs, (-1, 2)).T
    return DopplerMeasurements(u[per], r, np.maximum(s, MIN_RANGE_RATE_SIGMA),
                               np.repeat(np.arange(len(motions)), nb * n), np.array(win),
                               dcov[per])


def _direction_cov(s: Scatterer, positions, wavelength: float) -> np.ndarray:
    """Covariance ``[3, 3]`` of a detected direction's error: :data:`DIRECTION_SIGMA` along
    the azimuth and elevation the array resolves, :data:`UNRESOLVED_DIRECTION_SIGMA`
    along those it does not, and for those the second-order shortening along ``u``."""
    has = _apertures(positions, wavelength)
    h = 1e-6
    out = np.zeros((3, 3))
    for k, resolved in enumerate(has):
        dd = np.array([h, 0.0]) if k == 0 else np.array([0.0, h])
        axis = (direction(s.azimuth + dd[0], s.elevation + dd[1])
                - direction(s.azimuth - dd[0], s.elevation - dd[1])) / (2 * h)
        sig = DIRECTION_SIGMA if resolved else UNRESOLVED_DIRECTION_SIGMA
        if k == 1 and not resolved and s.elevation_sigma is not None:
            sig, resolved = s.elevation_sigma, True    # measured by phase comparison
        out += sig ** 2 * np.outer(axis, axis)
        if not resolved:      # second order: an angle e off shortens u by e^2 / 2
            u = s.direction   # (mean sig^2 / 2 and variance sig^4 / 2 of e^2 / 2, Gaussian)
            out += 0.75 * sig ** 4 * np.outer(u, u)
    return out


def self_calibrate(rcs: Sequence, frame_times: Sequence, element_positions, imu_time, gyro,
                   accel, *, wavelength: float, range_axis, scatterers=None,
                   estimate: Sequence[str] = ESTIMATES, time_offset: float = 0.0,
                   iterations: int = ITERATIONS, drift: bool = False, imu_interval: float = 0.0,
                   offset_search: float = OFFSET_SEARCH_HALF_WIDTH,
                   detect_grid=None, detect_gates=None, imu_errors: ImuErrors | None = None,
                   attitude_given: bool = True, blocks: int = DOPPLER_BLOCKS,
                   tilt_covariance=None, attitude_track=None, mounting=None, ground=None,
                   ground_gates=None, **options) -> CalibrationResult:
    """Estimate the clock offset, gyro bias and velocity of a record from its radar data.

    Parameters
    ----------
    rcs : sequence of ndarray, each shape ``[chirp, channel, range]``
        Range-compressed frames.
    frame_times : sequence of array_like, each shape ``[chirp]`` (or ``[chirp * slot]``)
        Times of every chirp (TDM: every slot, chirp major) of each frame [s,
        radar clock], uniform within a frame.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual element positions in A [m].
    imu_time, gyro, accel
        IMU log (:func:`compensation.integrate_imu`).
    wavelength : float
        Mid-chirp wavelength [m].
    range_axis : array_like, shape ``[range]``
        Range of each bin [m].
    scatterers : sequence of Scatterer, optional
        Stationary scatterers to use; default :func:`detect_scatterers` on the
        first frame over ``detect_grid`` (``(azimuth, elevation)`` [rad],
        default -60..60 deg in 2 deg steps) and the range bins ``detect_gates``
        (default all).
    estimate : sequence of str
        Subset of :data:`ESTIMATES`. The gyro bias needs two frames and an
        array that resolves azimuth or elevation (the drift of the angles it
        resolves); otherwise it is skipped (``gyro`` of the result is ``None``).
    time_offset : float
        First guess of IMU clock minus radar clock [s].
    offset_search : float
        Half-width of the coarse clock-offset search around ``time_offset``
        [s] (phase misfit on a grid of :data:`OFFSET_SEARCH_STEP`); 0 skips
        it (the first guess is then within about 1 ms).
    iterations : int
        Integrate-estimate passes for the clock offset and gyro bias.
    drift : bool
        Also estimate the clock drift in the clock-offset fit (reported; the
        radar-inertial estimate has the drift in its state and applies it).
    imu_interval : float
        Averaging interval of each IMU sample [s] (:mod:`compensation.clock_averaged`); 0 none.
    imu_errors : ImuErrors, optional
        Noise densities and bias spreads of the IMU, the process noise and priors of the
        radar-inertial estimate and the gyro-bias fit's prior; :data:`DEFAULT_IMU_ERRORS`.
    attitude_given : bool
        Whether ``initial_attitude`` is an estimate (a flight controller's,
        levelled) rather than the nominal hover attitude
        (:func:`compensation.radar_inertial.estimate_radar_inertial`).
    blocks : int
        Doppler blocks per frame (:func:`doppler_measurements`).
    tilt_covariance, attitude_track, ground : optional
        Covariance of the initial roll and pitch when measured [rad^2]; a flight
        controller's attitude at every frame's first time ``[frame, 3, 3]``
        (:func:`compensation.radar_inertial.estimate_radar_inertial`); ``(motions,
        tilt_covariance) -> (initial attitude, tilt covariance)``, the ground's tilt at
        the clock and gyro bias found (:class:`compensation.ground_refit.GroundRetilt`).
    mounting : array_like, shape ``[3, 3]``, optional
        ``R_BA`` of a mounted radar (A vectors to B vectors): the scatterers are
        detected and their beams formed in its nominal frame N (their directions,
        and ``scatterers``' and ``detect_grid``'s, are N's), each direction turned
        into W for the velocity, gyro-bias and Doppler models
        (:mod:`compensation.mounting`); default down-looking (N is W).
    ground_gates : array_like of int, optional
        Ground clutter bins joining the velocity's Doppler (:mod:`compensation.ground_doppler`).
    **options
        For :func:`compensation.integrate_imu` (``lever_arm``, ``initial_attitude``,
        ``initial_position``, ``velocity``, ``initial_velocity``, ``hover_window``,
        ``imu_grade`` ...) and :func:`compensation.rigid_body_projection`
        (``grid_shape``, ``channel_slot``, ``method``, ``focus``).

    Returns
    -------
    CalibrationResult
    """
    if bad := [e for e in estimate if e not in ESTIMATES]:
        raise ValueError(f"estimate: got {bad}, expected names of {ESTIMATES}")
    if len(rcs) != len(frame_times) or len(rcs) < 1:
        raise ValueError(f"rcs holds {len(rcs)} frames and frame_times {len(frame_times)}; "
                         f"expected the same number, at least one")
    frames = check_frame_times(list(frame_times))
    positions = finite_array("element_positions", element_positions, ndim=2)
    lam = positive("wavelength", wavelength)
    proj_keys = ("grid_shape", "channel_slot", "method", "focus")
    proj = {k: options.pop(k) for k in proj_keys if k in options}
    proj.update(wavelength=lam, range_axis=range_axis)
    # a few directions: a NUFFT plan per chirp costs more than the lattice sums
    proj.setdefault("method", "lattice" if proj.get("grid_shape") is not None else "direct")
    gyro = finite_array("gyro", gyro, ndim=2)
    mounting = mounting_rotation(mounting)

    def seen(ms):        # the motions as the beams see them: in N (mounting)
        return [radar_frame_motion(m, mounting) for m in ms]

    tau = float(finite_array("time_offset", time_offset, shape=()))
    errors = DEFAULT_IMU_ERRORS if imu_errors is None else imu_errors
    bias = np.zeros(3)
    clock, gb, clutter = None, None, ()

    def integrate():
        return integrate_record(imu_time, gyro - bias, accel, frames, time_offset=tau, **options)

    motions = integrate()
    if scatterers is None:
        grid = detect_grid if detect_grid is not None else (DETECT_AXIS, DETECT_AXIS)
        scatterers = detect_scatterers(rcs[0], positions, seen(motions)[0], azimuth=grid[0],
                                       elevation=grid[1], range_gates=detect_gates, **proj)
    scatterers = tuple(scatterers)
    if not scatterers:
        raise ValueError("scatterers: none given and none detected; nothing to calibrate on")
    mids = np.array([0.5 * (f[0] + f[-1]) for f in frames])
    t_ref = float(options.get("reference_time", frames[0][0]))
    u = world_directions(np.stack([sc.direction for sc in scatterers]), mounting)    # W
    corrections: list[EgoVelocity] = []

    def radar_velocity(ms):
        """Per-frame ego-velocity fits and the motions corrected with them."""
        y = _beams(rcs, positions, seen(ms), scatterers, proj)
        fits = []
        for k, m in enumerate(ms):
            t = _loop_motion(m, y.shape[2]).time
            vr = [slow_time_velocity(y[k, j], t, lam) for j in range(len(scatterers))]
            v, sig = (np.array(a) for a in zip(*vr, strict=True))
            fits.append(fit_ego_velocity(u, v, np.maximum(sig, MIN_RANGE_RATE_SIGMA)))
        dv = np.stack([f.velocity for f in fits])
        return apply_velocity(ms, mids, dv, t_ref), fits

    timed, mixed = scatterers, 0.0     # the clock's scatterers: one point a cell (point_tracks)
    if "time_offset" in estimate:
        timed, mixed = clock_scatterers(phase_tracks(_beams(
            rcs, positions, seen(motions), scatterers, proj), seen(motions), scatterers, lam),
            scatterers, offset_search)
    clock_fit = partial(fit_clock, drift=drift, imu_time=imu_time, interval=imu_interval,
                        aliased=(al := folds_vibration(imu_time, gyro, imu_interval)),
                        ambiguity=mixed)
    if "time_offset" in estimate and offset_search > 0:
        grid = tau + np.arange(-offset_search, offset_search + OFFSET_SEARCH_STEP / 2,
                               OFFSET_SEARCH_STEP)
        few = slice(0, SEARCH_FRAMES_AVERAGED if imu_interval > 0 or al else SEARCH_FRAMES)
        def misfit(cand):
            ms = integrate_record(imu_time, gyro, accel, frames[few], time_offset=cand, **options)
            y = _beams(rcs[few], positions, ms := seen(ms), timed, proj)
            return clock_misfit(phase_tracks(y, ms, timed, lam), imu_time, cand,
                                imu_interval, al)
        tau, clock_fit = coarse_offset(grid, [misfit(c) for c in grid], clock_fit, mixed)
        motions = integrate()
    for _ in range(int(iterations) if {"time_offset", "gyro_bias"} & set(estimate) else 0):
        if "time_offset" in estimate:
            y = _beams(rcs, positions, seen(motions), timed, proj)
            clock = clock_fit(phase_tracks(y, seen(motions), timed, lam), time_offset=tau)
            tau += clock.offset
            motions = integrate()
        if "gyro_bias" in estimate and len(frames) >= 2 and any(has := _apertures(positions, lam)):
            if "velocity" in estimate:     # parallax of a translation error is no rotation
                motions, _ = radar_velocity(motions)
            dirs = world_directions(_directions(rcs, positions, seen(motions), scatterers,
                                                proj), mounting)
            att = np.stack([m.attitude[m.num_chirps // 2] for m in motions])
            fit = fit_gyro_bias(mids, dirs, att, spread=np.where(has, 1.0, np.inf), frame=mounting)
            fused, cov = _with_prior(bias + fit.bias, fit.covariance, errors.gyro_bias_sigma)
            gb, bias = GyroBias(fused - bias, cov, fit.residual_rms), fused
            motions = integrate()
    ri = None
    if "velocity" in estimate:   # the ground's tilt again at the clock and gyro bias found
        att0, tilt_cov = ((motions[0].attitude[0], tilt_covariance) if ground is None
                          else ground(motions, tilt_covariance))
        def radar_inertial(offset: float, offset_sigma, first=motions[0]):
            return estimate_radar_inertial(
                imu_time, gyro, accel, frames,
                lambda ms: ground_measurements(doppler_measurements(
                    rcs, positions, ms, scatterers, proj, wavelength=lam, blocks=blocks,
                    mounting=mounting), rcs, positions, ms, clutter, wavelength=lam,
                    channel_slot=proj.get("channel_slot"), mounting=mounting),
                imu_errors=errors, initial_velocity=first.velocity[0],
                initial_attitude=att0, initial_position=first.position[0],
                time_offset=offset, gyro_bias=bias, clock_offset_sigma=offset_sigma,
                gyro_bias_cov=None if gb is None else gb.covariance,
                tilt_covariance=tilt_cov, attitude_track=attitude_track,
                attitude_given=attitude_given, reference_time=frames[0][0],
                **{k: v for k, v in options.items() if k in _INTEGRATION_KEYS})
        clutter = ground_scatterers(rcs[0], positions, seen(motions)[0], gates=ground_gates, **proj)
        ri = radar_inertial(tau, None if clock is None else clock.offset_sigma)
        if clock is not None:
            # the fits above saw the per-frame velocities' motion, its acceleration error bends
            # the phase tracks like an offset: fit again, estimate again where it moves
            y = _beams(rcs, positions, ms := seen(ri.motions), timed, proj)
            t0 = frames[0][0] + ri.time_offset   # the log placed with the estimate's drift
            t_imu = t0 + (np.asarray(imu_time, dtype=float) - t0) / (1.0 + float(ri.state[13]))
            refit = clock_fit(phase_tracks(y, ms, timed, lam), time_offset=ri.time_offset,
                              imu_time=t_imu)
            if abs(refit.offset) > refit.offset_sigma:
                clock, ri = refit, radar_inertial(ri.time_offset + refit.offset, refit.offset_sigma)
        motions, tau, bias = list(ri.motions), ri.time_offset, ri.gyro_bias
        cov0 = ri.initial_velocity_covariance
    else:
        cov0 = np.full((3, 3), np.nan)
    if clock is not None and offset_search > 0:      # set only where the offset is estimated
        clock = clock.beyond_search(tau - float(time_offset), offset_search, OFFSET_SEARCH_STEP)
    notes = [f"velocity: Doppler of {len(clutter)} ground scatterers (at rest)"] if clutter else []
    if "gyro_bias" in estimate and gb is None:
        notes.append("gyro_bias: not estimated (needs two frames or more and an array that "
                     "resolves azimuth or elevation)")
    v0 = motions[0].velocity[0]
    return CalibrationResult(tuple(motions), tau, clock, bias, gb, tuple(corrections),
                             np.asarray(v0, dtype=float), cov0, scatterers, tuple(notes), ri)

