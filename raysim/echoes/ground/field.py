r"""A persistent clutter field: seeded point scatterers fixed on the ground and walls in W.

Each scatterer ``i`` stands for a surface patch of area ``dA_i`` and is one
frozen path (``kind = DIFFUSE``) whose complex amplitude is

.. math::

    a_i = z_i \sqrt{\frac{P_t G^2 \lambda^2 \sigma^0(\theta_i) dA_i}{(4\pi)^3 R_i^4}},
    \qquad z_i \sim \mathcal{CN}(0, 1)

(radar equation, Skolnik, *Radar Handbook*, 3rd ed., eq. 7.1 with
``sigma = sigma0 dA``), so ``E|a_i|^2`` is the mean clutter power of the patch
and a resolution cell holding many scatterers has a complex Gaussian sum:
Rayleigh amplitude (Skolnik, sec. 7.5). Positions, ``dA_i`` and ``z_i`` are
drawn once (seeded) and kept for every chirp and frame while the radar stays
within ``reuse_distance`` of the pose the field was built for; what changes
with the pose is ``R_i``, ``theta_i`` and whether the scatterer is shadowed.

Density
-------
Scatterers are a Poisson process of intensity ``rho(p) = n_cell / A_cell(p)``,
with ``A_cell`` the area of one range x angle resolution cell on the facet
(:func:`raysim.echoes.ground.density.resolution_cell_area`): every cell the
radar can see holds ``n_cell`` scatterers on average at every incidence, so a
cell is a Rayleigh sum wherever it is, and the count is set by the visible area
and the range, not by the element pattern. The facets are the ground and, with
``walls`` (default), the walls (:meth:`GroundSurface.clutter_facets`).
Thinning a bounding intensity and weighting each kept point by
``dA_i = 1 / rho(p_i)`` keeps ``sum_i sigma0 dA_i`` an unbiased estimate of the
integral of ``sigma0`` over the surface. The expected count is computed from
the facets before anything is drawn; it is logged, and when it exceeds
``max_scatterers`` the density is scaled down uniformly, with a
:class:`FieldCapped` warning that gives the scatterers per cell left.

Wind
----
With ``wind_mps > 0`` the scatterers on vegetation materials (``vegetation``)
keep their positions but their amplitudes become ``a_i m_i(t)``, the internal
clutter motion of :mod:`raysim.echoes.ground.icm` (Billingsley's exponential
Doppler spectrum); :meth:`ClutterField.modulation` gives ``m_i`` at the chirps
and the synthesis applies it (:func:`raysim.echoes.rt.reproject.synthesize_paths`).
"""

from __future__ import annotations

import functools
import logging
import math
import time as _time
import warnings
from dataclasses import dataclass, field

import numpy as np

from raysim.echoes.ground.density import resolution_cell_area
from raysim.echoes.ground.icm import MIN_WIND_MPH, MPH, IcmProcess
from raysim.echoes.ground.sigma0 import CLUTTER_MATERIALS, POLARISATIONS, sigma0
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.rt.trace import DIFFUSE, PathSet
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.radar.pattern import PATTERN_FLOOR_DB

__all__ = ["FieldSettings", "ClutterField", "FieldCapped", "angular_resolution", "radar_scale"]

_LOG = logging.getLogger(__name__)

#: Longest edge of a ground facet before sampling [m]; smaller facets bound the density tightly.
MAX_EDGE = 1.0
#: Safety factor on the sampled density maximum of a facet.
BOUND_MARGIN = 1.5
#: Shortest distance kept before a scatterer on shadowing rays [m].
SHADOW_EPSILON = 0.01


class FieldCapped(UserWarning):
    """The expected scatterer count exceeded ``max_scatterers``: the density was scaled down."""


@dataclass(frozen=True)
class FieldSettings:
    """Options of a clutter field.

    Attributes
    ----------
    scatterers_per_cell : float
        Mean scatterers per range x angle resolution cell, at every incidence (> 0).
    walls : bool
        Draw scatterers on the walls (facets steeper than
        :data:`~raysim.echoes.ground.surface.MAX_TILT`) as well as on the ground.
    max_scatterers : int
        Bound on the expected number of scatterers (cost bound), >= 1.
    reuse_distance : float
        Radar displacement from the build pose up to which the field is re-used [m].
    shadowing : bool
        Cast a ray from the radar to every scatterer (Mitsuba) and drop the occluded.
    polarisation : {"VV", "HH", "HV"}
        Channel of ``sigma0`` (transmit-receive).
    fov_half_angle : float, optional
        Field of view around boresight [rad], in (0, pi/2]; default (``None``)
        the element pattern's cull cone (:meth:`fov`).
    seed : int
        Seed of positions and amplitudes.
    wind_mps : float
        Wind speed [m/s] moving the vegetation (internal clutter motion); 0
        (default) keeps every scatterer still, else at least 0.5 mph (0.224 m/s).
    vegetation : tuple of str, optional
        Clutter materials that move in the wind; default (``None``) those
        flagged ``vegetation`` in :data:`~raysim.echoes.ground.sigma0.CLUTTER_MATERIALS`.
    """

    scatterers_per_cell: float = 10.0
    walls: bool = True
    max_scatterers: int = 200_000
    reuse_distance: float = 0.5
    shadowing: bool = True
    polarisation: str = "VV"
    fov_half_angle: float | None = None
    seed: int = 0
    wind_mps: float = 0.0
    vegetation: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if not self.scatterers_per_cell > 0:
            raise ValueError(f"scatterers_per_cell must be > 0, got {self.scatterers_per_cell!r}")
        if int(self.max_scatterers) != self.max_scatterers or self.max_scatterers < 1:
            raise ValueError(f"max_scatterers must be an integer >= 1, "
                             f"got {self.max_scatterers!r}")
        if not self.reuse_distance >= 0:
            raise ValueError(f"reuse_distance must be >= 0 m, got {self.reuse_distance!r}")
        if self.polarisation not in POLARISATIONS:
            raise ValueError(f"polarisation must be one of {POLARISATIONS}, "
                             f"got {self.polarisation!r}")
        if self.fov_half_angle is not None and not 0 < self.fov_half_angle <= math.pi / 2:
            raise ValueError(f"fov_half_angle must lie in (0, pi/2] rad or be None, "
                             f"got {self.fov_half_angle!r}")
        if int(self.seed) != self.seed or self.seed < 0:
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")
        w = self.wind_mps
        if not (isinstance(w, (int, float)) and (w == 0 or w >= MIN_WIND_MPH * MPH)
                and math.isfinite(w)):
            raise ValueError(f"wind_mps must be 0 (still) or >= {MIN_WIND_MPH * MPH:.3f} m/s "
                             f"({MIN_WIND_MPH} mph), got {w!r}")
        if self.vegetation is not None:
            veg = (self.vegetation,) if isinstance(self.vegetation, str) else self.vegetation
            bad = [m for m in veg if m not in CLUTTER_MATERIALS]
            if bad:
                raise ValueError(f"vegetation must name clutter materials "
                                 f"{sorted(CLUTTER_MATERIALS)}, got {bad!r}")
            object.__setattr__(self, "vegetation", tuple(veg))

    def vegetation_materials(self) -> tuple[str, ...]:
        """Materials that move in the wind (``vegetation`` or the flagged ones)."""
        if self.vegetation is not None:
            return self.vegetation
        return tuple(n for n, m in CLUTTER_MATERIALS.items() if m.vegetation)

    def fov(self, config: RadarConfig) -> float:
        """Half-angle of the cone around boresight the field covers [rad].

        ``fov_half_angle`` if set, else where the element pattern's one-way gain
        falls :data:`~raysim.radar.pattern.PATTERN_FLOOR_DB` below its peak (the
        tracer's cull), at most 89 deg (the ground is below the horizon).
        """
        if self.fov_half_angle is not None:
            return float(self.fov_half_angle)
        return min(config.pattern.cull_angle(PATTERN_FLOOR_DB), math.radians(89.0))


def angular_resolution(array: VirtualArray, wavelength: float) -> tuple[float, float]:
    """Rayleigh resolution ``(du, dv)`` in direction cosines along ``x_A``, ``y_A``.

    ``lambda / (n s)`` for ``n`` distinct two-way phase-centre coordinates
    ``p_tx + p_rx`` at spacing ``s``; 2 (no resolution) along an axis with one.
    """
    p = array.tx_positions + array.rx_positions
    out = []
    for axis in (0, 1):
        u = np.unique(np.round(p[:, axis] / (1e-6 * wavelength)))
        if u.size < 2:
            out.append(2.0)
            continue
        s = float(np.min(np.diff(u))) * 1e-6 * wavelength
        out.append(min(2.0, wavelength / (u.size * s)))
    return out[0], out[1]


def radar_scale(config: RadarConfig) -> float:
    """``P_t lambda^2 / (4 pi)^3`` [W m^2]: received power is this times ``G_t G_r sigma / R^4``.

    0 dBi elements: like every :class:`~raysim.echoes.rt.trace.PathSet`, the
    clutter paths leave the two-way element gain to the re-projection
    (:func:`raysim.echoes.rt.reproject.pattern_amplitude`).
    """
    pt = 10 ** (config.tx_power_dbm / 10) * 1e-3
    return pt * config.wavelength**2 / (4 * math.pi) ** 3


def _subdivide(tris: np.ndarray, idx: np.ndarray, max_edge: float):
    """Split triangles into four until no edge exceeds ``max_edge``; keeps the parent index."""
    out_t, out_i = [tris[:0]], [idx[:0]]                     # none in range: no facet
    while len(tris):
        e = np.max(np.linalg.norm(tris - np.roll(tris, 1, axis=1), axis=-1), axis=1)
        small = e <= max_edge
        out_t.append(tris[small])
        out_i.append(idx[small])
        t, i = tris[~small], idx[~small]
        a, b, c = t[:, 0], t[:, 1], t[:, 2]
        ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
        tris = np.concatenate([np.stack(s, axis=1) for s in (
            (a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
        idx = np.tile(i, 4)
    return np.concatenate(out_t), np.concatenate(out_i)


@dataclass(frozen=True, eq=False)
class ClutterField:
    """Seeded ground scatterers fixed in W (build with :meth:`build`).

    Attributes
    ----------
    positions : ndarray, shape ``[scatterer, 3]``
        Positions in W [m].
    normals : ndarray, shape ``[scatterer, 3]``
        Normals of the surface there (upward on the ground, outward on walls).
    material : ndarray of str, shape ``[scatterer]``
        Clutter material ids.
    area : ndarray, shape ``[scatterer]``
        Ground area each scatterer stands for, ``dA_i`` [m^2].
    z : ndarray, complex128, shape ``[scatterer]``
        Unit complex Gaussian amplitude factors.
    anchor : ndarray, shape ``[3]``
        Radar position the field was built for, in W [m].
    settings : FieldSettings
    report : dict
        ``num_scatterers``, ``wall_scatterers`` (of them on walls), ``expected``,
        ``density_scale`` (1 unless capped),
        ``cell_area_nadir`` [m^2], ``resolution`` ``(dR, du, dv)``, ``build_s``
        (wall), ``build_cpu_s`` and, in wind, ``icm_scatterers``.
    icm : IcmProcess, optional
        Internal clutter motion of the vegetation scatterers (``settings.wind_mps > 0``).
    icm_index : ndarray of int, shape ``[icm scatterer]``, optional
        Which scatterers ``icm`` moves (rows of ``positions``).
    """

    positions: np.ndarray
    normals: np.ndarray
    material: np.ndarray
    area: np.ndarray
    z: np.ndarray
    anchor: np.ndarray
    settings: FieldSettings
    report: dict = field(default_factory=dict)
    icm: IcmProcess | None = None
    icm_index: np.ndarray | None = None

    @property
    def num_scatterers(self) -> int:
        """Number of scatterers."""
        return int(self.area.shape[0])

    def covers(self, radar_w) -> bool:
        """Whether a radar at ``radar_w`` [m] is within ``reuse_distance`` of the anchor."""
        d = np.linalg.norm(np.asarray(radar_w, dtype=float) - self.anchor)
        return bool(d <= self.settings.reuse_distance)

    # ------------------------------------------------------------------ build
    @classmethod
    def build(cls, ground: GroundSurface, config: RadarConfig, array: VirtualArray,
              radar_w, r_wb, settings: FieldSettings | None = None) -> ClutterField:
        """Sample the field for a radar at ``radar_w`` with attitude ``r_wb``.

        Parameters
        ----------
        ground : GroundSurface
        config : RadarConfig
            Range resolution and range window (``max_range``).
        array : VirtualArray
            Angular resolution.
        radar_w : array_like, shape ``[3]``
            Radar phase centre in W [m].
        r_wb : array_like, shape ``[3, 3]``
            Attitude (body to world); boresight is its third column.
        settings : FieldSettings, optional
        """
        if not isinstance(ground, GroundSurface):
            raise ValueError(f"ground must be a GroundSurface, got {type(ground)}")
        s = FieldSettings() if settings is None else settings
        t_wall, t_cpu = _time.perf_counter(), _time.process_time()
        x0 = np.asarray(radar_w, dtype=float)
        bore = np.asarray(r_wb, dtype=float)[:, 2]
        dr = config.range_resolution
        du, dv = angular_resolution(array, config.wavelength)
        r_max = config.max_range + s.reuse_distance
        cos_fov = math.cos(min(s.fov(config) + math.radians(5.0), math.pi / 2))

        tris, normals, mats = ground.clutter_facets(walls=s.walls)
        n_ground = len(ground.triangles)
        dist = np.linalg.norm(tris - x0, axis=-1)
        near = dist.min(axis=1) < r_max
        tris, idx = _subdivide(tris[near], np.nonzero(near)[0], MAX_EDGE)
        normals = normals[idx]

        def density(p, n):
            d = p - x0
            r = np.linalg.norm(d, axis=-1)
            u = d / r[..., None]
            cos_b = u @ bore
            cos_i = -np.sum(u * n, axis=-1)
            rho = s.scatterers_per_cell / resolution_cell_area(r, cos_b, cos_i, dr, du, dv)
            ok = (r < r_max) & (cos_b >= cos_fov) & (cos_i > 0)
            return np.where(ok, rho, 0.0)

        probes = np.concatenate([tris, 0.5 * (tris + np.roll(tris, 1, axis=1)),
                                 tris.mean(axis=1, keepdims=True)], axis=1)   # [facet, 7, 3]
        rho_probe = density(probes, normals[:, None, :])
        bound = BOUND_MARGIN * rho_probe.max(axis=1)
        areas = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]),
                                     axis=-1)
        # the job's size, known before anything is drawn
        expected = float(np.sum(rho_probe[:, -1] * areas))
        scale = min(1.0, s.max_scatterers / expected) if expected > 0 else 1.0
        _LOG.info("clutter field: %.0f scatterers expected (%g per cell) within %.1f m",
                  expected * scale, s.scatterers_per_cell * scale, r_max)
        if scale < 1.0:
            warnings.warn(FieldCapped(
                f"clutter field: {expected:.0f} scatterers expected at "
                f"{s.scatterers_per_cell:g} per resolution cell exceed max_scatterers = "
                f"{s.max_scatterers}; density scaled by {scale:.3g} to "
                f"{s.scatterers_per_cell * scale:.3g} per cell (raise max_scatterers or lower "
                f"scatterers_per_cell)"), stacklevel=2)
        rng = np.random.default_rng([s.seed, 0xC1077E])
        counts = rng.poisson(bound * scale * areas)
        f = np.repeat(np.arange(len(tris)), counts)
        r1, r2 = np.sqrt(rng.random(f.size)), rng.random(f.size)
        t = tris[f]
        p = ((1 - r1)[:, None] * t[:, 0] + (r1 * (1 - r2))[:, None] * t[:, 1]
             + (r1 * r2)[:, None] * t[:, 2])
        rho = scale * density(p, normals[f])
        keep = rng.random(f.size) * bound[f] * scale < rho
        p, f, rho = p[keep], f[keep], rho[keep]
        eff = np.minimum(rho, bound[f] * scale)                     # intensity actually drawn
        z = (rng.standard_normal(p.shape[0]) + 1j * rng.standard_normal(p.shape[0])) / math.sqrt(2)
        h = _height_above(ground, x0)
        nadir = float("nan") if h is None else h**2 * du * dv
        on_wall = idx[f] >= n_ground
        report = {"num_scatterers": int(p.shape[0]), "expected": expected * scale,
                  "wall_scatterers": int(np.sum(on_wall)),
                  "expected_uncapped": expected, "density_scale": scale,
                  "cell_area_nadir": float(nadir), "resolution": (dr, du, dv),
                  "scatterers_per_cell": s.scatterers_per_cell,
                  "build_s": _time.perf_counter() - t_wall,
                  "build_cpu_s": _time.process_time() - t_cpu}
        material = mats[idx[f]]
        icm = icm_index = None
        if s.wind_mps > 0:
            # a stream of its own: the still field's draws stay as they are
            icm_index = np.nonzero(np.isin(material, s.vegetation_materials()))[0]
            icm = IcmProcess.draw(icm_index.size, s.wind_mps, config.carrier_frequency,
                                  seed=s.seed)
            report["icm_scatterers"] = int(icm_index.size)
        return cls(p, normals[f], material, 1.0 / eff, z, x0.copy(), s, report, icm, icm_index)

    # ------------------------------------------------------------------ wind
    def modulation(self, vertices, times) -> tuple[np.ndarray, np.ndarray] | None:
        """ICM modulation of the paths among ``vertices`` that are moving scatterers.

        Parameters
        ----------
        vertices : ndarray, shape ``[path, 3]``
            First vertices of frozen paths in W [m]; a path is this field's
            scatterer where its vertex equals the scatterer's position exactly.
        times : array_like, shape ``[chirp]``
            Absolute instants [s].

        Returns
        -------
        (rows, m) or None
            ``rows`` [n] indices into ``vertices`` and ``m`` [n, chirp] complex
            multipliers of their amplitudes; None without wind or vegetation.
        """
        if self.icm is None or self.icm_index.size == 0:
            return None
        keys, order = self._icm_keys
        q = _void(np.asarray(vertices, dtype=np.float64))
        j = np.clip(np.searchsorted(keys, q), 0, keys.size - 1)
        hit = keys[j] == q
        return np.nonzero(hit)[0], self.icm.modulation(times, order[j[hit]])

    @functools.cached_property
    def _icm_keys(self) -> tuple[np.ndarray, np.ndarray]:
        """Sorted position keys of the moving scatterers and their rows in ``icm``."""
        keys = _void(self.positions[self.icm_index])
        order = np.argsort(keys)
        return keys[order], order

    # ------------------------------------------------------------------ paths
    def paths(self, config: RadarConfig, radar_w, r_wb, *, time: float = 0.0,
              occluders=None, min_range: float = 0.0) -> PathSet:
        """The scatterers seen from a radar at ``radar_w`` as frozen DIFFUSE paths.

        Parameters
        ----------
        config : RadarConfig
            Power, gain, wavelength and range window.
        radar_w : array_like, shape ``[3]``
            Radar phase centre in W [m]; must be within ``reuse_distance`` of ``anchor``.
        r_wb : array_like, shape ``[3, 3]``
            Attitude (boresight is its third column).
        time : float
            Trace instant stored in the PathSet [s].
        occluders : raysim.echoes.po.rays.RayScene, optional
            Geometry for shadowing rays (``settings.shadowing``); None skips them.
        min_range : float
            Smallest kept ``length / 2`` [m].

        Returns
        -------
        PathSet
            ``dropped`` counts ``"range"``, ``"fov"``, ``"shadow"``.
        """
        x0 = np.asarray(radar_w, dtype=float)
        if not self.covers(x0):
            raise ValueError(f"radar_w {x0.tolist()} is more than reuse_distance = "
                             f"{self.settings.reuse_distance} m from the field's anchor "
                             f"{self.anchor.tolist()}; build a new field")
        bore = np.asarray(r_wb, dtype=float)[:, 2]
        d = self.positions - x0
        r = np.linalg.norm(d, axis=-1)
        u = d / r[:, None]
        cos_i = -np.sum(u * self.normals, axis=-1)
        in_range = (r >= min_range) & (r < config.max_range)
        in_fov = (u @ bore >= math.cos(self.settings.fov(config))) & (cos_i > 0)
        ok = in_range & in_fov
        dropped = {"range": int(np.sum(~in_range)), "fov": int(np.sum(in_range & ~in_fov))}
        if occluders is not None and self.settings.shadowing and ok.any():
            sel = np.nonzero(ok)[0]
            free = occluders.unoccluded(np.broadcast_to(x0, (sel.size, 3)), u[sel],
                                        r[sel] - SHADOW_EPSILON)
            ok[sel[~free]] = False
            dropped["shadow"] = int(np.sum(~free))
        pos, r, cos_i = self.positions[ok], r[ok], cos_i[ok]
        theta = np.arccos(np.clip(cos_i, 0.0, 1.0 - 1e-12))
        s0 = np.empty(r.size)
        mats = self.material[ok]
        for m in np.unique(mats):
            sel = mats == m
            s0[sel] = sigma0(theta[sel], str(m), self.settings.polarisation,
                             wavelength=config.wavelength)
        amp = self.z[ok] * np.sqrt(radar_scale(config) * s0 * self.area[ok] / r**4)
        n = amp.size
        pol = np.zeros((n, 2, 2), complex)
        pol[:, 0, 0] = amp
        length = 2.0 * r
        return PathSet(pos, pos.copy(), length, amp, np.zeros((n, 3)), np.zeros(n),
                       np.full((n, 1), DIFFUSE, np.uint32), np.full(n, DIFFUSE, np.uint32), pol,
                       length / SPEED_OF_LIGHT, x0.copy(), x0.copy(), float(time), dropped)


def _void(a: np.ndarray) -> np.ndarray:
    """Rows of a float64 ``[n, 3]`` array as opaque keys (exact equality, sortable)."""
    a = np.ascontiguousarray(a, dtype=np.float64) + 0.0                    # -0.0 -> 0.0
    return a.view(np.dtype((np.void, 24))).ravel()


def _height_above(ground: GroundSurface, x0: np.ndarray) -> float | None:
    _, z = ground.locate(x0[None])
    return None if not np.isfinite(z[0]) else float(z[0] - x0[2])
