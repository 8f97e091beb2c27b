"""The public ``raysim`` namespace (lazy entry points) and ``to_xarray()`` of labelled results."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import raysim
from raysim.processing.maps import Map
from raysim.radar.arrays import tdm_mimo
from raysim.radar.config import RadarConfig
from raysim.synthesis.frame import RadarFrame

ROOT = Path(__file__).resolve().parents[1]


def test_import_raysim_is_cheap_and_entry_points_resolve():
    """``import raysim`` loads no submodule (nor NumPy); each entry point is its module's."""
    code = ("import sys, raysim; "
            "print(sorted(m for m in sys.modules if m.startswith('raysim') or m == 'numpy'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, check=True)
    assert out.stdout.strip() == "['raysim']"
    assert set(raysim.__all__) == {"__version__", *raysim._ENTRY_POINTS}
    import importlib

    for name, module in raysim._ENTRY_POINTS.items():
        assert getattr(raysim, name) is getattr(importlib.import_module(module), name), name
    assert {"Scenario", "load_scenario", "RadarConfig", "VirtualArray", "RadarFrame", "Map",
            "render", "evaluate", "estimate_motion"} <= set(raysim.__all__)
    assert set(raysim.__all__) <= set(dir(raysim))
    assert "Entry points" in raysim.__doc__


def test_unknown_attribute_names_the_value():
    with pytest.raises(AttributeError, match="no attribute 'Scenaro'; entry points: .*Scenario"):
        raysim.Scenaro    # noqa: B018


def test_map_to_xarray():
    rng = np.random.default_rng(0)
    values = rng.random((5, 3))
    m = Map(values, ("range", "doppler"),
            {"range": np.linspace(1.0, 5.0, 5), "doppler": np.array([-1.0, 0.0, 1.0])})
    da = m.to_xarray()
    assert da.dims == ("range", "doppler") and da.name == "power"
    np.testing.assert_array_equal(da.values, values)
    assert da["range"].attrs["units"] == "m" and da["doppler"].attrs["units"] == "m s-1"
    back = Map(da.values, tuple(da.dims), {d: da[d].values for d in da.dims})
    assert back.peak() == m.peak()
    for d in m.dims:
        np.testing.assert_array_equal(da[d].values, m.coords[d])
    ae = Map(values.T, ("azimuth", "elevation"),
             {"azimuth": np.deg2rad([-10.0, 0.0, 10.0]), "elevation": np.zeros(5)}).to_xarray()
    assert ae["azimuth"].attrs["units"] == "rad" and ae["elevation"].attrs["units"] == "rad"
    # a map without coordinates has plain dimensions
    assert Map(values, ("range", "doppler")).to_xarray().coords == {}


@pytest.mark.parametrize("complex_sampling", [True, False])
def test_radar_frame_to_xarray(complex_sampling):
    cfg = RadarConfig(num_chirps=4, chirp_duration=6.4e-6, sample_rate=10e6,
                      complex_sampling=complex_sampling)
    lam = cfg.wavelength
    arr = tdm_mimo(np.array([[0.0, 0.0, 0.0], [2 * lam, 0.0, 0.0]]),
                   np.array([[0.0, 0.0, 0.0], [lam / 2, 0.0, 0.0]]))
    shape = (cfg.num_chirps, arr.num_channels, cfg.num_samples)
    rng = np.random.default_rng(1)
    data = rng.standard_normal(shape) + (1j * rng.standard_normal(shape) if complex_sampling
                                         else 0.0)
    data = data.astype(np.complex64 if complex_sampling else np.float32)
    times = np.arange(cfg.num_chirps) * cfg.chirp_interval + 0.5
    fr = RadarFrame(data, cfg, arr, times, lever_arm=np.array([0.0, 0.0, 0.1]), frame_index=3)
    da = fr.to_xarray()
    assert da.dims == ("chirp", "channel", "sample") and da.name == "if_data"
    assert da.dtype == data.dtype
    np.testing.assert_array_equal(da.values, data)
    np.testing.assert_array_equal(da["chirp_time"].values, times)
    np.testing.assert_array_equal(da["sample"].values, fr.fast_time)
    np.testing.assert_array_equal(da["tx_slot"].values, arr.tx_slot)
    virt = np.stack([da[f"virtual_{a}"].values for a in "xyz"], axis=-1)
    np.testing.assert_array_equal(virt, arr.virtual_positions)
    assert da["chirp_time"].attrs["units"] == "s" and da["virtual_x"].attrs["units"] == "m"
    assert da.attrs["frame_index"] == 3 and da.attrs["lever_arm_m"] == [0.0, 0.0, 0.1]
    back = RadarFrame(da.values, cfg, arr, da["chirp_time"].values,
                      lever_arm=np.asarray(da.attrs["lever_arm_m"]),
                      frame_index=da.attrs["frame_index"])
    np.testing.assert_array_equal(back.data, fr.data)
