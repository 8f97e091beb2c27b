"""The detailed car's RCS against published 77 GHz measurements, and its scattering centres.

Full sweep and table: ``python -m raysim.studies.car_rcs`` (docs/cars.md); here a few
aspects, each averaged over -2, 0, +2 deg as the table is.
"""

from __future__ import annotations

import numpy as np

#: Aspect samples of one +-2.5 deg average [deg].
AVERAGE_OFFSETS_DEG = (-2.0, 0.0, 2.0)
#: Facet of the centre check [m] (the drone view is converged there: 17 centres at 5 cm
#: and at 10 cm, docs/cars.md).
CENTRES_FACET = 0.1
#: From the drone (45 deg elevation, 30 deg aspect) at least this many centres carry 90 %
#: of the power and none more than MAX_TOP_SHARE (measured 17 and 34 %; the simple car:
#: 3 centres, the strongest 68 %).
MIN_CENTRES_90 = 8
MAX_TOP_SHARE = 0.5


def _averaged_dbsm(parts, aspect: float, elevation: float) -> float:
    from raysim.studies.car_rcs import car_rcs

    r = car_rcs(parts, [aspect + d for d in AVERAGE_OFFSETS_DEG], [elevation])
    return float(10 * np.log10(r.po_m2.mean()))


def test_sedan_rcs_within_measured_ranges(rt_backend):
    """Ground level, 50 m, VV, PO + SBR of the default sedan: broadside and 60 deg aspect
    (+-2 deg averages) inside the published ranges (raysim.studies.car_rcs.MEASURED_DBSM,
    recalled, indicative): measured 25.6 and 10.1 dBsm in the full sweep."""
    from raysim.echoes.po.sedan import sedan_parts
    from raysim.studies.car_rcs import MEASURED_DBSM

    parts = sedan_parts()
    for aspect in (90, 60):
        db = _averaged_dbsm(parts, aspect, 0.0)
        print(f"sedan aspect {aspect} deg: {db:.1f} dBsm, measured {MEASURED_DBSM[aspect]}")
        lo, hi = MEASURED_DBSM[aspect]
        assert lo <= db <= hi, aspect


def test_drone_view_is_many_centres(rt_backend):
    """From 45 deg elevation at 30 deg aspect no single flash carries the car."""
    from raysim.studies.car_rcs import car_model, scattering_centres

    sedan = scattering_centres(car_model("sedan", CENTRES_FACET), 30.0, 45.0)
    simple = scattering_centres(car_model("simple"), 30.0, 45.0)
    print(f"centres carrying 90 %: sedan {sedan['n90']} (top "
          f"{sedan['centres'][0]['share']:.2f}), simple {simple['n90']} (top "
          f"{simple['centres'][0]['share']:.2f})")
    assert sedan["n90"] >= MIN_CENTRES_90
    assert sedan["centres"][0]["share"] < MAX_TOP_SHARE
    assert sedan["n90"] > simple["n90"]
    parts = {c["part"] for c in sedan["centres"]}
    assert len(parts) >= 2                      # body and details (mirrors, bumpers, ...)
