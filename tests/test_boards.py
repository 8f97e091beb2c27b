"""TI boards: layouts by name, the ambiguous-configuration error, antenna files, lane checks."""

from __future__ import annotations

import json

import numpy as np
import pytest

from raysim.io.mmwave_config import parse_sdk_cfg, read_mmwave_config, sdk_cfg_text
from raysim.io.ti_boards import BOARDS, read_antenna_positions, resolve_board
from raysim.io.ti_dca1000 import Dca1000Format, check_capture_fits, write_dca1000
from raysim.radar.config import RadarConfig


def _cfg(tx_order, carrier=77e9, rx=(0, 1, 2, 3), frames=2):
    cfg = RadarConfig(carrier_frequency=carrier, num_chirps=4, num_frames=frames,
                      num_tx_slots=len(tx_order), sample_rate=2.5e6)
    return cfg, sdk_cfg_text(cfg, tx_order=tx_order, rx_enabled=rx)


def _half(m) -> np.ndarray:
    return np.round(m.array.virtual_positions[:, :2] / (m.config.center_wavelength / 2), 9)


def test_every_board_has_its_layout():
    assert set(BOARDS) == {"xWR14xx", "xWR16xx", "xWR18xx", "IWR6843ISK", "IWR6843AOP",
                           "IWR6843ODS"}
    lay = resolve_board("AWR1642", tx_order=(0, 1), rx_enabled=(0, 1, 2, 3),
                        start_freq_hz=77e9, wavelength=2.0)
    assert lay.name == "xWR16xx" and np.allclose(lay.tx[:, :2], [[0, 0], [4, 0]])  # 2 lambda
    ods = resolve_board("ods", tx_order=(0, 1, 2), rx_enabled=(0, 1, 2, 3),
                        start_freq_hz=60.5e9, wavelength=2.0)
    assert ods.name == "IWR6843ODS" and np.array_equal(ods.rx_phase, [1, -1, -1, 1])
    # TI's ODS_6m_default.cfg: antGeometry0 (-x), antGeometry1 (y) in lambda/2
    ag0 = np.array([0, 0, -1, -1, -2, -2, -3, -3, -2, -2, -3, -3])
    ag1 = np.array([0, -1, -1, 0, 0, -1, -1, 0, -2, -3, -3, -2])
    virt = (ods.tx[:, None, :2] + ods.rx[None, :, :2]).reshape(-1, 2)
    assert np.allclose(virt, np.column_stack([-ag0, ag1]))
    with pytest.raises(ValueError, match=r"board 'AWR2944' is not known.*xWR14xx"):
        resolve_board("AWR2944", tx_order=(0,), rx_enabled=(0,), start_freq_hz=77e9,
                      wavelength=1.0)


def test_ambiguous_configuration_names_the_candidates():
    _, text = _cfg((0, 1))
    with pytest.raises(ValueError, match=r"fits boards with different antenna layouts: "
                                         r"\['xWR14xx', 'xWR16xx', 'xWR18xx'\].*--board"):
        parse_sdk_cfg(text)
    m16 = parse_sdk_cfg(text, board="xWR16xx")
    assert np.array_equal(_half(m16), [[i, 0] for i in range(8)])
    m18 = parse_sdk_cfg(text, board="xWR18xx")
    assert np.array_equal(_half(m18)[4:], [[2, 1], [3, 1], [4, 1], [5, 1]])
    # TX0 + TX2 at 77 GHz: the xWR16xx has no TX2; the 14xx and 18xx agree
    m = parse_sdk_cfg(_cfg((0, 2))[1])
    assert m.board == "xWR14xx/xWR18xx"
    with pytest.raises(ValueError, match=r"xWR16xx has 2 transmitters"):
        parse_sdk_cfg(_cfg((0, 2))[1], board="xWR16xx")
    _, text60 = _cfg((0,), carrier=60.5e9)
    with pytest.raises(ValueError, match="IWR6843ISK.*IWR6843AOP.*IWR6843ODS"):
        parse_sdk_cfg(text60)
    with pytest.raises(ValueError, match=r"xWR18xx works in 76-81 GHz"):
        parse_sdk_cfg(text60, board="xWR18xx")
    aop = parse_sdk_cfg(text60, board="IWR6843AOP")
    assert np.array_equal(aop.channel_sign, [1, -1, 1, -1])


def test_board_sets_lanes_and_a_contradiction_is_refused():
    _, text = _cfg((0, 2, 1))
    assert parse_sdk_cfg(text, board="xWR14xx").fmt.layout == "4lane"
    assert parse_sdk_cfg(text, board="xWR18xx").fmt.layout == "2lane"
    assert parse_sdk_cfg(text).fmt.layout == "2lane"          # 14xx/18xx: lanes not known
    with pytest.raises(ValueError, match=r"layout '4lane' does not match board xWR18xx"):
        parse_sdk_cfg(text, board="xWR18xx", layout="4lane")


@pytest.mark.parametrize("units, scale", [("wavelength", None), ("m", 1.0)])
def test_antenna_file_csv_and_json(tmp_path, units, scale):
    cfg, text = _cfg((0, 1))
    lam = cfg.center_wavelength
    k = lam if scale is None else 1.0
    tx = np.array([[0, 0, 0], [2, 0, 0]]) * (0.5 if scale is None else 0.002)
    rx = np.array([[i, 0, 0] for i in range(4)]) * (0.5 if scale is None else 0.002)
    rows = [f"tx{i},{x},{y},{z}" for i, (x, y, z) in enumerate(tx)]
    rows += [f"rx{i},{x},{y},{z},{1 if i % 2 == 0 else -1}" for i, (x, y, z) in enumerate(rx)]
    csv = tmp_path / "ant.csv"
    csv.write_text(f"# units: {units}\nantenna,x,y,z,phase\n"
                   + "\n".join(r if r.startswith("rx") else r + ",1" for r in rows) + "\n")
    cfg_path = tmp_path / "r.cfg"
    cfg_path.write_text(text)
    m = read_mmwave_config(cfg_path, antenna_positions=csv)
    assert m.board == str(csv)
    np.testing.assert_allclose(m.array.virtual_positions[4:, 0], tx[1, 0] * k + rx[:, 0] * k)
    assert np.array_equal(m.channel_sign, [1, -1, 1, -1] * 2)
    js = tmp_path / "ant.json"
    js.write_text(json.dumps({"units": units, "tx": tx.tolist(), "rx": rx.tolist()}))
    mj = read_mmwave_config(cfg_path, antenna_positions=js)
    np.testing.assert_allclose(mj.array.virtual_positions, m.array.virtual_positions)


def test_bad_antenna_files_are_named(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("antenna,x,y,z\ntx0,0,0,0\nrx0,0,0,0\n")
    with pytest.raises(ValueError, match=r"units must be stated.*\['wavelength', 'm'\]"):
        read_antenna_positions(p, 0.004)
    p.write_text("# units: m\nantenna,x,y,z\ntx0,0,0,0\nrx1,0,0,0\n")
    with pytest.raises(ValueError, match=r"rx antennas must be numbered 0..N-1, got \[1\]"):
        read_antenna_positions(p, 0.004)
    p.write_text("# units: m\nantenna,x,y,z\ntx0,0,zero,0\nrx0,0,0,0\n")
    with pytest.raises(ValueError, match="row 1: coordinates must be numbers"):
        read_antenna_positions(p, 0.004)
    p.write_text("# units: inch\nantenna,x,y\ntx0,0,0\nrx0,0,0\n")
    with pytest.raises(ValueError, match="got 'inch'"):
        read_antenna_positions(p, 0.004)
    with pytest.raises(ValueError, match="does not exist"):
        read_antenna_positions(tmp_path / "none.json", 0.004)
    cfg, text = _cfg((0, 1, 2))
    (tmp_path / "r.cfg").write_text(text)
    p.write_text("# units: m\nantenna,x,y,z\ntx0,0,0,0\ntx1,1,0,0\nrx0,0,0,0\nrx1,0,0,0\n"
                 "rx2,0,0,0\nrx3,0,0,0\n")
    with pytest.raises(ValueError, match=r"hold 2 TX; the configuration fires TX\[0, 1, 2\]"):
        read_mmwave_config(tmp_path / "r.cfg", antenna_positions=p)


def test_capture_that_does_not_fit_the_lanes_is_refused(tmp_path):
    two = Dca1000Format(num_samples=8, slot_interval=60e-6, num_rx=2, num_tx=1, num_loops=2)
    cube = np.random.default_rng(0).integers(-500, 500, (3, 2, 2, 8)) * (1 + 1j)
    path = write_dca1000(tmp_path / "adc.bin", cube, two)
    assert check_capture_fits(path, two, num_frames=3) == 3
    four = Dca1000Format(num_samples=8, slot_interval=60e-6, num_rx=2, num_tx=1, num_loops=2,
                         layout="4lane")
    with pytest.raises(ValueError, match=r"not a whole number of frames of 256 bytes \(4lane"
                                         r".*it is 3 whole frame\(s\) of the 2lane layout"):
        check_capture_fits(path, four)
    even = write_dca1000(tmp_path / "even.bin", np.concatenate([cube, cube[:1]]), two)
    with pytest.raises(ValueError, match=r"4 frames of the 2lane layout.*numFrames.*2 frames "
                                         r"of the 4lane.*--layout 2lane"):
        check_capture_fits(even, four, num_frames=4)
    with pytest.raises(ValueError, match=r"lanes of the disabled receivers.*not 4-lane"):
        check_capture_fits(even, four)
    ok = write_dca1000(tmp_path / "four.bin", cube[:2], four)
    assert check_capture_fits(ok, four, num_frames=2) == 2


def test_compensate_refuses_a_4lane_reading_of_a_2lane_capture(tmp_path, capsys):
    from raysim.cli import main

    cfg, text = _cfg((0,), rx=(0, 1), frames=4)
    (tmp_path / "r.cfg").write_text(text)
    m = parse_sdk_cfg(text)
    cube = np.random.default_rng(1).integers(-500, 500, (4, cfg.num_chirps, 2,
                                                         m.fmt.num_samples)) * (1 + 1j)
    cap = write_dca1000(tmp_path / "adc_data.bin", cube, m.fmt)
    args = ["compensate", str(cap), "--radar-config", str(tmp_path / "r.cfg"), "--chain",
            "none", "--range-m", "0:5", "--az-deg", "0:0:1", "--el-deg", "0:0:1"]
    assert main(args + ["--layout", "4lane", "--out", str(tmp_path / "b.zarr")]) == 2
    err = capsys.readouterr().err
    assert "numFrames" in err and "--layout 2lane" in err
    assert not (tmp_path / "b.zarr").exists()
    assert main(args + ["--out", str(tmp_path / "b.zarr")]) == 0
    assert main(args + ["--board", "xWR16xx", "--out", str(tmp_path / "c.zarr")]) == 0
    assert main(args + ["--board", "nope", "--out", str(tmp_path / "d.zarr")]) == 2
    assert "board 'nope' is not known" in capsys.readouterr().err
