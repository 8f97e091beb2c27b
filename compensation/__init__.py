"""IMU-driven motion compensation for FMCW MIMO radar cubes.

Independent of :mod:`raysim`: inputs are plain arrays (cube, element
positions, timing, IMU samples), so recorded data can be compensated directly.

Modules
-------
``strapdown``
    :func:`integrate_imu`: gyro and accelerometer samples to the pose at the
    chirp times (:class:`PlatformMotion`).
``paper``
    The published chain: :func:`slow_time_correction`, :func:`tilt_correction`,
    :func:`yaw_projection`, :func:`paper_chain`.
``exact``
    :func:`rigid_body_projection`: all six degrees of freedom in one
    beamformer on a fixed global grid.
``dpca``
    :func:`dpca_projection`: displaced-phase-centre sub-apertures held fixed
    in the world (horizontal motion undone for every scatterer in a beam),
    with its price (:class:`DPCAPlan`, :func:`dpca_plan`).
``projection``
    :func:`beam_projection` (the engine) and its result :class:`BeamCube`.
``realtime``
    :class:`RealtimeProjector`: the exact per-slot projection of
    ``rigid_body_projection(method="direct")`` for a stream of frames of one
    geometry (tables set up once, threads), equal within float32 rounding.
``stream``
    :class:`RealtimeStream`: raw IF frames in, compensated beams out (range
    transform of the gated bins, then the projection, buffers kept across
    frames); :func:`~compensation.stream.replay` plays a capture at its frame
    rate and gives each frame's latency.
``geometry``
    Direction and angle-grid helpers.
``autofocus``
    :func:`autofocus_beams`: the residual per-chirp phase common to the stationary
    scatterers after the IMU chain (vibration a low-rate IMU log cannot see),
    estimated from the beams (phase-gradient autofocus) and removed, with its
    uncertainty (:class:`Autofocus`).
``multiframe``
    Records of many frames: :func:`integrate_record` (one integration, split
    per frame), :func:`project_record`, :func:`accumulate`,
    :func:`~compensation.multiframe.apply_velocity`.
``ego_velocity``, ``clock_offset``, ``gyro_bias``
    Estimators from the radar, each with its uncertainty: platform velocity
    (:func:`fit_ego_velocity`), IMU-radar clock offset and drift
    (:func:`fit_time_shift`), gyro bias (:func:`fit_gyro_bias`).
``radar_inertial``
    :func:`~compensation.radar_inertial.estimate_radar_inertial`: one state
    over a record (velocity, attitude, IMU biases, clock) from the IMU and the
    Doppler of stationary scatterers; ``observability``: the components the
    scene leaves unconstrained (:class:`~compensation.observability.ObservabilityWarning`).
``calibration``
    :func:`self_calibrate`: the estimators run over a record and an IMU log.
``mounting``
    A mounted radar (``R_BA``): the motion seen from its nominal frame N
    (:func:`~compensation.mounting.radar_frame_motion`), directions measured
    there turned into W (:func:`~compensation.mounting.world_directions`).
``ingestion``
    IMU timing (gaps, jitter, rate against vibration), chirp times per
    frame, hover window by IMU grade.
``guards``
    Checks of the compensation's assumptions: IMU gaps (``ValueError``),
    hover window, levelling, small-angle tilt, published rotation phase
    (short strings in the ``warnings`` of :class:`PlatformMotion` and
    :class:`BeamCube`).

Axis names: ``chirp, channel, sample`` for IF data, ``range, doppler,
azimuth, elevation`` for processed data (docs/conventions.md).
"""

from .autofocus import Autofocus, autofocus_beams, correct_phase, estimate_phase_error
from .calibration import CalibrationResult, Scatterer, self_calibrate
from .clock_offset import ClockOffset, fit_time_shift
from .dpca import DPCABeams, DPCAPlan, dpca_plan, dpca_projection
from .ego_velocity import EgoVelocity, fit_ego_velocity
from .exact import rigid_body_projection
from .geometry import az_el, direction, grid_directions
from .guards import CompensationWarning, tilt_residual
from .gyro_bias import GyroBias, fit_gyro_bias
from .multiframe import accumulate, integrate_record, project_record
from .paper import (
    PAPER_STEPS,
    paper_chain,
    range_change,
    slow_time_correction,
    tilt_correction,
    yaw_projection,
)
from .projection import BeamCube, beam_projection
from .realtime import RealtimeProjector
from .strapdown import STANDARD_GRAVITY, PlatformMotion, integrate_imu, static_motion
from .stream import RealtimeStream

__version__ = "0.1.0"

__all__ = [
    "Autofocus", "autofocus_beams", "correct_phase", "estimate_phase_error",
    "BeamCube", "CalibrationResult", "ClockOffset", "CompensationWarning", "DPCABeams",
    "DPCAPlan", "EgoVelocity",
    "GyroBias", "PAPER_STEPS", "PlatformMotion", "RealtimeProjector", "RealtimeStream",
    "STANDARD_GRAVITY",
    "Scatterer", "accumulate", "fit_ego_velocity", "fit_gyro_bias", "fit_time_shift",
    "integrate_record", "project_record", "self_calibrate",
    "az_el", "beam_projection", "direction", "dpca_plan", "dpca_projection", "grid_directions",
    "integrate_imu", "paper_chain",
    "range_change", "rigid_body_projection", "slow_time_correction", "static_motion",
    "tilt_correction", "tilt_residual", "yaw_projection",
]
