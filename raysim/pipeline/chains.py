"""Compensation chains (stage 4 of the run path): range-compressed data -> beams.

The one place where a chain name (:data:`raysim.vocabulary.CHAINS`) turns
into a computation: ``none`` is the conventional beamformer
(:func:`compensation.beam_projection` without motion), ``paper`` the
published chain (:func:`compensation.paper_chain`, rotation phase as an
option), ``exact`` the rigid-body projection
(:func:`compensation.rigid_body_projection`), ``dpca`` the displaced-phase-centre
projection (:func:`compensation.dpca_projection`: a sub-aperture held fixed in
the world, its price in the result's ``plan``). Every study and command calls
:func:`project`.
"""

from __future__ import annotations

import numpy as np

from raysim.vocabulary import ChainSpec, parse_chain

__all__ = ["project"]


def project(chain: str | ChainSpec, rc, element_positions, *, wavelength: float, range_axis,
            azimuth, elevation, motion=None, direction=None, grid_shape=None, weights=None,
            range_gates=None, channel_slot=None, subaperture=None, order: int = 3):
    """Beams of a range-compressed cube through one chain.

    Parameters
    ----------
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published``, ``exact`` or ``dpca``.
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
        Pose at every chirp of ``rc`` (needed by ``paper``, ``exact`` and ``dpca``).
    direction : array_like, shape ``[3]``, optional
        Slow-time correction direction of the ``paper`` chain (unit vector in A).
    grid_shape, weights, range_gates
        As in :func:`compensation.beam_projection`. ``dpca`` tapers its
        sub-aperture, not the array: its ``weights`` are None (uniform), an
        array ``[sub]`` in the order of ``DPCAPlan.reference_index`` or a
        callable ``weights(index [sub, 2]) -> [sub]`` of the lattice indices
        counted from the sub-aperture's corner (a full-array ``[channel]``
        taper is refused with a ValueError).
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM transmit slot of each channel (``paper``, ``exact``, ``dpca``):
        ``motion`` then holds the pose at every transmit slot, chirp major,
        slot minor, and each channel is compensated with the pose of its own slot.
    subaperture : (int, int) or array_like of int, optional
        ``dpca`` only: elements per axis of the sub-aperture, or the lattice
        indices ``[sub, 2]`` of its elements (default the largest the motion
        of ``rc`` leaves; fix it to compare frames).
    order : {1, 3}
        ``dpca`` only: Lagrange interpolation order between sub-apertures,
        used where ``dpca`` interpolates with Lagrange weights (TDM arrays,
        lattices with holes); on a full lattice it estimates the shifted
        channels band-limited (:func:`compensation.dpca_projection`,
        ``interpolation="auto"``).

    Returns
    -------
    compensation.BeamCube
        ``data`` ``[chirp, range, azimuth, elevation]``; its ``warnings`` are
        the chain's guard warnings. ``dpca`` returns a
        :class:`compensation.DPCABeams` whose ``plan`` states the sub-aperture
        and its price (``plan.summary()``, ``gain_loss_db``,
        ``resolution_loss``); its ``dpca aperture`` / ``dpca rotation``
        warnings are among ``warnings``.

    Raises
    ------
    ValueError
        A compensated chain without ``motion``, ``paper`` without
        ``direction``, options of ``dpca`` given to another chain, or what the
        chain itself refuses (``dpca``: a displacement larger than the spare aperture).
    """
    from compensation import beam_projection, dpca_projection, paper_chain, rigid_body_projection

    spec = parse_chain(chain)
    if spec.name != "dpca" and (subaperture is not None or order != 3):
        raise ValueError(f"subaperture={subaperture!r}, order={order!r}: options of the dpca "
                         f"chain, got chain {spec.key!r}")
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
    if spec.name == "dpca":
        return dpca_projection(rc, element_positions, motion, channel_slot=channel_slot,
                               order=order, subaperture=subaperture, **kw)
    if direction is None:
        raise ValueError("chain 'paper' needs direction (its slow-time correction direction)")
    return paper_chain(rc, element_positions, motion, direction=np.asarray(direction),
                       rotation_phase=spec.rotation_phase, channel_slot=channel_slot, **kw)
