"""Records of many frames: one IMU integration, per-frame projection, accumulation.

A record is a sequence of frames, each with its own uniform chirp times; idle
time between frames is allowed (the frames are given as such), a non-uniform
chirp spacing inside a frame is refused because the Doppler axis of that
frame would be wrong. The IMU record is integrated once over all chirps, so
the attitude and velocity carry over from frame to frame, then split.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ._checks import finite_array
from .exact import rigid_body_projection
from .ingestion import check_frame_times
from .projection import BeamCube
from .strapdown import PlatformMotion, integrate_imu

__all__ = ["accumulate", "apply_velocity", "integrate_record", "project_record",
           "split_motion"]


def split_motion(motion: PlatformMotion, sizes: Sequence[int]) -> list[PlatformMotion]:
    """Per-frame motions of a motion over concatenated frames of ``sizes`` chirps each."""
    sizes = [int(n) for n in sizes]
    if sum(sizes) != motion.num_chirps or min(sizes, default=0) < 1:
        raise ValueError(f"frame sizes {sizes} must be positive and add up to the "
                         f"{motion.num_chirps} chirps of the motion")
    edges = np.cumsum([0, *sizes])
    return [motion.select(slice(int(a), int(b))) for a, b in zip(edges[:-1], edges[1:],
                                                                 strict=True)]


def integrate_record(imu_time, gyro, accel, frame_times, **options) -> list[PlatformMotion]:
    """One strapdown integration over all frames of a record, split per frame.

    Parameters
    ----------
    imu_time : array_like, shape ``[sample]``
        IMU time stamps [s, IMU clock].
    gyro, accel : array_like, shape ``[sample, 3]``
        Angular rate [rad/s] and specific force [m/s^2] in B.
    frame_times : sequence of array_like, each shape ``[chirp]``
        Chirp (or TDM slot) times of each frame [s, radar clock], uniform
        within a frame, frames in order.
    **options
        Passed to :func:`compensation.integrate_imu` (``time_offset``,
        ``velocity``, ``hover_window``, ``imu_grade`` ...); the reference time
        defaults to the first chirp of the record.

    Returns
    -------
    list of PlatformMotion
        One per frame, from the same integration.
    """
    frames = check_frame_times(frame_times)
    motion = integrate_imu(imu_time, gyro, accel, frames, **options)
    return split_motion(motion, [f.size for f in frames])


def project_record(rcs, element_positions, motions: Sequence[PlatformMotion], **options
                   ) -> list[BeamCube]:
    """Exact rigid-body projection of every frame with its own motion.

    Parameters
    ----------
    rcs : sequence of ndarray, each shape ``[chirp, channel, range]``
        Range-compressed frames.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual element positions in A [m].
    motions : sequence of PlatformMotion
        One per frame (:func:`integrate_record`).
    **options
        Passed to :func:`compensation.rigid_body_projection` (``wavelength``,
        ``range_axis``, ``azimuth``, ``elevation``, ``range_gates`` ...).

    Returns
    -------
    list of BeamCube
    """
    if len(rcs) != len(motions):
        raise ValueError(f"rcs holds {len(rcs)} frames but motions {len(motions)}; expected "
                         f"one motion per frame")
    return [rigid_body_projection(rc, element_positions, m, **options)
            for rc, m in zip(rcs, motions, strict=True)]


def accumulate(beams: Sequence[BeamCube], *, window: str | None = "hann",
               weights=None) -> np.ndarray:
    """Coherent zero-Doppler power of each frame, summed over frames.

    Within a frame the beams add coherently (the motion-compensated
    stationary scene sits at zero Doppler); across frames the unknown phase
    of each frame (position error, idle time) forbids a coherent sum, so the
    powers add.

    Parameters
    ----------
    beams : sequence of BeamCube
        Frames on the same grid.
    window : str or None
        Slow-time window of the coherent sum (``scipy.signal.get_window`` name).
    weights : array_like, shape ``[frame]``, optional
        Weight of each frame's power [1]; default 1.

    Returns
    -------
    ndarray, shape ``[range, azimuth, elevation]``
        Accumulated power [input unit squared].
    """
    if len(beams) < 1:
        raise ValueError("beams must hold at least one frame")
    w = np.ones(len(beams)) if weights is None else finite_array(
        "weights", weights, shape=(len(beams),))
    shape = beams[0].data.shape[1:]
    out = np.zeros(shape)
    for k, (b, wk) in enumerate(zip(beams, w, strict=True)):
        if b.data.shape[1:] != shape:
            raise ValueError(f"beams[{k}] has the grid {b.data.shape[1:]}, expected {shape} "
                             f"like beams[0]")
        out += wk * b.coherent_power(window=window)
    return out


def apply_velocity(motions: Sequence[PlatformMotion], times, corrections,
                   reference_time: float) -> list[PlatformMotion]:
    """Motions with a velocity correction interpolated between frames, integrated to position.

    Parameters
    ----------
    motions : sequence of PlatformMotion
        Per-frame motions of one integration.
    times : array_like, shape ``[frame]``
        Times of the corrections (frame centres) [s], increasing.
    corrections : array_like, shape ``[frame, 3]``
        Velocity to add at those times [m/s] (W).
    reference_time : float
        Time at which the position is known (no position change) [s].

    Returns
    -------
    list of PlatformMotion
        Velocity plus ``c(t)``, piecewise linear through the corrections
        (linear beyond the ends, constant for one frame); position plus
        ``int_{t_ref}^t c``, so the displacement within and between frames
        follows the corrected velocity.
    """
    from scipy.interpolate import make_interp_spline

    tm = finite_array("times", times, ndim=1)
    dv = finite_array("corrections", corrections, shape=(tm.size, 3))
    spline = make_interp_spline(tm, dv, k=min(1, tm.size - 1), axis=0)
    integral = spline.antiderivative()
    t_ref = float(reference_time)
    out = []
    for m in motions:
        out.append(PlatformMotion(m.time, m.attitude,
                                  m.position + integral(m.time) - integral(t_ref),
                                  m.velocity + spline(m.time), m.angular_rate, m.lever_arm,
                                  m.warnings))
    return out
