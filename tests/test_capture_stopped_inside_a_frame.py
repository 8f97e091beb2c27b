"""A DCA1000 capture stopped by hand ends inside a frame: refused by default, naming the
option; with ``--drop-incomplete`` its whole frames are read, exactly as from a capture
that stopped on a frame boundary, and the dropped bytes are noted."""

from __future__ import annotations

import contextlib
import io
import re

import numpy as np
import pytest
import xarray as xr

from raysim.cli import main
from raysim.io.mmwave_config import parse_sdk_cfg, sdk_cfg_text
from raysim.io.ti_dca1000 import check_capture_fits, write_dca1000
from raysim.radar.config import RadarConfig


@pytest.fixture
def capture(tmp_path):
    cfg = RadarConfig(num_chirps=4, num_frames=3, num_tx_slots=1, sample_rate=2.5e6)
    # numFrames 0: frames until the capture is stopped
    text = re.sub(r"^(frameCfg \S+ \S+ \S+) 3 ", r"\1 0 ",
                  sdk_cfg_text(cfg, tx_order=(0,), rx_enabled=(0, 1, 2, 3)), flags=re.M)
    assert "frameCfg 0 0 4 0 " in text
    (tmp_path / "r.cfg").write_text(text)
    m = parse_sdk_cfg(text, board="xWR18xx")
    cube = np.random.default_rng(4).integers(-500, 500, (3, cfg.num_chirps, 4,
                                                         m.fmt.num_samples)) * (1 + 1j)
    whole = write_dca1000(tmp_path / "whole.bin", cube, m.fmt)
    cut = tmp_path / "cut.bin"
    cut.write_bytes(whole.read_bytes()[:-1000])      # stopped 1000 bytes before the end
    return tmp_path, m, whole, cut


def _run(tmp_path, cap, *extra):
    err = io.StringIO()
    out = tmp_path / f"{cap.stem}{len(extra)}.zarr"
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        rc = main(["compensate", str(cap), "--radar-config", str(tmp_path / "r.cfg"),
                   "--chain", "none", "--range-m", "0:5", "--az-deg", "-10:10:5", "--el-deg",
                   "0:0:1", "--no-progress", "--out", str(out), *extra])
    return rc, err.getvalue(), out


def test_a_capture_stopped_inside_a_frame_keeps_its_whole_frames(capture):
    tmp_path, m, whole, cut = capture
    rc, err, out = _run(tmp_path, cut)
    assert rc == 2 and "keeps its 2 whole frame(s) with --drop-incomplete" in err
    assert not out.exists()
    rc, err, out = _run(tmp_path, cut, "--drop-incomplete")
    assert rc == 0, err
    assert f"its last {m.fmt.bytes_per_frame - 1000} bytes are dropped" in err
    rc_ref, _, ref = _run(tmp_path, whole, "--frames", "0:2")
    assert rc_ref == 0
    got, want = xr.open_zarr(out), xr.open_zarr(ref)
    assert got.sizes["frame"] == 2
    np.testing.assert_array_equal(got["beams"].values, want["beams"].values)


def test_a_size_the_other_layout_fits_is_still_refused(capture):
    tmp_path, m, whole, _ = capture
    from dataclasses import replace

    four = replace(m.fmt, layout="4lane", num_rx=2)
    two = replace(four, layout="2lane")
    cube = np.random.default_rng(5).integers(-500, 500, (3, 4, 2, four.num_samples)) * (1 + 1j)
    path = write_dca1000(tmp_path / "two.bin", cube, two)     # 3 whole 2-lane frames
    with pytest.raises(ValueError, match=r"2lane layout"):
        check_capture_fits(path, four, drop_incomplete=True)
