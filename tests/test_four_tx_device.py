"""A four-transmitter device (AWR2944-like TDM) read with its antenna positions given.

The boards known by name have three transmitters; a configuration that enables
a fourth is refused without positions, named with the remedy, and read with an
antenna file. A stationary point target in the capture then lies at its
azimuth on the 16-element virtual array (no motion: no compensation needed).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from raysim.cli import main
from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.io.mmwave_config import read_mmwave_config, sdk_cfg_text
from raysim.io.ti_dca1000 import write_dca1000
from raysim.platform.motion import stationary
from raysim.radar.config import RadarConfig

#: Positions in wavelengths: three TX 2 lambda apart, the fourth raised lambda/2 (x, y, z).
TX = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [4.0, 0.0, 0.0], [1.0, 0.5, 0.0]]
RX = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [1.0, 0.0, 0.0], [1.5, 0.0, 0.0]]
TX_ORDER = (0, 2, 3, 1)
#: Half the azimuth grid step [deg]: the peak's cell must hold the target.
GRID_STEP_DEG = 0.5


@pytest.fixture
def device(tmp_path):
    cfg = RadarConfig(num_chirps=8, num_frames=1, num_tx_slots=4, sample_rate=2.5e6)
    (tmp_path / "r.cfg").write_text(sdk_cfg_text(cfg, tx_order=TX_ORDER))
    (tmp_path / "ant.json").write_text(json.dumps({"units": "wavelength", "tx": TX, "rx": RX}))
    return tmp_path / "r.cfg", tmp_path / "ant.json"


def test_a_fourth_transmitter_needs_the_antenna_positions(device):
    cfg, ant = device
    with pytest.raises(ValueError, match=r"txChannelEn '?15'? must enable transmitters among "
                                         r"TX0..TX2 .*AWR2944.*--antenna-positions"):
        read_mmwave_config(cfg)
    m = read_mmwave_config(cfg, antenna_positions=ant)
    lam = m.config.center_wavelength
    want = np.concatenate([np.asarray(TX[t]) + np.asarray(RX) for t in TX_ORDER]) * lam
    np.testing.assert_allclose(m.array.virtual_positions, want, rtol=0, atol=1e-12)
    assert m.fmt.num_tx == 4 and m.tx_order == TX_ORDER


def test_a_target_in_a_four_tx_capture_lies_at_its_azimuth(device, tmp_path):
    cfg_path, ant = device
    m = read_mmwave_config(cfg_path, antenna_positions=ant)
    az = 17.0
    tgt = PointTarget.at(6.0, math.radians(az), 0.0)
    data = simulate_point_targets(m.config, m.array, [tgt], stationary(), frame=0,
                                  t0=m.fmt.t0).data
    cube = (data * (2000.0 / np.abs(data).max()))[None]
    cap = write_dca1000(tmp_path / "adc_data.bin", cube, m.fmt)
    out = tmp_path / "beams.npz"
    assert main(["compensate", str(cap), "--radar-config", str(cfg_path), "--antenna-positions",
                 str(ant), "--chain", "none", "--range-m", "5.5:6.5", "--az-deg",
                 f"-40:40:{GRID_STEP_DEG}", "--el-deg", "0:0:1", "--out", str(out),
                 "--no-progress"]) == 0
    with np.load(out) as z:
        beams, grid = z["beams"], z["azimuth_deg"]
    power = np.abs(beams).sum(axis=(0, 1))        # [chirp, range, az, el] -> az, el
    assert abs(float(grid[int(np.argmax(power[:, 0]))]) - az) <= GRID_STEP_DEG / 2 + 1e-9
