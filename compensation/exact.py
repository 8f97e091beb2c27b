"""Exact rigid-body compensation: one projection using all six degrees of freedom.

For every direction of a fixed global grid and every selected range gate the
beamformer uses, chirp by chirp, the full attitude ``R_WB`` and the displacement
of the radar phase centre ``T_n + R_n r_IR - r_IR`` (lever arm included), with
no small-angle approximation. The steering phase of every element is the exact
range from its displaced position to the focal point, projected on the world
direction, so the array-manifold change (roll, pitch, yaw) and the slow-time
motion phase (translation and lever-arm rotation) are removed in one step.
Doppler processing follows on the beam outputs (:meth:`BeamCube.doppler`).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ._checks import channel_slots
from .projection import BeamCube, beam_projection
from .strapdown import PlatformMotion


def rigid_body_projection(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                          range_axis, azimuth, elevation, range_gates=None,
                          focus: Literal["near", "far"] = "near",
                          grid_shape: tuple[int, int] | None = None,
                          method: Literal["auto", "nufft", "lattice", "direct"] = "auto",
                          weights=None, channel_slot=None, chirp_block: int = 32,
                          gate_block: int = 8) -> BeamCube:
    """Motion-compensated beams of a range-compressed cube on a fixed global grid.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (e.g. Hann-windowed range FFT of the IF cube).
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions ``p_tx + p_rx`` in the radar frame A [m].
    motion : PlatformMotion
        Pose at each chirp (``motion.num_chirps == chirp``), e.g. from
        :func:`compensation.strapdown.integrate_imu`. With ``channel_slot``
        (TDM MIMO): the pose at every transmit slot, chirp major, slot minor
        (``motion.num_chirps == chirp * slots``).
    wavelength : float
        Mid-chirp wavelength ``c / (f_c + B / 2)`` for range-compressed data [m].
    range_axis : array_like, shape ``[range]``
        Range of each bin [m], measured from the nominal radar phase centre.
    azimuth, elevation : array_like
        Global grid axes [rad].
    range_gates : array_like of int, optional
        Range bins to process (default all).
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM transmit slot of each channel (0 .. slots-1). Each slot's channels
        are projected with the pose of their own transmit instant and the
        partial beams are summed with their share of the weights. Gridded
        methods need each slot's channels to form a grid, otherwise use
        ``method="direct"`` (``"auto"`` does so).
    focus, grid_shape, method, weights, chirp_block, gate_block
        See :func:`compensation.projection.beam_projection`.

    Returns
    -------
    BeamCube
        ``data [chirp, range, azimuth, elevation]``; a static scatterer at a
        grid direction and gate has a constant slow-time sequence, so its
        Doppler spectrum peaks at 0 with the stationary mainlobe width.
        ``warnings`` are those of ``motion``.

    Examples
    --------
    >>> import numpy as np
    >>> from compensation.strapdown import static_motion
    >>> p = np.stack([np.arange(4) * 2e-3, np.zeros(4), np.zeros(4)], axis=1)
    >>> rc = np.ones((8, 4, 2), dtype=np.complex64)
    >>> beams = rigid_body_projection(rc, p, static_motion(np.arange(8) * 60e-6),
    ...                               wavelength=3.9e-3, range_axis=[10.0, 10.15],
    ...                               azimuth=[0.0], elevation=[0.0])
    >>> beams.data.shape, round(abs(complex(beams.data[0, 0, 0, 0])), 6)
    ((8, 2, 1, 1), 1.0)
    """
    if not isinstance(motion, PlatformMotion):
        raise ValueError(f"motion must be a compensation.PlatformMotion, got {type(motion)!r}")
    n_chirp = rc.shape[0] if hasattr(rc, "shape") else len(rc)
    common = dict(wavelength=wavelength, range_axis=range_axis, azimuth=azimuth,
                  elevation=elevation, range_gates=range_gates, focus=focus,
                  chirp_block=chirp_block, gate_block=gate_block)
    if channel_slot is None:
        if motion.num_chirps != n_chirp:
            raise ValueError(f"motion has {motion.num_chirps} chirp times but rc has "
                             f"{n_chirp} chirps")
        return beam_projection(rc, element_positions, chirp_time=motion.time,
                               attitude=motion.attitude,
                               displacement=motion.radar_displacement, grid_shape=grid_shape,
                               method=method, weights=weights,
                               **common).with_warnings(motion.warnings)
    x = np.asarray(rc)
    p = np.asarray(element_positions, dtype=float)
    slot = channel_slots(channel_slot, x.shape[1])
    n_slot = int(slot.max()) + 1
    if motion.num_chirps != n_chirp * n_slot:
        raise ValueError(f"with {n_slot} TDM slots motion must hold chirp * slots = "
                         f"{n_chirp * n_slot} poses (chirp major), got {motion.num_chirps}")
    w = np.ones(x.shape[1]) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (x.shape[1],):
        raise ValueError(f"weights must have shape [{x.shape[1]}], got {w.shape}")
    total, out = float(w.sum()), None
    if method == "auto" and grid_shape is None:
        method = "direct"
    for s in range(n_slot):
        sel = np.flatnonzero(slot == s)
        if sel.size == 0:
            continue
        m = motion.select(slice(s, None, n_slot))
        part = beam_projection(x[:, sel], p[sel], chirp_time=m.time, attitude=m.attitude,
                               displacement=m.radar_displacement,
                               grid_shape=None if method == "direct" else grid_shape,
                               method=method, weights=w[sel], **common)
        share = float(w[sel].sum()) / total
        out = part.data * np.float32(share) if out is None else out + part.data * np.float32(
            share)
    chirp_time = motion.time[::n_slot]
    return BeamCube(out.astype(np.complex64, copy=False), chirp_time, part.range, part.azimuth,
                    part.elevation, part.wavelength, motion.warnings)
