"""System tier: the paper's cases, simulated, compensated with an ideal IMU, measured.

The exact rigid-body chain must restore the stationary metrics. The paper
chain's numbers are computed in the same run and only checked to be finite:
they are reported by ``raysim reproduce``, not claimed to be good.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.studies.reproduce import ReproductionSettings, run_case

#: Residual pseudo-velocity bound [Doppler bins].
PV_TOL_BINS = 0.05
#: Doppler -3 dB width relative to the stationary width.
WIDTH_RTOL = 0.02
#: Angle error bound at chirp 128 [deg].
ANGLE_TOL_DEG = 0.1
#: Accumulated azimuth-elevation entropy bound against the stationary map [nats].
ENTROPY_TOL = 0.05
#: Accumulated map peak bound from the true direction (yaw case) [deg].
PEAK_TOL_DEG = 0.25

SETTINGS = ReproductionSettings.quick()


@pytest.mark.parametrize("name", ["rotation_y", "yaw", "translation_y", "translation_z",
                                  "stationary"])
def test_exact_chain_restores_stationary_metrics(name):
    rows = {r["chain"]: r for r in run_case(name, imu="ideal", settings=SETTINGS,
                                            chains=("none", "paper", "exact"))}
    ex = rows["exact"]
    assert abs(ex["pseudo_velocity_bins"]) <= PV_TOL_BINS
    assert ex["doppler_width_hz"] == pytest.approx(ex["stationary_doppler_width_hz"],
                                                   rel=WIDTH_RTOL)
    assert ex["angle_error_deg"] <= ANGLE_TOL_DEG
    if name == "yaw":
        assert ex["frames"] == 20
        assert abs(ex["entropy_ae_nats"] - ex["stationary_entropy_ae_nats"]) <= ENTROPY_TOL
        err = math.hypot(ex["map_az_deg"] - 25.0, ex["map_el_deg"] - 25.0)
        assert err <= PEAK_TOL_DEG
        # without compensation the 20-frame map is visibly defocused
        assert rows["none"]["entropy_ae_nats"] > ex["entropy_ae_nats"] + 0.5
    if name != "stationary":
        unc = rows["none"]
        assert (abs(unc["pseudo_velocity_bins"]) > 1.0 or unc["angle_error_deg"] > 1.0
                or unc["doppler_width_hz"] > 1.2 * unc["stationary_doppler_width_hz"])
    for key in ("pseudo_velocity_mps", "doppler_width_hz", "angle_error_deg", "entropy_ae_nats"):
        assert all(np.isfinite(r[key]) for r in rows.values())
