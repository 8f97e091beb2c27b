"""Frame storage: bit-exact Zarr and NetCDF round trips, resumable renders, atomic writes."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
import zarr

from raysim.io import storage
from raysim.pipeline.run import render, render_dataset
from raysim.pipeline.sources import render_frames
from raysim.scenario import scenario_from_case

SMALL = {"radar.num_chirps": 32, "array.nx": 4, "array.ny": 4,
         "radar.chirp_duration_s": 12.8e-6, "imu.preset": "tactical", "imu.rate_hz": 20000.0}


@pytest.fixture(scope="module")
def scenario():
    """Pitch case on a small radar: 3 frames x 32 chirps x 16 channels x 128 samples."""
    return scenario_from_case("rotation_y").with_values({**SMALL, "frames": 3, "noise": True})


def assert_bit_exact(a: xr.Dataset, b: xr.Dataset) -> None:
    """Same variables, dims, dtypes, bytes and attributes."""
    assert set(a.variables) == set(b.variables)
    for name in a.variables:
        va, vb = a[name], b[name]
        assert va.dims == vb.dims, name
        assert va.dtype == vb.dtype, name
        if va.dtype == object:  # labels: compare the strings (bytes would be pointers)
            assert va.values.tolist() == vb.values.tolist(), name
        else:
            assert va.values.tobytes() == vb.values.tobytes(), name
        assert va.attrs.keys() == vb.attrs.keys(), name
    xr.testing.assert_identical(a, b)


def test_layout_follows_conventions(scenario):
    ds = render_dataset(scenario)
    assert ds["if_data"].dims == ("frame", "chirp", "channel", "sample")
    assert ds["if_data"].shape == (3, 32, 16, 128) and ds["if_data"].dtype == np.complex64
    # sqrt(W) as a UDUNITS unit: volts into 1 ohm
    assert ds["if_data"].attrs["units"] == "V" and "sqrt(W)" in ds["if_data"].attrs["comment"]
    assert ds["pose_attitude"].dims == ("frame", "chirp", "euler")
    assert ds["imu_gyro"].dims == ("imu_time", "vector")
    assert ds.attrs["radar_carrier_frequency_hz"] == 77e9
    # truth pose: pitch 10 deg at 20 Hz, sampled at the chirp start times
    t = ds["chirp_time"].values
    np.testing.assert_allclose(ds["pose_attitude"].values[..., 1],
                               np.deg2rad(10) * np.sin(2 * np.pi * 20 * t), atol=1e-12)
    fr = storage.frame_from_dataset(ds, 2)
    ref = render_frames(scenario)[2]
    assert fr.config == ref.config and fr.frame_index == 2
    np.testing.assert_array_equal(fr.data, ref.data)
    np.testing.assert_array_equal(fr.array.virtual_positions, ref.array.virtual_positions)


def test_zarr_round_trip_is_bit_exact(scenario, tmp_path):
    ds = render_dataset(scenario)
    storage.write_store(tmp_path / "a.zarr", ds)
    back = storage.open_store(tmp_path / "a.zarr")
    expected = ds.copy()
    expected.attrs["frames_complete"] = 3
    assert_bit_exact(back, expected)
    with pytest.raises(ValueError, match="already exists"):
        storage.write_store(tmp_path / "a.zarr", ds)


def test_zarr_chunks_never_span_frames(scenario, tmp_path):
    render(scenario, tmp_path / "c.zarr")
    arr = zarr.open_group(str(tmp_path / "c.zarr"), mode="r")["if_data"]
    assert arr.chunks[0] == 1 and arr.shape[0] == 3


def test_netcdf_round_trip_is_bit_exact(scenario, tmp_path):
    ds = render_dataset(scenario)
    storage.export_netcdf(ds, tmp_path / "a.nc")
    back = storage.read_netcdf(tmp_path / "a.nc")
    assert back["if_data"].dtype == np.complex64
    assert_bit_exact(back, ds)
    assert not list(tmp_path.glob(".*.tmp"))        # temporary file moved into place


def test_render_resumes_after_interruption(scenario, tmp_path):
    path = tmp_path / "r.zarr"
    first = render(scenario, path, max_frames=1)    # stops after frame 0
    assert (first.frames_rendered, storage.frames_complete(path)) == (1, 1)
    rest = render(scenario, path)
    assert (rest.frames_resumed, rest.frames_rendered) == (1, 2)
    whole = render_dataset(scenario)
    whole.attrs["frames_complete"] = 3
    assert_bit_exact(storage.open_store(path), whole)
    again = render(scenario, path)                  # nothing left to do
    assert again.frames_rendered == 0 and again.frames_resumed == 3


def test_interrupted_append_is_cut_back_and_resumed(scenario, tmp_path, monkeypatch):
    path = tmp_path / "i.zarr"
    render(scenario, path, max_frames=1)

    # an append that dies after writing the IF cube but before marking the frame complete
    real = storage.frames_to_dataset

    def crash_midway(frames, trajectory=None, **kw):
        ds = real(frames, trajectory, **kw)
        part = ds[["if_data"]]
        part = part.drop_vars([c for c in part.coords if "frame" not in part[c].dims])
        part.attrs = dict(zarr.open_group(str(path), mode="r").attrs)
        part.to_zarr(str(path), append_dim="frame", consolidated=False)
        raise KeyboardInterrupt

    monkeypatch.setattr(storage, "frames_to_dataset", crash_midway)
    with pytest.raises(KeyboardInterrupt):
        render(scenario, path)
    monkeypatch.undo()
    assert zarr.open_group(str(path))["if_data"].shape[0] == 2   # half-written frame on disk
    assert storage.frames_complete(path) == 1
    assert storage.open_store(path).sizes["frame"] == 1          # readers ignore it
    summary = render(scenario, path)
    assert (summary.frames_resumed, summary.frames_rendered) == (1, 2)
    whole = render_dataset(scenario)
    whole.attrs["frames_complete"] = 3
    assert_bit_exact(storage.open_store(path), whole)


def test_resume_refuses_a_different_scenario(scenario, tmp_path):
    path = tmp_path / "d.zarr"
    render(scenario, path, max_frames=1)
    other = scenario.with_values({"seed": 5})
    with pytest.raises(ValueError, match="different scenario"):
        render(other, path)
    assert render(other, path, overwrite=True).frames_rendered == 3
    assert json.loads(storage.open_store(path).attrs["scenario_json"])["seed"] == 5


def test_atomic_write_and_errors(tmp_path):
    target = tmp_path / "x.txt"
    storage.atomic_write_text(target, "one")
    storage.atomic_write_text(target, "two")
    assert target.read_text() == "two"
    assert [p.name for p in tmp_path.iterdir() if p.name != ".raysim-outputs"] == ["x.txt"]
    with pytest.raises(ValueError, match="not a Zarr store"):
        storage.open_store(tmp_path)
    with pytest.raises(ValueError, match="does not exist"):
        storage.read_netcdf(tmp_path / "none.nc")
    with pytest.raises(ValueError, match="frames is empty"):
        storage.frames_to_dataset([])
