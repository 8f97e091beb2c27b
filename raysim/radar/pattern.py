r"""Antenna element power patterns ``G(theta, phi)`` in the radar frame A.

Angles (docs/conventions.md, "Element pattern"): ``theta`` is the angle from
boresight ``+z_A`` and ``phi`` the angle about it from ``+x_A`` towards
``+y_A``, so a unit vector is ``u = (sin theta cos phi, sin theta sin phi,
cos theta)``; the azimuth plane of the conventions is ``phi = 0``, the
elevation plane ``phi = 90 deg``.

A pattern is a linear power gain (not dB). Energy consistency: the radiated
power is ``(1 / 4 pi) \oint G dOmega = eta <= 1`` (the radiation efficiency),
so a lossless element's peak gain equals its directivity. The analytic
``cos^q`` family is lossless by construction (Balanis, *Antenna Theory*, 4th ed.,
sec. 2.6: ``U = cos^q theta`` on the front hemisphere has directivity
``D_0 = 2 (q + 1)``), i.e.

.. math::  G(\theta) = 2 (q + 1) \cos^q \theta \quad (\theta < \pi / 2),\; 0 \text{ behind}

so the element gain ``antenna_gain_dbi`` of :class:`raysim.radar.config.RadarConfig`
and ``q`` are tied by ``G_0 = 10^{G_{dBi} / 10} = 2 (q + 1)``: 10 dBi is ``q = 4``.

Patterns (:func:`element_pattern` parses their names):

* ``"patch"`` (default): ``cos^q`` with ``q`` from the stated gain
  ``antenna_gain_dbi`` (``q = G_0 / 2 - 1``); at the default 10 dBi that is
  ``cos^4``, half-power beamwidth 65.5 deg. A microstrip patch radiates into
  its front half space with E- and H-plane beamwidths of about 65-90 deg
  (Balanis, ch. 14); 3GPP TR 38.901 Table 7.3-1 models such an element with a
  65 deg beamwidth. ``cos^4`` has that beamwidth, is lossless, and keeps the
  project's 10 dBi element gain. A gain below 3.01 dBi (``q < 0``) is no
  front-facing element and is refused when the pattern is used.
* ``"cos^<q>"`` (e.g. ``"cos^6"``): a fixed ``q``; its gain is ``2 (q + 1)``.
* ``"tr38901"``: 3GPP TR 38.901 Table 7.3-1, exactly Sionna RT's ``tr38901``
  pattern (8 dBi peak, 65 deg, 30 dB front-to-back). Its sphere integral is
  0.657 (Sionna's ``compute_gain``: directivity 9.83 dB, efficiency 65.7 %).
  Its horizontal cut is the azimuth plane, its vertical cut the elevation plane.
* a CSV file (:class:`TabulatedPattern`): columns ``theta_deg, phi_deg,
  gain_dbi`` on a full regular grid, bilinear in dB.
* ``"constant"``: the same gain ``antenna_gain_dbi`` in every direction: the
  point-target oracle's reference model, not a physical antenna (it radiates
  ``10^{G/10}`` times the power it is fed); exempt from the energy check.
"""

from __future__ import annotations

import csv
import functools
import math
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: Default element pattern of the radar (see the module docstring).
DEFAULT_ELEMENT_PATTERN = "patch"
#: ``q`` of the ``"patch"`` element at the default 10 dBi: ``2 (q + 1) = 10``, 65.5 deg HPBW.
PATCH_Q = 4.0
#: Default floor of the two-way element gain relative to its peak [dB]; paths below it are culled.
PATTERN_FLOOR_DB = -40.0
#: Largest disagreement between ``antenna_gain_dbi`` and a pattern's peak gain [dB].
PEAK_GAIN_TOLERANCE_DB = 0.5
#: Largest sphere integral / 4 pi of a tabulated pattern (1 is lossless; the excess
#: allows the quadrature error of a coarse file grid).
MAX_EFFICIENCY = 1.03
#: Quadrature grid of sphere integrals: ``[theta, phi]`` midpoints.
_QUAD = (720, 720)
#: Names accepted by :func:`element_pattern` besides ``cos^<q>`` and a CSV path.
PATTERN_NAMES = ("patch", "tr38901", "constant")


def direction_angles(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, phi)`` [rad] of directions ``u`` in frame A, shape ``[..., 3]`` -> ``[...]``.

    ``u`` need not be normalised; ``theta`` in ``[0, pi]``, ``phi`` in ``(-pi, pi]``.
    """
    u = np.asarray(u, dtype=float)
    rho = np.hypot(u[..., 0], u[..., 1])
    return np.arctan2(rho, u[..., 2]), np.arctan2(u[..., 1], u[..., 0])


def _sphere_grid():
    nt, nph = _QUAD
    theta = (np.arange(nt) + 0.5) * np.pi / nt
    phi = (np.arange(nph) + 0.5) * 2 * np.pi / nph - np.pi
    weight = np.sin(theta)[:, None] * (np.pi / nt) * (2 * np.pi / nph)
    return theta, phi, weight


@dataclass(frozen=True)
class ElementPattern:
    """Base of the element power patterns (linear gain, frame A angles)."""

    name: str

    def gain(self, theta, phi) -> np.ndarray:
        """Power gain (linear, re isotropic) at ``theta``, ``phi`` [rad] (broadcast)."""
        raise NotImplementedError

    def gain_direction(self, u) -> np.ndarray:
        """Power gain towards directions ``u`` in A, shape ``[..., 3]`` -> ``[...]``."""
        theta, phi = direction_angles(u)
        return self.gain(theta, phi)

    @functools.cached_property
    def peak_gain(self) -> float:
        """Largest gain (linear) on a fine sphere grid and at boresight."""
        theta, phi, _ = _sphere_grid()
        g = self.gain(theta[:, None], phi[None, :])
        return float(max(g.max(), self.gain(0.0, 0.0)))

    @property
    def peak_gain_dbi(self) -> float:
        """Peak gain [dBi]."""
        return 10.0 * math.log10(self.peak_gain)

    @functools.cached_property
    def efficiency(self) -> float:
        """Sphere integral ``(1 / 4 pi) \\oint G dOmega`` (1 for a lossless element)."""
        theta, phi, w = _sphere_grid()
        return float(np.sum(self.gain(theta[:, None], phi[None, :]) * w) / (4 * np.pi))

    def half_power_beamwidth(self, phi: float = 0.0) -> float:
        """Full -3 dB width of the cut at ``phi`` through boresight [rad].

        Measured on both sides of boresight (``phi`` and ``phi + pi``) by
        bisection of the first crossing of half the boresight gain.
        """
        g0 = float(self.gain(0.0, 0.0))
        width = 0.0
        for p in (phi, phi + np.pi):
            grid = np.linspace(0, np.pi, 3601)
            below = np.nonzero(self.gain(grid, p) < 0.5 * g0)[0]
            if below.size == 0:
                return 2 * np.pi
            lo, hi = grid[below[0] - 1], grid[below[0]]
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if self.gain(mid, p) >= 0.5 * g0 else (lo, mid)
            width += 0.5 * (lo + hi)
        return width

    def cull_angle(self, floor_db: float = PATTERN_FLOOR_DB) -> float:
        """Smallest ``theta`` [rad] beyond which the one-way gain stays ``floor_db`` below peak.

        Beyond it every direction has ``G / G_peak < 10^{floor_db / 10}``, so any
        path with a leg there has a two-way gain below the floor too (the
        other leg's factor is at most 1): the cone the scene budget may prune
        outside of. ``pi`` when no such angle exists. Kept per pattern and floor
        (every trace asks; the sphere grid costs a few ms).
        """
        cache = self.__dict__.setdefault("_cull_angles", {})   # frozen: no attribute set
        if floor_db not in cache:
            cache[floor_db] = self._cull_angle(floor_db)
        return cache[floor_db]

    def _cull_angle(self, floor_db: float) -> float:
        theta, phi, _ = _sphere_grid()
        rel = self.gain(theta[:, None], phi[None, :]).max(axis=1) / self.peak_gain
        above = np.nonzero(rel >= 10 ** (floor_db / 10))[0]
        if above.size == 0 or above[-1] == theta.size - 1:
            return float(np.pi)
        # the next grid row is below the floor; step half a row out to stay conservative
        return float(min(np.pi, theta[above[-1]] + np.pi / theta.size))


@dataclass(frozen=True)
class CosinePattern(ElementPattern):
    """``G = 2 (q + 1) cos^q theta`` on the front hemisphere, 0 behind (lossless)."""

    q: float = PATCH_Q

    def __post_init__(self) -> None:
        if not (math.isfinite(self.q) and self.q >= 0):
            raise ValueError(f"cos^q pattern: q must be a finite number >= 0, got {self.q!r}")

    def gain(self, theta, phi) -> np.ndarray:
        c = np.cos(np.asarray(theta, dtype=float))
        g = 2.0 * (self.q + 1.0) * np.power(np.clip(c, 0.0, None), self.q)
        return np.where(c > 0, g, 0.0) + 0.0 * np.asarray(phi, dtype=float)

    @property
    def peak_gain(self) -> float:
        return 2.0 * (self.q + 1.0)

    @property
    def efficiency(self) -> float:
        return 1.0


@dataclass(frozen=True)
class ConstantGain(ElementPattern):
    """The same gain ``gain_dbi`` in every direction (the oracle's reference model)."""

    gain_dbi: float = 0.0

    def gain(self, theta, phi) -> np.ndarray:
        shape = np.broadcast(np.asarray(theta), np.asarray(phi)).shape
        return np.full(shape, 10 ** (self.gain_dbi / 10))

    @property
    def peak_gain(self) -> float:
        return 10 ** (self.gain_dbi / 10)

    @property
    def efficiency(self) -> float:
        return self.peak_gain


@dataclass(frozen=True)
class Tr38901Pattern(ElementPattern):
    """3GPP TR 38.901 Table 7.3-1 element, as Sionna RT's ``tr38901`` pattern.

    Sionna's element looks along its local ``x`` with zenith ``z``; here its
    boresight is ``+z_A``, its horizontal cut the azimuth plane (towards
    ``+x_A``) and its vertical cut the elevation plane (``+y_A`` up): Sionna's
    zenith angle is ``arccos(u_y)`` and its azimuth ``atan2(u_x, u_z)``.
    """

    def gain(self, theta, phi) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        phi = np.asarray(phi, dtype=float)
        st = np.sin(theta)
        ux, uy, uz = st * np.cos(phi), st * np.sin(phi), np.cos(theta)
        zen = np.arccos(np.clip(uy, -1.0, 1.0))
        azi = np.arctan2(ux, uz)
        beam = math.radians(65.0)
        a_v = -np.minimum(12.0 * ((zen - np.pi / 2) / beam) ** 2, 30.0)
        a_h = -np.minimum(12.0 * (azi / beam) ** 2, 30.0)
        a_db = -np.minimum(-(a_v + a_h), 30.0) + 8.0
        return 10 ** (a_db / 10)

    @property
    def peak_gain(self) -> float:
        return 10 ** 0.8


@dataclass(frozen=True)
class TabulatedPattern(ElementPattern):
    """A gain table on a regular ``[theta, phi]`` grid, interpolated bilinearly in dB.

    Attributes
    ----------
    theta : ndarray, shape ``[theta]``
        Increasing grid from 0 to pi [rad].
    phi : ndarray, shape ``[phi]``
        Increasing grid covering one turn, ``phi[-1] - phi[0] < 2 pi`` [rad]
        (periodic: the last cell wraps to the first column).
    gain_db : ndarray, shape ``[theta, phi]``
        Gain [dBi].
    """

    theta: np.ndarray = field(default_factory=lambda: np.zeros(0))
    phi: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gain_db: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    def __post_init__(self) -> None:
        t, p, g = (np.asarray(x, dtype=float) for x in (self.theta, self.phi, self.gain_db))
        if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0) \
                or abs(t[0]) > 1e-9 or abs(t[-1] - np.pi) > 1e-9:
            raise ValueError(f"{self.name}: theta_deg must increase from 0 to 180 deg, got "
                             f"{np.degrees(t[:3])}...{np.degrees(t[-2:])}")
        if p.ndim != 1 or p.size < 1 or np.any(np.diff(p) <= 0) or p[-1] - p[0] >= 2 * np.pi:
            raise ValueError(f"{self.name}: phi_deg must increase within one turn "
                             f"(e.g. 0 to 355), got {np.degrees(p)}")
        if g.shape != (t.size, p.size) or not np.all(np.isfinite(g)):
            raise ValueError(f"{self.name}: gain_dbi must be finite on the full theta x phi grid "
                             f"({t.size} x {p.size}), got shape {g.shape}")
        object.__setattr__(self, "theta", t)
        object.__setattr__(self, "phi", p)
        object.__setattr__(self, "gain_db", g)

    def gain(self, theta, phi) -> np.ndarray:
        from scipy.interpolate import RegularGridInterpolator

        theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
        p = np.concatenate([self.phi, [self.phi[0] + 2 * np.pi]])
        g = np.concatenate([self.gain_db, self.gain_db[:, :1]], axis=1)
        interp = RegularGridInterpolator((self.theta, p), g, method="linear")
        wrapped = self.phi[0] + np.mod(phi - self.phi[0], 2 * np.pi)
        pts = np.stack([np.clip(theta, 0.0, np.pi), wrapped], axis=-1)
        return 10 ** (interp(pts.reshape(-1, 2)).reshape(theta.shape) / 10)

    @classmethod
    def from_csv(cls, path: str | os.PathLike) -> TabulatedPattern:
        """Read a pattern file.

        Format: UTF-8 CSV with the header ``theta_deg,phi_deg,gain_dbi`` and one
        row per grid point (any order); ``theta_deg`` from 0 to 180, ``phi_deg``
        a regular or irregular grid within one turn (e.g. 0, 5, ..., 355), every
        (theta, phi) pair exactly once; ``gain_dbi`` the element's gain [dBi]
        (radiation efficiency included). A file whose sphere integral exceeds
        :data:`MAX_EFFICIENCY` (gain above directivity) is refused; lines
        starting with ``#`` are comments.
        """
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as err:
            raise ValueError(f"element pattern file {str(path)!r} cannot be read: {err}") from None
        rows = [r for r in csv.reader(line for line in text.splitlines()
                                      if line.strip() and not line.lstrip().startswith("#"))]
        header = [h.strip() for h in rows[0]] if rows else []
        if header != ["theta_deg", "phi_deg", "gain_dbi"]:
            raise ValueError(f"element pattern file {str(path)!r}: header must be "
                             f"'theta_deg,phi_deg,gain_dbi', got {','.join(header)!r}")
        try:
            data = np.array([[float(x) for x in r] for r in rows[1:]], dtype=float)
        except ValueError as err:
            raise ValueError(f"element pattern file {str(path)!r}: {err}") from None
        if data.ndim != 2 or data.shape[1] != 3:
            raise ValueError(f"element pattern file {str(path)!r}: expected 3 numbers a row")
        t, p = np.unique(data[:, 0]), np.unique(data[:, 1])
        if data.shape[0] != t.size * p.size:
            raise ValueError(f"element pattern file {str(path)!r}: {data.shape[0]} rows do not "
                             f"fill the {t.size} x {p.size} theta x phi grid once")
        grid = np.full((t.size, p.size), np.nan)
        grid[np.searchsorted(t, data[:, 0]), np.searchsorted(p, data[:, 1])] = data[:, 2]
        if np.any(np.isnan(grid)):
            raise ValueError(f"element pattern file {str(path)!r}: repeated (theta, phi) pairs")
        pattern = cls(str(path), np.radians(t), np.radians(p), grid)
        if pattern.efficiency > MAX_EFFICIENCY:
            raise ValueError(
                f"element pattern file {str(path)!r} integrates to {pattern.efficiency:.3f} x "
                f"4 pi: its gain exceeds its directivity; gain_dbi must be gain over isotropic "
                f"(sphere integral <= 4 pi)")
        if pattern.efficiency < 0.5:
            warnings.warn(f"element pattern file {str(path)!r} radiates "
                          f"{pattern.efficiency:.0%} of its input power (radiation efficiency); "
                          "check that gain_dbi is gain over isotropic", UserWarning, stacklevel=2)
        return pattern


_COS_RE = re.compile(r"^cos\^\s*([0-9.eE+-]+)$")


@functools.lru_cache(maxsize=32)
@dataclass(frozen=True)
class MountedPattern(ElementPattern):
    """``base`` turned by a mounting ``R_BA`` (``rotation``, 3 rows of 3): gains towards B
    directions."""

    base: ElementPattern
    rotation: tuple

    def gain_direction(self, u) -> np.ndarray:
        # u_A = R_BA^T u_B, i.e. the row vector u_B @ R_BA
        return self.base.gain_direction(np.asarray(u, dtype=float) @ np.asarray(self.rotation))

    def gain(self, theta, phi) -> np.ndarray:
        u = np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                         np.cos(theta)), axis=-1)
        return self.gain_direction(u)

    @property
    def peak_gain(self) -> float:
        return self.base.peak_gain


def _cached(spec: str, gain_dbi: float, stamp: float) -> ElementPattern:
    if spec == "tr38901":
        return Tr38901Pattern("tr38901")
    if spec == "constant":
        return ConstantGain("constant", gain_dbi)
    if spec == "patch":
        q = 10 ** (gain_dbi / 10) / 2.0 - 1.0
        if q < 0:
            raise ValueError(f"element_pattern 'patch' (cos^q, q = G0 / 2 - 1) needs "
                             f"antenna_gain_dbi >= 3.01 dBi, got {gain_dbi!r} dBi; choose "
                             f"element_pattern = 'constant' for a direction-free gain")
        return CosinePattern("patch", q)
    m = _COS_RE.match(spec)
    if m:
        try:
            q = float(m.group(1))
        except ValueError:
            q = math.nan
        return CosinePattern(spec, q)
    if spec.lower().endswith(".csv") or os.sep in spec or "/" in spec:
        return TabulatedPattern.from_csv(spec)
    raise ValueError(f"element_pattern must be one of {', '.join(PATTERN_NAMES)}, 'cos^<q>' "
                     f"(e.g. 'cos^6') or the path of a CSV pattern file, got {spec!r}")


def element_pattern(spec: str, gain_dbi: float | None = None) -> ElementPattern:
    """The pattern named by ``spec`` (see the module docstring), cached.

    Parameters
    ----------
    spec : str
        ``"patch"``, ``"cos^<q>"``, ``"tr38901"``, ``"constant"`` or a CSV path.
    gain_dbi : float, optional
        The stated element gain [dBi]: sets ``q`` of ``"patch"`` (default 10 dBi,
        ``q = 4``) and the level of ``"constant"`` (required there).

    Returns
    -------
    ElementPattern
    """
    if not isinstance(spec, str) or not spec.strip():
        raise ValueError(f"element_pattern must be a non-empty string, got {spec!r}")
    spec = spec.strip()
    if spec == "constant" and gain_dbi is None:
        raise ValueError(f"element_pattern {spec!r} needs the element gain antenna_gain_dbi")
    if spec == "patch" and gain_dbi is None:
        gain_dbi = 10 * math.log10(2 * (PATCH_Q + 1))
    stamp = 0.0
    if spec.lower().endswith(".csv"):
        try:
            stamp = os.stat(spec).st_mtime
        except OSError as err:
            raise ValueError(f"element_pattern file {spec!r} cannot be read: {err}") from None
    return _cached(spec, float(gain_dbi or 0.0), stamp)


def check_peak_gain(pattern: ElementPattern, gain_dbi: float) -> None:
    """Refuse an element gain that disagrees with the pattern's peak.

    The peak of an energy-consistent pattern is fixed by its shape (``cos^q``:
    ``2 (q + 1)``), so a stated ``antenna_gain_dbi`` more than
    :data:`PEAK_GAIN_TOLERANCE_DB` away from it is inconsistent.
    ``"constant"`` is exempt.
    """
    if isinstance(pattern, ConstantGain):
        return
    peak = pattern.peak_gain_dbi
    if abs(peak - float(gain_dbi)) > PEAK_GAIN_TOLERANCE_DB:
        hint = ""
        if isinstance(pattern, CosinePattern):
            q = 10 ** (float(gain_dbi) / 10) / 2.0 - 1.0
            hint = f", or element_pattern = 'cos^{q:.4g}' for {gain_dbi:g} dBi" if q >= 0 else ""
        raise ValueError(
            f"antenna_gain_dbi {gain_dbi!r} dBi disagrees with element_pattern "
            f"{pattern.name!r}, whose peak gain is {peak:.2f} dBi (energy-consistent pattern; "
            f"cos^q: G0 = 2 (q + 1)); set antenna_gain_dbi = {peak:.2f}{hint}")


def resolve_element_gain(spec: str, gain_dbi: float, given: bool) -> float:
    """The element gain [dBi] a scenario means: ``gain_dbi`` if ``given``, else the pattern's peak.

    An explicit gain is checked against the pattern (:func:`check_peak_gain`);
    ``"constant"`` and ``"patch"`` take ``gain_dbi`` (they are defined by it).
    """
    pattern = element_pattern(spec, gain_dbi)
    if given:
        check_peak_gain(pattern, gain_dbi)
    if given or isinstance(pattern, ConstantGain) or spec.strip() == "patch":
        return float(gain_dbi)
    return round(pattern.peak_gain_dbi, 6)


def two_way_gain(pattern: ElementPattern, u_tx, u_rx) -> np.ndarray:
    """``G_t(u_tx) G_r(u_rx)`` (linear) of a path leaving along ``u_tx`` and arriving from ``u_rx``.

    Both directions point from the radar towards the scene, in frame A, shape
    ``[..., 3]`` (not necessarily unit); transmit and receive elements share the pattern.
    """
    return pattern.gain_direction(u_tx) * pattern.gain_direction(u_rx)


def path_gain(pattern: ElementPattern, rotations, origins, p_dep, p_arr) -> np.ndarray:
    """``sqrt(G_t(u_dep) G_r(u_arr))`` of paths leaving to ``p_dep``, arriving from ``p_arr``.

    Parameters
    ----------
    pattern : ElementPattern
        Transmit and receive element pattern (frame A).
    rotations : array_like, shape ``[chirp, 3, 3]``
        Radar attitude at each chirp, frame A -> W.
    origins : array_like, shape ``[chirp, 3]``
        Radar phase centre at each chirp in W [m].
    p_dep, p_arr : array_like, shape ``[path, chirp, 3]``
        First and last path vertex in W at each chirp [m].

    Returns
    -------
    ndarray, shape ``[path, chirp]``
        Two-way element amplitude factor (linear).
    """
    mats = np.asarray(rotations, dtype=float)
    o = np.asarray(origins, dtype=float)[None]
    # W -> A is the transpose of R: (R^T d)_i = sum_j R_ji d_j
    u_dep = np.einsum("cji,pcj->pci", mats, np.asarray(p_dep, dtype=float) - o)
    u_arr = np.einsum("cji,pcj->pci", mats, np.asarray(p_arr, dtype=float) - o)
    return np.sqrt(two_way_gain(pattern, u_dep, u_arr))
