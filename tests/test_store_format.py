"""Frame stores a user can open anywhere: consolidated metadata, coordinate values, CF units,
a time epoch; stores of the previous layout still open."""

from __future__ import annotations

import re
import warnings
from datetime import datetime

import numpy as np
import pytest
import xarray as xr
import zarr

from raysim.io import storage
from raysim.pipeline.run import render, render_dataset
from raysim.scenario import scenario_from_case

SMALL = {"radar.num_chirps": 16, "array.nx": 2, "array.ny": 2,
         "radar.chirp_duration_s": 12.8e-6, "imu.preset": "tactical", "imu.rate_hz": 20000.0}

#: UDUNITS-2 symbols the stores may use (SI base / derived units and the dimensionless "1").
UDUNITS_SYMBOLS = {"m", "s", "rad", "V", "W", "Hz", "kg", "K", "A", "1"}


def udunits_ok(units: str) -> bool:
    """Whether ``units`` parses as UDUNITS-2: products of ``symbol[integer exponent]``
    separated by spaces (``m s-2``, ``rad s-1``, ``1``), or ``<unit> since <ISO instant>``."""
    m = re.fullmatch(r"(seconds|s|days|hours|minutes) since (\S+)", units)
    if m:
        try:
            datetime.fromisoformat(m.group(2).replace("Z", "+00:00"))
        except ValueError:
            return False
        return True
    terms = units.split(" ")
    return bool(terms) and all(
        (mm := re.fullmatch(r"([A-Za-z]+|1)(-?[0-9]+)?", t)) and mm.group(1) in UDUNITS_SYMBOLS
        for t in terms)


def test_udunits_table_rejects_what_udunits_rejects():
    for good in ("m", "rad s-1", "m s-2", "1", "V", "seconds since 1970-01-01T00:00:00Z"):
        assert udunits_ok(good), good
    for bad in ("sqrt(W)", "rad/s^2", "m/s^2", "deg/s", "", "seconds since yesterday"):
        assert not udunits_ok(bad), bad


@pytest.fixture(scope="module")
def scenario():
    """Pitch case, small radar: 3 frames x 16 chirps x 4 channels x 128 samples."""
    return scenario_from_case("rotation_y").with_values({**SMALL, "frames": 3})


@pytest.fixture(scope="module")
def store(scenario, tmp_path_factory):
    """A store rendered in two appends (1 frame, then 2)."""
    path = tmp_path_factory.mktemp("fmt") / "s.zarr"
    render(scenario, path, max_frames=1)
    render(scenario, path)
    return path


def test_plain_open_zarr_opens_without_warning(store):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ds = xr.open_zarr(store)
    assert ds.sizes["frame"] == 3 and ds.attrs["frames_complete"] == 3
    meta = zarr.open_group(str(store), mode="r").metadata
    assert meta.consolidated_metadata is not None          # consolidated after the last append
    assert meta.consolidated_metadata.metadata["if_data"].shape[0] == 3


def test_coordinates_have_values(store):
    ds = xr.open_zarr(store)
    assert ds["vector"].values.tolist() == ["x", "y", "z"]
    assert ds["euler"].values.tolist() == ["roll", "pitch", "yaw"]
    assert ds["pose_attitude"].sel(euler="pitch").dims == ("frame", "chirp")
    assert ds["tx_position"].sel(vector="z").shape == (4,)
    ref = storage.open_store(store)
    np.testing.assert_array_equal(ds["sample"].values, ref["fast_time"].values)
    assert ds["sample"].attrs["units"] == "s"
    assert ds["sample"].values[1] == pytest.approx(1.0 / ref.attrs["radar_sample_rate_hz"])
    # every channel: its transmit and receive element, consistent with the positions
    tx_i, rx_i = ds["tx_index"].values, ds["rx_index"].values
    for pos, idx in ((ref["tx_position"].values, tx_i), (ref["rx_position"].values, rx_i)):
        for i in np.unique(idx):
            assert np.ptp(pos[idx == i], axis=0).max() == 0.0          # same element
        assert len(np.unique(idx)) == len(np.unique(pos, axis=0))       # distinct elements
    assert ds["channel_label"].values.tolist() == [
        f"tx{t} rx{r}" for t, r in zip(tx_i, rx_i, strict=True)]
    assert ds["if_data"].isel(channel=np.flatnonzero(tx_i == tx_i[0])).sizes["channel"] >= 1


def test_cf_conventions_and_units(store):
    ds = xr.open_zarr(store, decode_times=False)
    assert ds.attrs["Conventions"] == "CF-1.10"
    for name, var in ds.variables.items():
        if var.dtype.kind in "OTU":         # labels: CF gives strings no units
            continue
        assert "units" in var.attrs, name
        assert udunits_ok(var.attrs["units"]), (name, var.attrs["units"])
    assert ds["imu_gyro"].attrs["units"] == "rad s-1"
    assert ds["imu_accel"].attrs["units"] == "m s-2"


def test_time_epoch_aligns_frames_with_a_clock(store, scenario, tmp_path):
    ds = xr.open_zarr(store)                # CF decoding: chirp times become datetimes
    epoch = ds.attrs["time_epoch_utc"]
    assert epoch == "1970-01-01T00:00:00Z"
    assert ds["chirp_time"].dtype.kind == "M"
    seconds = storage.open_store(store)["chirp_time"].values      # float seconds since epoch
    back = (ds["chirp_time"].values - np.datetime64("1970-01-01T00:00:00")) / np.timedelta64(
        1, "ns") * 1e-9
    np.testing.assert_allclose(back, seconds, rtol=0, atol=1e-9)
    # another epoch: the same float seconds, decoded relative to it
    mem = render_dataset(scenario.with_values({"frames": 1}))
    ds2 = storage.frames_to_dataset(storage.dataset_to_frames(mem), epoch="2024-05-01T12:00:00Z")
    assert ds2["chirp_time"].attrs["units"] == "seconds since 2024-05-01T12:00:00Z"
    storage.write_store(tmp_path / "e.zarr", ds2)
    t0 = xr.open_zarr(tmp_path / "e.zarr")["chirp_time"].values[0, 0]
    assert t0 == np.datetime64("2024-05-01T12:00:00")
    with pytest.raises(ValueError, match="ISO 8601"):
        storage.frames_to_dataset(storage.dataset_to_frames(mem), epoch="yesterday")
    with pytest.raises(ValueError, match="UTC"):
        storage.frames_to_dataset(storage.dataset_to_frames(mem), epoch="2024-05-01T12:00+02:00")


def test_range_axis(store):
    ds = storage.open_store(store)
    r = storage.range_axis(ds)
    assert r.dims == ("range",) and r.attrs["units"] == "m"
    assert r.sizes["range"] == ds.sizes["sample"]                 # complex sampling
    assert r.values[1] == pytest.approx(ds.attrs["radar_range_resolution_m"])


def test_old_layout_still_opens(scenario, tmp_path):
    """A store of raysim_format 1: no consolidated metadata, no coordinate values, old units."""
    ds = render_dataset(scenario)
    old = ds.drop_vars(["vector", "euler", "sample", "tx_index", "rx_index", "channel_label"])
    old.attrs = {k: v for k, v in old.attrs.items()
                 if k not in ("Conventions", "time_epoch_utc", "title", "source")}
    old.attrs.update(raysim_format=1, frames_complete=3)
    old["chirp_time"].attrs = {"units": "s", "long_name": "chirp start time"}
    old["if_data"].attrs["units"] = "sqrt(W)"
    path = tmp_path / "old.zarr"
    old.to_zarr(path, mode="w", consolidated=False, write_empty_chunks=True)
    back = storage.open_store(path)
    assert back.sizes["frame"] == 3 and "vector" not in back.coords
    np.testing.assert_array_equal(back["if_data"].values, ds["if_data"].values)
    fr = storage.frame_from_dataset(back, 1)
    np.testing.assert_array_equal(fr.chirp_times, ds["chirp_time"].values[1])


def test_scenario_epoch_reaches_the_store(tmp_path):
    """``time_epoch_utc`` of a scenario file dates the stored chirp times."""
    import pandas as pd
    import xarray as xr

    from raysim.pipeline.run import render
    from raysim.scenario import scenario_from_case

    scen = scenario_from_case("stationary").with_values(
        {"radar.num_chirps": 8, "array.nx": 2, "array.ny": 2,
         "time_epoch_utc": "2026-05-01T12:00:00Z"})
    render(scen, tmp_path / "e.zarr")
    ds = xr.open_zarr(tmp_path / "e.zarr")
    assert ds.attrs["time_epoch_utc"] == "2026-05-01T12:00:00Z"
    assert pd.Timestamp(ds["chirp_time"].values[0, 0]) == pd.Timestamp("2026-05-01T12:00:00")
    with pytest.raises(ValueError, match="time_epoch_utc"):
        scen.with_values({"time_epoch_utc": "yesterday"})
    with pytest.raises(ValueError, match="UTC"):
        scen.with_values({"time_epoch_utc": "2026-05-01T12:00:00+02:00"})
