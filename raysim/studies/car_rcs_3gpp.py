"""Monostatic RCS of a passenger car by the 3GPP TR 38.901 vehicle model.

3GPP TR 38.901 Rel-19, clause 7.9.2.1, RCS model 2 of a vehicle with a single
scattering point (Table 7.9.2.1-4; "vehicle type 2" of TR 37.885, a passenger
car 5 x 2 x 1.6 m): ``10 lg(sigma_M sigma_D)`` (eq. 7.9.2-3) is one of five
lobes (front, left, back, right, roof), each a parabola in dB about its centre
in zenith and azimuth, clipped ``sigma_max`` below its peak ``G_max``; the lobe
is picked by the bisector of the incident and scattered directions. The third
component ``sigma_S`` is lognormal: ``10 lg(sigma_S)`` is Gaussian with standard
deviation ``sigma_S,dB = 3.41 dB`` and the mean ``-ln(10)/20 sigma_S,dB^2`` that
makes the linear mean of ``sigma_S`` 1 (eq. 7.9.2-1). It is evaluated by Sionna
RT's own :class:`sionna.rt.rcs.tr38901.TR38901RCS` with the parameters of
:func:`sionna.rt.rcs.tr38901.get_target_parameters` (:data:`TR38901_PROVENANCE`).

Angles. The model's frame is the car's (:mod:`raysim.studies.car_rcs`): ``x``
forward (front lobe at ``phi = 0``), ``y`` left (left lobe at ``phi = 90 deg``),
``z`` up (roof lobe at ``theta = 0``). The radar seen from the car at aspect
``az`` and elevation ``el`` lies along ``u = (cos el cos az, cos el sin az,
sin el)``; monostatic, the incident wave travels along ``k_i = -u`` and the
scattered wave along ``k_s = u``, so the bistatic angle is 0 and the bisector is
``u``: zenith ``theta = 90 deg - el``, azimuth ``phi = az``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["TR38901_OBJECT_TYPE", "TR38901_MODEL", "TR38901_PROVENANCE", "BAND_PROBABILITIES",
           "VehicleModelRcs", "tr38901_parameters", "model_angles_deg", "sigma_s_quantile_db",
           "tr38901_vehicle_rcs", "LOBE_SECTORS_DEG", "sector_median_db",
           "sector_table_markdown"]

#: Sensing target of Sionna's tables: the vehicle with a single scattering point.
TR38901_OBJECT_TYPE = "vehicle-single-sp"
#: RCS model of clause 7.9.2.1 (2: with the angular component ``sigma_D``).
TR38901_MODEL = 2
#: Where the model's numbers come from (printed with the table).
TR38901_PROVENANCE = ("3GPP TR 38.901 Rel-19 Table 7.9.2.1-4, read from sionna-rt 2.2's "
                      "implementation")
#: Aspect sectors of the model's lobes at 0-180 deg [deg]: ``[low, high)``, the back's
#: closed at 180 (the lobes' azimuth ranges; right mirrors left).
LOBE_SECTORS_DEG = {"front": (0.0, 45.0), "side": (45.0, 135.0), "back": (135.0, 180.0)}
#: Probabilities of the band of ``sigma_S`` around the model's mean (5-95 %).
BAND_PROBABILITIES = (0.05, 0.95)


class VehicleModelRcs:
    """The TR 38.901 vehicle's monostatic RCS on an aspect x elevation grid.

    Attributes
    ----------
    azimuth_deg, elevation_deg : ndarray, shapes ``[aspect]``, ``[elevation]``
        Aspect (0 nose, 90 left side, 180 tail) and elevation above the horizon [deg].
    mean_dbsm : ndarray, shape ``[aspect, elevation]``
        ``10 lg(sigma_M sigma_D)``: the model's mean RCS (``sigma_S``'s linear mean is 1) [dBsm].
    low_dbsm, high_dbsm : ndarray, shape ``[aspect, elevation]``
        The :data:`BAND_PROBABILITIES` quantiles of ``sigma_M sigma_D sigma_S`` [dBsm].
    median_dbsm : ndarray, shape ``[aspect, elevation]``
        Its median [dBsm] (the mean minus ``ln(10)/20 sigma_S,dB^2``).
    """

    def __init__(self, azimuth_deg, elevation_deg, mean_dbsm, sigma_s_std_db: float):
        self.azimuth_deg = np.asarray(azimuth_deg, float)
        self.elevation_deg = np.asarray(elevation_deg, float)
        self.mean_dbsm = np.asarray(mean_dbsm, float)
        self.sigma_s_std_db = float(sigma_s_std_db)
        lo, hi = (sigma_s_quantile_db(p, sigma_s_std_db) for p in BAND_PROBABILITIES)
        self.low_dbsm = self.mean_dbsm + lo
        self.high_dbsm = self.mean_dbsm + hi
        self.median_dbsm = self.mean_dbsm + sigma_s_quantile_db(0.5, sigma_s_std_db)


def tr38901_parameters():
    """Sionna's parameters of the vehicle (:data:`TR38901_OBJECT_TYPE`, model 2).

    Returns
    -------
    sionna.rt.rcs.tr38901.TargetParameters
        Lobes (Table 7.9.2.1-4), ``k1``, ``k2``, ``sigma_m_db``, ``sigma_s_db``, ``dimensions``.
    """
    from raysim.echoes.rt.backend import sionna_rt

    sionna_rt()                     # the Mitsuba variant is chosen before sionna.rt loads
    from sionna.rt.rcs.tr38901 import get_target_parameters

    return get_target_parameters(TR38901_OBJECT_TYPE, TR38901_MODEL)


def model_angles_deg(azimuth_deg, elevation_deg) -> tuple[np.ndarray, np.ndarray]:
    """Zenith ``theta`` and azimuth ``phi`` of the model for aspect ``az`` and elevation ``el``.

    ``theta = 90 - el``, ``phi = az`` wrapped to ``[-180, 180)`` [deg] (module docstring);
    inputs broadcast against each other.
    """
    az = np.asarray(azimuth_deg, float)
    el = np.asarray(elevation_deg, float)
    return 90.0 - el, (az + 180.0) % 360.0 - 180.0


def sigma_s_quantile_db(probability: float, sigma_s_std_db: float) -> float:
    """Quantile of ``10 lg(sigma_S)`` [dB]: Gaussian, mean ``-ln(10)/20 s^2``, deviation ``s``.

    The truncation three deviations above the mean (eq. 7.9.4-1) leaves the
    quantiles below 99.8 % unchanged.
    """
    from scipy.stats import norm

    s = float(sigma_s_std_db)
    return -math.log(10.0) / 20.0 * s * s + s * float(norm.ppf(probability))


def tr38901_vehicle_rcs(azimuth_deg, elevation_deg) -> VehicleModelRcs:
    """The vehicle model's monostatic RCS, evaluated by Sionna's ``TR38901RCS``.

    Parameters
    ----------
    azimuth_deg, elevation_deg : sequence of float
        Aspects [deg] (any; 0 nose, 90 left side) and elevations above the horizon
        [deg] (-90 to 90).

    Returns
    -------
    VehicleModelRcs
        On the grid ``[aspect, elevation]``.

    Raises
    ------
    ValueError
        A non-finite angle or an elevation outside -90..90 deg.
    """
    az = np.atleast_1d(np.asarray(azimuth_deg, float))
    el = np.atleast_1d(np.asarray(elevation_deg, float))
    if not (np.all(np.isfinite(az)) and np.all(np.isfinite(el))):
        raise ValueError(f"aspects and elevations must be finite [deg], got {az}, {el}")
    if np.any(np.abs(el) > 90.0):
        raise ValueError(f"elevation must lie in -90..90 deg, got {el[np.abs(el) > 90.0]}")
    params = tr38901_parameters()
    import mitsuba as mi
    from sionna.rt.rcs.tr38901 import TR38901RCS

    rcs = TR38901RCS(params.lobes, k1=params.k1, k2=params.k2, sigma_m_db=params.sigma_m_db,
                     sigma_s_std_db=params.sigma_s_db, random_sigma_s=False)
    a, e = np.meshgrid(np.radians(az), np.radians(el), indexing="ij")
    u = [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)]
    k_s = mi.Vector3f(*(mi.Float(c.ravel()) for c in u))
    # monostatic: the wave arrives along -u and returns along u (bistatic angle 0)
    mean = np.array(rcs.sigma_md_db(-k_s, k_s), float).reshape(a.shape)
    return VehicleModelRcs(az, el, mean, params.sigma_s_db)


def sector_median_db(values_db, azimuth_deg, sector: str) -> np.ndarray:
    """Median over the aspects of a lobe's sector (:data:`LOBE_SECTORS_DEG`) [dB].

    Parameters
    ----------
    values_db : array_like, shape ``[aspect, ...]``
        Values in dB (e.g. dBsm).
    azimuth_deg : array_like, shape ``[aspect]``
        Aspects [deg], 0-180.
    sector : {"front", "side", "back"}

    Returns
    -------
    ndarray, shape ``[...]``

    Raises
    ------
    ValueError
        Unknown sector, or no aspect in it.
    """
    if sector not in LOBE_SECTORS_DEG:
        raise ValueError(f"sector: got {sector!r}, expected one of {list(LOBE_SECTORS_DEG)}")
    lo, hi = LOBE_SECTORS_DEG[sector]
    az = np.asarray(azimuth_deg, float)
    inside = (az >= lo) & ((az < hi) | ((hi == 180.0) & (az <= hi)))
    if not inside.any():
        raise ValueError(f"no aspect in the {sector} sector {lo:g}-{hi:g} deg: {az}")
    return np.median(np.asarray(values_db, float)[inside], axis=0)


def sector_table_markdown(cars: dict, model: VehicleModelRcs) -> str:
    """Markdown table: per car, elevation and lobe sector, the median over the sector of
    the car's RCS against the model's median and band.

    Parameters
    ----------
    cars : dict
        Car name -> ``(azimuth_deg [aspect], elevation_deg [elevation], rcs_dbsm [aspect,
        elevation])``: aspects 0-180 deg, the RCS in dBsm (the study's ``+-2.5 deg``
        power averages).
    model : VehicleModelRcs
        On the same aspects and elevations.

    Returns
    -------
    str
        One row per car, elevation and sector; the last column says whether the car's
        median lies inside the model's 5-95 % band about the model's median, or by how
        many dB it misses it.
    """
    lines = ["| model | elevation [deg] | sector | car, median [dBsm] | "
             "TR 38.901 median (5-95 %) [dBsm] | car against the band |",
             "|---|---|---|---|---|---|"]
    half = sigma_s_quantile_db(BAND_PROBABILITIES[1], model.sigma_s_std_db) \
        - sigma_s_quantile_db(0.5, model.sigma_s_std_db)
    for name, (az, el, car) in cars.items():
        for j, e in enumerate(np.asarray(el, float)):
            k = int(np.flatnonzero(np.isclose(model.elevation_deg, e))[0])
            for sector in LOBE_SECTORS_DEG:
                c = float(sector_median_db(np.asarray(car)[:, j], az, sector))
                m = float(sector_median_db(model.median_dbsm[:, k], model.azimuth_deg, sector))
                d = c - m
                verdict = ("inside" if abs(d) <= half else
                           f"{'over' if d > 0 else 'under'} by {abs(d) - half:.1f} dB")
                lines.append(f"| {name} | {e:g} | {sector} | {c:.1f} | {m:.1f} ({m - half:.1f} "
                             f"to {m + half:.1f}) | {verdict} |")
    return "\n".join(lines) + "\n"
