"""Geometry targets as frozen paths: PO + SBR terms clustered into scattering centres.

A scene object marked as a geometry target (a :class:`~raysim.echoes.rt.scenes.SceneTarget`
with a ``mesh``) is traced here instead of by Sionna. From the radar position of
the trace, every lit sub-facet (single-bounce PO, :func:`~raysim.echoes.po.rcs.facet_terms_near`)
and every ray tube that returns after 2..``max_bounces`` hits
(:func:`~raysim.echoes.po.sbr.sbr_contributions`) gives a complex term with its
own two-way length ``L_i`` and an *equivalent point* ``p_i``: the point on the
return ray at ``L_i / 2`` from the radar (a sub-facet's centroid; for a
trihedral's triple bounce, a point at the depth of the apex).

Granularity: one path per scattering centre. Terms are grouped in cells of
``cell_range`` along the line of sight and ``cell_cross`` across it, anchored
at the target's reference point (its phase centre: a trihedral's apex), so a
target smaller than a cell is one path. The defaults are the range resolution
``c / 2B`` and ``R * CLUSTER_ANGLE``: finer than the radar resolves (the
resolution cell of an 8-element array at 15 m is 3.7 m across), so the map of
the clustered paths equals the map of the terms at the trace pose. A centre
sits at the mean equivalent point of its strongest bounce order and carries the
coherent sum of all its terms, phase-referred to its own length ``2 |p_c - x_radar|``.

Error under platform motion: re-projection moves the centre as one point
scatterer, while the terms would each move with their own legs. For a radar
displacement ``delta`` the term phases change by ``-k delta . (d_first + d_last)``
and the centre's by ``-2 k delta . d_c``; :func:`reprojection_error` measures the
resulting complex error of a centre. For a trihedral the exact retro-reflected
length is ``2 |apex - x_radar|`` for any radar position, so its centre is exact
(to the edge terms); on extended targets the error grows with the centre's size
``s`` as ``~ 2 k |delta| s / R``.

Ground: each target with ``min_bounces == 1`` is traced with a flat apron of
its local ground (:func:`ground_apron`), which radiates nothing itself; target
hits also return by the ground (the image method, Fresnel and Ament factors).
The ground-target-ground ghost of a retro-reflector clusters at the target's
image below the ground, which re-projects exactly as a point: ``|x - p'| =
|x' - p|`` for any radar position ``x`` (mirror isometry); the one-bounce ghosts
sit between target and image, exact only to first order.

Amplitudes follow the radar equation like the tracer's point targets:
``A = sqrt(P_t) lambda F / (4 pi R^2)`` [sqrt(W)] (0 dBi: the element pattern
is applied at re-projection) with ``F`` the near-field
scattering amplitude normalised at the reference range ``R``
(``sigma = 4 pi |F|^2``, :mod:`raysim.echoes.po.rcs`).
"""

from __future__ import annotations

import math
import time as _time
import weakref
from dataclasses import dataclass

import numpy as np

from raysim.echoes.ground.sigma0 import CLUTTER_MATERIALS, ament_factor
from raysim.echoes.po.edges import edge_terms_near, sharp_edges
from raysim.echoes.po.mesh import TriangleMesh, po_material
from raysim.echoes.po.rays import RayScene
from raysim.echoes.po.rcs import EDGE_SEGMENT_WAVELENGTHS, MAX_BOUNCES, facet_terms_near
from raysim.echoes.po.sbr import TubeTerms, sbr_contributions
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

__all__ = ["PO_CENTRE", "CLUSTER_ANGLE", "TUBES_PER_WAVELENGTH", "PATHS_FRESNEL_FRACTION",
           "ScatteringTerms", "scattering_terms", "cluster_terms", "reprojection_error",
           "geometry_paths", "tube_spacing", "ground_apron", "ground_coherence",
           "APRON_MAX_HALF_SIDE", "APRON_FIT_RADIUS"]

#: Interaction bit of a PO scattering centre in ``PathSet.interactions`` (above
#: Sionna's five bits); re-projected like a point scatterer (frozen vertex).
PO_CENTRE = 32
#: Cross-range cell of a scattering centre [rad] (see the module docstring).
CLUSTER_ANGLE = math.radians(2.0)
#: Default ray-tube density: tubes per wavelength along each transverse axis.
#: A trihedral's triple bounce is within 0.2 dB of its closed form from 2 tubes
#: per wavelength (``raysim.bench.tube_density``), at a twenty-fifth of the
#: tubes of the ``raysim rcs`` default (10).
TUBES_PER_WAVELENGTH = 2.0
#: Sub-facet edge of the single-bounce PO at most this share of the Fresnel length
#: ``sqrt(lambda R)``: the two-way quadratic phase left out over a sub-facet,
#: ``k s^2 / (4 R)``, is then at most ``pi / 32`` rad (0.1 rad). Coarser than the
#: ``raysim rcs`` default (0.1, 0.016 rad) to keep scene traces short: the car meshes'
#: 5 cm facets need no subdivision beyond 16 m.
PATHS_FRESNEL_FRACTION = 0.25
#: Largest number of tubes per target: the spacing widens to stay below it
#: (a car, 5.2 m across, gets 1 cm tubes, 2.6 wavelengths; the tube integral
#: is exact for the linear phase over a flat footprint, and a trihedral at
#: 0.5 tubes per wavelength is still within 0.4 dB of its closed form).
MAX_TUBES = 250_000
#: Largest half-side of a target's ground apron [m] (:func:`ground_apron`).
APRON_MAX_HALF_SIDE = 8.0
#: Radius of the ground patch under a target whose mean plane is its apron [m]
#: (the clutter's rough mirror fits its plane over the same 2 m).
APRON_FIT_RADIUS = 2.0


@dataclass(frozen=True)
class ScatteringTerms:
    """PO and SBR terms of one target from one radar position (world frame W).

    Attributes
    ----------
    amplitude : ndarray of complex, shape ``[term]``
        Share of the scattering amplitude ``F`` [m], normalised to ``range_m``,
        phase referred to the length ``2 range_m``.
    point : ndarray, shape ``[term, 3]``
        Equivalent point in W [m] (``|point - radar| = length / 2``).
    first, last : ndarray, shape ``[term, 3]``
        First and last hit in W [m].
    length : ndarray, shape ``[term]``
        Two-way length [m].
    bounces : ndarray of int, shape ``[term]``
        1 for facet PO, else the hit number of the tube term.
    radar : ndarray, shape ``[3]``
        Radar position in W [m].
    reference : ndarray, shape ``[3]``
        Target reference point in W [m].
    range_m : float
        ``|radar - reference|`` [m].
    wavelength : float
        [m].
    tubes : int
        SBR tubes launched.
    spacing : float
        Tube side at the reference point [m].
    seconds : float
        Wall time of the terms [s].
    """

    amplitude: np.ndarray
    point: np.ndarray
    first: np.ndarray
    last: np.ndarray
    length: np.ndarray
    bounces: np.ndarray
    radar: np.ndarray
    reference: np.ndarray
    range_m: float
    wavelength: float
    tubes: int
    spacing: float
    seconds: float

    @property
    def rcs_m2(self) -> float:
        """Apparent RCS of the whole target ``4 pi |sum F|^2`` [m^2]."""
        return float(4 * math.pi * abs(np.sum(self.amplitude)) ** 2)


def tube_spacing(wavelength: float, tubes_per_wavelength: float = TUBES_PER_WAVELENGTH) -> float:
    """Tube side [m]: ``wavelength / tubes_per_wavelength``."""
    if not (math.isfinite(tubes_per_wavelength) and tubes_per_wavelength > 0):
        raise ValueError(f"tubes_per_wavelength must be > 0, got {tubes_per_wavelength!r}")
    return wavelength / tubes_per_wavelength


def _basis(u: np.ndarray, polarisation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(e_h, e_v)`` transverse to ``u`` with ``e_v`` along ``polarisation``'s transverse part."""
    e_v = polarisation - (polarisation @ u) * u
    if np.linalg.norm(e_v) < 1e-6:       # polarisation along the line of sight: any transverse
        e_v = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
    e_v = e_v / np.linalg.norm(e_v)
    return np.cross(e_v, u), e_v


def _parts(mesh_w, material) -> tuple[list, list]:
    if isinstance(mesh_w, TriangleMesh):
        mesh_w, material = [mesh_w], [material]
    meshes, names = list(mesh_w), [material] * len(mesh_w) if isinstance(material, str) \
        else list(material)
    if not meshes or len(meshes) != len(names):
        raise ValueError(f"give one material per mesh part: {len(meshes)} meshes, "
                         f"{len(names)} materials")
    return meshes, names


def scattering_terms(mesh_w, material, radar_w, reference_w, *,
                     frequency: float, polarisation_w=(1.0, 0.0, 0.0),
                     tubes_per_wavelength: float = TUBES_PER_WAVELENGTH,
                     max_bounces: int = MAX_BOUNCES, min_bounces: int = 1,
                     fresnel_fraction: float = PATHS_FRESNEL_FRACTION,
                     ground=None, diffraction: bool = False) -> ScatteringTerms:
    """PO + SBR terms of a mesh seen from a point radar (near field, exact spreading).

    Parameters
    ----------
    mesh_w : TriangleMesh or sequence of TriangleMesh
        Target in W [m], whole or as parts (traced together: they shadow each
        other and bounce between each other).
    material : str or sequence of str
        Scene material name (:func:`~raysim.echoes.po.mesh.po_material`), one per part.
    radar_w, reference_w : array_like, shape ``[3]``
        Radar phase centre and target reference point in W [m].
    frequency : float
        Carrier [Hz].
    polarisation_w : array_like, shape ``[3]``
        Radar polarisation direction in W (its ``X_A`` axis).
    tubes_per_wavelength : float
        SBR tube density per transverse axis; the tube side is widened so that
        a target launches at most :data:`MAX_TUBES`.
    max_bounces : int
        Deepest hit (1 = facet PO only).
    min_bounces : int
        Smallest hit kept (2 = multiple bounces only).
    fresnel_fraction : float
        Sub-facet edge as a share of ``sqrt(lambda R)`` (see :data:`PATHS_FRESNEL_FRACTION`).
    ground : tuple (TriangleMesh, str), optional
        Ground apron in W and its scene material: traced with the target so
        that target-ground, ground-target and ground-target-ground bounces
        appear, while its own bounces (single PO, tubes that hit only the
        ground) are left out; its reflections carry the material's Ament
        factor (:func:`ground_coherence`).
    diffraction : bool
        Add the PTD fringe wave of the sharp edges of the conducting parts
        (:mod:`~raysim.echoes.po.edges`) as single-bounce terms, one per edge
        segment (at most a wavelength and a facet's Fresnel size long, at its
        midpoint); parts of other materials have none.

    Returns
    -------
    ScatteringTerms
    """
    if int(min_bounces) != min_bounces or not 1 <= min_bounces <= max_bounces:
        raise ValueError(f"min_bounces must be an integer in 1..max_bounces={max_bounces}, "
                         f"got {min_bounces!r}")
    start = _time.perf_counter()
    meshes, names = _parts(mesh_w, material)
    n_target = len(meshes)
    if ground is not None:
        meshes, names = meshes + [ground[0]], names + [ground[1]]
    radar = np.asarray(radar_w, dtype=float)
    ref = np.asarray(reference_w, dtype=float)
    wavelength = SPEED_OF_LIGHT / frequency
    k = 2 * math.pi / wavelength
    locals_ = [TriangleMesh(m.vertices - ref, m.faces) for m in meshes]
    offsets = np.cumsum([0] + [len(m.vertices) for m in locals_])
    local = TriangleMesh(np.concatenate([m.vertices for m in locals_]),
                         np.concatenate([m.faces + o for m, o in zip(locals_, offsets,
                                                                     strict=False)]))
    which = np.concatenate([np.full(len(m.faces), i) for i, m in enumerate(locals_)])
    rel = radar - ref
    range_m = float(np.linalg.norm(rel))
    body = TriangleMesh(np.concatenate([m.vertices for m in locals_[:n_target]]),
                        np.concatenate([m.faces + o for m, o in zip(
                            locals_[:n_target], offsets, strict=False)]))
    cover = None
    if ground is not None:       # tubes over the target and its image in the apron plane
        g = locals_[n_target]
        n_g = np.cross(g.vertices[1] - g.vertices[0], g.vertices[2] - g.vertices[0])
        n_g /= np.linalg.norm(n_g)
        image = body.vertices - 2 * ((body.vertices - g.vertices[0]) @ n_g)[:, None] * n_g
        cover = np.concatenate([body.vertices, image])
    if not range_m > body.radius:
        raise ValueError(f"radar at {radar.tolist()} lies inside the target's bounding sphere "
                         f"(radius {body.radius:.3g} m about {ref.tolist()})")
    u = rel / range_m
    e_h, e_v = _basis(u, np.asarray(polarisation_w, dtype=float))
    spacing = tube_spacing(wavelength, tubes_per_wavelength)
    # the target sets the spacing (an apron leaves its direct return unchanged); the
    # grid over its ground image adds up to about as many tubes again
    spacing = max(spacing, 2 * body.radius / math.sqrt(MAX_TUBES))
    mats = [po_material(n, frequency) for n in names]
    scene = RayScene(local)
    if not (math.isfinite(fresnel_fraction) and 0 < fresnel_fraction <= 1):
        raise ValueError(f"fresnel_fraction must lie in (0, 1], got {fresnel_fraction!r}")
    fresnel_edge = fresnel_fraction * math.sqrt(wavelength * range_m)
    f_amp, cent = [], []
    for part, mat in zip(locals_[:n_target], mats if min_bounces == 1 else [], strict=False):
        a, c = facet_terms_near(scene, part.subdivided(fresnel_edge), mat, u, e_v, k, range_m,
                                spacing)
        f_amp.append(a)
        cent.append(c)
        if diffraction and mat.is_pec:
            segments = sharp_edges(part).split(min(EDGE_SEGMENT_WAVELENGTHS * wavelength,
                                                   fresnel_edge))
            a, c = edge_terms_near(segments, u, e_v, k, range_m, scene)
            f_amp.append(a)
            cent.append(c)
    f_amp = np.concatenate(f_amp) if f_amp else np.zeros(0, complex)
    cent = np.concatenate(cent) if cent else np.zeros((0, 3))
    tubes = sbr_contributions(scene, mats if len(mats) > 1 else mats[0], u, e_v, e_h, e_v,
                              wavelength, spacing=spacing,
                              max_bounces=int(max_bounces),
                              range_m=range_m, facet_material=which if len(mats) > 1 else None,
                              ground=None if ground is None else which == n_target,
                              coherence=None if ground is None else ground_coherence(
                                  ground[1], wavelength), cover=cover)
    if min_bounces > 2:
        keep = tubes.bounces >= min_bounces
        tubes = TubeTerms(*(getattr(tubes, f)[keep] for f in (
            "amplitude", "first", "last", "length", "back", "bounces")), tubes.tubes)
    radar_l = range_m * u
    f_len = 2 * np.linalg.norm(radar_l - cent, axis=1)
    t_point = radar_l - tubes.back * (tubes.length / 2)[:, None]
    return ScatteringTerms(
        amplitude=np.concatenate([f_amp, tubes.amplitude]),
        point=np.concatenate([cent, t_point]) + ref,
        first=np.concatenate([cent, tubes.first]) + ref,
        last=np.concatenate([cent, tubes.last]) + ref,
        length=np.concatenate([f_len, tubes.length]),
        bounces=np.concatenate([np.ones(len(f_amp), np.int64), tubes.bounces]),
        radar=radar, reference=ref, range_m=range_m, wavelength=wavelength,
        tubes=tubes.tubes, spacing=spacing, seconds=_time.perf_counter() - start)


def ground_coherence(material: str, wavelength: float):
    """Coherent share of a ground reflection, ``cos_i [ray] -> factor [ray]``.

    The Ament factor ``exp(-2 (k s cos theta_i)^2)`` of the material's RMS
    height ``s`` (:func:`raysim.echoes.ground.sigma0.ament_factor`) for a
    material with a clutter model; 1 for any other (a smooth surface).
    """
    if material not in CLUTTER_MATERIALS:
        return None
    return lambda cos_i: ament_factor(material, np.arccos(np.clip(cos_i, 0.0, 1.0)),
                                      wavelength)


def ground_apron(ground_surface, position, radar, radius: float, wavelength: float):
    """Local ground under a target as a flat square apron in W, or ``None``.

    The mean plane of the ground within :data:`APRON_FIT_RADIUS` of the point under
    ``position`` (:meth:`GroundSurface.mean_plane`), a square about that point
    of half-side ``radius + h / tan(elevation) + 2 sqrt(lambda R)``: the
    target's bounding radius, the length of the shadow of its top ``h = 2 *
    radius`` above ground cast by the radar, and two Fresnel lengths, so the
    specular bounce points of every target-ground leg lie on it. Capped at
    :data:`APRON_MAX_HALF_SIDE`.

    Returns
    -------
    (TriangleMesh, str) or None
        The two-triangle apron in W and its clutter material id; ``None`` when
        the target is off the ground surface or the radar below the plane.
    """
    p = np.asarray(position, dtype=float)
    facet, zg = ground_surface.locate(p[None])
    if facet[0] < 0 or not np.isfinite(zg[0]):
        return None
    plane = ground_surface.mean_plane(np.array([p[0], p[1], zg[0]]), APRON_FIT_RADIUS)
    if plane is None:
        return None
    o, n = plane
    foot = p - ((p - o) @ n) * n                    # the target's foot on the plane
    rel = np.asarray(radar, dtype=float) - foot
    height = float(rel @ n)
    if height <= 0:
        return None
    horizontal = float(np.linalg.norm(rel - height * n))
    range_m = float(np.linalg.norm(rel))
    half = min(APRON_MAX_HALF_SIDE, radius + 2 * radius * horizontal / height
               + 2 * math.sqrt(wavelength * range_m))
    e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    corners = foot + half * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) @ np.stack([e1, e2])
    mesh = TriangleMesh(corners, np.array([[0, 1, 2], [0, 2, 3]]))
    return mesh, str(ground_surface.material[facet[0]])


def cluster_terms(terms: ScatteringTerms, cell_range: float,
                  cell_cross: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Group the terms into scattering centres.

    Parameters
    ----------
    terms : ScatteringTerms
    cell_range : float
        Cell along the line of sight [m] (e.g. the range resolution).
    cell_cross : float, optional
        Cell across it [m]; default ``range_m * CLUSTER_ANGLE``.

    Returns
    -------
    centre : ndarray, shape ``[centre, 3]``
        Mean equivalent point of the centre's strongest bounce order in W [m].
    amplitude : ndarray of complex, shape ``[centre]``
        Coherent sum of the terms, phase-referred to ``2 |centre - radar|``
        (still normalised to ``range_m``).
    label : ndarray of int, shape ``[term]``
        Centre of each term.
    """
    if not (math.isfinite(cell_range) and cell_range > 0):
        raise ValueError(f"cell_range must be > 0 m, got {cell_range!r}")
    cross = terms.range_m * CLUSTER_ANGLE if cell_cross is None else cell_cross
    if not (math.isfinite(cross) and cross > 0):
        raise ValueError(f"cell_cross must be > 0 m, got {cell_cross!r}")
    n = len(terms.amplitude)
    if n == 0:
        return np.zeros((0, 3)), np.zeros(0, complex), np.zeros(0, np.int64)
    u = (terms.radar - terms.reference) / terms.range_m
    e_h, e_v = _basis(u, np.array([1.0, 0.0, 0.0]))
    rel = terms.point - terms.reference
    key = np.stack([np.round(rel @ u / cell_range), np.round(rel @ e_h / cross),
                    np.round(rel @ e_v / cross)], axis=1).astype(np.int64)
    _, label = np.unique(key, axis=0, return_inverse=True)
    label = label.reshape(-1)
    m = int(label.max()) + 1
    # Terms of one bounce order inside a cell interfere (a tilted face's sub-facets
    # nearly cancel), so a centre sits at the |term|-weighted mean point of its
    # strongest bounce order (largest |coherent sum|): a trihedral's centre is then
    # its apex, where every triple-bounce term has its equivalent point.
    _, sub = np.unique(np.stack([label, terms.bounces], 1), axis=0, return_inverse=True)
    sub = sub.reshape(-1)
    ms = int(sub.max()) + 1
    mag = np.abs(terms.amplitude) + 1e-300
    sub_point = (np.stack([np.bincount(sub, mag * terms.point[:, i], ms) for i in range(3)], 1)
                 / np.bincount(sub, mag, ms)[:, None])
    sub_power = np.abs(np.bincount(sub, terms.amplitude.real, ms)
                       + 1j * np.bincount(sub, terms.amplitude.imag, ms)) ** 2
    sub_label = np.zeros(ms, np.int64)
    sub_label[sub] = label
    best = np.full(m, -1)
    for j in np.argsort(sub_power):              # ascending: the strongest group wins
        best[sub_label[j]] = j
    centre = sub_point[best]
    k = 2 * math.pi / terms.wavelength
    l_c = 2 * np.linalg.norm(centre - terms.radar, axis=1)
    total = (np.bincount(label, terms.amplitude.real, m)
             + 1j * np.bincount(label, terms.amplitude.imag, m))
    return centre, total * np.exp(1j * k * (l_c - 2 * terms.range_m)), label


def reprojection_error(terms: ScatteringTerms, centre: np.ndarray, amplitude: np.ndarray,
                       label: np.ndarray, displacement) -> np.ndarray:
    """Complex error of each centre after the radar moves by ``displacement`` [m].

    Terms are re-projected by the frozen-vertex rule of
    :mod:`raysim.echoes.rt.reproject` (first and last legs re-measured), the
    centre as one point (phases referred to ``2 range_m``, as ``cluster_terms``
    returns them). Returns ``|A_c' - sum_i A_i'| / |sum_i A_i'|``, shape
    ``[centre]`` (both at the new position, spreading unchanged).
    """
    delta = np.asarray(displacement, dtype=float)
    if delta.shape != (3,) or not np.all(np.isfinite(delta)):
        raise ValueError(f"displacement must be 3 finite numbers [m], got {displacement!r}")
    k = 2 * math.pi / terms.wavelength
    moved = terms.radar + delta
    legs0 = (np.linalg.norm(terms.first - terms.radar, axis=1)
             + np.linalg.norm(terms.last - terms.radar, axis=1))
    legs1 = (np.linalg.norm(terms.first - moved, axis=1)
             + np.linalg.norm(terms.last - moved, axis=1))
    phasor = terms.amplitude * np.exp(-1j * k * (legs1 - legs0))
    m = len(centre)
    exact = np.bincount(label, phasor.real, m) + 1j * np.bincount(label, phasor.imag, m)
    l1 = 2 * np.linalg.norm(centre - moved, axis=1)
    approx = amplitude * np.exp(-1j * k * (l1 - 2 * terms.range_m))
    return np.abs(approx - exact) / np.maximum(np.abs(exact), 1e-300)


def _rows(centre, amp, range_m: float, target, config: RadarConfig, link_budget: bool) -> list:
    """``(centre, amplitude [sqrt(W) or unitless], velocity)`` of one target's centres."""
    scale = config.wavelength / (4 * math.pi * range_m**2)
    if link_budget:   # 0 dBi: the element pattern is applied at re-projection
        scale *= math.sqrt(10 ** (config.tx_power_dbm / 10) * 1e-3)
    return [(c, scale * a, target.velocity) for c, a in zip(centre, amp, strict=True)]


#: Ground surface of each scene in use (read from its meshes once, not per trace).
_GROUNDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _ground_of(scene):
    """The scene's :class:`~raysim.echoes.ground.surface.GroundSurface`, cached per scene."""
    from raysim.echoes.ground.surface import GroundSurface

    if scene not in _GROUNDS:
        _GROUNDS[scene] = GroundSurface.from_scene(scene)
    return _GROUNDS[scene]


def geometry_paths(scene, targets, config: RadarConfig, radar_w, r_wb, time: float, *,
                   fov_half_angle: float, min_range: float, max_range: float | None,
                   link_budget: bool = True,
                   tubes_per_wavelength: float = TUBES_PER_WAVELENGTH,
                   max_bounces: int = MAX_BOUNCES, ground: bool = True, fidelity=None):
    """Scattering centres of the scene's geometry targets as a :class:`PathSet`.

    Parameters
    ----------
    scene : RadarScene
        Gives the S -> W placement of the target meshes.
    targets : list of SceneTarget
        Targets with a ``mesh`` (PLY in frame S) and a ``material``.
    config : RadarConfig
        Carrier, power, range resolution and window (0 dBi elements: the
        re-projection applies the element pattern).
    radar_w : ndarray, shape ``[3]``
        Radar phase centre in W [m].
    r_wb : ndarray, shape ``[3, 3]``
        Platform attitude (B -> W); ``X_A`` is the polarisation, ``Z_A`` the boresight.
    time : float
        Trace instant [s].
    fov_half_angle, min_range, max_range
        The tracer's culls (half-angle [rad]; one-way ranges [m], ``None`` =
        ``config.max_range``).
    ground : bool
        Trace each target (``min_bounces == 1``) with its local ground apron
        (:func:`ground_apron`): target-ground multipath. Targets that keep only
        multiple bounces carry their own apron in their mesh.
    fidelity : raysim.echoes.po.fidelity.FidelityLadder, optional
        Per-target echo model (:mod:`raysim.echoes.po.fidelity`): a target whose
        reduced model is re-usable from this radar position is not traced again;
        a traced one gets the level the ladder picks. None: every target's mesh
        centres (the ladder's ``"mesh"`` level).

    Returns
    -------
    dict
        The fields of :class:`raysim.echoes.rt.trace.PathSet` (this module does
        not import the tracer): one path per centre, ``interactions =
        [[PO_CENTRE]]``, ``dropped`` with ``"range"`` and ``"fov"`` counts; plus
        ``"stats"`` (targets, tubes, terms, seconds) that is not a PathSet field.
    """
    radar = np.asarray(radar_w, dtype=float)
    rows = []
    stats = {"targets": len(targets), "tubes": 0, "terms": 0, "seconds": 0.0, "aprons": 0}
    surface = None
    if ground and any(t.min_bounces == 1 for t in targets):
        surface = _ground_of(scene)
    for t in targets:
        hit = None if fidelity is None else fidelity.lookup(t.name, radar)
        if hit is not None:     # reduced model of this object and aspect: no trace
            rows += _rows(hit[0], hit[1], float(np.linalg.norm(radar - t.position)), t, config,
                          link_budget)
            continue
        files = [t.mesh] if isinstance(t.mesh, str) else list(t.mesh)
        parts = [TriangleMesh.load(f) for f in files]
        mesh_w = [TriangleMesh(scene.to_world(m.vertices), m.faces) for m in parts]
        apron = None
        if surface is not None and t.min_bounces == 1:
            radius = max(float(np.max(np.linalg.norm(m.vertices - t.position, axis=1)))
                         for m in mesh_w)
            apron = ground_apron(surface, t.position, radar, radius, config.wavelength)
            stats["aprons"] += apron is not None
        terms = scattering_terms(mesh_w, t.material, radar, t.position,
                                 frequency=config.carrier_frequency, polarisation_w=r_wb[:, 0],
                                 tubes_per_wavelength=tubes_per_wavelength,
                                 max_bounces=max_bounces, min_bounces=t.min_bounces,
                                 ground=apron, diffraction=t.diffraction)
        centre, amp, _ = cluster_terms(terms, config.range_resolution)
        stats["tubes"] += terms.tubes
        stats["terms"] += len(terms.amplitude)
        stats["seconds"] += terms.seconds
        if fidelity is not None:
            centre, amp = fidelity.choose(t.name, centre, amp, radar, r_wb, config,
                                          range_m=terms.range_m, trace_seconds=terms.seconds)
        rows += _rows(centre, amp, terms.range_m, t, config, link_budget)
    n = len(rows)
    centre = np.array([r[0] for r in rows]).reshape(n, 3)
    amp = np.array([r[1] for r in rows], dtype=complex)
    vel = np.array([r[2] for r in rows], dtype=float).reshape(n, 3)
    rel = centre - radar
    dist = np.linalg.norm(rel, axis=1)
    length = 2 * dist
    unit = rel / np.maximum(dist, 1e-300)[:, None]
    doppler = 2 * np.einsum("pi,pi->p", vel, unit) / config.wavelength
    r_max = config.max_range if max_range is None else max_range
    in_range = (dist >= min_range) & (dist < r_max)
    in_fov = unit @ r_wb[:, 2] >= math.cos(fov_half_angle)
    ok = in_range & in_fov
    pol = np.zeros((n, 2, 2), complex)
    pol[:, 0, 0] = amp
    inter = np.full((n, 1), PO_CENTRE, np.uint32)
    dropped = {"range": int(np.sum(~in_range)), "fov": int(np.sum(in_range & ~in_fov))}
    return {"first_vertex": centre[ok], "last_vertex": centre[ok].copy(), "length": length[ok],
            "amplitude": amp[ok], "velocity": vel[ok], "doppler": doppler[ok],
            "interactions": inter[ok], "kind": inter[ok, 0].copy(), "polarimetric": pol[ok],
            "solver_delay": length[ok] / SPEED_OF_LIGHT, "tx_position": radar.copy(),
            "rx_position": radar.copy(), "trace_time": float(time), "dropped": dropped,
            "stats": stats}
