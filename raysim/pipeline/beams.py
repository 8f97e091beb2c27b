"""The beamformer of every point measurement: one chain over a frame, TDM slots included.

:class:`Beamformer` wraps :func:`raysim.pipeline.chains.project` (the one
place a chain name becomes beams) for the cells of one frame: it picks the
poses of the chirps it is given from the frame's motion, at every transmit
slot for a compensated chain on a TDM array, and collects the chain's guard
warnings. :mod:`raysim.measure.point` measures every point metric through it.
"""

from __future__ import annotations

import numpy as np

from raysim.pipeline.chains import project
from raysim.radar.arrays import VirtualArray
from raysim.vocabulary import ChainSpec, parse_chain

__all__ = ["Beamformer"]


class Beamformer:
    """Beams of one chain on the cells of one frame.

    Parameters
    ----------
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    array : VirtualArray
        Virtual array of the frame (positions ``[channel, 3]`` in A [m], TDM
        slot of every channel, UPA grid shape).
    wavelength : float
        Wavelength of the phase model [m].
    motion : compensation.PlatformMotion, optional
        Pose at every transmit slot of every chirp of the frame, chirp major,
        slot minor (one pose per chirp for a single-slot array); required by
        the compensated chains. A compensated chain on a TDM array projects
        each slot's channels with the pose of its own transmit instant;
        ``none`` ignores the motion.
    warnings : list, optional
        Receives the chain's guard warnings (str), each once.

    Raises
    ------
    ValueError
        A compensated chain without ``motion``.
    """

    def __init__(self, chain: str | ChainSpec, array: VirtualArray, wavelength: float, *,
                 motion=None, warnings: list | None = None) -> None:
        self.spec = parse_chain(chain)
        if self.spec.compensated and motion is None:
            raise ValueError(f"chain {self.spec.key!r} needs motion (the platform pose at "
                             f"every chirp)")
        self.array = array
        self.wavelength = float(wavelength)
        self.motion = motion if self.spec.compensated else None
        self.warnings = [] if warnings is None else warnings

    @property
    def compensated(self) -> bool:
        """Whether the chain uses the motion (False for ``none``, a linear beam scan)."""
        return self.spec.compensated

    def __call__(self, rc: np.ndarray, chirps, ranges, azimuth, elevation,
                 direction=None) -> np.ndarray:
        """Beams of the chirps ``chirps`` of the frame.

        Parameters
        ----------
        rc : ndarray, shape ``[chirp, channel, range]``
            Range-compressed cells of the chirps ``chirps`` [sqrt(W)].
        chirps : array_like of int, shape ``[chirp]``
            Index of each chirp of ``rc`` in the frame (selects its poses).
        ranges : array_like, shape ``[range]``
            Range of every bin of ``rc`` [m].
        azimuth, elevation : array_like
            Grid axes [rad].
        direction : array_like, shape ``[3]``, optional
            Slow-time correction direction of the ``paper`` chain (unit vector in A).

        Returns
        -------
        ndarray, shape ``[chirp, range, azimuth, elevation]``, complex
            Beam outputs [sqrt(W)].
        """
        arr = self.array
        c = np.asarray(chirps, dtype=int).reshape(-1)
        if c.size != np.shape(rc)[0]:
            raise ValueError(f"chirps holds {c.size} indices, rc has {np.shape(rc)[0]} chirps; "
                             f"expected one index per chirp")
        slots = arr.num_slots
        mot, channel_slot = None, None
        if self.motion is not None and slots > 1:   # every TDM slot at its own pose
            mot = self.motion.select((c[:, None] * slots + np.arange(slots)).ravel())
            channel_slot = arr.tx_slot
        elif self.motion is not None:
            mot = self.motion.select(c)
        out = project(self.spec, rc, arr.virtual_positions, wavelength=self.wavelength,
                      range_axis=np.atleast_1d(ranges), azimuth=np.atleast_1d(azimuth),
                      elevation=np.atleast_1d(elevation), motion=mot, direction=direction,
                      grid_shape=arr.grid_shape, channel_slot=channel_slot)
        self.warnings.extend(w for w in out.warnings if w not in self.warnings)
        return out.data
