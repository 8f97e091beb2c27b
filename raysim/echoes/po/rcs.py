"""Monostatic RCS of a triangle mesh: facet PO (single bounce) + SBR (multiple bounces).

Geometry (the frame of ``raysim rcs``): the radar sits at ``R u(az, el)``,
``u = (cos el sin az, sin el, cos el cos az)``, looking at the origin. The
polarisation vectors are ``e_v = du/d(el)`` (VV) and
``e_h = (cos az, 0, -sin az)`` (HH); transmit and receive share one.

Single bounce: the PO integral over the illuminated, unshadowed part of every
facet (Mitsuba shadow rays from each facet's centroid and corners; facets in
partial shadow are split down to the SBR tube side), each integrated in closed form
(:func:`~raysim.echoes.po.integral.polygon_phase_integral`). In the far field
the incident wave is plane. At a finite range the facets are first
subdivided until no edge exceeds ``FRESNEL_FRACTION * sqrt(lambda R)``, and each
sub-facet is integrated with its own direction to the radar, its exact
path length ``R_i`` and spreading ``(R / R_i)^2`` (the apparent RCS at range
``R`` is ``4 pi R^2 |E_s|^2 / |E_i(origin)|^2``).

Multiple bounces: :func:`~raysim.echoes.po.sbr.sbr_amplitude` with tubes of
side ``lambda / rays_per_wavelength``.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np

# u(az, el) = (cos el sin az, sin el, cos el cos az): one definition of the direction
from compensation.geometry import direction as radar_direction
from raysim.echoes.po.edges import (
    edge_amplitude,
    edge_terms_near,
    facing_edge_pairs,
    pair_amplitude,
    sharp_edges,
)
from raysim.echoes.po.integral import po_vector, polygon_phase_integral
from raysim.echoes.po.mesh import PoMaterial, TriangleMesh
from raysim.echoes.po.rays import RayScene
from raysim.echoes.po.sbr import sbr_amplitude
from raysim.radar.config import SPEED_OF_LIGHT

__all__ = ["RcsResult", "monostatic_rcs", "facet_terms_near", "radar_direction",
           "polarisation_basis", "DEFAULT_FREQUENCY", "RAYS_PER_WAVELENGTH", "FRESNEL_FRACTION",
           "MAX_BOUNCES", "MAX_RCS_FACETS", "MAX_RCS_WORK", "rcs_job_size",
           "EDGE_SEGMENT_WAVELENGTHS"]

#: Default carrier [Hz].
DEFAULT_FREQUENCY = 77e9
#: Default SBR tube density: tubes per wavelength along each transverse axis
#: (tube side lambda / 10: the linear phase over a tube is integrated exactly,
#: and ten tubes per wavelength resolve facet edges to lambda / 10).
RAYS_PER_WAVELENGTH = 10.0
#: Near field: sub-facet edge ``s`` at most this share of the Fresnel length
#: ``sqrt(lambda R)``; the two-way quadratic phase left out over a sub-facet,
#: ``k s^2 / (4 R)``, is then at most ``pi / 200`` rad (0.016 rad).
FRESNEL_FRACTION = 0.1
#: Default deepest bounce traced.
MAX_BOUNCES = 3
#: Most facets (after the near-field subdivision) of one RCS job.
MAX_RCS_FACETS = 2_000_000
#: Most facet and ray-tube evaluations of one RCS job (directions x (facets + tubes));
#: 10 x 10 directions of a 0.1 m plate at the default density are about 1.3e7 (10 s).
MAX_RCS_WORK = 2e9
#: Cost of one direction itself, in facet evaluations (its basis, shadow test set-up and
#: output row): 100 x 100 directions of a 2-facet plate took 4.7 s more than 10 x 10
#: (0.47 ms a direction, 2 cores, wall clock), about 600 evaluations at 1.3e6 per second.
DIRECTION_EVALUATIONS = 500
#: Diffraction: edge segments at most this many wavelengths long (each segment's midpoint
#: decides its shadow; the phase along a segment is integrated exactly).
EDGE_SEGMENT_WAVELENGTHS = 1.0
#: Memory per facet while a mesh is traced (vertices, normals, scene, terms) [bytes].
FACET_BYTES = 400


def rcs_job_size(mesh: TriangleMesh, directions: int, spacing: float, max_bounces: int,
                 near_edge: float | None = None, edge_segments: int = 0) -> dict:
    """Size of an RCS job before anything is traced, refused when too large.

    Parameters
    ----------
    mesh : TriangleMesh
        The target [m].
    directions : int
        Azimuths x elevations.
    spacing : float
        SBR tube side [m].
    max_bounces : int
        Deepest bounce (1: no ray tubes).
    near_edge : float, optional
        Near field: largest sub-facet edge [m] (facets are split to it).
    edge_segments : int
        Diffraction: edge segments evaluated per direction.

    Returns
    -------
    dict
        ``facets`` (traced), ``tubes`` (per direction, at most), ``work``.

    Raises
    ------
    ValueError
        More than :data:`MAX_RCS_FACETS` facets, more than :data:`MAX_RCS_WORK`
        evaluations, or more memory than is available; the message gives the
        size and the settings to change.
    """
    from raysim.resources import check_memory

    facets = len(mesh.faces)
    if near_edge is not None and facets:
        t = mesh.triangles
        edge = np.max(np.linalg.norm(t - np.roll(t, 1, axis=1), axis=2), axis=1)
        facets = int(np.sum(np.ceil(edge / near_edge) ** 2))
    if facets > MAX_RCS_FACETS:
        raise ValueError(f"MESH: {facets} facets to trace"
                         + (f" ({len(mesh.faces)} in the file, split for the near field)"
                            if facets != len(mesh.faces) else "")
                         + f", expected at most {MAX_RCS_FACETS}: decimate the mesh"
                         + (", or use the far field (no --range-m)" if near_edge else ""))
    check_memory(facets * FACET_BYTES, f"a mesh of {facets} facets", "the mesh (decimate it)")
    side = 2.0 * mesh.radius / spacing + 2.0
    tubes = int(side * side) if max_bounces > 1 else 0
    work = float(directions) * (facets + tubes + edge_segments + DIRECTION_EVALUATIONS)
    if work > MAX_RCS_WORK:
        edge_text = f" + {edge_segments} edge segments" if edge_segments else ""
        raise ValueError(f"rcs: {directions} directions x ({facets} facets + about {tubes} SBR "
                         f"ray tubes{edge_text} + {DIRECTION_EVALUATIONS} for the direction "
                         f"itself) = {work:.3g} evaluations, expected at most "
                         f"{MAX_RCS_WORK:.3g}: reduce --az-deg / --el-deg (fewer directions)"
                         + (", --rays-per-wavelength, the mesh, or give --max-bounces 1"
                            if tubes else ", or the mesh"))
    return {"facets": facets, "tubes": tubes, "work": work}


def polarisation_basis(az: float, el: float) -> tuple[np.ndarray, np.ndarray]:
    """Polarisation vectors ``(e_h, e_v)``, shape ``[3]`` each.

    Horizontal ``(cos az, 0, -sin az)``, vertical ``du/d(el)``.
    """
    e_h = np.array([math.cos(az), 0.0, -math.sin(az)])
    e_v = np.array([-math.sin(el) * math.sin(az), math.cos(el), -math.sin(el) * math.cos(az)])
    return e_h, e_v


@dataclass(frozen=True)
class RcsResult:
    """Monostatic RCS on an azimuth x elevation grid.

    Attributes
    ----------
    frequency : float
        Carrier [Hz].
    range_m : float or None
        Radar range [m]; ``None`` for the far field.
    azimuth_deg, elevation_deg : ndarray, shapes ``[azimuth]``, ``[elevation]``
        Aspect axes [deg].
    rcs_m2 : ndarray, shape ``[azimuth, elevation]``
        RCS [m^2].
    polarisation : str
        ``"VV"`` or ``"HH"``.
    info : dict
        Solver settings (tube spacing, rays traced, bounces, facets).
    """

    frequency: float
    range_m: float | None
    azimuth_deg: np.ndarray
    elevation_deg: np.ndarray
    rcs_m2: np.ndarray
    polarisation: str = "VV"
    info: dict = field(default_factory=dict)

    @property
    def rcs_dbsm(self) -> np.ndarray:
        """RCS [dBsm], shape ``[azimuth, elevation]`` (floored at -300 dBsm)."""
        return 10 * np.log10(np.maximum(self.rcs_m2, 1e-30))

    def to_json(self) -> dict:
        """The JSON of ``raysim rcs --json``."""
        return {"frequency_hz": self.frequency, "range_m": self.range_m,
                "azimuth_deg": [float(a) for a in self.azimuth_deg],
                "elevation_deg": [float(e) for e in self.elevation_deg],
                "rcs_dbsm": [[round(float(x), 4) for x in row] for row in self.rcs_dbsm]}


def _split4(tri: np.ndarray) -> np.ndarray:
    """Each triangle ``[m, 3, 3]`` into its four midpoint triangles ``[4 m, 3, 3]`` (same turn)."""
    v0, v1, v2 = tri[:, 0], tri[:, 1], tri[:, 2]
    m01, m12, m20 = (v0 + v1) / 2, (v1 + v2) / 2, (v2 + v0) / 2
    return np.concatenate([np.stack(t, axis=1) for t in
                           ((v0, m01, m20), (m01, v1, m12), (m20, m12, v2), (m01, m12, m20))])


def _lit(scene: RayScene, tri: np.ndarray, u: np.ndarray, range_m: float | None,
         min_edge: float) -> tuple[np.ndarray, np.ndarray]:
    """Lit parts of the facets ``tri`` [m, 3, 3] and their normals facing the radar.

    A facet's centroid and its corners (pulled 5 % towards the centroid) are
    tested for a clear line to the radar (direction ``u`` in the far field, the
    point ``range_m * u`` otherwise). All clear: lit; none: shadowed; mixed: the
    facet is split in four and tested again, down to edges of ``min_edge`` [m]
    where the centroid decides.
    """
    out_t, out_n = [], []
    while len(tri):
        cent = tri.mean(axis=1)
        cr = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        n = cr / np.linalg.norm(cr, axis=1, keepdims=True)
        pts = np.concatenate([cent[:, None], tri + 0.05 * (cent[:, None] - tri)], axis=1)
        if range_m is None:
            toward = np.broadcast_to(u, pts.shape)
            dist = np.full(pts.shape[:2], np.inf)
        else:
            rel = range_m * u - pts
            dist = np.linalg.norm(rel, axis=2)
            toward = rel / dist[..., None]
        facing = np.einsum("fi,fi->f", n, toward[:, 0])
        keep = np.abs(facing) > 1e-12
        tri, n, pts, toward, dist = tri[keep], n[keep], pts[keep], toward[keep], dist[keep]
        n = n * np.sign(np.einsum("fi,fi->f", n, toward[:, 0]))[:, None]
        start = pts + scene.epsilon * n[:, None]
        seen = scene.unoccluded(start.reshape(-1, 3), toward.reshape(-1, 3),
                                dist.reshape(-1)).reshape(-1, 4)
        big = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2).max(axis=1) > min_edge
        mixed = seen.any(axis=1) & ~seen.all(axis=1) & big
        done = ~mixed & seen[:, 0]
        out_t.append(tri[done])
        out_n.append(n[done])
        tri = _split4(tri[mixed])
    return np.concatenate(out_t), np.concatenate(out_n)


def _single_far(scene: RayScene, material: PoMaterial, u, e_pol, k, min_edge) -> complex:
    tri, n_eff = _lit(scene, scene.mesh.triangles, u, None, min_edge)
    if len(tri) == 0:
        return 0j
    d = np.broadcast_to(-u, n_eff.shape)
    e = np.broadcast_to(e_pol.astype(complex), n_eff.shape)
    co = po_vector(material, d, e, n_eff, u) @ e_pol
    integral = polygon_phase_integral(tri, 2 * k * u)
    return complex((-1j * k / (4 * np.pi)) * np.sum(co * integral))


def facet_terms_near(scene: RayScene, fine: TriangleMesh, material: PoMaterial, u, e_pol, k,
                     range_m: float, min_edge: float) -> tuple[np.ndarray, np.ndarray]:
    """Single-bounce PO terms of the lit sub-facets for a radar at ``range_m * u``.

    Parameters
    ----------
    fine : TriangleMesh
        The target subdivided to the Fresnel length (see the module docstring).
    u, e_pol : ndarray, shape ``[3]``
        Unit direction to the radar and polarisation.
    k : float
        Wavenumber [rad/m].
    min_edge : float
        Smallest facet split for partial shadow [m].

    Returns
    -------
    terms : ndarray of complex, shape ``[facet]``
        Each sub-facet's share of ``F_co`` [m] (normalised to ``range_m``, phase
        referred to ``2 range_m``).
    centroids : ndarray, shape ``[facet, 3]``
        Sub-facet centroids [m], whose two-way length is the term's delay.
    """
    tri, n_eff = _lit(scene, fine.triangles, u, range_m, min_edge)
    if len(tri) == 0:
        return np.zeros(0, complex), np.zeros((0, 3))
    cent = tri.mean(axis=1)
    to_radar = range_m * u - cent
    ri = np.linalg.norm(to_radar, axis=1)
    ui = to_radar / ri[:, None]
    e = e_pol - (ui @ e_pol)[:, None] * ui
    e = (e / np.linalg.norm(e, axis=1, keepdims=True)).astype(complex)
    co = np.einsum("fi,fi->f", po_vector(material, -ui, e, n_eff, ui), e.real)
    w = 2 * k * ui
    local = polygon_phase_integral(tri, w) * np.exp(-1j * np.einsum("fi,fi->f", w, cent))
    amp = (range_m / ri) ** 2 * np.exp(-2j * k * (ri - range_m))
    return (-1j * k / (4 * np.pi)) * co * amp * local, cent


def _single_near(scene: RayScene, fine: TriangleMesh, material: PoMaterial, u, e_pol, k,
                 range_m: float, min_edge) -> complex:
    terms, _ = facet_terms_near(scene, fine, material, u, e_pol, k, range_m, min_edge)
    return complex(np.sum(terms))


def _angles(values, name: str) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or len(arr) == 0 or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a non-empty list of finite angles [deg], got {values!r}")
    return arr


def monostatic_rcs(mesh: TriangleMesh, material: PoMaterial, azimuth_deg, elevation_deg, *,
                   frequency: float = DEFAULT_FREQUENCY, range_m: float | None = None,
                   polarisation: str = "VV", max_bounces: int = MAX_BOUNCES,
                   rays_per_wavelength: float = RAYS_PER_WAVELENGTH,
                   variant: str | None = None, progress: bool = False,
                   diffraction: bool = False, multiple_diffraction: bool = False) -> RcsResult:
    """Monostatic PO + SBR RCS of ``mesh`` for every (azimuth, elevation).

    Parameters
    ----------
    mesh : TriangleMesh
        Target [m], in the frame described in this module.
    material : PoMaterial
        Material of the whole mesh (:func:`~raysim.echoes.po.mesh.po_material`).
    azimuth_deg, elevation_deg : float or sequence of float
        Aspect axes [deg], shapes ``[azimuth]`` and ``[elevation]``.
    frequency : float
        Carrier [Hz].
    range_m : float, optional
        Radar range [m] (spherical wave); ``None`` for the far field.
    polarisation : {"VV", "HH"}
        Co-polar channel.
    max_bounces : int
        Deepest bounce (1 = facet PO only, no SBR).
    rays_per_wavelength : float
        SBR tube density per transverse axis.
    variant : str, optional
        Mitsuba backend if none is configured (``"cpu"``, ``"gpu"``).
    progress : bool
        Show a tqdm bar on stderr, one step per direction.
    diffraction : bool
        Add the PTD fringe wave of the mesh's sharp edges
        (:mod:`~raysim.echoes.po.edges`; conductors only). ``False`` (default):
        PO + SBR alone, unchanged.
    multiple_diffraction : bool
        With ``diffraction``, add the multiple diffraction (double and higher
        orders, summed) between the facing parallel edges of flat faces (a
        plate's opposite sides; hard polarisation;
        :func:`~raysim.echoes.po.edges.pair_amplitude`). Far field only.
        ``False`` (default): first order only, unchanged.

    Returns
    -------
    RcsResult
        ``rcs_m2`` shaped ``[azimuth, elevation]``; with ``diffraction``, ``info``
        reports ``edges``, ``edge_segments`` (and ``edge_pairs``,
        ``pair_segments`` with ``multiple_diffraction``) and the wall-clock
        seconds spent on them (``edge_seconds``) and in all (``seconds``).

    Raises
    ------
    ValueError
        Non-positive frequency, range or density, unknown polarisation,
        ``max_bounces`` outside 1..10, a job too large (:func:`rcs_job_size`),
        ``diffraction`` not a bool or asked of a material other than a conductor,
        ``multiple_diffraction`` without ``diffraction`` or with a finite range.
    """
    started = time.perf_counter()
    if not (math.isfinite(frequency) and frequency > 0):
        raise ValueError(f"frequency must be a positive number of Hz, got {frequency!r}")
    if range_m is not None and not (math.isfinite(range_m) and range_m > 0):
        raise ValueError(f"range_m must be a positive distance [m] or None, got {range_m!r}")
    pol = str(polarisation).upper()
    if pol not in ("VV", "HH"):
        raise ValueError(f"polarisation must be 'VV' or 'HH', got {polarisation!r}")
    if int(max_bounces) != max_bounces or not 1 <= max_bounces <= 10:
        raise ValueError(f"max_bounces must be an integer in 1..10, got {max_bounces!r}")
    if not (math.isfinite(rays_per_wavelength) and rays_per_wavelength > 0):
        raise ValueError(f"rays_per_wavelength must be > 0, got {rays_per_wavelength!r}")
    if not isinstance(diffraction, (bool, np.bool_)):
        raise ValueError(f"diffraction must be True or False, got {diffraction!r}")
    if not isinstance(multiple_diffraction, (bool, np.bool_)):
        raise ValueError(f"multiple_diffraction must be True or False, "
                         f"got {multiple_diffraction!r}")
    if multiple_diffraction and not (diffraction and range_m is None):
        raise ValueError("multiple_diffraction adds to first-order diffraction in the far field: "
                         "give diffraction=True and range_m=None, or leave it off")
    if diffraction and not material.is_pec:
        raise ValueError(f"diffraction: the edge fringe wave is that of a perfect conductor; "
                         f"material {material.name!r} is not one (use 'metal' or 'pec', or "
                         f"leave diffraction off)")
    az = _angles(azimuth_deg, "azimuth_deg")
    el = _angles(elevation_deg, "elevation_deg")
    wavelength = SPEED_OF_LIGHT / frequency
    k = 2 * math.pi / wavelength
    spacing = wavelength / rays_per_wavelength
    near_edge = None
    if range_m is not None:
        if range_m <= mesh.radius:
            raise ValueError(f"range_m={range_m!r} puts the radar inside the target "
                             f"(radius {mesh.radius:.3g} m)")
        near_edge = FRESNEL_FRACTION * math.sqrt(wavelength * range_m)
    edges = segments = pairs = edge_pairs = None
    if diffraction:
        edges = sharp_edges(mesh)
        seg_len = EDGE_SEGMENT_WAVELENGTHS * wavelength
        segments = edges.split(seg_len if near_edge is None else min(seg_len, near_edge))
        if multiple_diffraction:
            edge_pairs = facing_edge_pairs(edges)
            pairs = edge_pairs.split(seg_len)
    rcs_job_size(mesh, len(az) * len(el), spacing, int(max_bounces), near_edge,
                 0 if segments is None else len(segments))
    scene = RayScene(mesh, variant)
    fine = None if near_edge is None else mesh.subdivided(near_edge)
    out = np.zeros((len(az), len(el)))
    from tqdm.auto import tqdm

    edge_seconds = 0.0
    bar = tqdm(total=out.size, desc="rcs", unit="direction", file=sys.stderr,
               disable=not progress, leave=False, mininterval=0.0)
    for i, a in enumerate(np.radians(az)):
        for j, e in enumerate(np.radians(el)):
            u = radar_direction(a, e)
            e_h, e_v = polarisation_basis(a, e)
            e_pol = e_v if pol == "VV" else e_h
            if range_m is None:
                f = _single_far(scene, material, u, e_pol, k, spacing)
            else:
                f = _single_near(scene, fine, material, u, e_pol, k, range_m, spacing)
            f += sbr_amplitude(scene, material, u, e_pol, e_h, e_v, wavelength,
                               spacing=spacing, max_bounces=int(max_bounces), range_m=range_m)
            if segments is not None:
                t0 = time.perf_counter()
                if range_m is None:
                    f += edge_amplitude(segments, u, e_pol, k, scene)
                    if pairs is not None:
                        f += pair_amplitude(pairs, u, e_pol, k, scene)
                else:
                    f += complex(np.sum(edge_terms_near(segments, u, e_pol, k, range_m,
                                                        scene)[0]))
                edge_seconds += time.perf_counter() - t0
            out[i, j] = 4 * math.pi * abs(f) ** 2
            bar.update()
    bar.close()
    info = {"tube_spacing_m": spacing, "rays_per_wavelength": rays_per_wavelength,
            "max_bounces": int(max_bounces), "facets": len(mesh.faces),
            "near_field_facets": None if fine is None else len(fine.faces),
            "material": material.name, "diffraction": bool(diffraction)}
    if segments is not None:
        info.update(edges=len(edges), edge_segments=len(segments),
                    edge_seconds=edge_seconds, seconds=time.perf_counter() - started)
    if pairs is not None:
        info.update(multiple_diffraction=True, edge_pairs=len(edge_pairs),
                    pair_segments=len(pairs))
    return RcsResult(frequency, range_m, az, el, out, pol, info)
