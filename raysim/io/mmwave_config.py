"""TI mmWave radar configurations: mmWave SDK ``.cfg`` files and mmWave Studio JSON exports.

A capture is only readable with the chirp configuration that produced it. This
module turns that configuration into the project's objects, so nobody types
sample counts by hand:

* :class:`~raysim.radar.config.RadarConfig`: waveform and sampling,
* :class:`~raysim.radar.arrays.VirtualArray`: channels in TDM slot order,
* :class:`~raysim.io.ti_dca1000.Dca1000Format`: the binary layout and ramp times.

Sources (field order as TI publishes it)
----------------------------------------
mmWave SDK CLI file (``.cfg``; "mmWave SDK User Guide", section "Configuration
(.cfg) File Format"), one command per line, ``%`` starts a comment:

``channelCfg <rxChannelEn> <txChannelEn> <cascading>``
    Bit masks of the enabled receivers and transmitters.
``adcCfg <numADCBits> <adcOutputFmt>``
    ``numADCBits`` 0/1/2 = 12/14/16 bit; ``adcOutputFmt`` 0 real, 1 complex
    1x, 2 complex 2x.
``profileCfg <profileId> <startFreq GHz> <idleTime us> <adcStartTime us>
<rampEndTime us> <txOutPower> <txPhaseShifter> <freqSlopeConst MHz/us>
<txStartTime us> <numAdcSamples> <digOutSampleRate ksps> <hpfCornerFreq1>
<hpfCornerFreq2> <rxGain>``
``chirpCfg <startIdx> <endIdx> <profileId> <startFreqVar Hz> <freqSlopeVar
kHz/us> <idleTimeVar us> <adcStartTimeVar us> <txEnable>``
``frameCfg <chirpStartIdx> <chirpEndIdx> <numLoops> <numFrames>
<framePeriodicity ms> <triggerSelect> <frameTriggerDelay ms>``

Other commands (``sensorStop``, ``lvdsStreamCfg``, ``guiMonitor``, ...) are
ignored; ``advFrameCfg`` (sub-frames) and an enabled ``bpmCfg`` (BPM MIMO) are
refused. The SDK file does not name
the LVDS lane count; ``layout`` says it, else the board's.

Antennas: the configuration does not say the board. The layout is the
``board``'s (:mod:`raysim.io.ti_boards`: xWR14xx, xWR16xx, xWR18xx,
IWR6843ISK, IWR6843AOP, IWR6843ODS, from TI's EVM user guides), or read from
an antenna file (``antenna_positions``), or, when neither is given, the one
layout every board that fits the configuration shares (a 77 GHz cfg firing TX2
is an xWR14xx/xWR18xx, which share theirs); where they differ (TX0 + TX1 at 77
GHz: xWR16xx places TX1 2 lambda along azimuth, xWR14xx/18xx raise it; every
60 GHz cfg: ISK, AOP and ODS differ) a ``ValueError`` names the candidates.

mmWave Studio JSON export (``*.mmwave.json``): ``mmWaveDevices[0]`` holds
``rfConfig`` with ``rlChanCfg_t`` (``rxChannelEn``, ``txChannelEn``),
``rlAdcOutCfg_t.fmt`` (``b2AdcBits``, ``b2AdcOutFmt``), ``rlProfiles[*].rlProfileCfg_t``
(``startFreqConst_GHz``, ``idleTimeConst_usec``, ``adcStartTimeConst_usec``,
``rampEndTime_usec``, ``freqSlopeConst_MHz_usec``, ``numAdcSamples``,
``digOutSampleRate`` [ksps]), ``rlChirps[*].rlChirpCfg_t`` (``chirpStartIdx``,
``chirpEndIdx``, ``profileId``, ``startFreqVar_MHz``, ``freqSlopeVar_KHz_usec``,
``idleTimeVar_usec``, ``adcStartTimeVar_usec``, ``txEnable``) and ``rlFrameCfg_t``
(``chirpStartIdx``, ``chirpEndIdx``, ``numLoops``, ``numFrames``,
``framePeriodicity_msec``), and ``rawDataCaptureConfig.rlDevLaneEnable_t.laneEn``
(LVDS lane mask: 2 lanes ``0x3``, 4 lanes ``0xF``). Bit masks may be numbers
or hexadecimal strings (``"0x7"``).

Mapping
-------
TDM MIMO: the chirps ``chirpStartIdx .. chirpEndIdx`` of ``frameCfg`` are the
transmit slots of one loop, in that order; each must enable exactly one
transmitter (``txEnable``) that ``channelCfg`` enables. The virtual channels
are ordered slot major, receiver minor, as the DCA1000 reader returns them.

The sampled ramp starts ``adcStartTime`` after the ramp start, so the
carrier frequency of :class:`RadarConfig` (the frequency at the first sample)
is ``startFreq + slope adcStartTime``, ``chirp_duration = numAdcSamples /
digOutSampleRate``, ``bandwidth = slope chirp_duration`` and ``idle_time =
idleTime + rampEndTime - chirp_duration`` (the slot interval stays
``idleTime + rampEndTime``). The chirp times of the capture are the first ADC
sample of every ramp: ``Dca1000Format.t0 = t0 + adcStartTime``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from raysim.io.ti_dca1000 import Dca1000Format
from raysim.radar.arrays import VirtualArray, tdm_mimo  # noqa: F401 (annotation)
from raysim.radar.config import RadarConfig

__all__ = ["MmwaveConfig", "read_mmwave_config", "parse_sdk_cfg", "parse_studio_json",
           "sdk_cfg_text", "ti_antenna_positions"]

#: ``numADCBits`` / ``b2AdcBits`` code -> ADC word width [bit].
ADC_BITS = {0: 12, 1: 14, 2: 16}
#: ``adcOutputFmt`` / ``b2AdcOutFmt`` code -> complex samples.
ADC_COMPLEX = {0: False, 1: True, 2: True}
#: LVDS lane mask -> DCA1000 layout.
LANE_LAYOUT = {0x3: "2lane", 0xF: "4lane"}
#: Fields of each SDK command, in TI's order (the ones read are named).
SDK_FIELDS = {
    "channelCfg": ("rxChannelEn", "txChannelEn", "cascading"),
    "adcCfg": ("numADCBits", "adcOutputFmt"),
    "profileCfg": ("profileId", "startFreq", "idleTime", "adcStartTime", "rampEndTime",
                   "txOutPower", "txPhaseShifter", "freqSlopeConst", "txStartTime",
                   "numAdcSamples", "digOutSampleRate", "hpfCornerFreq1", "hpfCornerFreq2",
                   "rxGain"),
    "chirpCfg": ("startIdx", "endIdx", "profileId", "startFreqVar", "freqSlopeVar",
                 "idleTimeVar", "adcStartTimeVar", "txEnable"),
    "frameCfg": ("chirpStartIdx", "chirpEndIdx", "numLoops", "numFrames", "framePeriodicity",
                 "triggerSelect", "frameTriggerDelay"),
}
_REQUIRED = ("channelCfg", "profileCfg", "chirpCfg", "frameCfg")


def ti_antenna_positions(wavelength: float) -> tuple[np.ndarray, np.ndarray]:
    """Physical antennas of the TI xWR18xx/xWR68xx boosters (3 Tx, 4 Rx), frame A [m].

    The layout of :func:`raysim.radar.arrays.ti_3tx4rx`: receivers on x at
    ``lambda/2``, TX0 at the origin, TX1 at ``(lambda, lambda/2)``, TX2 at
    ``(2 lambda, 0)``.

    Returns
    -------
    (ndarray, ndarray)
        ``tx [3, 3]`` and ``rx [4, 3]`` positions [m], indexed by TX / RX number.
    """
    d = float(wavelength) / 2.0
    rx = np.array([[i * d, 0.0, 0.0] for i in range(4)])
    tx = np.array([[0.0, 0.0, 0.0], [2 * d, d, 0.0], [4 * d, 0.0, 0.0]])
    return tx, rx


@dataclass(frozen=True)
class MmwaveConfig:
    """A TI chirp configuration in the project's terms.

    Attributes
    ----------
    config : RadarConfig
        Waveform and sampling (``num_chirps`` = loops, ``num_tx_slots`` = slots).
    array : VirtualArray
        Channels slot major, receiver minor; ``tx_slot`` the slot of each.
    fmt : Dca1000Format
        DCA1000 layout and ramp times of a capture with this configuration.
    tx_order : tuple of int
        Transmitter (TX number) of each TDM slot.
    rx_enabled : tuple of int
        Enabled receivers (RX numbers), in channel order.
    num_frames : int
        Frames the configuration asks for (0: until stopped).
    source : str
        File read ("" for text or a dict).
    board : str
        Board whose antenna layout was used (:mod:`raysim.io.ti_boards`; several
        names where they share it), or the antenna file.
    channel_sign : ndarray, shape ``[channel]`` or None
        Feed sign (+1 / -1) of every virtual channel (the RX phase of the
        board): multiply a capture's channels by it before beamforming.
    """

    config: RadarConfig
    array: VirtualArray
    fmt: Dca1000Format
    tx_order: tuple[int, ...]
    rx_enabled: tuple[int, ...]
    num_frames: int
    source: str = ""
    board: str = ""
    channel_sign: np.ndarray | None = None


def _bits(name: str, value) -> list[int]:
    """Indices of the set bits of a mask given as an int or a ``"0x.."`` string."""
    try:
        mask = int(value, 0) if isinstance(value, str) else int(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a bit mask (integer or '0x..'), got {value!r}") \
            from None
    if mask < 0 or float(mask) != float(value if not isinstance(value, str) else mask):
        raise ValueError(f"{name} must be a non-negative integer bit mask, got {value!r}")
    return [b for b in range(mask.bit_length()) if mask >> b & 1]


def _num(name: str, value, *, positive: bool = False, integer: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v < 0 or (positive and v == 0):
        raise ValueError(f"{name} must be a finite {'positive' if positive else 'non-negative'}"
                         f" number, got {value!r}")
    if integer and v != int(v):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    return int(v) if integer else v


def _build(*, rx_mask, tx_mask, adc_bits_code, adc_fmt_code, profiles: dict, chirps: list,
           frame: dict, layout: str | None, t0: float, tx_positions, rx_positions,
           source: str, board: str | None = None, antenna_positions=None) -> MmwaveConfig:
    """Check one configuration (already in TI's units) and convert it.

    ``profiles``: profileId -> dict of the profile fields (GHz, us, MHz/us,
    ksps); ``chirps``: dicts with startIdx, endIdx, profileId, the four
    variations and txEnable; ``frame``: chirpStartIdx, chirpEndIdx, numLoops,
    numFrames, framePeriodicity [ms].
    """
    where = f"{source}: " if source else ""
    rx = _bits("rxChannelEn", rx_mask)
    tx_on = _bits("txChannelEn", tx_mask)
    if not rx or max(rx) > 3:
        raise ValueError(f"{where}rxChannelEn {rx_mask!r} must enable receivers among RX0..RX3")
    # the boards known here have three transmitters; a device with more (AWR2944: four)
    # is read with its antenna positions given, which then say how many there are
    positions_given = antenna_positions is not None or tx_positions is not None
    if tx_on and max(tx_on) > 3:
        raise ValueError(f"{where}txChannelEn {tx_mask!r} must enable transmitters among "
                         f"TX0..TX3 (TI single-chip devices have at most four)")
    if not tx_on or (max(tx_on) > 2 and not positions_given):
        raise ValueError(f"{where}txChannelEn {tx_mask!r} must enable transmitters among "
                         f"TX0..TX2 (the boards known here have three); a device with more "
                         f"(AWR2944, AWR2544: four) is read with its antenna positions "
                         f"(--antenna-positions FILE)")
    if adc_bits_code not in ADC_BITS:
        raise ValueError(f"{where}numADCBits must be one of {sorted(ADC_BITS)} (12/14/16 bit),"
                         f" got {adc_bits_code!r}")
    if adc_fmt_code not in ADC_COMPLEX:
        raise ValueError(f"{where}adcOutputFmt must be 0 (real), 1 or 2 (complex), got "
                         f"{adc_fmt_code!r}")
    first = _num("chirpStartIdx", frame["chirpStartIdx"], integer=True)
    last = _num("chirpEndIdx", frame["chirpEndIdx"], integer=True)
    if last < first:
        raise ValueError(f"{where}frameCfg chirpEndIdx {last} is below chirpStartIdx {first}")
    by_index: dict[int, dict] = {}
    for ch in chirps:
        a = _num("chirpCfg startIdx", ch["startIdx"], integer=True)
        b = _num("chirpCfg endIdx", ch["endIdx"], integer=True)
        if b < a:
            raise ValueError(f"{where}chirpCfg endIdx {b} is below startIdx {a}")
        for k in range(a, b + 1):
            if k in by_index:
                raise ValueError(f"{where}chirpCfg: chirp index {k} is configured twice")
            by_index[k] = ch
    slots, profile_ids = [], set()
    for k in range(first, last + 1):
        if k not in by_index:
            raise ValueError(f"{where}frameCfg uses chirp index {k} (chirpStartIdx {first} .. "
                             f"chirpEndIdx {last}) but no chirpCfg defines it")
        ch = by_index[k]
        for var in ("startFreqVar", "freqSlopeVar", "idleTimeVar", "adcStartTimeVar"):
            if float(ch[var]) != 0.0:
                raise ValueError(f"{where}chirpCfg {k}: {var} {ch[var]!r} is not supported "
                                 f"(every slot must use its profile unchanged; expected 0)")
        tx = _bits("chirpCfg txEnable", ch["txEnable"])
        if len(tx) != 1:
            raise ValueError(f"{where}chirpCfg {k}: txEnable {ch['txEnable']!r} must enable "
                             f"exactly one transmitter (TDM MIMO), got TX {tx}")
        if tx[0] not in tx_on:
            raise ValueError(f"{where}chirpCfg {k}: txEnable {ch['txEnable']!r} fires TX"
                             f"{tx[0]}, which channelCfg txChannelEn {tx_mask!r} disables")
        slots.append(tx[0])
        profile_ids.add(int(ch["profileId"]))
    if len(set(slots)) != len(slots):
        raise ValueError(f"{where}chirpCfg txEnable: a transmitter fires twice in one loop "
                         f"(slots fire TX {slots}); expected each TX once")
    if len(profile_ids) != 1:
        raise ValueError(f"{where}chirpCfg profileId: the slots use profiles "
                         f"{sorted(profile_ids)}; expected one profile")
    pid = profile_ids.pop()
    if pid not in profiles:
        raise ValueError(f"{where}chirpCfg profileId {pid} has no profileCfg (profiles: "
                         f"{sorted(profiles)})")
    p = profiles[pid]
    f_start = _num("startFreq", p["startFreq"], positive=True) * 1e9
    idle = _num("idleTime", p["idleTime"]) * 1e-6
    adc_start = _num("adcStartTime", p["adcStartTime"]) * 1e-6
    ramp_end = _num("rampEndTime", p["rampEndTime"], positive=True) * 1e-6
    slope = _num("freqSlopeConst", p["freqSlopeConst"], positive=True) * 1e12   # Hz/s
    n_samples = _num("numAdcSamples", p["numAdcSamples"], positive=True, integer=True)
    fs = _num("digOutSampleRate", p["digOutSampleRate"], positive=True) * 1e3
    sampled = n_samples / fs
    if adc_start + sampled > ramp_end * (1 + 1e-9):
        raise ValueError(
            f"{where}profileCfg {pid}: rampEndTime {p['rampEndTime']} us is shorter than "
            f"adcStartTime + numAdcSamples / digOutSampleRate = {(adc_start + sampled) * 1e6:.4g}"
            f" us; the ADC would sample past the ramp")
    loops = _num("numLoops", frame["numLoops"], positive=True, integer=True)
    n_frames = _num("numFrames", frame["numFrames"], integer=True)
    period = _num("framePeriodicity", frame["framePeriodicity"], positive=True) * 1e-3
    slot_interval = idle + ramp_end
    if period < loops * len(slots) * slot_interval * (1 - 1e-9):
        raise ValueError(
            f"{where}frameCfg framePeriodicity {frame['framePeriodicity']} ms is shorter than "
            f"the frame's chirps, numLoops {loops} x {len(slots)} slots x (idleTime + "
            f"rampEndTime) = {loops * len(slots) * slot_interval * 1e3:.6g} ms")
    if layout not in (None, "2lane", "4lane"):
        raise ValueError(f"{where}layout must be '2lane' or '4lane', got {layout!r}")
    cfg = RadarConfig(carrier_frequency=f_start + slope * adc_start, bandwidth=slope * sampled,
                      chirp_duration=sampled, idle_time=max(slot_interval - sampled, 0.0),
                      sample_rate=fs,
                      num_chirps=loops, num_frames=max(n_frames, 1),
                      complex_sampling=ADC_COMPLEX[adc_fmt_code], frame_period=period,
                      num_tx_slots=len(slots))
    ant = _antennas(board, antenna_positions, tx_positions, rx_positions, slots, rx,
                    f_start, cfg.center_wavelength, where)
    if layout is None:
        layout = ant.layout or "2lane"
    elif ant.layout is not None and layout != ant.layout and board is not None:
        raise ValueError(f"{where}layout {layout!r} does not match board {ant.name}, whose "
                         f"DCA1000 captures use {ant.layout!r}; leave the layout out or give "
                         f"the right board")
    tx_pos = ant.tx if tx_positions is None else np.asarray(tx_positions, dtype=float)
    rx_pos = ant.rx if rx_positions is None else np.asarray(rx_positions, dtype=float)
    if tx_pos.ndim != 2 or tx_pos.shape[1] != 3 or tx_pos.shape[0] <= max(slots):
        raise ValueError(f"tx_positions must have shape [tx >= {max(slots) + 1}, 3], got "
                         f"{tx_pos.shape}")
    if rx_pos.ndim != 2 or rx_pos.shape[1] != 3 or rx_pos.shape[0] <= max(rx):
        raise ValueError(f"rx_positions must have shape [rx >= {max(rx) + 1}, 3], got "
                         f"{rx_pos.shape}")
    array = tdm_mimo(tx_pos[slots], rx_pos[rx],
                     name=f"TI TDM MIMO, slots TX{slots}, RX{rx}")
    fmt = Dca1000Format(num_samples=n_samples, slot_interval=slot_interval, num_rx=len(rx),
                        num_tx=len(slots), num_loops=loops, layout=layout,
                        complex=ADC_COMPLEX[adc_fmt_code], frame_period=period,
                        t0=float(t0) + adc_start, adc_bits=ADC_BITS[adc_bits_code])
    if ant.rx_phase.shape[0] <= max(rx):
        raise ValueError(f"{where}the antenna layout {ant.name} has {ant.rx_phase.shape[0]} "
                         f"receivers; channelCfg enables RX{rx}")
    sign = np.tile(ant.rx_phase[rx], len(slots))
    return MmwaveConfig(cfg, array, fmt, tuple(slots), tuple(rx), n_frames, source, ant.name,
                        sign)


def _antennas(board, antenna_positions, tx_positions, rx_positions, slots, rx, f_start,
              wavelength, where):
    """The antenna layout: given positions, a file, a board, or the board the cfg implies."""
    from raysim.io.ti_boards import AntennaLayout, read_antenna_positions, resolve_board

    given = sum(x is not None for x in (board, antenna_positions)) + (
        tx_positions is not None or rx_positions is not None)
    if given > 1:
        raise ValueError(f"{where}give one of board, antenna_positions or tx/rx_positions, "
                         f"not several")
    if tx_positions is not None or rx_positions is not None:
        tx_d, rx_d = ti_antenna_positions(wavelength)
        n_rx = (rx_d if rx_positions is None else np.asarray(rx_positions)).shape[0]
        return AntennaLayout(tx_d, rx_d, np.ones(max(n_rx, 4)), "tx/rx positions given")
    if antenna_positions is not None:
        lay = read_antenna_positions(antenna_positions, wavelength)
        if lay.tx.shape[0] <= max(slots):
            raise ValueError(f"{where}antenna positions {str(antenna_positions)!r} hold "
                             f"{lay.tx.shape[0]} TX; the configuration fires TX{slots}")
        if lay.rx.shape[0] <= max(rx):
            raise ValueError(f"{where}antenna positions {str(antenna_positions)!r} hold "
                             f"{lay.rx.shape[0]} RX; channelCfg enables RX{rx}")
        return lay
    return resolve_board(board, tx_order=slots, rx_enabled=rx, start_freq_hz=f_start,
                         wavelength=wavelength, where=where)


def parse_sdk_cfg(text: str, *, layout: str | None = None, t0: float = 0.0, tx_positions=None,
                  rx_positions=None, source: str = "", board: str | None = None,
                  antenna_positions=None) -> MmwaveConfig:
    """Parse the text of an mmWave SDK ``.cfg`` file (module docstring).

    Parameters
    ----------
    text : str
        The file's text.
    layout : {"2lane", "4lane"}, optional
        LVDS lanes of the DCA1000 capture (the SDK file does not say); default
        the board's (:mod:`raysim.io.ti_boards`), else ``"2lane"``. A layout
        that contradicts a given board raises.
    t0 : float
        Start of the first ramp of frame 0 on the radar clock [s].
    tx_positions, rx_positions : array_like, shape ``[tx, 3]`` / ``[rx, 3]``, optional
        Physical antennas in frame A [m], indexed by TX / RX number.
    source : str
        File name for messages.
    board : str, optional
        TI board (:data:`raysim.io.ti_boards.BOARDS`: xWR14xx, xWR16xx,
        xWR18xx, IWR6843ISK, IWR6843AOP, IWR6843ODS, or a part number). Left
        out (and no positions given): the layout the boards that fit the
        configuration share; where they differ, ``ValueError`` names them.
    antenna_positions : str or path-like, optional
        CSV / JSON antenna file (:func:`raysim.io.ti_boards.read_antenna_positions`).

    Raises
    ------
    ValueError
        A missing command, a command with the wrong number of fields, a value
        out of range or inconsistent (the message names the field), an
        advanced frame (``advFrameCfg``), or an ambiguous board.
    """
    where = f"{source}: " if source else ""
    found: dict[str, list[dict]] = {k: [] for k in SDK_FIELDS}
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.split("%", 1)[0].strip()
        if not line:
            continue
        cmd, *vals = line.split()
        if cmd not in SDK_FIELDS:
            continue
        names = SDK_FIELDS[cmd]
        if len(vals) < len(names):
            raise ValueError(f"{where}line {n}: {cmd} needs {len(names)} fields "
                             f"({' '.join(names)}), got {len(vals)}")
        found[cmd].append(dict(zip(names, vals, strict=False)))  # later SDKs append fields
    adv = [ln for ln in text.splitlines() if ln.split("%", 1)[0].split()[:1] == ["advFrameCfg"]]
    if adv and not found["frameCfg"]:
        raise ValueError(f"{where}advFrameCfg (advanced frame: sub-frames with their own "
                         f"profiles, chirps and loops) is not supported; a capture is read with "
                         f"one frameCfg (one profile, one TDM slot order): capture each "
                         f"sub-frame's configuration with frameCfg")
    for ln in text.splitlines():     # bpmCfg <subFrameIdx> <enabled> <chirp0Idx> <chirp1Idx>
        words = ln.split("%", 1)[0].split()
        if words[:1] == ["bpmCfg"] and len(words) > 2 and words[2] not in ("0", "0.0"):
            raise ValueError(f"{where}{ln.strip()!r}: BPM MIMO (binary phase-coded TX, bpmCfg "
                             f"enabled) is not supported; expected TDM (bpmCfg enabled 0)")
    missing = [c for c in _REQUIRED if not found[c]]
    if missing and text.lstrip().startswith(("{", "[")):
        raise ValueError(f"{where}holds JSON, not an mmWave SDK .cfg (CLI commands, one per "
                         f"line); an mmWave Studio export is read from a .json file")
    if missing:
        raise ValueError(f"{where}missing command(s) {missing}; an SDK .cfg needs "
                         f"{list(_REQUIRED)}")
    for c in ("channelCfg", "frameCfg", "adcCfg"):
        if len(found[c]) > 1:
            raise ValueError(f"{where}{c} is given {len(found[c])} times; expected once")
    ch, fr = found["channelCfg"][0], found["frameCfg"][0]
    adc = found["adcCfg"][0] if found["adcCfg"] else {"numADCBits": "2", "adcOutputFmt": "1"}
    profiles = {}
    for p in found["profileCfg"]:
        pid = _num("profileCfg profileId", p["profileId"], integer=True)
        if pid in profiles:
            raise ValueError(f"{where}profileCfg profileId {pid} is given twice")
        profiles[pid] = p
    return _build(rx_mask=ch["rxChannelEn"], tx_mask=ch["txChannelEn"],
                  adc_bits_code=_num("numADCBits", adc["numADCBits"], integer=True),
                  adc_fmt_code=_num("adcOutputFmt", adc["adcOutputFmt"], integer=True),
                  profiles=profiles, chirps=found["chirpCfg"], frame=fr, layout=layout, t0=t0,
                  tx_positions=tx_positions, rx_positions=rx_positions, source=source,
                  board=board, antenna_positions=antenna_positions)


def _get(d, key: str, where: str):
    if not isinstance(d, dict) or key not in d:
        raise ValueError(f"{where}mmWave Studio JSON lacks {key!r}")
    return d[key]


def parse_studio_json(doc: dict, *, layout: str | None = None, t0: float = 0.0,
                      tx_positions=None, rx_positions=None, source: str = "",
                      board: str | None = None, antenna_positions=None) -> MmwaveConfig:
    """Convert a parsed mmWave Studio JSON export (module docstring).

    ``layout`` None takes it from ``rlDevLaneEnable_t.laneEn`` (the board's
    if absent, else 2 lanes); other parameters as in :func:`parse_sdk_cfg`.

    Raises
    ------
    ValueError
        A missing key (named) or a value out of range or inconsistent.
    """
    where = f"{source}: " if source else ""
    devices = _get(doc, "mmWaveDevices", where)
    if not isinstance(devices, list) or not devices:
        raise ValueError(f"{where}mmWaveDevices must be a non-empty list")
    if len(devices) > 1:     # a cascade (MMWCAS): one array over several chips' captures
        raise ValueError(f"{where}mmWaveDevices holds {len(devices)} devices (a cascaded "
                         f"radar); one device's DCA1000 capture is read, expected one device")
    dev = devices[0]
    rf = _get(dev, "rfConfig", where)
    # Studio writes both frame structures; these two fields say which the radar ran
    for key, only in (("waveformType", "legacyFrameChirp"), ("MIMOScheme", "TDM")):
        if rf.get(key, only) != only:
            raise ValueError(f"{where}rfConfig {key} {rf[key]!r} is not supported, expected "
                             f"{only!r} (one frame of chirps, TDM MIMO: each chirp one TX)")
    chan = _get(rf, "rlChanCfg_t", where)
    fmt = _get(_get(rf, "rlAdcOutCfg_t", where), "fmt", where)
    profiles = {}
    for item in _get(rf, "rlProfiles", where):
        p = _get(item, "rlProfileCfg_t", where)
        pid = _num("rlProfileCfg_t profileId", _get(p, "profileId", where), integer=True)
        profiles[pid] = {"startFreq": _get(p, "startFreqConst_GHz", where),
                         "idleTime": _get(p, "idleTimeConst_usec", where),
                         "adcStartTime": _get(p, "adcStartTimeConst_usec", where),
                         "rampEndTime": _get(p, "rampEndTime_usec", where),
                         "freqSlopeConst": _get(p, "freqSlopeConst_MHz_usec", where),
                         "numAdcSamples": _get(p, "numAdcSamples", where),
                         "digOutSampleRate": _get(p, "digOutSampleRate", where)}
    chirps = []
    for item in _get(rf, "rlChirps", where):
        c = _get(item, "rlChirpCfg_t", where)
        chirps.append({"startIdx": _get(c, "chirpStartIdx", where),
                       "endIdx": _get(c, "chirpEndIdx", where),
                       "profileId": _get(c, "profileId", where),
                       "startFreqVar": c.get("startFreqVar_MHz", 0),
                       "freqSlopeVar": c.get("freqSlopeVar_KHz_usec", 0),
                       "idleTimeVar": c.get("idleTimeVar_usec", 0),
                       "adcStartTimeVar": c.get("adcStartTimeVar_usec", 0),
                       "txEnable": _get(c, "txEnable", where)})
    f = _get(rf, "rlFrameCfg_t", where)
    frame = {k: _get(f, k, where) for k in ("chirpStartIdx", "chirpEndIdx", "numLoops",
                                            "numFrames")}
    frame["framePeriodicity"] = _get(f, "framePeriodicity_msec", where)
    if layout is None:
        lanes = dev.get("rawDataCaptureConfig", {}).get("rlDevLaneEnable_t", {}).get("laneEn")
        if lanes is not None:
            mask = sum(1 << b for b in _bits("laneEn", lanes))
            if mask not in LANE_LAYOUT:
                raise ValueError(f"{where}laneEn {lanes!r} must be 0x3 (2 LVDS lanes) or 0xF "
                                 f"(4 lanes)")
            layout = LANE_LAYOUT[mask]
    return _build(rx_mask=_get(chan, "rxChannelEn", where),
                  tx_mask=_get(chan, "txChannelEn", where),
                  adc_bits_code=_num("b2AdcBits", _get(fmt, "b2AdcBits", where), integer=True),
                  adc_fmt_code=_num("b2AdcOutFmt", _get(fmt, "b2AdcOutFmt", where),
                                    integer=True),
                  profiles=profiles, chirps=chirps, frame=frame, layout=layout, t0=t0,
                  tx_positions=tx_positions, rx_positions=rx_positions, source=source,
                  board=board, antenna_positions=antenna_positions)


def read_mmwave_config(path: str | os.PathLike, *, layout: str | None = None, t0: float = 0.0,
                       tx_positions=None, rx_positions=None, board: str | None = None,
                       antenna_positions=None) -> MmwaveConfig:
    """Read an mmWave SDK ``.cfg`` or an mmWave Studio ``.json`` export.

    The format follows the suffix (``.json``: Studio, anything else: SDK
    CLI text). ``layout`` None: the Studio file's lane mask, else the
    board's, else ``"2lane"``. ``board`` / ``antenna_positions``: the antenna
    layout (:func:`parse_sdk_cfg`). Other parameters as in :func:`parse_sdk_cfg`.

    Raises
    ------
    ValueError
        A missing file, invalid JSON, or an invalid configuration.
    """
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"radar configuration {str(path)!r} is a folder; expected an mmWave "
                         f"SDK .cfg or mmWave Studio .json file")
    if not path.is_file():
        raise ValueError(f"radar configuration {str(path)!r} does not exist")
    text = path.read_text(encoding="utf-8", errors="replace")
    kw = dict(t0=t0, tx_positions=tx_positions, rx_positions=rx_positions, source=str(path),
              board=board, antenna_positions=antenna_positions)
    try:
        if path.suffix.lower() == ".json":
            try:
                doc = json.loads(text)
            except json.JSONDecodeError as exc:
                raise ValueError(f"not valid JSON ({exc})") from None
            return parse_studio_json(doc, layout=layout, **kw)
        return parse_sdk_cfg(text, layout=layout, **kw)
    except ValueError as exc:       # every message names the file once
        if str(path) in str(exc):
            raise
        raise ValueError(f"{path}: {exc}") from None


def sdk_cfg_text(config: RadarConfig, *, tx_order=(0,), rx_enabled=(0, 1, 2, 3),
                 adc_bits: int = 16) -> str:
    """mmWave SDK ``.cfg`` text of a :class:`RadarConfig` (ADC sampling from the ramp start).

    Parameters
    ----------
    config : RadarConfig
        ``num_tx_slots`` must equal ``len(tx_order)``.
    tx_order : sequence of int
        TX number fired in each slot.
    rx_enabled : sequence of int
        Enabled RX numbers.
    adc_bits : int
        12, 14 or 16.

    Returns
    -------
    str
        ``channelCfg``, ``adcCfg``, ``profileCfg``, one ``chirpCfg`` per slot
        and ``frameCfg``; :func:`parse_sdk_cfg` reads it back to ``config``
        (``adcStartTime`` 0, ``rampEndTime`` = ``chirp_duration``).
    """
    tx_order, rx_enabled = [int(t) for t in tx_order], [int(r) for r in rx_enabled]
    if len(tx_order) != config.num_tx_slots:
        raise ValueError(f"tx_order {tx_order} must name one TX per slot "
                         f"(num_tx_slots {config.num_tx_slots})")
    codes = {v: k for k, v in ADC_BITS.items()}
    if adc_bits not in codes:
        raise ValueError(f"adc_bits must be 12, 14 or 16, got {adc_bits!r}")
    slope = config.bandwidth / config.chirp_duration
    period = config.frame_interval
    lines = [
        "% raysim: mmWave SDK CLI configuration (profileCfg, chirpCfg, frameCfg fields in the "
        "SDK's order)",
        "sensorStop", "flushCfg", "dfeDataOutputMode 1",
        f"channelCfg {sum(1 << r for r in rx_enabled)} {sum(1 << t for t in tx_order)} 0",
        f"adcCfg {codes[adc_bits]} {1 if config.complex_sampling else 0}",
        f"profileCfg 0 {config.carrier_frequency / 1e9!r} {config.idle_time * 1e6!r} 0 "
        f"{config.chirp_duration * 1e6!r} 0 0 {slope / 1e12!r} 0 {config.num_samples} "
        f"{config.sample_rate / 1e3!r} 0 0 30",
    ]
    lines += [f"chirpCfg {s} {s} 0 0 0 0 0 {1 << t}" for s, t in enumerate(tx_order)]
    lines += [f"frameCfg 0 {len(tx_order) - 1} {config.num_chirps} {config.num_frames} "
              f"{period * 1e3!r} 1 0", "sensorStart", ""]
    return "\n".join(lines)

