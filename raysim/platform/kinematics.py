"""Where and when the radar's elements are: TDM slot times, element times and world positions.

One definition of the transmit timing of a TDM-MIMO frame for every echo
source, synthesis, processing and the compensation of recordings: the
channels of TDM slot ``s`` fire ``s * slot_interval`` after their chirp
loop starts (``slot_interval = T_c + idle``, :attr:`RadarConfig.slot_interval`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["slot_times", "element_times", "element_world_positions"]


def slot_times(chirp_times, num_slots: int, slot_interval: float) -> np.ndarray:
    """Transmit instant of every TDM slot of every chirp loop [s].

    Parameters
    ----------
    chirp_times : array_like, shape ``[...]``
        Chirp-loop start times [s] (any leading shape, e.g. ``[frame, chirp]``).
    num_slots : int
        TDM transmit slots per loop (1 without TDM).
    slot_interval : float
        Ramp-to-ramp interval of consecutive slots [s].

    Returns
    -------
    ndarray, shape ``[..., slot]``
        ``chirp_times[..., None] + arange(num_slots) * slot_interval``.
    """
    if not (isinstance(num_slots, (int, np.integer)) and num_slots >= 1):
        raise ValueError(f"num_slots must be an integer >= 1, got {num_slots!r}")
    if not (np.isfinite(slot_interval) and slot_interval >= 0):
        raise ValueError(f"slot_interval must be a finite time >= 0 s, got {slot_interval!r}")
    return (np.asarray(chirp_times, dtype=float)[..., None]
            + np.arange(int(num_slots)) * float(slot_interval))


def element_times(config, array, frame: int = 0, t0: float = 0.0) -> np.ndarray:
    """Transmit instant of every (chirp, channel), shape ``[chirp, channel]`` [s].

    Parameters
    ----------
    config : raysim.radar.config.RadarConfig
    array : raysim.radar.arrays.VirtualArray
        ``tx_slot`` gives each channel's TDM slot.
    frame : int
        Frame index.
    t0 : float
        Start of frame 0 [s].
    """
    if array.num_slots != config.num_tx_slots:
        raise ValueError(
            f"array has {array.num_slots} TDM slots but config.num_tx_slots = "
            f"{config.num_tx_slots}; set RadarConfig(num_tx_slots={array.num_slots})"
        )
    per_slot = slot_times(config.chirp_times(frame, t0), array.num_slots,
                          config.slot_interval)                     # [chirp, slot]
    return per_slot[:, np.asarray(array.tx_slot, dtype=int)]


def element_world_positions(trajectory, times: np.ndarray, points_a: np.ndarray,
                            lever_arm: np.ndarray) -> np.ndarray:
    """World positions of radar-frame points at per-(chirp, channel) times.

    ``x(t) = T(t) + R_WB(t) (r_IR + p)`` (docs/conventions.md).

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    times : ndarray, shape ``[chirp, channel]`` or ``[chirp, channel, sample]``
        Time of each evaluation [s].
    points_a : ndarray, shape ``[channel, 3]``
        Points in frame A (axes parallel to B) [m].
    lever_arm : ndarray, shape ``[3]``
        Radar origin in B [m].

    Returns
    -------
    ndarray, shape ``times.shape + (3,)`` [m]
    """
    # evaluate each distinct time once (a virtual UPA shares one time per chirp)
    uniq, inverse = np.unique(times, return_inverse=True)
    pos, rot = trajectory.pose(uniq)
    mats = rot.as_matrix()[inverse.reshape(times.shape)]       # [..., 3, 3]
    body = points_a + np.asarray(lever_arm, dtype=float)       # [channel, 3]
    body = body.reshape((1, body.shape[0]) + (1,) * (times.ndim - 2) + (3,))
    return pos[inverse.reshape(times.shape)] + np.einsum("...ij,...j->...i", mats, body)
