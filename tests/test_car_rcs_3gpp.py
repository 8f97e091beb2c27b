"""The 3GPP TR 38.901 vehicle RCS model (raysim.studies.car_rcs_3gpp).

The model is evaluated by Sionna RT's ``TR38901RCS``; these tests check the angle mapping
on the lobe centres, eq. 7.9.2-3 written out here, the 5-95 % band against Sionna's own
draws of ``sigma_S``, and the verdicts of the study's per-sector table. The sedan is
compared with the model on the study's full sweep (docs/cars.md), not here: a sweep
coarse enough for a test fixes a sector's median no better than the model's spread.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

#: Float32 evaluation (Dr.Jit's ``mi.Float``) of a dB value near 20 dBsm [dB].
FLOAT32_DB_TOL = 1e-3
#: Draws of ``sigma_S`` for the band check; the standard error of the 5 % quantile is
#: ``s sqrt(p (1 - p) / N) / phi(z_p)``: 0.05 dB for s = 3.41 dB, N = 20 000.
SIGMA_S_DRAWS = 20_000
#: Five standard errors of the 5 and 95 % quantiles of the draws [dB].
QUANTILE_TOL_DB = 0.25
#: Five standard errors of the draws' linear mean (lognormal, deviation 0.92 for
#: s = 3.41 dB: ``sqrt(exp((s ln10 / 10)^2) - 1)``).
LINEAR_MEAN_TOL = 5 * 0.92 / math.sqrt(SIGMA_S_DRAWS)


def _oracle_db(theta_deg: float, phi_deg: float, lobes, k1: float, k2: float) -> float:
    """Eq. 7.9.2-3 at bistatic angle 0 (``-k1 sin(0) + 5 lg cos 0 = 0``), the lobe picked
    by its zenith and azimuth ranges (Table 7.9.2.1-4), written out from the table."""
    for lobe in lobes:
        t_lo, t_hi = lobe.theta_range
        p_lo, p_hi = lobe.phi_range
        in_theta = t_lo <= theta_deg < t_hi or (t_hi == 180.0 and theta_deg == 180.0)
        in_phi = (p_hi - p_lo >= 360.0) or ((phi_deg - p_lo) % 360.0 < p_hi - p_lo)
        if not (in_theta and in_phi):
            continue
        v = -min(12 * ((theta_deg - lobe.theta_center) / lobe.theta_3db) ** 2, lobe.sigma_max)
        h = 0.0
        if lobe.phi_center is not None:
            off = (phi_deg - lobe.phi_center + 180.0) % 360.0 - 180.0
            h = -min(12 * (off / lobe.phi_3db) ** 2, lobe.sigma_max)
        return max(lobe.g_max - min(-(v + h), lobe.sigma_max), lobe.g_max - lobe.sigma_max)
    raise AssertionError(f"no lobe for theta {theta_deg}, phi {phi_deg}")


@pytest.mark.sionna
def test_lobe_centres_give_g_max(rt_backend):
    """Aspect and elevation of each lobe's centre (theta = 90 - el, phi = az) give its
    peak G_max of Table 7.9.2.1-4: front (nose, 18.25 deg up) 15.52, left and right
    (broadside) 20.75, back (tail) 14.56, roof (from above) 21.26 dBsm."""
    from raysim.studies.car_rcs_3gpp import tr38901_parameters, tr38901_vehicle_rcs

    params = tr38901_parameters()
    assert params.dimensions == (5.0, 2.0, 1.6)
    names = set()
    for lobe in params.lobes:
        az = 0.0 if lobe.phi_center is None else lobe.phi_center
        r = tr38901_vehicle_rcs([az], [90.0 - lobe.theta_center])
        assert r.mean_dbsm[0, 0] == pytest.approx(lobe.g_max, abs=FLOAT32_DB_TOL), lobe.name
        names.add(lobe.name)
    assert names == {"front", "left", "back", "right", "roof"}
    # the nose is the front lobe, not the back one (a sign error of x would swap them)
    front = next(lb for lb in params.lobes if lb.name == "front")
    back = next(lb for lb in params.lobes if lb.name == "back")
    r = tr38901_vehicle_rcs([0.0, 180.0], [90.0 - front.theta_center])
    assert r.mean_dbsm[0, 0] == pytest.approx(front.g_max, abs=FLOAT32_DB_TOL)
    assert r.mean_dbsm[1, 0] < back.g_max - 0.5


@pytest.mark.sionna
def test_model_is_eq_7_9_2_3(rt_backend):
    """Sionna's evaluation on a grid of aspects and elevations (the lobes' boundaries at
    45 and 135 deg aspect and 60 deg elevation left out: there two lobes' floors differ
    by 0.01 dB and float32 rounding picks either) equals eq. 7.9.2-3 written out."""
    from raysim.studies.car_rcs_3gpp import (
        model_angles_deg,
        tr38901_parameters,
        tr38901_vehicle_rcs,
    )

    params = tr38901_parameters()
    az = np.array([a for a in np.arange(-180.0, 181.0, 7.5) if abs(a) not in (45.0, 135.0)])
    el = np.array([-20.0, 0.0, 10.0, 30.0, 45.0, 59.0, 61.0, 75.0, 90.0])
    r = tr38901_vehicle_rcs(az, el)
    assert r.mean_dbsm.shape == (az.size, el.size)
    for i, a in enumerate(az):
        for j, e in enumerate(el):
            theta, phi = model_angles_deg(a, e)
            want = _oracle_db(float(theta), float(phi), params.lobes, params.k1, params.k2)
            assert r.mean_dbsm[i, j] == pytest.approx(want, abs=FLOAT32_DB_TOL), (a, e)
    # mirror symmetry of the car: aspect a and -a (left and right lobes) are equal
    for i, a in enumerate(az):
        k = np.flatnonzero(az == -a)
        if a > 0 and k.size:
            assert r.mean_dbsm[i] == pytest.approx(r.mean_dbsm[k[0]], abs=FLOAT32_DB_TOL), a


@pytest.mark.sionna
def test_band_matches_sionnas_draws(rt_backend):
    """The 5-95 % band (and the median) of sigma_S, from its Gaussian in dB with mean
    -ln(10)/20 s^2, equal the quantiles of Sionna's own draws (random_sigma_s) over
    many directions, and the draws' linear mean is 1 (eq. 7.9.2-1)."""
    import mitsuba as mi
    from sionna.rt.rcs.tr38901 import TR38901RCS

    from raysim.studies.car_rcs_3gpp import (
        BAND_PROBABILITIES,
        sigma_s_quantile_db,
        tr38901_parameters,
    )

    params = tr38901_parameters()
    assert params.sigma_s_db == pytest.approx(3.41)
    rcs = TR38901RCS(params.lobes, k1=params.k1, k2=params.k2,
                     sigma_s_std_db=params.sigma_s_db, random_sigma_s=True)
    u = np.random.default_rng(11).normal(size=(3, SIGMA_S_DRAWS))
    u /= np.linalg.norm(u, axis=0)
    k_s = mi.Vector3f(*(mi.Float(c) for c in u))
    draws = np.array(rcs.sigma_s_db(-k_s, k_s, seed=5), float)
    for p in (*BAND_PROBABILITIES, 0.5):
        want = sigma_s_quantile_db(p, params.sigma_s_db)
        assert np.quantile(draws, p) == pytest.approx(want, abs=QUANTILE_TOL_DB), p
    assert np.mean(10 ** (draws / 10)) == pytest.approx(1.0, abs=LINEAR_MEAN_TOL)


def test_bad_angles_refused():
    from raysim.studies.car_rcs_3gpp import sector_median_db, tr38901_vehicle_rcs

    with pytest.raises(ValueError, match="elevation"):
        tr38901_vehicle_rcs([0.0], [95.0])
    with pytest.raises(ValueError, match="finite"):
        tr38901_vehicle_rcs([float("nan")], [0.0])
    with pytest.raises(ValueError, match="sector"):
        sector_median_db(np.zeros(3), [0.0, 10.0, 20.0], "roof")
    with pytest.raises(ValueError, match="no aspect"):
        sector_median_db(np.zeros(3), [0.0, 10.0, 20.0], "back")


@pytest.mark.sionna
def test_table_has_the_model_at_every_elevation(rt_backend):
    """The study's table carries the model's mean and 5-95 % band on every row."""
    from raysim.studies.car_rcs import MEASURED_DBSM, CarRcs, table_markdown
    from raysim.studies.car_rcs_3gpp import tr38901_vehicle_rcs

    az = np.arange(0.0, 181.0, 2.0)
    el = np.array([0.0, 30.0, 45.0, 60.0])
    ones = np.ones((len(az), len(el)))
    model = tr38901_vehicle_rcs(az, el)
    rows = table_markdown({"m": CarRcs(az, el, ones, ones, 0.0)}, model=model).splitlines()[2:]
    assert len(rows) == len(MEASURED_DBSM) * len(el)
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        i = int(np.flatnonzero(az == float(cells[1]))[0])
        j = int(np.flatnonzero(el == float(cells[2]))[0])
        assert cells[6] == (f"{model.mean_dbsm[i, j]:.1f} ({model.low_dbsm[i, j]:.1f} to "
                            f"{model.high_dbsm[i, j]:.1f})")
    assert model.high_dbsm[0, 0] - model.mean_dbsm[0, 0] == pytest.approx(4.27, abs=0.01)
    assert model.mean_dbsm[0, 0] - model.low_dbsm[0, 0] == pytest.approx(6.95, abs=0.01)


def test_sector_table_verdicts():
    """A car flat at the model's mean is inside the band (the mean is 1.34 dB over the
    median, the band 5.61 dB either side of it); 10 dB higher it is over by
    10 + 1.34 - 5.61 = 5.73 dB; 10 dB lower, under by 10 - 1.34 - 5.61 = 3.05 dB."""
    from raysim.studies.car_rcs_3gpp import VehicleModelRcs, sector_table_markdown

    az = np.arange(0.0, 181.0, 2.0)
    el = np.array([0.0, 30.0])
    model = VehicleModelRcs(az, el, np.full((az.size, el.size), 10.0), 3.41)
    verdicts = {}
    for name, db in (("flat", 10.0), ("high", 20.0), ("low", 0.0)):
        rows = sector_table_markdown({name: (az, el, np.full((az.size, el.size), db))}, model)
        rows = rows.splitlines()[2:]
        assert len(rows) == 3 * el.size
        verdicts[name] = {[c.strip() for c in row.strip("|").split("|")][5] for row in rows}
    assert verdicts == {"flat": {"inside"}, "high": {"over by 5.7 dB"},
                        "low": {"under by 3.1 dB"}}
