"""Fractional shifts of a sub-aperture (the DPCA's interpolation): band-limited and Lagrange.

The channel signal of a uniform linear array (element ``i`` at ``i a``) is a
sum of plane waves ``exp(-j psi i)`` with the phase step ``psi = 2 pi / lambda
u . a`` of each echo's direction ``u``; every echo lies in the visible band
``|psi| <= psi_v = 2 pi |a| / lambda`` (``pi`` for half-wavelength spacing).
The value at a fractional position ``t`` (element spacings) is estimated from
all ``n`` channels with the least-squares (Wiener) interpolator of a signal
whose spectrum is flat on the design band ``|psi| <= band psi_v`` and
:data:`OUT_OF_BAND_WEIGHT` times that on the rest of the visible band
(Oetken, Parks & Schuessler, "New results in the design of digital
interpolators", IEEE Trans. ASSP 23 (1975) 301-309; the band-limited version
of Whittaker-Shannon interpolation for a finite aperture). Its weights
``g(t)`` solve ``G g = r(t)`` with the closed forms::

    G_ik = S(i - k),  r_i(t) = S(i - t),
    S(x) = 2 B sinc(B x / pi) + w 2 psi_v sinc(psi_v x / pi),  B = band psi_v

(``sinc(y) = sin(pi y) / (pi y)``), which are real. At an integer ``t`` inside
the array the weights are ``delta(i - t)`` (exact); ``t`` may reach a little
beyond the array (:data:`REACH`, extrapolation). The error of the estimate for
an echo at ``psi``, ``|sum_i g_i exp(-j psi i) - exp(-j psi t)|``, is given in
closed form by :func:`shift_error`: small on the design band away from the
array's ends, larger near its ends and outside the band (near endfire).
"""

from __future__ import annotations

from math import factorial

import numpy as np

#: Default design band: the largest ``|u . a| / |a|`` (direction cosine along the
#: array axis) of the echoes the interpolation is designed for (+-44 deg off boresight).
BAND = 0.7
#: Weight of the visible band outside the design band in the least-squares design
#: (bounds the weights' gain there; 0 would let them grow without bound).
OUT_OF_BAND_WEIGHT = 1e-2
#: Interpolation stencils (sub-aperture offsets ``l`` around ``floor(shift)``) by order.
STENCILS = {1: (0, 1), 3: (-1, 0, 1, 2)}
#: ``max_f |prod_l (f - l)|`` over ``0 <= f < 1`` for each stencil (Lagrange remainder).
_NODE_PRODUCT = {1: 0.25, 3: 9.0 / 16.0}
#: Lebesgue constant ``max_f sum_l |h_l(f)|`` of each stencil (bounds the error by ``1 + L``).
_LEBESGUE = {1: 1.0, 3: 1.25}
#: How far beyond the array's end elements a position may be interpolated [element spacings].
REACH = 0.6


def _spectrum_integral(x, b: float, visible: float) -> np.ndarray:
    """``S(x)``: the design weight's integral of ``exp(j psi x)`` over the visible band."""
    x = np.asarray(x, dtype=float)
    return (2.0 * b * np.sinc(b * x / np.pi)
            + OUT_OF_BAND_WEIGHT * 2.0 * visible * np.sinc(visible * x / np.pi))


def _band(band, visible) -> tuple[float, float]:
    band, visible = float(band), float(visible)
    if not (0.0 < band <= 1.0 and np.isfinite(band)):
        raise ValueError(f"band must be in (0, 1] (largest direction cosine along the array "
                         f"axis of the echoes the interpolation is designed for), got {band!r}")
    if not (visible > 0.0 and np.isfinite(visible)):
        raise ValueError(f"visible must be the positive phase step of an endfire echo "
                         f"2 pi |a| / lambda [rad], got {visible!r}")
    return band * visible, visible


def shift_kernel(positions, n: int, *, band: float = BAND, visible: float = np.pi) -> np.ndarray:
    """Weights that estimate the channel signal at fractional positions from ``n`` channels.

    Parameters
    ----------
    positions : array_like, shape ``[pos]``
        Positions ``t`` to estimate [element spacings, element 0 at 0].
    n : int
        Channels along the axis (elements ``0 .. n-1``).
    band : float
        Design band as a fraction of the visible band (:data:`BAND`).
    visible : float
        Phase step of an endfire echo ``2 pi |a| / lambda`` [rad].

    Returns
    -------
    ndarray, shape ``[pos, n]``
        Real weights ``g``: the estimate at ``t`` is ``sum_i g_i x_i``.
    """
    b, v = _band(band, visible)
    t = np.atleast_1d(np.asarray(positions, dtype=float))
    i = np.arange(int(n), dtype=float)
    gram = _spectrum_integral(i[:, None] - i[None, :], b, v)
    rhs = _spectrum_integral(i[:, None] - t[None, :], b, v)
    g = np.linalg.solve(gram, rhs).T
    whole = np.isclose(t, np.rint(t), rtol=0.0, atol=1e-12) & (t >= 0) & (t <= n - 1)
    g[whole] = np.eye(int(n))[np.rint(t[whole]).astype(int)]          # exact, no round-off
    return g


def shift_error(positions, n: int, psi, *, band: float = BAND,
                visible: float = np.pi) -> np.ndarray:
    """Error of :func:`shift_kernel` for a unit echo at phase step ``psi``.

    Parameters
    ----------
    positions : array_like, shape ``[pos]``
        Positions ``t`` [element spacings].
    n : int
    psi : array_like, shape ``[phase]``
        Phase step per element of the echo [rad].
    band, visible
        As :func:`shift_kernel`.

    Returns
    -------
    ndarray, shape ``[pos, phase]``
        ``|sum_i g_i(t) exp(-j psi i) - exp(-j psi t)|`` [1].
    """
    t = np.atleast_1d(np.asarray(positions, dtype=float))
    ps = np.atleast_1d(np.asarray(psi, dtype=float))
    g = shift_kernel(t, n, band=band, visible=visible)
    got = g @ np.exp(-1j * np.arange(int(n))[:, None] * ps[None, :])
    return np.abs(got - np.exp(-1j * t[:, None] * ps[None, :]))


def shift_channels(x: np.ndarray, grid_shape: tuple[int, int], tx: np.ndarray, ty: np.ndarray,
                   *, band: float = BAND, visible=(np.pi, np.pi)) -> np.ndarray:
    """A uniform rectangular array's channels estimated at fractional lattice positions.

    Separable: :func:`shift_kernel` along each lattice axis.

    Parameters
    ----------
    x : ndarray, shape ``[chirp, channel, range]``
        Channels of an ``nx x ny`` grid, x index major.
    grid_shape : (int, int)
        ``(nx, ny)``.
    tx, ty : ndarray, shape ``[chirp, kx]``, ``[chirp, ky]``
        Positions along ``a`` and ``b`` at every chirp [element spacings].
    band : float
        Design band (:data:`BAND`).
    visible : (float, float)
        Endfire phase step along ``a`` and ``b`` [rad] (unused along an axis of
        one element, whose positions are 0).

    Returns
    -------
    ndarray, shape ``[chirp, kx * ky, range]``, complex64
        The estimates, x index major.
    """
    nx, ny = (int(v) for v in grid_shape)
    n_chirp = x.shape[0]
    cube = np.asarray(x).reshape(n_chirp, nx, ny, -1)
    def weights(t, n, vis):                 # an axis of one element holds still
        if n == 1:
            return np.ones((n_chirp, t.shape[1], 1))
        return shift_kernel(t.ravel(), n, band=band, visible=vis).reshape(n_chirp, -1, n)

    gx, gy = weights(tx, nx, visible[0]), weights(ty, ny, visible[1])
    out = np.einsum("cqi,cijg->cqjg", gx.astype(np.float32), cube, optimize=True)
    out = np.einsum("crj,cqjg->cqrg", gy.astype(np.float32), out, optimize=True)
    return out.reshape(n_chirp, tx.shape[1] * ty.shape[1], -1).astype(np.complex64, copy=False)


def reachable_block(shift, full) -> tuple[set, tuple[int, int]]:
    """Largest block of lattice indices whose shifted positions stay within :data:`REACH`.

    Parameters
    ----------
    shift : ndarray, shape ``[chirp, 2]``
        Shifts along ``a`` and ``b`` [element spacings].
    full : (int, int)
        Elements per axis of the array (indices from 0).

    Returns
    -------
    block : set of (int, int)
        Indices ``(ix, iy)`` of the block (empty when none is left).
    need : (int, int)
        Elements per axis the shifts would need for a block of one element.
    """
    tol = 1e-9
    lo = np.ceil(-REACH - shift.min(axis=0) - tol).astype(int)            # first index
    hi = np.floor(np.array(full) - 1 + REACH - shift.max(axis=0) + tol).astype(int)
    need = tuple(int(v) for v in np.ceil(np.ptp(shift, axis=0) - 2 * REACH - tol) + 1)
    if np.any(hi < lo):
        return set(), need
    return {(ix, iy) for ix in range(lo[0], hi[0] + 1) for iy in range(lo[1], hi[1] + 1)}, need


def lagrange_weights(frac, order: int = 3) -> np.ndarray:
    """Lagrange weights ``h_l(f)`` of the stencil :data:`STENCILS` ``[order]``.

    Parameters
    ----------
    frac : array_like, shape ``[chirp]``
        Fractional shifts ``0 <= f < 1`` [element spacings].
    order : {1, 3}
        Polynomial order (1 linear, 3 cubic).

    Returns
    -------
    ndarray, shape ``[chirp, stencil]``
        Weights of the sub-apertures at ``floor(shift) + l``; each row sums to one.
    """
    nodes = np.asarray(STENCILS[order_checked(order)], dtype=float)
    f = np.atleast_1d(np.asarray(frac, dtype=float))[:, None]
    out = np.ones((f.shape[0], nodes.size))
    for i, li in enumerate(nodes):
        for lm in nodes:
            if lm != li:
                out[:, i] *= (f[:, 0] - lm) / (li - lm)
    return out


def interpolation_error(delta_psi, order: int = 3) -> np.ndarray:
    """Bound of the interpolation error for a scatterer off the beam direction, per axis.

    A scatterer whose per-element phase step differs from the beam's by
    ``dpsi`` contributes ``Y_s = Y_0 exp(j dpsi s)`` to the sub-aperture at
    integer offset ``s``; the Lagrange combination at ``s = i + f`` gives
    ``sum_l h_l(f) Y_(i + l)``. Relative to ``|Y_0|`` the error is at most
    ``|dpsi|^L / L! max_f |prod_l (f - l)|`` (``L`` stencil points; the
    Hermite-Genocchi form of the remainder holds for complex functions), i.e.
    ``dpsi^2 / 8`` (order 1) and ``3 dpsi^4 / 128`` (order 3), and never more
    than one plus the Lebesgue constant. Zero at the beam direction. Along
    two axes the errors ``e_x, e_y`` combine to at most ``e_x (1 + e_y) + e_y``.

    Parameters
    ----------
    delta_psi : array_like
        ``2 pi / lambda (u - u_G) . a`` [rad] (``a`` the lattice step).
    order : {1, 3}

    Returns
    -------
    ndarray, same shape as ``delta_psi`` [1]
    """
    order = order_checked(order)
    n = len(STENCILS[order])
    x = np.abs(np.asarray(delta_psi, dtype=float))
    return np.minimum(x ** n / factorial(n) * _NODE_PRODUCT[order], 1.0 + _LEBESGUE[order])


def order_checked(order) -> int:
    if order not in STENCILS:
        raise ValueError(f"order must be one of {tuple(STENCILS)} (1 linear, 3 cubic "
                         f"Lagrange interpolation between sub-apertures), got {order!r}")
    return int(order)


def lagrange_groups(shift, order: int) -> dict[tuple[int, int], tuple[np.ndarray, np.ndarray]]:
    """Chirps ``[k]`` and Lagrange weights ``[k]`` of every integer sub-aperture offset.

    Chirp ``n`` takes the offsets ``floor(shift[n]) + (lx, ly)`` over the
    stencil of each axis with weight ``h_lx(fx) h_ly(fy)``; zero weights (an
    integer shift) are dropped, so an integer shift uses one sub-aperture.
    """
    floor = np.floor(shift).astype(int)
    frac = shift - floor
    h = [lagrange_weights(frac[:, ax], order) for ax in (0, 1)]
    acc: dict[tuple[int, int], list[tuple[np.ndarray, np.ndarray]]] = {}
    for ix, lx in enumerate(STENCILS[order]):
        for iy, ly in enumerate(STENCILS[order]):
            w = h[0][:, ix] * h[1][:, iy]
            off = floor + np.array([lx, ly])
            for o in np.unique(off[w != 0], axis=0):
                sel = np.flatnonzero(np.all(off == o, axis=1) & (w != 0))
                acc.setdefault((int(o[0]), int(o[1])), []).append((sel, w[sel]))
    return {o: (np.concatenate([c for c, _ in v]), np.concatenate([w for _, w in v]))
            for o, v in acc.items()}
