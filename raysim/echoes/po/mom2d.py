"""Two-dimensional method of moments (MoM): full-wave echo width of conducting cylinders.

A reference for the physical-optics engine's edge diffraction
(:mod:`~raysim.echoes.po.edges`): a perfectly conducting cylinder, infinite
along ``z``, whose cross-section is a polyline in the ``x-y`` plane, open (a
strip, a bent sheet) or closed (a polygon, a wedge's cross-section, a faceted
circle), lit by a plane wave normal to ``z``. The electric-field integral
equation (EFIE) is solved with the currents on the contour's straight segments:

* **TM** (electric field along ``z``, the edges' direction; the engine's VV on
  a plate rotated about its edges): the axial current ``J_z``, one pulse per
  segment (no condition at open ends, where ``J_z`` is singular);
* **TE** (magnetic field along ``z``; the engine's HH): the tangential current,
  one rooftop (triangle) per interior node, zero at open ends (where the
  current normal to a sheet's edge vanishes), the mixed-potential form (vector
  potential plus the charge's scalar potential, the derivative moved onto the
  test function).

Both are tested with the basis itself (Galerkin) and the kernel is the 2-D
Green function ``G = H_0^(2)(k R) / (4 j)`` (time ``exp(+j omega t)``, the
project's). Segment pairs are integrated by Gauss-Legendre quadrature; on
neighbouring pairs the logarithmic singularity ``-j (2/pi) ln(k R)`` of
``H_0^(2)`` is integrated in closed form along the source segment and only the
smooth rest numerically (Peterson, Ray & Mittra, *Computational Methods for
Electromagnetics*, IEEE Press 1998, ch. 2).

Geometry: the radar lies in the direction ``(sin phi, cos phi)`` from the
origin, ``phi`` from the ``+y`` axis towards ``+x``; a strip along ``x`` is seen
broadside at ``phi = 0`` and edge-on at ``phi = 90 deg`` (the engine's azimuth
on a plate in ``z = 0`` rotated about its ``y`` edges). The monostatic echo
width (2-D radar cross-section) is

``sigma_2D = lim 2 pi rho |E_s|^2 / |E_i|^2 = (k / 4) |V^T I|^2``  [m],

with ``V`` the excitation vector and ``I = Z^-1 V`` the currents (reciprocity:
the receiving pattern is the excitation). A wide strip gives ``k w^2`` at
broadside in both polarisations (physical optics); a cylinder ``L`` long
(``L >> lambda``, seen normal to its length) has ``sigma_3D = sigma_2D 2 L^2 / lambda``
(Knott, Shaeffer & Tuley, *Radar Cross Section*, 2nd ed., 1993: the 2-D to 3-D relation).

What it cannot give: a closed contour is wrong near its interior resonances
(the EFIE's spurious modes, e.g. a circle's ``J_0(k a) = 0`` in TM and
``J_1(k a) = 0`` in TE); zero-thickness sheets only as open contours.

References
----------
A. F. Peterson, S. L. Ray, R. Mittra, *Computational Methods for Electromagnetics*, 1998.
C. A. Balanis, *Advanced Engineering Electromagnetics*, 2nd ed., Wiley 2012, ch. 11
(scattering by circular cylinders: the test reference) and ch. 12 (integral equations).
R. F. Harrington, *Field Computation by Moment Methods*, 1968, ch. 4.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.special

__all__ = ["Contour", "MomEchoWidth", "strip", "polyline", "regular_polygon", "echo_width",
           "MAX_UNKNOWNS", "SEGMENTS_PER_WAVELENGTH", "mom_job_size"]

#: Largest number of unknowns (the kernel samples and the matrices, ``BYTES_PER_PAIR`` per
#: unknown squared, stay near 1 GB at the peak).
MAX_UNKNOWNS = 1000
#: Default segment density [segments per wavelength].
SEGMENTS_PER_WAVELENGTH = 20.0
#: Gauss-Legendre points per segment on well-separated pairs and on neighbouring pairs.
FAR_POINTS = 4
NEAR_POINTS = 8
#: Segment pairs whose midpoints are closer than this many (longer) segment lengths get
#: the closed-form logarithm.
NEAR_SEGMENTS = 2.5
#: Peak memory per unknown pair [bytes] (for the job size): per pair of quadrature points
#: the separations, distances, Bessel values and Hankel kernel (64 B), then the four
#: segment kernels and the matrix (80 B).
BYTES_PER_PAIR = 64 * FAR_POINTS**2 + 80

_EULER_GAMMA = 0.5772156649015329


@dataclass(frozen=True)
class Contour:
    """A cylinder's cross-section: a polyline of straight segments.

    Attributes
    ----------
    nodes : ndarray, shape ``[node, 2]``
        Segment end points ``(x, y)`` [m], in order; a closed contour does not
        repeat its first node.
    closed : bool
        Whether the last node joins the first.
    """

    nodes: np.ndarray
    closed: bool = False

    def __post_init__(self) -> None:
        v = np.asarray(self.nodes, dtype=float)
        least = 3 if self.closed else 2
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < least or not np.isfinite(v).all():
            raise ValueError(f"nodes must be finite (x, y) points, shape [node >= {least}, 2], "
                             f"got shape {v.shape}")
        object.__setattr__(self, "nodes", v)
        object.__setattr__(self, "closed", bool(self.closed))
        if not np.all(self.lengths > 0):
            raise ValueError("nodes: consecutive nodes must be distinct (no zero-length segment)")

    @property
    def starts(self) -> np.ndarray:
        """Segment starts, shape ``[segment, 2]`` [m]."""
        return self.nodes if self.closed else self.nodes[:-1]

    @property
    def ends(self) -> np.ndarray:
        """Segment ends, shape ``[segment, 2]`` [m]."""
        return np.roll(self.nodes, -1, axis=0) if self.closed else self.nodes[1:]

    @property
    def lengths(self) -> np.ndarray:
        """Segment lengths, shape ``[segment]`` [m]."""
        return np.linalg.norm(self.ends - self.starts, axis=1)

    def __len__(self) -> int:
        """Number of segments."""
        return len(self.nodes) if self.closed else len(self.nodes) - 1


def _positive(value, name: str) -> float:
    if not (isinstance(value, (int, float, np.floating, np.integer)) and math.isfinite(value)
            and value > 0):
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return float(value)


def polyline(vertices, max_segment: float, *, closed: bool = False) -> Contour:
    """A polyline through ``vertices``, each side cut into equal segments.

    Parameters
    ----------
    vertices : array_like, shape ``[vertex, 2]``
        Corner points [m] (at least 2; 3 for a closed contour), consecutive ones distinct.
    max_segment : float
        Longest segment [m].
    closed : bool
        Join the last vertex to the first.

    Returns
    -------
    Contour
    """
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[1] != 2 or len(v) < (3 if closed else 2) or not np.isfinite(v).all():
        raise ValueError(f"vertices must be finite (x, y) points, shape [vertex, 2] with at least "
                         f"{3 if closed else 2} vertices, got shape {v.shape}")
    max_segment = _positive(max_segment, "max_segment")
    a = v
    b = np.roll(v, -1, axis=0) if closed else v[1:]
    a = a[:len(b)]
    side = np.linalg.norm(b - a, axis=1)
    if not np.all(side > 0):
        raise ValueError("vertices: consecutive vertices must be distinct")
    pieces = np.maximum(1, np.ceil(side / max_segment - 1e-9)).astype(int)
    nodes = [a[i] + np.outer(np.arange(p) / p, b[i] - a[i]) for i, p in enumerate(pieces)]
    if not closed:
        nodes.append(v[-1:])
    return Contour(np.concatenate(nodes), closed)


def strip(width: float, max_segment: float) -> Contour:
    """A zero-thickness strip of ``width`` [m] along ``x``, centred, normal ``+y``."""
    width = _positive(width, "width")
    return polyline([[-width / 2, 0.0], [width / 2, 0.0]], max_segment)


def regular_polygon(radius: float, sides: int, max_segment: float | None = None) -> Contour:
    """A closed regular polygon with its vertices on a circle of ``radius`` [m].

    ``sides`` facets (at least 3), each cut to ``max_segment`` [m] if given.
    """
    radius = _positive(radius, "radius")
    if int(sides) != sides or sides < 3:
        raise ValueError(f"sides must be an integer >= 3, got {sides!r}")
    ang = 2 * np.pi * np.arange(int(sides)) / int(sides)
    v = radius * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    side = 2 * radius * math.sin(math.pi / int(sides))
    return polyline(v, side if max_segment is None else max_segment, closed=True)


def mom_job_size(contour: Contour, polarisation: str) -> int:
    """Unknowns of a solve, checked against ``MAX_UNKNOWNS`` before anything is allocated.

    Raises
    ------
    ValueError
        Too many unknowns (with the memory it would take).
    """
    n = len(contour) if polarisation == "TM" else len(contour.nodes) - (0 if contour.closed else 2)
    if n < 1:
        raise ValueError(f"the contour has no {polarisation} unknowns ({len(contour)} segments)")
    if n > MAX_UNKNOWNS:
        raise ValueError(f"{n} unknowns ({n * n * BYTES_PER_PAIR / 1e9:.2g} GB), expected at most "
                         f"{MAX_UNKNOWNS}: use fewer segments per wavelength or a smaller contour")
    return n


def _hankel(x: np.ndarray) -> np.ndarray:
    """``H_0^(2)(x)``, x > 0 (``j0``, ``y0`` of Cephes: faster than AMOS's ``hankel2``)."""
    return scipy.special.j0(x) - 1j * scipy.special.y0(x)


def _hankel_smooth(x: np.ndarray) -> np.ndarray:
    """``H_0^(2)(x) + j (2/pi) ln x``, continuous: ``1 - j (2/pi)(gamma - ln 2)`` at 0."""
    small = x < 1e-8
    xs = np.where(small, 1.0, x)
    val = _hankel(xs) + 2j / np.pi * np.log(xs)
    return np.where(small, 1 - 2j / np.pi * (_EULER_GAMMA - math.log(2)), val)


def _log_moments(obs: np.ndarray, a: np.ndarray, t: np.ndarray, length: np.ndarray):
    """``int_0^D ln R ds`` and ``int_0^D s ln R ds``, ``R = |obs - a - s t|``, in closed form.

    ``obs`` [..., 2], ``a``, ``t`` (unit) [..., 2], ``length`` ``D`` [...]; with
    ``u = s - s0`` and ``d`` the distance to the line:
    ``int ln R du = (u ln(u^2+d^2) - 2u + 2 d atan(u/d)) / 2``,
    ``int u ln R du = ((u^2+d^2) ln(u^2+d^2) - u^2) / 4``.
    """
    rel = obs - a
    s0 = np.einsum("...i,...i->...", rel, t)
    d = np.abs(rel[..., 0] * t[..., 1] - rel[..., 1] * t[..., 0])

    def f0(u):
        q = u * u + d * d
        return (scipy.special.xlogy(u, q) - 2 * u + 2 * d * np.arctan2(u, d)) / 2

    def f1(u):
        q = u * u + d * d
        return (scipy.special.xlogy(q, q) - u * u) / 4

    u1, u2 = -s0, length - s0
    i0 = f0(u2) - f0(u1)
    return i0, f1(u2) - f1(u1) + s0 * i0


def _segment_kernels(contour: Contour, k: float) -> np.ndarray:
    """``K[a, b, m, n] = int_m int_n p_a(s) p_b(s') H_0^(2)(k R) ds ds'`` [m^2].

    ``p_0 = 1 - s/D``, ``p_1 = s/D`` on each segment (``s`` from its start);
    shape ``[2, 2, segment, segment]``.
    """
    a, b = contour.starts, contour.ends
    length = contour.lengths
    t = (b - a) / length[:, None]
    x, w = np.polynomial.legendre.leggauss(FAR_POINTS)
    x, w = (x + 1) / 2, w / 2
    pts = a[:, None] + x[None, :, None] * (b - a)[:, None]               # [seg, q, 2]
    basis = np.stack([1 - x, x]) * w                                     # [2, q]
    flat = pts.reshape(-1, 2)
    r = np.sqrt(((flat[:, None] - flat[None]) ** 2).sum(-1))
    h = _hankel(k * np.maximum(r, 1e-300)).reshape(len(a), len(x), len(a), len(x))
    kern = np.einsum("aq,bp,mqnp->abmn", basis, basis, h)
    kern *= length[None, None, :, None] * length[None, None, None, :]
    # neighbouring pairs: closed-form logarithm along the source segment
    mid = (a + b) / 2
    gap = np.linalg.norm(mid[:, None] - mid[None], axis=2)
    near_m, near_n = np.nonzero(gap < NEAR_SEGMENTS * np.maximum(length[:, None], length[None]))
    xn, wn = np.polynomial.legendre.leggauss(NEAR_POINTS)
    xn, wn = (xn + 1) / 2, wn / 2
    pn = np.stack([1 - xn, xn])                                          # [2, q]
    lm, ln_ = length[near_m], length[near_n]
    obs = a[near_m, None] + xn[None, :, None] * (b - a)[near_m, None]    # [pair, q, 2]
    src = a[near_n, None] + xn[None, :, None] * (b - a)[near_n, None]    # [pair, p, 2]
    rr = np.sqrt(((obs[:, :, None] - src[:, None]) ** 2).sum(-1))        # [pair, q, p]
    smooth = np.einsum("bp,p,iqp->ibq", pn, wn, _hankel_smooth(k * rr)) * ln_[:, None, None]
    i0, i1 = _log_moments(obs, a[near_n, None], t[near_n, None], ln_[:, None])
    lg = np.stack([i0 - i1 / ln_[:, None], i1 / ln_[:, None]], axis=1)  # [pair, b, q]
    lg = lg + math.log(k) * ln_[:, None, None] / 2
    inner = smooth - 2j / np.pi * lg                                     # [pair, b, q]
    kern[:, :, near_m, near_n] = np.einsum("aq,q,ibq->abi", pn, wn, inner) * lm
    return kern


def _rooftops(contour: Contour) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rooftop unknowns: their node, rising segment (ending at it) and falling segment."""
    nseg = len(contour)
    if contour.closed:
        node = np.arange(nseg)
        return node, (node - 1) % nseg, node
    node = np.arange(1, nseg)
    return node, node - 1, node


def _excitation(contour: Contour, k: float, phi: np.ndarray, polarisation: str) -> np.ndarray:
    """``V[unknown, phi]``: the incident field (unit amplitude) tested with each basis."""
    a, b = contour.starts, contour.ends
    x, w = np.polynomial.legendre.leggauss(NEAR_POINTS)
    x, w = (x + 1) / 2, w / 2
    pts = a[:, None] + x[None, :, None] * (b - a)[:, None]              # [seg, q, 2]
    rho = np.stack([np.sin(phi), np.cos(phi)], axis=1)                 # [phi, 2]
    wave = np.exp(1j * k * np.einsum("sqi,fi->sqf", pts, rho))          # [seg, q, phi]
    length = contour.lengths
    if polarisation == "TM":
        return np.einsum("q,sqf->sf", w, wave) * length[:, None]
    t = (b - a) / length[:, None]
    # E_i = eta H_i (rho x z); eta divides out of Z I = V
    et = t[:, 0, None] * rho[None, :, 1] - t[:, 1, None] * rho[None, :, 0]   # [seg, phi]
    half = [np.einsum("q,sqf->sf", w * p, wave) * length[:, None] * et for p in (1 - x, x)]
    _, rise, fall = _rooftops(contour)
    return half[1][rise] + half[0][fall]


def _impedance(contour: Contour, k: float, polarisation: str) -> np.ndarray:
    """Galerkin matrix ``Z[test, basis]`` normalised to the impedance ``eta = 1``."""
    kern = _segment_kernels(contour, k)
    if polarisation == "TM":
        return (k / 4) * kern.sum(axis=(0, 1))
    length = contour.lengths
    starts, ends = contour.starts, contour.ends
    t = (ends - starts) / length[:, None]
    tt = t @ t.T
    total = kern.sum(axis=(0, 1))
    _, rise, fall = _rooftops(contour)
    # (segment, half-basis index, derivative) of each rooftop's two pieces
    pieces = [(rise, 1, 1.0 / length[rise]), (fall, 0, -1.0 / length[fall])]
    z = np.zeros((len(rise), len(rise)), complex)
    for sm, am, dm in pieces:
        for sn, bn, dn in pieces:
            vec = kern[am, bn][np.ix_(sm, sn)] * tt[np.ix_(sm, sn)]
            scal = total[np.ix_(sm, sn)] * np.outer(dm, dn)
            z += (k * vec - scal / k) / 4
    return z


@dataclass(frozen=True)
class MomEchoWidth:
    """Monostatic echo width of a 2-D conductor from the method of moments.

    Attributes
    ----------
    phi_deg : ndarray, shape ``[phi]``
        Radar angle from ``+y`` towards ``+x`` [deg].
    echo_width_m : ndarray, shape ``[phi]``
        ``sigma_2D`` [m].
    polarisation : str
        ``"TM"`` (E along the cylinder's axis) or ``"TE"`` (H along it).
    wavelength : float
        [m].
    unknowns : int
        Size of the linear system.
    current : ndarray of complex, shape ``[unknown, phi]``
        Expansion coefficients (TM: ``eta J_z`` per unit incident ``E`` on each
        segment; TE: the tangential ``J`` per unit incident ``H`` at each rooftop's node).
    info : dict
        ``segments`` and the wall-clock ``seconds`` spent.
    """

    phi_deg: np.ndarray
    echo_width_m: np.ndarray
    polarisation: str
    wavelength: float
    unknowns: int
    current: np.ndarray
    info: dict = field(default_factory=dict)

    @property
    def echo_width_db_lambda(self) -> np.ndarray:
        """``sigma_2D / lambda`` [dB], shape ``[phi]`` (floored at -300 dB)."""
        return 10 * np.log10(np.maximum(self.echo_width_m / self.wavelength, 1e-30))


def echo_width(contour: Contour, wavelength: float, phi_deg, polarisation: str = "TM"
               ) -> MomEchoWidth:
    """Monostatic echo width of a perfectly conducting cylinder (cross-section ``contour``).

    Parameters
    ----------
    contour : Contour
        Cross-section [m] (:func:`strip`, :func:`polyline`, :func:`regular_polygon`);
        segments of ``wavelength / SEGMENTS_PER_WAVELENGTH`` or shorter give
        about 0.05 dB (the tests' convergence check).
    wavelength : float
        [m].
    phi_deg : float or array_like, shape ``[phi]``
        Radar directions [deg], from ``+y`` towards ``+x``.
    polarisation : {"TM", "TE"}
        TM: electric field along ``z``; TE: magnetic field along ``z``.

    Returns
    -------
    MomEchoWidth

    Raises
    ------
    ValueError
        A non-positive wavelength, non-finite angles, an unknown polarisation, a
        contour that is not a :class:`Contour`, or too many unknowns (:func:`mom_job_size`).
    """
    started = time.perf_counter()
    wavelength = _positive(wavelength, "wavelength")
    pol = str(polarisation).upper()
    if pol not in ("TM", "TE"):
        raise ValueError(f"polarisation must be 'TM' or 'TE', got {polarisation!r}")
    if not isinstance(contour, Contour):
        raise ValueError(f"contour must be a Contour (strip, polyline, regular_polygon), "
                         f"got {type(contour).__name__}")
    phi = np.atleast_1d(np.asarray(phi_deg, dtype=float))
    if phi.ndim != 1 or len(phi) == 0 or not np.isfinite(phi).all():
        raise ValueError(f"phi_deg must be a non-empty list of finite angles [deg], "
                         f"got {phi_deg!r}")
    n = mom_job_size(contour, pol)
    k = 2 * math.pi / wavelength
    z = _impedance(contour, k, pol)
    v = _excitation(contour, k, np.radians(phi), pol)
    current = scipy.linalg.lu_solve(scipy.linalg.lu_factor(z), v)
    sigma = (k / 4) * np.abs(np.einsum("uf,uf->f", v, current)) ** 2
    return MomEchoWidth(phi, sigma, pol, wavelength, n, current,
                        {"segments": len(contour), "seconds": time.perf_counter() - started})
