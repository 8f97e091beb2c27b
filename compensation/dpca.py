"""Displaced-phase-centre (DPCA) projection: a sub-aperture that stays put in the world.

A horizontal displacement ``D`` of the radar moves every virtual element by
``2 D`` in the virtual (``p_tx + p_rx``, one-way phase) coordinates, so the
echo of a static scatterer at direction ``u`` changes phase by
``-4 pi / lambda u . D``. Two scatterers in one beam change their *relative*
phase by ``-4 pi / lambda D . (u1 - u2)``: a per-beam phase correction (the
exact chain, :mod:`compensation.exact`) removes the phase of the beam
direction only, so the clutter inside a beam decorrelates from chirp to chirp.

DPCA undoes the displacement instead of correcting it: at chirp ``n`` it uses
the sub-aperture whose elements sit, in the world, where the reference
sub-aperture's elements sat. With the lattice ``p = p0 + ix a + iy b`` of the
virtual array, the attitude ``R_n`` and the phase-centre displacement ``d_n``
(lever arm included), the sub-aperture's centroid ``c`` must move in the
radar frame A to ``R_n^T (c - 2 d_n)``; its in-plane part, in element
spacings along ``a`` and ``b``, is the shift ``(sx_n, sy_n)`` (at the nominal
attitude: ``-2 D / spacing`` for a horizontal ``D``). The part normal to the
array (vertical displacement) cannot be undone by a shift and is left to the
projection.

A fractional shift is estimated one of two ways (``interpolation``;
``"auto"`` takes the first on a full rectangular lattice with one TDM slot):

* ``"bandlimited"`` (:mod:`compensation.subaperture_shift`): the
  sub-aperture's channels are estimated at their shifted positions
  ``q + s_n`` from all the array's channels, separably along ``a`` and ``b``,
  with the least-squares interpolator of a signal band-limited to
  ``|u . a| / |a| <= band`` (echoes beyond it, near endfire, are estimated
  with larger errors); positions may reach
  :data:`~compensation.subaperture_shift.REACH` spacings beyond the array.
  The estimates sit in A at ``p_q + s_n . (a, b)``, which is ``p_q`` on a
  radar displaced by ``R_n s_n . (a, b) / 2`` more: one exact projection of
  the reference positions with that motion. The error for an echo at phase
  step ``psi`` per element is closed-form
  (:func:`~compensation.subaperture_shift.shift_error`); a beam with taper
  ``w`` is off by at most ``sum_q |w_q| e_q / |sum_q w_q|`` of the echo's
  amplitude.
* ``"lagrange"``: integer shifts select a sub-aperture; for ``s = i + f``
  the beam outputs of the neighbouring integer sub-apertures ``i + l`` are
  combined with Lagrange weights ``h_l(f)`` (``order`` 1: ``l = 0, 1``,
  linear; ``order`` 3: ``l = -1 .. 2``, cubic), separably along ``a`` and
  ``b``; any lattice, each TDM slot's channels at their own pose.
  Interpolating the beam outputs is interpolating the channel data
  demodulated by the beam's steering phase: a scatterer whose per-element
  phase step differs from the beam's by ``dpsi = 2 pi / lambda (u - u_G) . a``
  gets ``sum_l h_l exp(j dpsi l)`` instead of ``exp(j dpsi f)``, an error of
  at most (Lagrange remainder, :func:`interpolation_error`)::

      order 1:  dpsi^2 / 8            order 3:  3 dpsi^4 / 128

  per axis: -29 dB (linear) and -55 dB (cubic) inside the main lobe of a
  12-element sub-aperture; beyond ``|dpsi| = pi / 2`` neither helps much.

Every sub-aperture is projected as :func:`compensation.exact.rigid_body_projection`
does (attitude and displacement of every chirp and TDM slot), rotation and the
vertical displacement as in the exact chain (an echo from the beam direction
is exact with Lagrange weights, within the interpolation error band-limited).

Price (:class:`DPCAPlan`): the sub-aperture keeps the largest block whose
shifted positions stay within reach of the array (band-limited) or ``K = N -
span - (stencil - 1)`` elements per axis (Lagrange, ``span`` the range of the
integer shifts over the frame); the beamwidth grows by ``N / K`` and the
coherent gain falls by ``10 log10(M / M_sub)`` dB. Failure: no element left
(``ValueError``); the aperture halved (``"dpca aperture"`` warning); a
rotation that moves the sub-aperture's elements by more than half a spacing
from their world positions (``"dpca rotation"`` warning: the sub-aperture no
longer overlaps itself, the fixed phase centre still holds).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ._checks import channel_slots, choice, complex_cube, finite_array, positive
from .exact import rigid_body_projection
from .guards import BEAMWIDTH_FACTOR, merge
from .projection import LATTICE_TOL, BeamCube, lattice_vectors
from .strapdown import PlatformMotion
from .subaperture_shift import (
    BAND,
    REACH,
    STENCILS,
    interpolation_error,  # noqa: F401  (part of this module's interface)
    lagrange_groups,
    lagrange_weights,  # noqa: F401
    order_checked,
    reachable_block,
    shift_channels,
)

#: A shift within this many element spacings of an integer counts as that integer.
FRAC_TOL = 1e-6
#: Ways to estimate a sub-aperture at a fractional shift: ``"bandlimited"`` (the
#: channels estimated at the shifted positions from the whole array,
#: :mod:`compensation.subaperture_shift`; a full rectangular lattice, one TDM slot)
#: and ``"lagrange"`` (beam outputs of neighbouring sub-apertures combined, any lattice).
INTERPOLATIONS = ("bandlimited", "lagrange")
#: Fraction of the elements per axis below which the sub-aperture is reported
#: (``"dpca aperture"`` warning: beamwidth more than doubled).
MIN_KEEP_FRACTION = 0.5
#: Largest in-plane movement of a sub-aperture element from its world position
#: over the frame, in element spacings, before ``"dpca rotation"`` is reported.
ROTATION_LIMIT = 0.5


@dataclass(frozen=True, eq=False)
class DPCAPlan:
    """Sub-aperture choice of the DPCA projection for one frame, and its price.

    Attributes
    ----------
    shift : ndarray, shape ``[chirp, 2]``
        Sub-aperture shift along the lattice steps ``a`` and ``b`` [element
        spacings]; 0 along an axis with one element.
    lattice : ndarray, shape ``[3, 3]``
        Rows ``p0, a, b``: element ``(ix, iy)`` sits at ``p0 + ix a + iy b`` in A [m].
    element_index : ndarray of int, shape ``[channel, 2]``
        Lattice index ``(ix, iy)`` of every channel.
    reference_index : ndarray of int, shape ``[sub, 2]``
        Lattice indices of the reference sub-aperture (offset 0), x major; the
        sub-aperture used at offset ``o`` is ``reference_index + o``.
    reference_positions : ndarray, shape ``[sub, 3]``
        Where the reference sub-aperture's elements sit in A at the nominal
        pose [m]: the positions the DPCA holds fixed in the world.
    order : int
        Lagrange interpolation order (1 linear, 3 cubic; unused when band-limited).
    full_shape, sub_shape : (int, int)
        Elements per axis of the array and of the sub-aperture (extent of the indices).
    beamwidth_full, beamwidth_sub : (float, float)
        Boresight 3 dB beamwidth ``0.886 lambda / (n |a|)`` per axis [rad] (inf for one element).
    gain_loss_db : float
        Coherent gain lost, ``10 log10(channel / sub)`` [dB].
    residual_displacement : float
        Largest displacement the shift cannot undo (normal to the array, or
        along an axis with one element), ``max |r_n| / 2`` [m].
    rotation_misplacement : float
        Largest in-plane movement of a sub-aperture element from its world
        position over the frame [element spacings] (rotation about the centroid).
    overlap : float
        Fraction of the sub-aperture's elements that stay within
        :data:`ROTATION_LIMIT` of their world positions.
    warnings : tuple of str
        ``"dpca aperture: ..."``, ``"dpca rotation: ..."``; empty when none.
    interpolation : str
        ``"bandlimited"`` or ``"lagrange"`` (:data:`INTERPOLATIONS`).
    band : float
        Design band of the band-limited interpolation (largest direction
        cosine along a lattice axis it is designed for, :data:`BAND`).
    """

    shift: np.ndarray
    lattice: np.ndarray
    element_index: np.ndarray
    reference_index: np.ndarray
    reference_positions: np.ndarray
    order: int
    full_shape: tuple[int, int]
    sub_shape: tuple[int, int]
    beamwidth_full: tuple[float, float]
    beamwidth_sub: tuple[float, float]
    gain_loss_db: float
    residual_displacement: float
    rotation_misplacement: float
    overlap: float
    warnings: tuple[str, ...] = ()
    interpolation: str = "lagrange"
    band: float = BAND

    def positions(self) -> tuple[np.ndarray, np.ndarray]:
        """Where the sub-aperture's elements are estimated at every chirp (band-limited).

        Returns
        -------
        tx, ty : ndarray, shape ``[chirp, kx]``, ``[chirp, ky]``
            Lattice positions along ``a`` and ``b`` [element spacings]:
            ``reference_index + shift``.
        """
        lo = self.reference_index.min(axis=0)
        tx = lo[0] + np.arange(self.sub_shape[0])[None, :] + self.shift[:, :1]
        ty = lo[1] + np.arange(self.sub_shape[1])[None, :] + self.shift[:, 1:]
        return tx, ty

    def anchor_chirps(self) -> np.ndarray:
        """Chirps whose shifts reach the frame's extremes along each axis.

        The reference sub-aperture of a projection depends on the extremes of
        the shifts of its chirps; projecting these chirps with any others
        reproduces the whole frame's reference.
        """
        if self.interpolation == "bandlimited":
            lo, hi = self.shift, self.shift
        else:
            nodes = STENCILS[self.order]
            floor = np.floor(self.shift).astype(int)
            whole = (self.shift - floor) == 0
            lo = floor + np.where(whole, 0, min(nodes))
            hi = floor + np.where(whole, 0, max(nodes))
        pick = [np.argmin(lo[:, a]) for a in (0, 1)] + [np.argmax(hi[:, a]) for a in (0, 1)]
        return np.unique(np.asarray(pick, dtype=int))

    @property
    def resolution_loss(self) -> tuple[float, float]:
        """Beamwidth growth ``N / K`` per axis [1]."""
        return tuple(float(n / k) for n, k in zip(self.full_shape, self.sub_shape, strict=True))

    @property
    def is_grid(self) -> bool:
        """Whether the sub-aperture is a full ``sub_shape`` block of the lattice."""
        return int(np.prod(self.sub_shape)) == self.reference_index.shape[0]

    def channels(self, offset) -> np.ndarray:
        """Channels of the sub-aperture at integer ``offset = (ox, oy)``, shape ``[sub]``."""
        lookup = {tuple(int(v) for v in e): m for m, e in enumerate(self.element_index)}
        want = self.reference_index + np.asarray(offset, dtype=int)
        try:
            return np.array([lookup[tuple(int(v) for v in e)] for e in want], dtype=int)
        except KeyError as err:
            raise ValueError(f"offset {tuple(offset)} takes the sub-aperture outside the "
                             f"array (lattice point {err.args[0]} missing)") from None

    def summary(self) -> str:
        """One line: elements kept per axis, beamwidth growth, gain lost."""
        (nx, ny), (kx, ky) = self.full_shape, self.sub_shape
        rx, ry = self.resolution_loss
        how = (f"band-limited, |u| <= {self.band:g}" if self.interpolation == "bandlimited"
               else f"order {self.order}")
        return (f"dpca: sub-aperture {kx} x {ky} of {nx} x {ny} elements ({how}),"
                f" beamwidth x{rx:.3g} / x{ry:.3g}, gain -{self.gain_loss_db:.3g} dB")


@dataclass(frozen=True, eq=False)
class DPCABeams(BeamCube):
    """:class:`BeamCube` of :func:`dpca_projection` with its :class:`DPCAPlan` (``plan``)."""

    plan: DPCAPlan | None = None

    def to_xarray(self):
        """:meth:`BeamCube.to_xarray` with the plan's price in the attrs.

        Extra attributes: ``dpca`` (:meth:`DPCAPlan.summary`),
        ``dpca_sub_shape`` and ``dpca_gain_loss_db``.
        """
        out = super().to_xarray()
        if self.plan is not None:
            out.attrs.update(dpca=self.plan.summary(), dpca_sub_shape=list(self.plan.sub_shape),
                             dpca_gain_loss_db=float(self.plan.gain_loss_db))
        return out


def _lattice(p: np.ndarray, grid_shape) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``p0, a, b`` and the integer index ``[channel, 2]`` of every element."""
    if grid_shape is not None:
        p0, a, b = lattice_vectors(p, grid_shape)
        nx, ny = (int(v) for v in grid_shape)
        idx = np.stack(np.divmod(np.arange(nx * ny), ny), axis=1)
        return np.stack([p0, a, b]), idx
    steps, origin = np.zeros((2, 3)), p.min(axis=0).copy()
    idx = np.zeros((p.shape[0], 2), dtype=int)
    for axis in (0, 1):
        c = np.unique(np.round(p[:, axis], 12))
        if c.size < 2:
            continue
        step = float(np.diff(c).min())
        steps[axis, axis] = step
        idx[:, axis] = np.rint((p[:, axis] - origin[axis]) / step).astype(int)
    origin[2] = p[0, 2]
    lat = np.stack([origin, steps[0], steps[1]])
    err = np.abs(origin + idx @ lat[1:] - p).max()
    if err > LATTICE_TOL + 1e-9 * np.abs(p).max():
        raise ValueError(f"element_positions do not lie on a rectangular lattice in the x-y "
                         f"plane of A (deviation {err:.3g} m); DPCA shifts the sub-aperture by "
                         f"whole element spacings, give grid_shape for a skewed grid")
    return lat, idx


def _shifts(lat, motion: PlatformMotion, centre, n_slot: int):
    """In-plane shift ``[chirp, 2]`` (element spacings) and the residual ``[chirp]`` [m]."""
    d = motion.radar_displacement                                       # [pose, 3]
    target = np.einsum("nji,nj->ni", motion.attitude, centre - 2.0 * d) - centre
    target = target.reshape(-1, n_slot, 3).mean(axis=1)                 # [chirp, 3]
    basis = lat[1:]                                                     # [2, 3]
    live = np.linalg.norm(basis, axis=1) > 0
    shift = np.zeros((target.shape[0], 2))
    if live.any():
        coef, *_ = np.linalg.lstsq(basis[live].T, target.T, rcond=None)
        shift[:, live] = coef.T
    resid = target - shift @ basis
    near = np.rint(shift)
    shift = np.where(np.abs(shift - near) < FRAC_TOL, near, shift)
    return shift, np.linalg.norm(resid, axis=1) / 2.0


def _interpolation(interpolation, n_chan: int, full, n_slot: int) -> str:
    """The interpolation a plan uses: ``"auto"`` is band-limited on a full lattice, one slot."""
    choice("interpolation", interpolation, ("auto",) + INTERPOLATIONS)
    complete = n_chan == int(np.prod(full)) and n_slot == 1
    if interpolation == "auto":
        return "bandlimited" if complete else "lagrange"
    if interpolation == "bandlimited" and not complete:
        raise ValueError(f'interpolation="bandlimited" needs every point of a rectangular '
                         f'lattice and one TDM slot (got {n_chan} channels on a {full[0]} x '
                         f'{full[1]} lattice, {n_slot} slots); use "lagrange" or "auto"')
    return interpolation


def _given_block(subaperture, allowed: set) -> np.ndarray:
    """The lattice indices ``[sub, 2]`` of a given sub-aperture, checked against ``allowed``."""
    q = np.asarray(subaperture)
    if q.shape[1:] != (2,) or q.size == 0 or not np.issubdtype(q.dtype, np.integer):
        raise ValueError(f"subaperture as lattice indices must be integers of shape [sub, 2], "
                         f"got shape {q.shape} dtype {q.dtype}")
    got = {tuple(e) for e in q.tolist()}
    lo, n = q.min(axis=0), np.ptp(q, axis=0) + 1
    if len(got) != int(np.prod(n)) or len(got) != q.shape[0]:
        raise ValueError(f"subaperture as lattice indices must be a full rectangular block "
                         f"without repeats, got {q.shape[0]} indices spanning {n[0]} x {n[1]}")
    if not got <= allowed:
        raise ValueError(f"subaperture: the block of {n[0]} x {n[1]} elements at {tuple(lo)} "
                         f"leaves what this motion allows (a block within "
                         f"{tuple(np.min(sorted(allowed), axis=0))} .. "
                         f"{tuple(np.max(sorted(allowed), axis=0))})")
    return np.array(sorted(got), dtype=int)


def _beamwidth(n: int, step, wavelength: float) -> float:
    length = n * float(np.linalg.norm(step))
    return BEAMWIDTH_FACTOR * wavelength / length if length > 0 else float("inf")


def dpca_plan(element_positions, motion: PlatformMotion, *, wavelength: float,
              grid_shape: tuple[int, int] | None = None, channel_slot=None, order: int = 3,
              subaperture: tuple[int, int] | None = None, interpolation: str = "auto",
              band: float = BAND) -> DPCAPlan:
    """Choose the DPCA sub-apertures of a frame and state their price.

    Parameters
    ----------
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions ``p_tx + p_rx`` in A [m], on a lattice
        ``p0 + ix a + iy b``: a UPA (``grid_shape``) or any array whose
        elements sit on a rectangular x-y lattice (e.g. a TDM virtual array).
    motion : PlatformMotion
        Pose at every chirp, or at every TDM slot (chirp major) with ``channel_slot``.
    wavelength : float
        [m] (beamwidths only).
    grid_shape : (int, int), optional
        ``(nx, ny)`` for a UPA (x major); otherwise the lattice is inferred
        from the positions (steps along x and y of A).
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM slot of each channel; the shift of a chirp is the mean over its slots' poses.
    order : {1, 3}
        Lagrange interpolation between sub-apertures: 1 linear, 3 cubic (default).
    subaperture : (int, int) or array_like of int, optional
        Elements per axis to keep (centred in the largest possible
        sub-aperture), or the lattice indices ``[sub, 2]`` of a full block
        (e.g. another plan's ``reference_index``: the same elements);
        default the largest.
    interpolation : {"auto", "bandlimited", "lagrange"}
        How a fractional shift is estimated (:data:`INTERPOLATIONS`); ``"auto"``
        (default): band-limited on a full rectangular lattice with one TDM
        slot, Lagrange otherwise.
    band : float
        Design band of the band-limited interpolation (:data:`BAND`).

    Returns
    -------
    DPCAPlan

    Raises
    ------
    ValueError
        If the displacement over the frame leaves no sub-aperture (it exceeds
        the spare aperture), ``subaperture`` does not fit, or the positions
        are not on a lattice.
    """
    if not isinstance(motion, PlatformMotion):
        raise ValueError(f"motion must be a compensation.PlatformMotion, got {type(motion)!r}")
    order = order_checked(order)
    lam = positive("wavelength", wavelength)
    band = positive("band", band)
    if band > 1.0:
        raise ValueError(f"band must be in (0, 1] (largest direction cosine along a lattice "
                         f"axis the interpolation is designed for), got {band!r}")
    p = finite_array("element_positions", element_positions, shape=(None, 3),
                     what="(one row per channel)")
    n_chan = p.shape[0]
    n_slot = 1
    if channel_slot is not None:
        n_slot = int(channel_slots(channel_slot, n_chan).max()) + 1
    if motion.num_chirps % n_slot:
        raise ValueError(f"with {n_slot} TDM slots motion must hold chirp * slots poses, got "
                         f"{motion.num_chirps}")
    lat, idx = _lattice(p, grid_shape)
    if len({tuple(e) for e in idx.tolist()}) != n_chan:
        raise ValueError("element_positions hold two channels at one virtual position; DPCA "
                         "needs distinct elements (drop the repeats)")
    centre = p.mean(axis=0)
    shift, resid = _shifts(lat, motion, centre, n_slot)
    full = tuple(int(v) for v in np.ptp(idx, axis=0) + 1)
    interp = _interpolation(interpolation, n_chan, full, n_slot)
    if interp == "bandlimited":
        ref, need = reachable_block(shift, full)
        how = f"band-limited interpolation (up to {REACH:g} spacings beyond the array)"
    else:
        offsets = np.array(sorted(lagrange_groups(shift, order)))          # [offset, 2]
        elements = {tuple(e) for e in idx.tolist()}
        ref = set(elements)
        for ox, oy in offsets.tolist():
            ref &= {(ex - ox, ey - oy) for ex, ey in elements}
        need = tuple(int(v) + 1 for v in np.ptp(offsets, axis=0))
        how = f"the order-{order} stencil"
    if not ref:
        span_m = [float(np.ptp(shift[:, ax])) * float(np.linalg.norm(lat[1 + ax])) / 2.0
                  for ax in (0, 1)]
        raise ValueError(
            f"dpca: the displacement over the frame shifts the sub-aperture by "
            f"{np.ptp(shift[:, 0]):.3g} x {np.ptp(shift[:, 1]):.3g} element spacings "
            f"({1e3 * span_m[0]:.3g} x {1e3 * span_m[1]:.3g} mm); with {how} "
            f"that needs {need[0]} x {need[1]} elements but the array has "
            f"{full[0]} x {full[1]}: no sub-aperture is left (displacement larger than the "
            f"spare aperture); use the exact chain, a shorter frame or a larger array")
    q = np.array(sorted(ref), dtype=int)
    if subaperture is not None and np.ndim(subaperture) == 2:
        q = _given_block(subaperture, ref)
    elif subaperture is not None:
        have = np.ptp(q, axis=0) + 1
        try:
            want = tuple(int(v) for v in subaperture)
        except (TypeError, ValueError):
            want = ()
        if len(want) != 2 or min(want) < 1 or want[0] > have[0] or want[1] > have[1]:
            raise ValueError(f"subaperture must be (kx, ky) with 1 <= k <= {tuple(have)} (the "
                             f"largest sub-aperture this motion leaves), got {subaperture!r}")
        lo = q.min(axis=0) + (have - np.array(want)) // 2
        keep = np.all((q >= lo) & (q < lo + np.array(want)), axis=1)
        q = q[keep]
    sub = tuple(int(v) for v in np.ptp(q, axis=0) + 1)
    ref_pos = lat[0] + q @ lat[1:]
    # world (virtual) positions of the used elements at every pose, in-plane deviation
    pose_shift = np.repeat(shift, n_slot, axis=0)                          # [pose, 2]
    at = ref_pos[None] + (pose_shift @ lat[1:])[:, None, :]               # [pose, sub, 3]
    world = 2.0 * motion.radar_displacement[:, None, :] + np.einsum(
        "nij,nkj->nki", motion.attitude, at)
    dev = world - world.mean(axis=0)
    live = np.linalg.norm(lat[1:], axis=1) > 0
    move = np.zeros(dev.shape[:2])
    if live.any():
        coef = dev @ np.linalg.pinv(lat[1:][live].T).T                    # [pose, sub, live]
        move = np.abs(coef).max(axis=(0, 2))
    else:
        move = move.max(axis=0)
    n_sub = q.shape[0]
    bw_full = tuple(_beamwidth(full[ax], lat[1 + ax], lam) for ax in (0, 1))
    bw_sub = tuple(_beamwidth(sub[ax], lat[1 + ax], lam) for ax in (0, 1))
    gain = 10.0 * np.log10(n_chan / n_sub)
    warn = []
    if any(k < MIN_KEEP_FRACTION * n for k, n in zip(sub, full, strict=True)):
        warn.append(f"dpca aperture: the sub-aperture keeps {sub[0]} x {sub[1]} of "
                    f"{full[0]} x {full[1]} elements (displacement over the frame "
                    f"{np.ptp(shift[:, 0]):.3g} x {np.ptp(shift[:, 1]):.3g} element spacings, "
                    f"{how}): beamwidth x{full[0] / sub[0]:.3g} / "
                    f"x{full[1] / sub[1]:.3g}, gain -{gain:.3g} dB")
    worst = float(move.max()) if move.size else 0.0
    overlap = float(np.mean(move <= ROTATION_LIMIT)) if move.size else 1.0
    if worst > ROTATION_LIMIT:
        what = ("no element stays there: the sub-aperture no longer overlaps itself"
                if overlap == 0 else f"{100 * overlap:.0f} % of the elements stay within it")
        warn.append(f"dpca rotation: the attitude change over the frame moves sub-aperture "
                    f"elements by up to {worst:.3g} element spacings from their world positions "
                    f"(limit {ROTATION_LIMIT:g}); {what}. The phase centre is still held, the "
                    f"clutter in a beam decorrelates as with the exact chain")
    return DPCAPlan(shift=shift, lattice=lat, element_index=idx, reference_index=q,
                    reference_positions=ref_pos, order=order, full_shape=full, sub_shape=sub,
                    beamwidth_full=bw_full, beamwidth_sub=bw_sub, gain_loss_db=float(gain),
                    residual_displacement=float(resid.max()) if resid.size else 0.0,
                    rotation_misplacement=worst, overlap=overlap, warnings=tuple(warn),
                    interpolation=interp, band=band)


def _sub_weights(weights, plan: DPCAPlan) -> np.ndarray | None:
    if weights is None:
        return None
    n_sub = plan.reference_index.shape[0]
    if callable(weights):
        w = weights(plan.reference_index - plan.reference_index.min(axis=0))
    else:
        w = weights
    w = finite_array("weights", w, shape=(n_sub,),
                     what=f"(one per sub-aperture element, {plan.sub_shape[0]} x "
                          f"{plan.sub_shape[1]} = {n_sub}, order of plan.reference_index)")
    if w.sum() <= 0:
        raise ValueError(f"weights must have a positive sum, got {w.sum()!r}")
    return w


def dpca_projection(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                    range_axis, azimuth, elevation, range_gates=None,
                    focus: Literal["near", "far"] = "near",
                    grid_shape: tuple[int, int] | None = None,
                    method: Literal["auto", "nufft", "lattice", "direct"] = "auto",
                    weights=None, channel_slot=None, order: int = 3,
                    subaperture: tuple[int, int] | None = None, chirp_block: int = 32,
                    gate_block: int = 8, interpolation: str = "auto",
                    band: float = BAND) -> DPCABeams:
    """Beams of a range-compressed cube from a sub-aperture held fixed in the world.

    Same inputs and output as :func:`compensation.exact.rigid_body_projection`;
    per chirp, the sub-aperture whose elements stay fixed in world coordinates
    (module docstring): its channels estimated at the shifted positions from the
    whole array (band-limited) or the neighbouring integer sub-apertures' beams
    combined (Lagrange), projected with the exact chain.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (complex).
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions ``p_tx + p_rx`` in A [m], on a lattice (see :func:`dpca_plan`).
    motion : PlatformMotion
        Pose at each chirp, or at each TDM slot (chirp major) with ``channel_slot``.
    wavelength : float
        Mid-chirp wavelength [m].
    range_axis : array_like, shape ``[range]``
        Range of each bin [m].
    azimuth, elevation : array_like
        Global grid axes [rad].
    range_gates, focus, chirp_block, gate_block
        As :func:`compensation.exact.rigid_body_projection`.
    grid_shape : (int, int), optional
        ``(nx, ny)`` of a UPA (x major); without it the lattice is inferred
        from the positions. A rectangular sub-aperture is projected with the
        gridded ``method`` (``"auto"``: non-uniform FFT), others with ``"direct"``.
    method : {"auto", "nufft", "lattice", "direct"}
        Projection method of each sub-aperture; with ``channel_slot`` only
        ``"auto"`` or ``"direct"`` (a slot's channels are not a grid).
    weights : None, array_like or callable
        Real taper of the *sub-aperture*: an array ``[sub]`` in the order of
        ``plan.reference_index`` (:func:`dpca_plan` gives it beforehand), or
        ``weights(index) -> [sub]`` with ``index [sub, 2]`` the lattice indices
        counted from the sub-aperture's corner (e.g. ``wx[i[:, 0]] * wy[i[:, 1]]``
        for a separable taper). Default uniform.
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM slot of each channel: each slot's channels of a sub-aperture are
        projected with the pose of their own transmit instant.
    order : {1, 3}
        Lagrange interpolation order between sub-apertures (1 linear, 3 cubic).
    subaperture : (int, int) or array_like of int, optional
        Elements per axis to keep, or the lattice indices ``[sub, 2]`` of the
        block (:func:`dpca_plan`); default the largest the motion allows.
    interpolation : {"auto", "bandlimited", "lagrange"}
        How a fractional shift is estimated (module docstring); ``"auto"``:
        band-limited on a full rectangular lattice with one TDM slot.
    band : float
        Design band of the band-limited interpolation
        (:data:`compensation.subaperture_shift.BAND`).

    Returns
    -------
    DPCABeams
        A :class:`BeamCube` ``data [chirp, range, azimuth, elevation]`` with
        ``plan`` (:class:`DPCAPlan`: elements used, beamwidth and gain lost)
        and ``warnings`` those of ``motion`` plus ``"dpca aperture"`` /
        ``"dpca rotation"``.

    Raises
    ------
    ValueError
        Bad input, or a displacement larger than the spare aperture.

    Examples
    --------
    >>> import numpy as np
    >>> from compensation.strapdown import static_motion
    >>> p = np.stack([np.arange(4) * 2e-3, np.zeros(4), np.zeros(4)], axis=1)
    >>> rc = np.ones((8, 4, 2), dtype=np.complex64)
    >>> beams = dpca_projection(rc, p, static_motion(np.arange(8) * 60e-6), wavelength=3.9e-3,
    ...                         range_axis=[10.0, 10.15], azimuth=[0.0], elevation=[0.0])
    >>> beams.data.shape, beams.plan.sub_shape, round(abs(complex(beams.data[0, 0, 0, 0])), 6)
    ((8, 2, 1, 1), (4, 1), 1.0)
    """
    x = complex_cube("rc", rc)
    n_chirp, n_chan, _ = x.shape
    p = finite_array("element_positions", element_positions, shape=(n_chan, 3),
                     what="(one row per channel of rc)")
    choice("method", method, ("auto", "nufft", "lattice", "direct"))
    if not isinstance(motion, PlatformMotion):
        raise ValueError(f"motion must be a compensation.PlatformMotion, got {type(motion)!r}")
    slot, n_slot = None, 1
    if channel_slot is not None:
        slot = channel_slots(channel_slot, n_chan)
        n_slot = int(slot.max()) + 1
        if method not in ("auto", "direct"):
            raise ValueError(f'with channel_slot the sub-apertures are projected with '
                             f'method="direct" (a slot\'s channels are no grid), got {method!r}')
    if motion.num_chirps != n_chirp * n_slot:
        raise ValueError(f"motion must hold chirp * slots = {n_chirp} * {n_slot} = "
                         f"{n_chirp * n_slot} poses (chirp major), got {motion.num_chirps}")
    plan = dpca_plan(p, motion, wavelength=wavelength, grid_shape=grid_shape,
                     channel_slot=slot, order=order, subaperture=subaperture,
                     interpolation=interpolation, band=band)
    w_sub = _sub_weights(weights, plan)
    common = dict(wavelength=wavelength, range_axis=range_axis, azimuth=azimuth,
                  elevation=elevation, range_gates=range_gates, focus=focus,
                  chirp_block=chirp_block, gate_block=gate_block)
    if plan.interpolation == "bandlimited":
        part = _bandlimited_beams(x, p, motion, plan, w_sub, method, common)
        return DPCABeams(part.data, part.chirp_time, part.range, part.azimuth, part.elevation,
                         part.wavelength, merge(motion.warnings, plan.warnings), plan=plan)
    groups = lagrange_groups(plan.shift, plan.order)
    gridded = slot is None and plan.is_grid
    out, part = None, None
    for offset, (chirps, wts) in sorted(groups.items()):
        chans = plan.channels(offset)
        xs = x[chirps][:, chans]
        if slot is None:
            part = rigid_body_projection(
                xs, p[chans], motion.select(chirps), grid_shape=plan.sub_shape if gridded else None,
                method=method if gridded else ("direct" if method == "auto" else method),
                weights=w_sub, **common)
            data = part.data
        else:
            data, part = _tdm_part(xs, p[chans], slot[chans], motion, chirps, n_slot, w_sub,
                                   common)
        if out is None:
            out = np.zeros((n_chirp,) + data.shape[1:], dtype=np.complex64)
        np.add.at(out, chirps, data * wts.astype(np.float32)[:, None, None, None])
    chirp_time = motion.time[::n_slot]
    return DPCABeams(out, chirp_time, part.range, part.azimuth, part.elevation, part.wavelength,
                     merge(motion.warnings, plan.warnings), plan=plan)


def _bandlimited_beams(x, p, motion: PlatformMotion, plan: DPCAPlan, w_sub, method, common):
    """The sub-aperture's channels estimated at its shifted positions, projected once.

    The estimates sit in A at ``p_q + shift_n . (a, b)``, i.e. in W at the
    positions of ``p_q`` on a radar displaced by ``R_n shift_n . (a, b) / 2``
    more (virtual positions move twice the displacement): the exact projection
    of ``p_q`` with that motion.
    """
    from dataclasses import replace

    gates = common["range_gates"]
    if gates is not None:                          # estimate the asked bins only
        gates = np.asarray(gates, dtype=int)
        x = x[:, :, gates]
        common = dict(common, range_axis=np.asarray(common["range_axis"])[gates],
                      range_gates=None)
    idx = plan.element_index - plan.element_index.min(axis=0)
    order = np.lexsort((idx[:, 1], idx[:, 0]))                     # x major, y minor
    tx, ty = plan.positions()
    lam = float(common["wavelength"])
    visible = tuple(2.0 * np.pi * float(np.linalg.norm(v)) / lam for v in plan.lattice[1:])
    est = shift_channels(x[:, order], plan.full_shape, tx, ty, band=plan.band,
                         visible=visible)
    step = plan.shift @ plan.lattice[1:]                                # [chirp, 3] in A
    moved = replace(motion, position=motion.position
                    + np.einsum("nij,nj->ni", motion.attitude, step) / 2.0)
    try:                                  # the elements' own positions where they exist
        ref_pos = p[plan.channels((0, 0))]
    except ValueError:                    # a block beyond the array: its lattice positions
        ref_pos = plan.reference_positions
    return rigid_body_projection(est, ref_pos, moved,
                                 grid_shape=plan.sub_shape, method=method, weights=w_sub,
                                 **common)


def _tdm_part(xs, ps, slots, motion: PlatformMotion, chirps, n_slot: int, w_sub, common):
    """One sub-aperture of a TDM array: each slot's channels at their own pose, shares summed."""
    w = np.ones(ps.shape[0]) if w_sub is None else w_sub
    total, data, part = float(w.sum()), None, None
    for s in range(n_slot):
        sel = np.flatnonzero(slots == s)
        if sel.size == 0:
            continue
        part = rigid_body_projection(xs[:, sel], ps[sel], motion.select(chirps * n_slot + s),
                                     method="direct", weights=w[sel], **common)
        share = np.float32(float(w[sel].sum()) / total)
        data = part.data * share if data is None else data + part.data * share
    return data, part
