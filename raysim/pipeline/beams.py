"""The beamformer of every point measurement: one chain over a frame, TDM slots included.

:class:`Beamformer` wraps :func:`raysim.pipeline.chains.project` (the one
place a chain name becomes beams) for the cells of one frame: it picks the
poses of the chirps it is given from the frame's motion, at every transmit
slot for a compensated chain on a TDM array, and collects the chain's guard
warnings. For ``dpca`` it plans the sub-aperture once from the whole frame's
motion (:func:`compensation.dpca_plan`, :attr:`Beamformer.plan`) and holds its
size for every call, so beams of any chirps of the frame come from
sub-apertures of one size. :mod:`raysim.measure.point` measures every point metric through it.
"""

from __future__ import annotations

import numpy as np

from raysim.pipeline.chains import project
from raysim.radar.arrays import VirtualArray
from raysim.vocabulary import ChainSpec, parse_chain

__all__ = ["Beamformer", "PRICE_PREFIX"]

#: Start of the line a ``dpca`` beamformer adds to its warnings to state its price
#: (elements kept, beamwidth growth, gain lost: :meth:`compensation.DPCAPlan.summary`).
PRICE_PREFIX = "dpca price: "


class Beamformer:
    """Beams of one chain on the cells of one frame.

    Parameters
    ----------
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published``, ``exact`` or ``dpca``.
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
        Receives the chain's guard warnings (str), each once. ``dpca`` adds, from
        the start, its price (:data:`PRICE_PREFIX` then the plan's summary:
        sub-aperture kept, beamwidth growth, gain lost) and its plan's
        ``dpca aperture`` / ``dpca rotation`` warnings, so both reach every
        command that reports the warnings.
    subaperture : (int, int), optional
        ``dpca``: elements per axis of its sub-aperture (default the largest
        the frame's motion leaves, :attr:`plan`).

    Attributes
    ----------
    plan : compensation.DPCAPlan or None
        ``dpca``: the sub-aperture of the whole frame and its price
        (``summary()``, ``gain_loss_db``, ``resolution_loss``); None otherwise.

    Raises
    ------
    ValueError
        A compensated chain without ``motion``; ``dpca`` with a displacement
        over the frame larger than the spare aperture.
    """

    def __init__(self, chain: str | ChainSpec, array: VirtualArray, wavelength: float, *,
                 motion=None, warnings: list | None = None, subaperture=None) -> None:
        self.spec = parse_chain(chain)
        if self.spec.compensated and motion is None:
            raise ValueError(f"chain {self.spec.key!r} needs motion (the platform pose at "
                             f"every chirp)")
        self.array = array
        self.wavelength = float(wavelength)
        self.motion = motion if self.spec.compensated else None
        self.warnings = [] if warnings is None else warnings
        self.plan = None
        if self.spec.name == "dpca":
            from compensation import dpca_plan

            self.plan = dpca_plan(array.virtual_positions, self.motion,
                                  wavelength=self.wavelength, grid_shape=array.grid_shape,
                                  channel_slot=array.tx_slot if array.num_slots > 1 else None,
                                  subaperture=subaperture)
            price = PRICE_PREFIX + self.plan.summary().removeprefix("dpca: ")
            self.warnings.extend(w for w in (price, *self.plan.warnings)
                                 if w not in self.warnings)

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
                      grid_shape=arr.grid_shape, channel_slot=channel_slot,
                      subaperture=None if self.plan is None else self.plan.sub_shape)
        # dpca: the frame's plan stated its aperture and rotation warnings; a call on
        # some of the frame's chirps would restate them for those chirps only
        fresh = [w for w in out.warnings if self.plan is None or not w.startswith("dpca ")]
        self.warnings.extend(w for w in fresh if w not in self.warnings)
        return out.data
