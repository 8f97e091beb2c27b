"""Compensation chains (stage 4 of the run path): range-compressed data -> beams.

The one place where a chain name (:data:`raysim.vocabulary.CHAINS`) turns
into a computation: ``none`` is the conventional beamformer
(:func:`compensation.beam_projection` without motion), ``paper`` the
published chain (:func:`compensation.paper_chain`, rotation phase as an
option), ``exact`` the rigid-body projection
(:func:`compensation.rigid_body_projection`). Every study and command calls
:func:`project`.
"""

from __future__ import annotations

import numpy as np

from raysim.vocabulary import ChainSpec, parse_chain

__all__ = ["project"]


def project(chain: str | ChainSpec, rc, element_positions, *, wavelength: float, range_axis,
            azimuth, elevation, motion=None, direction=None, grid_shape=None, weights=None,
            range_gates=None, channel_slot=None):
    """Beams of a range-compressed cube through one chain.

    Parameters
    ----------
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed data.
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual element positions in A [m].
    wavelength : float
        Wavelength of the phase model [m].
    range_axis : array_like, shape ``[range]``
        Range of every bin of ``rc`` [m].
    azimuth, elevation : array_like
        Grid axes [rad].
    motion : compensation.PlatformMotion, optional
        Pose at every chirp of ``rc`` (needed by ``paper`` and ``exact``).
    direction : array_like, shape ``[3]``, optional
        Slow-time correction direction of the ``paper`` chain (unit vector in A).
    grid_shape, weights, range_gates
        As in :func:`compensation.beam_projection`.
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM transmit slot of each channel (``paper`` and ``exact``): ``motion``
        then holds the pose at every transmit slot, chirp major, slot minor, and
        each channel is compensated with the pose of its own slot.

    Returns
    -------
    compensation.BeamCube
        ``data`` ``[chirp, range, azimuth, elevation]``; its ``warnings`` are
        the chain's guard warnings.
    """
    from compensation import beam_projection, paper_chain, rigid_body_projection

    spec = parse_chain(chain)
    kw = dict(wavelength=wavelength, range_axis=range_axis, azimuth=azimuth,
              elevation=elevation, grid_shape=grid_shape, weights=weights,
              range_gates=range_gates)
    if spec.name == "none":
        return beam_projection(rc, element_positions, **kw)
    if motion is None:
        raise ValueError(f"chain {spec.key!r} needs motion (the platform pose at every chirp)")
    if spec.name == "exact":
        return rigid_body_projection(rc, element_positions, motion, channel_slot=channel_slot,
                                     **kw)
    if direction is None:
        raise ValueError("chain 'paper' needs direction (its slow-time correction direction)")
    return paper_chain(rc, element_positions, motion, direction=np.asarray(direction),
                       rotation_phase=spec.rotation_phase, channel_slot=channel_slot, **kw)
