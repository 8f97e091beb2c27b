"""TI radar configurations (mmWave SDK .cfg, mmWave Studio JSON) into RadarConfig, array, format.

Files are written here in TI's published field order ("mmWave SDK User Guide",
CLI configuration commands; "mmWave Studio" JSON export ``*.mmwave.json``).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from raysim.io.mmwave_config import (
    parse_sdk_cfg,
    parse_studio_json,
    read_mmwave_config,
    sdk_cfg_text,
    ti_antenna_positions,
)
from raysim.radar.config import RadarConfig

#: Relative tolerance of values that pass through decimal text (us, MHz/us, ksps).
REL_TOL = 1e-9

# an AWR1843 3 Tx x 4 Rx TDM profile: TX0, TX2 (azimuth), then TX1 (elevation)
SDK_CFG = """\
% awr1843 TDM MIMO, 3 Tx x 4 Rx
sensorStop
flushCfg
dfeDataOutputMode 1
channelCfg 15 7 0
adcCfg 2 1
adcbufCfg -1 0 1 1 1
profileCfg 0 77 7 6 60 0 0 29.982 1 256 5000 0 0 30
chirpCfg 0 0 0 0 0 0 0 1
chirpCfg 1 1 0 0 0 0 0 4
chirpCfg 2 2 0 0 0 0 0 2
frameCfg 0 2 32 8 40 1 0
lowPower 0 0
sensorStart
"""


def _studio(**frame) -> dict:
    """The same configuration as an mmWave Studio JSON export."""
    f = {"chirpStartIdx": 0, "chirpEndIdx": 2, "numLoops": 32, "numFrames": 8,
         "numAdcSamples": 512, "framePeriodicity_msec": 40.0, "triggerSelect": 1,
         "frameTriggerDelay": 0.0}
    f.update(frame)
    chirp = {"profileId": 0, "startFreqVar_MHz": 0.0, "freqSlopeVar_KHz_usec": 0.0,
             "idleTimeVar_usec": 0.0, "adcStartTimeVar_usec": 0.0}
    return {"mmWaveDevices": [{
        "mmWaveDeviceId": 0,
        "rfConfig": {
            "rlChanCfg_t": {"rxChannelEn": "0xF", "txChannelEn": "0x7", "cascading": 0},
            "rlAdcOutCfg_t": {"fmt": {"b2AdcBits": 2, "b2AdcOutFmt": 1}},
            "rlProfiles": [{"rlProfileCfg_t": {
                "profileId": 0, "startFreqConst_GHz": 77.0, "idleTimeConst_usec": 7.0,
                "adcStartTimeConst_usec": 6.0, "rampEndTime_usec": 60.0,
                "freqSlopeConst_MHz_usec": 29.982, "txStartTime_usec": 1.0,
                "numAdcSamples": 256, "digOutSampleRate": 5000, "rxGain_dB": "0x1E"}}],
            "rlChirps": [{"rlChirpCfg_t": {**chirp, "chirpStartIdx": i, "chirpEndIdx": i,
                                           "txEnable": tx}}
                         for i, tx in enumerate(("0x1", "0x4", "0x2"))],
            "rlFrameCfg_t": f},
        "rawDataCaptureConfig": {"rlDevLaneEnable_t": {"laneEn": "0x3"}}}]}


def _check_awr1843(m):
    """Closed forms of TI's profile: B = S N / f_s, T_slot = idle + rampEnd, f_0 = f + S t_adc."""
    cfg, fmt = m.config, m.fmt
    slope = 29.982e12                                   # Hz/s
    assert m.tx_order == (0, 2, 1) and m.rx_enabled == (0, 1, 2, 3)
    assert cfg.num_samples == 256 and fmt.num_samples == 256
    assert math.isclose(cfg.sample_rate, 5e6, rel_tol=REL_TOL)
    assert math.isclose(cfg.bandwidth, slope * 256 / 5e6, rel_tol=REL_TOL)
    assert math.isclose(cfg.carrier_frequency, 77e9 + slope * 6e-6, rel_tol=REL_TOL)
    assert math.isclose(cfg.slot_interval, 67e-6, rel_tol=REL_TOL)
    assert math.isclose(fmt.slot_interval, 67e-6, rel_tol=REL_TOL)
    assert cfg.num_tx_slots == fmt.num_tx == 3 and cfg.num_chirps == fmt.num_loops == 32
    assert math.isclose(cfg.frame_period, 0.04, rel_tol=REL_TOL) and m.num_frames == 8
    assert cfg.complex_sampling and fmt.complex and fmt.adc_bits == 16
    assert math.isclose(fmt.t0, 6e-6, rel_tol=REL_TOL)    # first ADC sample of the ramp
    # channels slot major, rx minor: slot 1 is TX2 (2 lambda along x), slot 2 TX1 (raised)
    tx, rx = ti_antenna_positions(cfg.center_wavelength)
    p = m.array.virtual_positions
    assert np.array_equal(m.array.tx_slot, np.repeat(np.arange(3), 4))
    assert np.allclose(p[4:8], tx[2] + rx) and np.allclose(p[8:], tx[1] + rx)
    # ramp times: slot k of loop n at n * 3 * T_slot + k * T_slot (+ t_adc)
    t = fmt.chirp_times(2)
    assert math.isclose(t[1, 5, 2] - t[0, 0, 0], 0.04 + (5 * 3 + 2) * 67e-6, rel_tol=REL_TOL)


def test_sdk_cfg_gives_config_array_and_format(tmp_path):
    path = tmp_path / "awr1843.cfg"
    path.write_text(SDK_CFG)
    _check_awr1843(read_mmwave_config(path))


def test_studio_json_gives_the_same(tmp_path):
    path = tmp_path / "awr1843.mmwave.json"
    path.write_text(json.dumps(_studio()))
    m = read_mmwave_config(path)
    _check_awr1843(m)
    assert m.fmt.layout == "2lane"
    doc = _studio()
    doc["mmWaveDevices"][0]["rawDataCaptureConfig"]["rlDevLaneEnable_t"]["laneEn"] = 15
    assert parse_studio_json(doc).fmt.layout == "4lane"


def test_written_cfg_reads_back():
    cfg = RadarConfig(num_chirps=16, sample_rate=2.5e6, idle_time=10e-6, num_tx_slots=2,
                      frame_period=0.02, complex_sampling=False)
    m = parse_sdk_cfg(sdk_cfg_text(cfg, tx_order=(2, 0), rx_enabled=(0, 1), adc_bits=12))
    assert m.tx_order == (2, 0) and m.rx_enabled == (0, 1) and m.fmt.adc_bits == 12
    assert not m.config.complex_sampling and m.config.num_samples == cfg.num_samples
    for name in ("carrier_frequency", "bandwidth", "chirp_duration", "sample_rate",
                 "slot_interval", "frame_period"):
        assert math.isclose(getattr(m.config, name), getattr(cfg, name), rel_tol=REL_TOL), name


@pytest.mark.parametrize("old, new, field", [
    ("chirpCfg 1 1 0 0 0 0 0 4", "chirpCfg 1 1 0 0 0 0 0 5", "txEnable"),
    ("channelCfg 15 7 0", "channelCfg 15 3 0", "txChannelEn"),
    ("frameCfg 0 2 32 8 40 1 0", "frameCfg 0 2 32 8 5 1 0", "framePeriodicity"),
    ("profileCfg 0 77 7 6 60", "profileCfg 0 77 7 6 50", "rampEndTime"),
    ("frameCfg 0 2 32", "frameCfg 0 3 32", "chirp index 3"),
    ("chirpCfg 2 2 0 0 0 0 0 2", "chirpCfg 2 2 0 0 0 0 0 1", "fires twice"),
    ("chirpCfg 2 2 0 0 0 0 0 2", "chirpCfg 2 2 0 0 0 1 0 2", "idleTimeVar"),
    ("adcCfg 2 1", "adcCfg 3 1", "numADCBits"),
    ("profileCfg 0 77 7 6 60 0 0 29.982 1 256", "profileCfg 0 77 7 6 60 0 0 29.982 1 25x6",
     "numAdcSamples"),
    ("frameCfg 0 2 32 8 40 1 0", "frameCfg 0 2 32", "frameCfg needs 7 fields"),
    ("channelCfg 15 7 0\n", "", "channelCfg"),
])
def test_bad_sdk_cfg_names_the_field(old, new, field):
    assert old in SDK_CFG
    with pytest.raises(ValueError, match=field):
        parse_sdk_cfg(SDK_CFG.replace(old, new))


def test_bad_studio_json_names_the_field(tmp_path):
    doc = _studio()
    del doc["mmWaveDevices"][0]["rfConfig"]["rlFrameCfg_t"]["numLoops"]
    with pytest.raises(ValueError, match="numLoops"):
        parse_studio_json(doc)
    with pytest.raises(ValueError, match="framePeriodicity"):
        parse_studio_json(_studio(framePeriodicity_msec=1.0))
    (tmp_path / "x.json").write_text("{")
    with pytest.raises(ValueError, match="not valid JSON"):
        read_mmwave_config(tmp_path / "x.json")
    with pytest.raises(ValueError, match="does not exist"):
        read_mmwave_config(tmp_path / "none.cfg")


def test_studio_json_of_another_waveform_or_a_cascade_is_refused():
    import copy

    base = _studio()
    assert parse_studio_json(base).fmt.num_loops > 0          # the fields absent: TDM, legacy
    for key, value in (("waveformType", "advancedFrameChirp"), ("MIMOScheme", "BPM")):
        doc = copy.deepcopy(base)
        doc["mmWaveDevices"][0]["rfConfig"][key] = value
        with pytest.raises(ValueError, match=rf"rfConfig {key} '{value}' is not supported"):
            parse_studio_json(doc)
    doc = copy.deepcopy(base)
    doc["mmWaveDevices"] = doc["mmWaveDevices"] * 4                    # MMWCAS: four chips
    with pytest.raises(ValueError, match="holds 4 devices"):
        parse_studio_json(doc)


def test_an_enabled_bpm_is_refused_and_a_disabled_one_read():
    cfg = RadarConfig(num_chirps=4, num_tx_slots=2, sample_rate=2.5e6)
    text = sdk_cfg_text(cfg, tx_order=(0, 2))
    assert parse_sdk_cfg(text + "bpmCfg -1 0 0 1\n").fmt.num_tx == 2
    with pytest.raises(ValueError, match=r"'bpmCfg -1 1 0 1': BPM MIMO .* not supported"):
        parse_sdk_cfg(text + "bpmCfg -1 1 0 1\n")


def test_a_json_file_named_cfg_is_named_as_json(tmp_path):
    path = tmp_path / "mmw-xWR18xx.cfg"           # a tool's own JSON template, .cfg suffix
    path.write_text('{\n  "channelCfg": {"rxMask": null, "txMask": null}\n}\n')
    with pytest.raises(ValueError, match=r"mmw-xWR18xx\.cfg: holds JSON, not an mmWave SDK"):
        read_mmwave_config(path)
