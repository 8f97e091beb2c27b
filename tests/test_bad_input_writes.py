"""Atomic writes and interrupted runs: nothing half-written may stay on disk.

Part of the bad-input catalogue (tests/test_bad_input*.py): every writer of
raysim either leaves the complete new file or the previous one, never a
partial file or a temporary behind.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from bad_input_common import imu_samples as _imu_samples

from raysim.io.files import MANIFEST


def _listing(folder: Path) -> list[str]:
    """Names in ``folder`` without raysim's manifest of its outputs."""
    return sorted(n for n in os.listdir(folder) if n != MANIFEST)


# --------------------------------------------------------------- atomic writes
def test_atomic_write_interrupted_leaves_nothing(tmp_path):
    """A write interrupted half-way leaves neither the file nor a temporary behind."""
    from raysim.studies.stability import atomic_write

    target = tmp_path / "map.json"

    def half(p: Path) -> None:
        p.write_text('{"half": ')
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(target, half)
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_interrupted_keeps_old_file(tmp_path):
    from raysim.io.files import atomic_write_text
    from raysim.studies.stability import atomic_write

    target = tmp_path / "map.json"
    atomic_write_text(target, "old")

    def half(p: Path) -> None:
        p.write_text("new, but half")
        raise OSError("disk full")

    with pytest.raises(OSError):
        atomic_write(target, half)
    assert target.read_text() == "old"
    assert _listing(tmp_path) == ["map.json"]


def test_interrupted_stability_run_keeps_finished_maps(tmp_path, monkeypatch):
    """An interrupted ``raysim stability`` keeps the maps it finished and resumes from them."""
    from raysim.studies import stability
    from raysim.studies.stability import runner

    calls = []
    real = runner.run_map

    def fake_run_map(name, **kw):
        calls.append(name)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(name, **kw)

    small = {k: stability.MAPS[k] for k in ("lever_arm", "clock")}
    monkeypatch.setattr(runner, "MAPS", small)
    monkeypatch.setattr(runner, "run_map", fake_run_map)
    monkeypatch.setattr(runner, "evaluate", _cheap_evaluate)
    with pytest.raises(KeyboardInterrupt):
        stability.write_stability(tmp_path, quick=True, progress=False, executor="serial")
    assert _listing(tmp_path) == ["lever_arm.json", "lever_arm.nc", "lever_arm.png", "points"]
    assert not [p for p in tmp_path.rglob("*")                             # no partial files
                if p.name.startswith(".") and p.name != MANIFEST]
    for rec in (tmp_path / "points").rglob("*.json"):
        json.loads(rec.read_text())                                        # complete records
    calls.clear()
    monkeypatch.setattr(runner, "run_map", real)
    stability.write_stability(tmp_path, quick=True, progress=False, executor="serial")
    assert (tmp_path / "clock.nc").exists() and (tmp_path / "summary.json").exists()


def _cheap_evaluate(point, chains=("none", "paper", "paper:published", "exact"), **_):
    """Stand-in for :func:`raysim.studies.stability.evaluate` (file handling only)."""
    rec = {"pseudo_velocity_mps": 0.01, "pseudo_velocity_bins": 0.08,
           "doppler_width_hz": 94.0, "angle_error_worst_deg": 0.1, "angle_error_deg": 0.1,
           "map_angle_error_deg": 0.1, "entropy_ae_nats": 3.5}
    out = {c: dict(rec) for c in chains}
    out["warnings"] = []
    out["strapdown"] = "stub"
    return out


# ----------------------------------------------- interrupted writes of other writers
def test_storage_atomic_write_interrupted_at_rename(tmp_path, monkeypatch):
    """raysim.io.storage writes aside and renames: an interruption leaves no file at all."""
    from raysim.io import storage

    def boom(*_a, **_k):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        storage.atomic_write_text(tmp_path / "points.json", '{"a": 1}')
    assert list(tmp_path.iterdir()) == []


def test_stability_netcdf_interrupted_at_rename(tmp_path, monkeypatch):
    import xarray as xr

    from raysim.studies.stability import write_netcdf

    ds = xr.Dataset({"fail": (("x",), np.array([True, False]))}, coords={"x": [0.0, 1.0]})

    def boom(*_a, **_k):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        write_netcdf(ds, tmp_path / "map.nc")
    assert list(tmp_path.iterdir()) == []


def _interrupt_writers(monkeypatch, which: str) -> None:
    """Make ``which`` writer fail half-way through its file."""
    from raysim.io import imu_log, ti_dca1000

    if which == "imu":
        calls = []

        def interrupted_repr(v):
            calls.append(1)
            if len(calls) > 300:
                raise KeyboardInterrupt
            return repr(v)

        monkeypatch.setattr(imu_log, "repr", interrupted_repr, raising=False)
    else:
        class HalfWritten(np.ndarray):
            def tofile(self, fid, *a, **k):
                np.asarray(self).ravel()[: self.size // 2].tofile(fid)
                raise OSError("disk full")

        real = np.ascontiguousarray

        class NumpyProxy:
            def __getattr__(self, name):
                return getattr(np, name)

            @staticmethod
            def ascontiguousarray(a, dtype=None):
                return real(a, dtype=dtype).view(HalfWritten)

        monkeypatch.setattr(ti_dca1000, "np", NumpyProxy())


@pytest.mark.parametrize("which", ["imu", "dca1000"])
def test_interrupted_writer_leaves_no_partial_file(tmp_path, monkeypatch, which):
    from raysim.io import imu_log, ti_dca1000
    from raysim.io.ti_dca1000 import Dca1000Format

    _interrupt_writers(monkeypatch, which)
    with pytest.raises((KeyboardInterrupt, OSError)):
        if which == "imu":
            imu_log.write_imu_csv(tmp_path / "out", _imu_samples(np.arange(200) * 1e-3))
        else:
            fmt = Dca1000Format(num_samples=16, slot_interval=60e-6, num_rx=4, num_tx=1,
                                num_loops=4)
            ti_dca1000.write_dca1000(tmp_path / "out", np.ones((2, 4, 4, 16), np.complex64), fmt)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("which", ["imu", "dca1000"])
def test_interrupted_writer_keeps_existing_file(tmp_path, monkeypatch, which):
    """An interrupted IMU-log or capture write leaves the previous file byte for byte and no
    temporary file; the next complete write replaces it."""
    from raysim.io import imu_log, ti_dca1000
    from raysim.io.ti_dca1000 import Dca1000Format

    fmt = Dca1000Format(num_samples=16, slot_interval=60e-6, num_rx=4, num_tx=1, num_loops=4)
    if which == "imu":
        target = tmp_path / "imu.csv"

        def write(n):
            return imu_log.write_imu_csv(target, _imu_samples(np.arange(n) * 1e-3))
    else:
        target = tmp_path / "adc.bin"

        def write(n):
            return ti_dca1000.write_dca1000(target, np.full((n, 4, 4, 16), 3 + 1j, np.complex64),
                                            fmt)
    write(2)
    old = target.read_bytes()
    with monkeypatch.context() as mp:
        _interrupt_writers(mp, which)
        with pytest.raises((KeyboardInterrupt, OSError)):
            write(200)
    assert target.read_bytes() == old
    assert _listing(tmp_path) == [target.name]
    write(3)
    assert len(target.read_bytes()) > len(old)
    assert _listing(tmp_path) == [target.name]
