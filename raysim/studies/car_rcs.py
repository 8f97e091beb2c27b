"""RCS of the car meshes versus aspect and elevation, their scattering centres, and measurements.

Run ``python -m raysim.studies.car_rcs --out docs/cars_table.md`` (or ``raysim rcs
car:sedan ...`` for one sweep). Geometry: the car in its own frame
(:mod:`raysim.echoes.po.sedan`: ``x`` forward, ``y`` left, ``z`` up, ground at
``z = 0``), the radar at ``range_m`` from the reference point ``(0, 0, CAR_REFERENCE_Z)``
in the direction ``(cos el cos az, cos el sin az, sin el)``: aspect ``az = 0`` is
the nose, 90 deg the left side (broadside), 180 deg the tail; ``el`` above the
horizon (a drone 15 m up at 15 m ground distance sees the car at 45 deg). No
ground (a car on a turntable in an anechoic sense); the scene tracer adds the
car-ground multipath (docs/scattering.md).

Solver: :func:`raysim.echoes.po.paths.scattering_terms` (facet PO of every part
with its material, SBR to 3 bounces between all parts) at ``range_m`` (spherical
wave); with diffraction the PTD fringe wave of the conducting parts' sharp edges
(:mod:`raysim.echoes.po.edges`) is added coherently. Measurements average the
power over a few degrees of aspect (turntable steps, a beam's width): the table
averages the power over ``+-AVERAGE_HALF_WIDTH_DEG``.

Beside the meshes the table gives the 3GPP TR 38.901 vehicle (RCS model 2, one
scattering point; :mod:`raysim.studies.car_rcs_3gpp`): its mean and 5-95 % band
at every elevation, and per lobe sector the cars' medians against it.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

__all__ = ["CAR_MODELS", "car_model", "car_rcs", "aspect_average", "scattering_centres",
           "swing_db", "MEASURED_DBSM", "MEASURED_PROVENANCE", "CAR_REFERENCE_Z",
           "AVERAGE_HALF_WIDTH_DEG", "CENTRE_CELL_M", "CarRcs", "table_markdown"]

#: Height of the car's reference point (phase centre of the sweep) [m].
CAR_REFERENCE_Z = 0.7
#: Half-width of the aspect average [deg] (measurements: about +-2.5 deg).
AVERAGE_HALF_WIDTH_DEG = 2.5
#: Cell of a scattering centre along and across the line of sight [m] (a wheel,
#: a mirror, a plate: the features a 4 GHz-wide radar separates on a car).
CENTRE_CELL_M = 0.25
#: Share of the centres' summed power that the counted centres carry.
CENTRE_POWER_SHARE = 0.9

#: 77 GHz RCS of passenger cars seen from the ground (elevation 0-5 deg),
#: ``aspect [deg] -> (low, high)`` [dBsm], after averaging over a few degrees: ranges over
#: cars RECALLED from the figures of Kamel, Peden et al. (recalled as IEEE TAP 2017; the
#: abstract read is Bel Kamel, Peden & Pajusco, EuCAP 2017), Geary et al. (2013),
#: Schipper et al. (24 GHz, EuCAP 2011) and Silberling et al. (DRI-TM-14-70-1, 2014).
#: The stored copies of these sources that could be searched give only their first
#: page (title, abstract, contents): no value per aspect was read, so none replaces a
#: recalled one (:data:`MEASURED_PROVENANCE`; docs/cars.md lists what was read). No
#: 77 GHz measurement from 30-60 deg elevation is known to us.
MEASURED_DBSM = {0: (10.0, 20.0), 30: (5.0, 15.0), 60: (5.0, 15.0), 90: (20.0, 35.0),
                 120: (5.0, 15.0), 150: (5.0, 15.0), 180: (10.0, 20.0)}
#: Where each range of :data:`MEASURED_DBSM` comes from: ``"recalled"`` (from memory of
#: a paper's figure; the table says so) or ``"read"`` (read in a cited source, with
#: its statistic, the radar's elevation and the car in docs/cars.md).
MEASURED_PROVENANCE = {a: "recalled" for a in MEASURED_DBSM}


def _models():
    from raysim.echoes.po.car import car_parts
    from raysim.echoes.po.sedan import sedan_parts

    return {"simple": car_parts, "sedan": sedan_parts}


#: Car models by name: ``simple`` (:func:`raysim.echoes.po.car.car_parts`, lofted
#: body, glass, tyres) and ``sedan`` (:func:`raysim.echoes.po.sedan.sedan_parts` with
#: its grille and headlamp openings).
CAR_MODELS = ("simple", "sedan")


def car_model(name: str, facet: float | None = None) -> list:
    """Parts ``(name, mesh, material)`` of the car model ``name`` (default size).

    Raises
    ------
    ValueError
        Unknown model name, or ``facet`` given for the simple car.
    """
    if name not in CAR_MODELS:
        raise ValueError(f"car model: got {name!r}, expected one of {list(CAR_MODELS)}")
    make = _models()[name]
    if facet is None:
        return make(openings=True) if name == "sedan" else make()
    if name != "sedan":
        raise ValueError(f"car model {name!r} has a fixed facet size; facet applies to 'sedan'")
    return make(facet=facet, openings=True)


class CarRcs:
    """RCS of a car on an aspect x elevation grid.

    Attributes
    ----------
    azimuth_deg, elevation_deg : ndarray, shapes ``[aspect]``, ``[elevation]``
        Aspect (0 nose, 90 broadside, 180 tail) and elevation [deg].
    po_m2 : ndarray, shape ``[aspect, elevation]``
        PO + SBR RCS [m^2].
    diffraction_m2 : ndarray or None, shape ``[aspect, elevation]``
        PO + SBR + edge diffraction RCS [m^2], if computed.
    seconds : float
        Wall-clock time of the sweep [s].
    """

    def __init__(self, azimuth_deg, elevation_deg, po_m2, diffraction_m2, seconds):
        self.azimuth_deg = np.asarray(azimuth_deg, float)
        self.elevation_deg = np.asarray(elevation_deg, float)
        self.po_m2 = po_m2
        self.diffraction_m2 = diffraction_m2
        self.seconds = seconds


def _radar(az: float, el: float, range_m: float) -> np.ndarray:
    a, e = math.radians(az), math.radians(el)
    return (np.array([0.0, 0.0, CAR_REFERENCE_Z])
            + range_m * np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a),
                                  math.sin(e)]))


def _polarisation(az: float, pol: str) -> np.ndarray:
    a = math.radians(az)
    return np.array([0.0, 0.0, 1.0]) if pol == "VV" else np.array([-math.sin(a),
                                                                   math.cos(a), 0.0])


def car_rcs(parts, azimuth_deg, elevation_deg, *, range_m: float = 50.0,
            frequency: float = 77e9, polarisation: str = "VV", diffraction: bool = False,
            max_bounces: int = 3, tubes_per_wavelength: float | None = None,
            progress: bool = False) -> CarRcs:
    """PO + SBR (and, with ``diffraction``, PO + SBR + PTD) RCS of ``parts``.

    Parameters
    ----------
    parts : list of (str, TriangleMesh, str)
        The car (:func:`car_model`), in its own frame [m].
    azimuth_deg, elevation_deg : sequence of float
        Aspects and elevations [deg] (see the module docstring).
    range_m : float
        Radar range from the reference point [m].
    frequency : float
        Carrier [Hz].
    polarisation : {"VV", "HH"}
        VV: E in the vertical plane through the line of sight; HH: horizontal.
    diffraction : bool
        Also compute PO + SBR + the edges' fringe wave.
    max_bounces : int
        Deepest bounce (1: facet PO only).
    tubes_per_wavelength : float, optional
        SBR tube density (default that of the scene tracer).
    progress : bool
        A tqdm bar on stderr, one step per direction.

    Returns
    -------
    CarRcs

    Raises
    ------
    ValueError
        Unknown polarisation, a range of 10 m or less, or a job too large
        (:func:`raysim.echoes.po.rcs.rcs_job_size`: directions x (facets + tubes)).
    """
    from tqdm.auto import tqdm

    from raysim.echoes.po.edges import edge_terms_near, sharp_edges
    from raysim.echoes.po.mesh import TriangleMesh, po_material
    from raysim.echoes.po.paths import (
        MAX_TUBES,
        PATHS_FRESNEL_FRACTION,
        TUBES_PER_WAVELENGTH,
        scattering_terms,
    )
    from raysim.echoes.po.rays import RayScene
    from raysim.echoes.po.rcs import EDGE_SEGMENT_WAVELENGTHS, rcs_job_size
    from raysim.radar.config import SPEED_OF_LIGHT

    pol = str(polarisation).upper()
    if pol not in ("VV", "HH"):
        raise ValueError(f"polarisation must be 'VV' or 'HH', got {polarisation!r}")
    if not (math.isfinite(range_m) and range_m > 10.0):
        raise ValueError(f"range_m (--range-m) must be a distance over 10 m (the car "
                         f"is 5 m long), got {range_m!r}")
    az = np.atleast_1d(np.asarray(azimuth_deg, float))
    el = np.atleast_1d(np.asarray(elevation_deg, float))
    meshes = [m for _, m, _ in parts]
    mats = [mat for _, _, mat in parts]
    tpw = TUBES_PER_WAVELENGTH if tubes_per_wavelength is None else tubes_per_wavelength
    wavelength = SPEED_OF_LIGHT / frequency
    k = 2 * math.pi / wavelength
    ref = np.array([0.0, 0.0, CAR_REFERENCE_Z])
    whole = TriangleMesh(np.concatenate([m.vertices for m in meshes]), np.concatenate(
        [m.faces + o for m, o in zip(meshes, np.cumsum([0] + [len(m.vertices) for m in meshes]),
                                     strict=False)]))
    # sized before anything is traced: the tracer's tubes are capped at MAX_TUBES per direction
    rcs_job_size(whole, az.size * el.size, max(wavelength / tpw, 2 * whole.radius
                                               / math.sqrt(MAX_TUBES)), int(max_bounces))
    segments = scene = None
    if diffraction:
        local = [TriangleMesh(m.vertices - ref, m.faces) for m in meshes]
        offsets = np.cumsum([0] + [len(m.vertices) for m in local])
        scene = RayScene(TriangleMesh(np.concatenate([m.vertices for m in local]),
                                      np.concatenate([m.faces + o for m, o in
                                                      zip(local, offsets, strict=False)])))
        seg_len = min(EDGE_SEGMENT_WAVELENGTHS * wavelength,
                      PATHS_FRESNEL_FRACTION * math.sqrt(wavelength * range_m))
        segments = [sharp_edges(m).split(seg_len) for m, mat in zip(local, mats, strict=True)
                    if po_material(mat, frequency).is_pec and len(sharp_edges(m))]
    po = np.zeros((len(az), len(el)))
    dif = np.zeros_like(po) if diffraction else None
    start = time.perf_counter()
    bar = tqdm(total=po.size, desc="car rcs", unit="direction", file=sys.stderr,
               disable=not progress, leave=False)
    for i, a in enumerate(az):
        for j, e in enumerate(el):
            radar = _radar(a, e, range_m)
            pw = _polarisation(a, pol)
            terms = scattering_terms(meshes, mats, radar, ref, frequency=frequency,
                                     polarisation_w=pw, tubes_per_wavelength=tpw,
                                     max_bounces=max_bounces)
            total = complex(np.sum(terms.amplitude))
            po[i, j] = 4 * math.pi * abs(total) ** 2
            if diffraction:
                u = (radar - ref) / terms.range_m
                e_v = pw - (pw @ u) * u                 # as the tracer: pw's transverse part
                e_v /= np.linalg.norm(e_v)
                for seg in segments:
                    total += complex(np.sum(edge_terms_near(seg, u, e_v, k, terms.range_m,
                                                            scene)[0]))
                dif[i, j] = 4 * math.pi * abs(total) ** 2
            bar.update()
    bar.close()
    return CarRcs(az, el, po, dif, time.perf_counter() - start)


def aspect_average(rcs_m2: np.ndarray, azimuth_deg, half_width_deg: float =
                   AVERAGE_HALF_WIDTH_DEG) -> np.ndarray:
    """Power average over ``+-half_width_deg`` of aspect, shape as ``rcs_m2`` ``[aspect, ...]``.

    The car is mirror-symmetric, so aspects beyond 0 and 180 deg are read back
    into 0..180 (``-a -> a``, ``180 + a -> 180 - a``).
    """
    az = np.asarray(azimuth_deg, float)
    step = float(np.min(np.diff(az))) if len(az) > 1 else 1.0
    offsets = np.arange(-math.floor(half_width_deg / step + 1e-9),
                        math.floor(half_width_deg / step + 1e-9) + 1) * step
    out = np.empty_like(rcs_m2)
    for i, a in enumerate(az):
        x = a + offsets
        x = np.where(x < 0, -x, np.where(x > 180, 360 - x, x))
        idx = np.argmin(np.abs(az[None, :] - x[:, None]), axis=1)
        out[i] = rcs_m2[idx].mean(axis=0)
    return out


def swing_db(rcs_m2: np.ndarray, azimuth_deg, span_deg: float = 10.0) -> np.ndarray:
    """Largest max/min ratio of ``rcs_m2`` within any ``span_deg`` of aspect [dB], ``[...]``."""
    db = 10 * np.log10(np.maximum(rcs_m2, 1e-30))
    az = np.asarray(azimuth_deg, float)
    best = np.zeros(db.shape[1:])
    for a in az:
        w = (az >= a) & (az <= a + span_deg)
        best = np.maximum(best, db[w].max(axis=0) - db[w].min(axis=0))
    return best


def scattering_centres(parts, az: float, el: float, *, range_m: float = 50.0,
                       frequency: float = 77e9, cell: float = CENTRE_CELL_M,
                       share: float = CENTRE_POWER_SHARE) -> dict:
    """The car's scattering centres seen from one direction, strongest first.

    Terms are grouped into ``cell`` x ``cell`` cells along and across the line of
    sight (:func:`raysim.echoes.po.paths.cluster_terms`).

    Returns
    -------
    dict
        ``count`` (centres), ``n90`` (fewest centres carrying ``share`` of the
        centres' summed power), ``centres``: list of ``{"xyz" (car frame, m),
        "part", "share", "dbsm"}`` for the ``n90`` strongest.
    """
    from raysim.echoes.po.paths import cluster_terms, scattering_terms

    meshes = [m for _, m, _ in parts]
    mats = [mat for _, _, mat in parts]
    ref = np.array([0.0, 0.0, CAR_REFERENCE_Z])
    terms = scattering_terms(meshes, mats, _radar(az, el, range_m), ref, frequency=frequency,
                             polarisation_w=_polarisation(az, "VV"))
    centre, amp, _ = cluster_terms(terms, cell, cell)
    power = np.abs(amp) ** 2
    order = np.argsort(power)[::-1]
    cum = np.cumsum(power[order]) / power.sum()
    n90 = int(np.searchsorted(cum, share) + 1)
    out = []
    # parts cut from one vertex array (the sedan's body, glass, recesses) own only the
    # vertices their facets use
    used = [m.vertices[np.unique(m.faces)] for m in meshes]
    for c in order[:n90]:
        d = [np.min(np.linalg.norm(u - centre[c], axis=1)) for u in used]
        out.append({"xyz": [round(float(x), 2) for x in centre[c]],
                    "part": parts[int(np.argmin(d))][0], "share": float(power[c] / power.sum()),
                    "dbsm": float(10 * np.log10(4 * math.pi * power[c]))})
    return {"count": len(power), "n90": n90, "centres": out}


def table_markdown(results: dict, aspects=tuple(MEASURED_DBSM), model=None) -> str:
    """Markdown table: aspect, elevation, PO + SBR, PO + SBR + PTD, measured range [dBsm]
    with its provenance (:data:`MEASURED_PROVENANCE`), and the 3GPP TR 38.901 vehicle.

    ``results`` maps a model name to a :class:`CarRcs` computed with diffraction
    on a 1 deg aspect grid; values are the ``+-2.5 deg`` power averages. ``model``
    (:class:`raysim.studies.car_rcs_3gpp.VehicleModelRcs` on the aspects and the
    results' elevations) fills the last column with its mean and 5-95 % band at
    every elevation; without it the column is ``-``.
    """
    lines = ["| model | aspect [deg] | elevation [deg] | PO + SBR [dBsm] | "
             "PO + SBR + PTD [dBsm] | measured, ground level [dBsm] (provenance) | "
             "TR 38.901 vehicle, mean (5-95 %) [dBsm] |",
             "|---|---|---|---|---|---|---|"]
    for name, r in results.items():
        po = 10 * np.log10(aspect_average(r.po_m2, r.azimuth_deg))
        di = 10 * np.log10(aspect_average(r.diffraction_m2, r.azimuth_deg))
        for j, e in enumerate(r.elevation_deg):
            for a in aspects:
                i = int(np.argmin(np.abs(r.azimuth_deg - a)))
                meas = MEASURED_DBSM.get(a)
                m = (f"{meas[0]:g} to {meas[1]:g} ({MEASURED_PROVENANCE[a]})"
                     if (meas and e <= 5) else "-")
                lines.append(f"| {name} | {a:g} | {e:g} | {po[i, j]:.1f} | {di[i, j]:.1f} | {m} "
                             f"| {_model_cell(model, a, e)} |")
    return "\n".join(lines) + "\n"


def _model_cell(model, aspect: float, elevation: float) -> str:
    """``mean (low to high)`` of ``model`` [dBsm] at its aspect nearest ``aspect`` (as the
    cars' rows) and at ``elevation``, or ``-`` without a model."""
    if model is None:
        return "-"
    j = np.flatnonzero(np.isclose(model.elevation_deg, elevation))
    if not j.size:
        raise ValueError(f"the TR 38.901 model has no value at elevation {elevation:g} deg "
                         f"(it has {model.elevation_deg})")
    i, j = int(np.argmin(np.abs(model.azimuth_deg - aspect))), j[0]
    return (f"{model.mean_dbsm[i, j]:.1f} ({model.low_dbsm[i, j]:.1f} to "
            f"{model.high_dbsm[i, j]:.1f})")


def summary_markdown(results: dict, model=None) -> str:
    """Per model and elevation: median, 10-90 % range and largest 10 deg swing [dB].

    ``model`` (:class:`raysim.studies.car_rcs_3gpp.VehicleModelRcs`, on the results'
    grid) adds a row per elevation: the median and 10-90 % of its mean over aspect.
    """
    lines = ["| model | elevation [deg] | median PO + SBR (PTD) [dBsm] | 10-90 % [dBsm] | "
             "swing in 10 deg, samples / averaged [dB] |", "|---|---|---|---|---|"]
    for name, r in results.items():
        avg = aspect_average(r.diffraction_m2, r.azimuth_deg)
        po_avg = aspect_average(r.po_m2, r.azimuth_deg)
        raw_swing, avg_swing = swing_db(r.diffraction_m2, r.azimuth_deg), swing_db(
            avg, r.azimuth_deg)
        for j, e in enumerate(r.elevation_deg):
            db = 10 * np.log10(avg[:, j])
            lines.append(f"| {name} | {e:g} | {np.median(10 * np.log10(po_avg[:, j])):.1f} "
                         f"({np.median(db):.1f}) | {np.percentile(db, 10):.1f} to "
                         f"{np.percentile(db, 90):.1f} | {raw_swing[j]:.1f} / {avg_swing[j]:.1f} |")
    if model is not None:
        for j, e in enumerate(model.elevation_deg):
            db = model.mean_dbsm[:, j]
            lines.append(f"| TR 38.901 vehicle, mean | {e:g} | {np.median(db):.1f} | "
                         f"{np.percentile(db, 10):.1f} to {np.percentile(db, 90):.1f} | - |")
    return "\n".join(lines) + "\n"


#: Markers of the generated block in a markdown file (docs/cars.md).
BLOCK_BEGIN = "<!-- generated by python -m raysim.studies.car_rcs: begin -->"
BLOCK_END = "<!-- generated by python -m raysim.studies.car_rcs: end -->"


def _write_block(path: str, text: str) -> None:
    """Replace the generated block of ``path`` (between the markers), or write the file."""
    from pathlib import Path

    out = Path(path)
    old = out.read_text() if out.exists() else ""
    if BLOCK_BEGIN in old and BLOCK_END in old:
        head, _, rest = old.partition(BLOCK_BEGIN)
        _, _, tail = rest.partition(BLOCK_END)
        out.write_text(f"{head}{BLOCK_BEGIN}\n{text}{BLOCK_END}{tail}")
    else:
        out.write_text(text)


def main(argv=None) -> int:
    """Sweep the car models and write the tables (markdown) and the raw sweep (NPZ)."""
    p = argparse.ArgumentParser(prog="python -m raysim.studies.car_rcs", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--models", default="simple,sedan", help="comma list (default both)")
    p.add_argument("--az-step", type=float, default=1.0, help="aspect step [deg] (default 1)")
    p.add_argument("--elevations", default="0,30,45,60", help="elevations [deg]")
    p.add_argument("--range-m", type=float, default=50.0, help="radar range [m] (default 50)")
    p.add_argument("--out", required=True, help="markdown file: its generated block (between "
                   "the markers) is replaced, or the whole file written")
    p.add_argument("--npz", default=None, help="also save the sweep (NPZ)")
    p.add_argument("--load", default=None, metavar="NPZ[,NPZ]",
                   help="read the sweep from these NPZ files (written by --npz) instead of "
                   "tracing it; the scattering centres are traced again")
    args = p.parse_args(argv)
    models = args.models.split(",")
    if args.load:
        results = _load(args.load.split(","), models)
        az, el = results[models[0]].azimuth_deg, results[models[0]].elevation_deg
    else:
        az = np.arange(0.0, 180.0 + 1e-9, args.az_step)
        el = np.array([float(x) for x in args.elevations.split(",")])
        results = {}
    centres = {}
    for name in models:
        parts = car_model(name)
        if name not in results:
            results[name] = car_rcs(parts, az, el, range_m=args.range_m, diffraction=True,
                                    progress=True)
            print(f"{name}: {az.size * el.size} directions in {results[name].seconds:.0f} s "
                  f"(wall clock)", file=sys.stderr)
        centres[name] = {(a, e): scattering_centres(parts, a, e, range_m=args.range_m)
                         for a in (30, 60, 90, 150) for e in (0, 45)}
    from raysim.studies.car_rcs_3gpp import (
        TR38901_PROVENANCE,
        sector_table_markdown,
        tr38901_vehicle_rcs,
    )

    model = tr38901_vehicle_rcs(az, el)
    text = ["## RCS versus aspect (+-2.5 deg power average)\n",
            f"The last column: the 3GPP TR 38.901 vehicle (RCS model 2, one scattering point; "
            f"{TR38901_PROVENANCE}), its mean and the 5-95 % band of its lognormal spread, "
            f"at every elevation.\n", table_markdown(results, model=model),
            "\n## Over all aspects 0-180 deg\n", summary_markdown(results, model),
            "\n## Per lobe sector against the TR 38.901 vehicle\n",
            "Medians over each lobe's aspect sector (front 0-45, side 45-135, back 135-180 "
            "deg) of the +-2.5 deg averages (PO + SBR, VV), against the model's median and "
            "its 5-95 % band (lognormal sigma_S, 3.41 dB).\n",
            sector_table_markdown({n: (r.azimuth_deg, r.elevation_deg, 10 * np.log10(
                aspect_average(r.po_m2, r.azimuth_deg))) for n, r in results.items()}, model),
            "\n## Scattering centres (0.25 m cells, VV)\n",
            "The strongest centres: part, share of the power, position (x forward, y left, "
            "z up from the ground under the car's centre) [m].\n",
            "| model | aspect [deg] | elevation [deg] | centres | carrying 90 % | strongest |",
            "|---|---|---|---|---|---|"]
    for name, cs in centres.items():
        for (a, e), c in cs.items():
            top = "; ".join(f"{x['part']} {100 * x['share']:.0f} % at "
                            f"({x['xyz'][0]:.2f}, {x['xyz'][1]:.2f}, {x['xyz'][2]:.2f})"
                            for x in c["centres"][:3])
            text.append(f"| {name} | {a} | {e} | {c['count']} | {c['n90']} | {top} |")
    _write_block(args.out, "\n".join(text) + "\n")
    if args.npz:
        np.savez(args.npz, azimuth_deg=az, elevation_deg=el,
                 **{f"{n}_po_m2": r.po_m2 for n, r in results.items()},
                 **{f"{n}_diffraction_m2": r.diffraction_m2 for n, r in results.items()})
    return 0


def _load(paths, models) -> dict:
    """Sweeps of ``models`` read from NPZ files written by ``--npz``."""
    out = {}
    for path in paths:
        with np.load(path) as d:
            for name in models:
                if f"{name}_po_m2" in d:
                    out[name] = CarRcs(d["azimuth_deg"], d["elevation_deg"], d[f"{name}_po_m2"],
                                       d[f"{name}_diffraction_m2"], float("nan"))
    missing = [m for m in models if m not in out]
    if missing:
        raise ValueError(f"--load: no sweep of {missing} in {paths}")
    return out


if __name__ == "__main__":
    raise SystemExit(main())
