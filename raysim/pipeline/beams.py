"""The beamformer of every point measurement: one chain over a frame, TDM slots included.

:class:`Beamformer` wraps :func:`raysim.pipeline.chains.project` (the one
place a chain name becomes beams) for the cells of one frame: it picks the
poses of the chirps it is given from the frame's motion, at every transmit
slot for a compensated chain on a TDM array, and collects the chain's guard
warnings. For ``dpca`` it plans the sub-aperture once from the whole frame's
motion (:func:`compensation.dpca_plan`, :attr:`Beamformer.plan`) and holds it
for every call: every call is given the plan's elements
(``DPCAPlan.reference_index``) and also projects the (zero) cells of the
frame's :attr:`Beamformer.anchors`, the chirps whose sub-aperture shifts are
the frame's extremes, so the reference sub-aperture (its phase centre) is the
whole frame's whichever chirps a call asks for. Beams of a
chirp are then the same in every call. :mod:`raysim.measure.point` measures
every point metric through it.
"""

from __future__ import annotations

import numpy as np

from raysim.pipeline.chains import project
from raysim.radar.arrays import VirtualArray
from raysim.vocabulary import ChainSpec, parse_chain

__all__ = ["Beamformer", "PRICE_PREFIX", "common_subaperture"]

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
    subaperture : (int, int) or array_like of int, optional
        ``dpca``: elements per axis of its sub-aperture, or the lattice indices
        ``[sub, 2]`` of its elements (default the largest the frame's motion
        leaves, :attr:`plan`).

    Attributes
    ----------
    plan : compensation.DPCAPlan or None
        ``dpca``: the sub-aperture of the whole frame and its price
        (``summary()``, ``gain_loss_db``, ``resolution_loss``); None otherwise.
    anchors : ndarray of int, shape ``[k]``
        ``dpca``: chirps (``k <= 4``) whose sub-aperture offsets are the
        frame's smallest and largest along each lattice axis; empty otherwise.

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
        self.plan, self.anchors = None, np.zeros(0, dtype=int)
        if self.spec.name == "dpca":
            from compensation import dpca_plan

            self.plan = dpca_plan(array.virtual_positions, self.motion,
                                  wavelength=self.wavelength, grid_shape=array.grid_shape,
                                  channel_slot=array.tx_slot if array.num_slots > 1 else None,
                                  subaperture=subaperture)
            price = PRICE_PREFIX + self.plan.summary().removeprefix("dpca: ")
            self.warnings.extend(w for w in (price, *self.plan.warnings)
                                 if w not in self.warnings)
            self.anchors = _anchors(self.plan)

    @property
    def compensated(self) -> bool:
        """Whether the chain uses the motion (False for ``none``, a linear beam scan)."""
        return self.spec.compensated

    def __call__(self, rc: np.ndarray, chirps, ranges, azimuth, elevation,
                 direction=None) -> np.ndarray:
        """Beam outputs of the chirps ``chirps`` of the frame (:meth:`cube`'s data).

        Returns
        -------
        ndarray, shape ``[chirp, range, azimuth, elevation]``, complex
            Beam outputs [sqrt(W)].
        """
        return self.cube(rc, chirps, ranges, azimuth, elevation, direction=direction).data

    def cube(self, rc: np.ndarray, chirps, ranges, azimuth, elevation, *, direction=None,
             range_gates=None, weights=None):
        """Beams of the chirps ``chirps`` of the frame, with their axes.

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
        range_gates : array_like of int, optional
            Bins of ``rc`` to beamform (default all).
        weights : None, array_like or callable, optional
            Channel weights handed to the chain (``dpca``: its sub-aperture taper).

        Returns
        -------
        compensation.BeamCube
            ``data`` ``[chirp, range, azimuth, elevation]`` [sqrt(W)] of the asked
            chirps, the chain's guard warnings (also added to :attr:`warnings`).
        """
        from dataclasses import replace

        arr = self.array
        c = np.asarray(chirps, dtype=int).reshape(-1)
        if c.size != np.shape(rc)[0]:
            raise ValueError(f"chirps holds {c.size} indices, rc has {np.shape(rc)[0]} chirps; "
                             f"expected one index per chirp")
        n_asked = c.size
        extra = np.setdiff1d(self.anchors, c)
        if extra.size:          # dpca: the frame's extreme offsets fix its reference
            rc = np.concatenate([np.asarray(rc), np.zeros((extra.size,) + np.shape(rc)[1:],
                                                          dtype=np.asarray(rc).dtype)])
            c = np.concatenate([c, extra])
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
                      range_gates=range_gates, weights=weights,
                      subaperture=None if self.plan is None else self.plan.reference_index)
        # dpca: the frame's plan stated its aperture and rotation warnings; a call on
        # some of the frame's chirps would restate them for those chirps only
        fresh = [w for w in out.warnings if self.plan is None or not w.startswith("dpca ")]
        self.warnings.extend(w for w in fresh if w not in self.warnings)
        if n_asked == out.data.shape[0]:
            return out
        return replace(out, data=out.data[:n_asked], chirp_time=out.chirp_time[:n_asked])


def common_subaperture(positions: np.ndarray, motions, wavelength: float, *, grid_shape=None,
                       channel_slot=None) -> tuple[tuple[int, int], str]:
    """The ``dpca`` sub-aperture every frame of a record can hold, and its price.

    One size for all frames, so their maps are comparable: per axis the
    smallest the frames' plans (:func:`compensation.dpca_plan`) allow.

    Parameters
    ----------
    positions : ndarray, shape ``[channel, 3]``
        Virtual element positions in A [m].
    motions : sequence of compensation.PlatformMotion
        Pose at every transmit slot of every chirp, one per frame.
    wavelength : float
        [m].
    grid_shape, channel_slot
        As :func:`compensation.dpca_plan` takes them.

    Returns
    -------
    sub : (int, int)
        Elements per lattice axis.
    price : str
        :data:`PRICE_PREFIX` then the plan's summary at that size.

    Raises
    ------
    ValueError
        The plan's error for a frame whose displacement exceeds the spare aperture.
    """
    from compensation import dpca_plan

    motions = list(motions)
    plans = [dpca_plan(positions, m, wavelength=wavelength, grid_shape=grid_shape,
                       channel_slot=channel_slot) for m in motions]
    sub = tuple(int(min(p.sub_shape[a] for p in plans)) for a in (0, 1))
    plan = dpca_plan(positions, motions[0], wavelength=wavelength, grid_shape=grid_shape,
                     channel_slot=channel_slot, subaperture=sub)
    return sub, PRICE_PREFIX + plan.summary().removeprefix("dpca: ")


def _anchors(plan) -> np.ndarray:
    """Chirps whose sub-aperture shifts reach the frame's extremes along each axis.

    The reference sub-aperture of a projection is what every shift of its
    chirps keeps inside the array (:meth:`compensation.DPCAPlan.anchor_chirps`),
    so projecting these chirps with any others reproduces the whole frame's reference.
    """
    return plan.anchor_chirps()
