"""TI mmWave evaluation boards: antenna layouts by board name, or antenna positions from a file.

The chirp configuration (mmWave SDK ``.cfg``, mmWave Studio ``.json``) says which
transmitters fire in which slot and which receivers are on, never which board
they sit on; the virtual array depends on the board. :func:`resolve_board`
picks the layout: the ``board`` given, or, without one, the only layout the
boards that fit the configuration (carrier band, transmitters used) agree on;
where they disagree it raises, naming the candidates.

Layouts (antenna centres in frame A, ``x`` along azimuth, ``y`` up, units of
half the centre wavelength ``lambda/2``; ``TXn`` / ``RXn`` numbered from 0 as
in ``channelCfg``):

==============  ====================================  ===========================  =====
board           TX (x, y)                             RX (x, y); phase             lanes
==============  ====================================  ===========================  =====
``xWR14xx``     (0, 0), (2, 1), (4, 0)                (0..3, 0); all +1            4
``xWR16xx``     (0, 0), (4, 0)                        (0..3, 0); all +1            2
``xWR18xx``     (0, 0), (2, 1), (4, 0)                (0..3, 0); all +1            2
``IWR6843ISK``  (0, 0), (2, 1), (4, 0)                (0..3, 0); all +1            2
``IWR6843AOP``  (0, 0), (2, -2), (0, -2)              (1,-1),(1,0),(0,-1),(0,0);   2
                                                      +1, -1, +1, -1
``IWR6843ODS``  (0, 0), (2, 0), (2, -2)               (0,0),(0,-1),(1,-1),(1,0);   2
                                                      +1, -1, -1, +1
==============  ====================================  ===========================  =====

The RX phase is the sign of each receiver's feed (the AOP and ODS patches are
fed from opposite sides): a capture's channels are multiplied by it before
beamforming. ``lanes``: the LVDS lanes a DCA1000 capture of the board uses
(:mod:`raysim.io.ti_dca1000`).

Sources: TI EVM user guides and TI's configurations for these boards --
"xWR1443 BoosterPack EVM User's Guide" (SWRU518) and "xWR1843 Evaluation
Module (xWR1843BOOST) Single-Chip mmWave Sensing Solution" (SPRUIM4): TX1 raised
``lambda/2`` and offset ``lambda`` in azimuth between TX0 and TX2, 2 lambda
apart; "xWR1642 BoosterPack EVM User's Guide" (SWRU508): two TX ``2 lambda``
apart in azimuth, four RX ``lambda/2`` apart; "IWR6843ISK(-ODS) Single-Chip
mmWave Sensing Solution" (SWRU546) and "IWR6843AOPEVM User's Guide"
(SPRUIX6); the virtual-antenna tables ``antGeometry0`` / ``antGeometry1`` /
``antPhaseRot`` of TI's 3D People Tracking configurations (Radar Toolbox,
``ISK_6m_default.cfg``, ``AOP_6m_default.cfg``, ``ODS_6m_default.cfg``), whose
azimuth column is ``-x`` and elevation column ``y`` (in ``lambda/2``) above, with
the same virtual order (TX major, RX minor).

Antenna file (:func:`read_antenna_positions`), for any other board or a
measured array. CSV, one antenna a row, a header naming the columns::

    # units: wavelength        (or: m)
    antenna,x,y,z
    tx0,0,0,0
    tx1,1,0.5,0
    rx0,0,0,0
    ...

optionally with a ``phase`` column (+1 / -1). JSON: ``{"units": "wavelength",
"tx": [[x, y, z], ...], "rx": [[x, y, z], ...], "rx_phase": [1, -1, ...]}``.
Units must be stated: ``wavelength`` (of the centre frequency of the
configuration) or ``m``.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Board", "BOARDS", "AntennaLayout", "board_names", "resolve_board",
           "read_antenna_positions"]


@dataclass(frozen=True)
class Board:
    """One TI board's antennas (module docstring), positions in ``lambda/2``.

    Attributes
    ----------
    name : str
    band_ghz : (float, float)
        RF band of the part [GHz] (the ``profileCfg`` start frequency lies in it).
    tx : tuple of (float, float)
        TX centres (x, y) [lambda/2], indexed by TX number.
    rx : tuple of (float, float)
        RX centres (x, y) [lambda/2], indexed by RX number.
    rx_phase : tuple of int
        Feed sign of each RX (+1 / -1).
    layout : {"2lane", "4lane"}
        LVDS lanes of a DCA1000 capture.
    """

    name: str
    band_ghz: tuple
    tx: tuple
    rx: tuple
    rx_phase: tuple
    layout: str


_LINE_RX = ((0, 0), (1, 0), (2, 0), (3, 0))
_BAND_77 = (76.0, 81.0)
_BAND_60 = (57.0, 64.0)
#: The boards, by name.
BOARDS = {b.name: b for b in (
    Board("xWR14xx", _BAND_77, ((0, 0), (2, 1), (4, 0)), _LINE_RX, (1, 1, 1, 1), "4lane"),
    Board("xWR16xx", _BAND_77, ((0, 0), (4, 0)), _LINE_RX, (1, 1, 1, 1), "2lane"),
    Board("xWR18xx", _BAND_77, ((0, 0), (2, 1), (4, 0)), _LINE_RX, (1, 1, 1, 1), "2lane"),
    Board("IWR6843ISK", _BAND_60, ((0, 0), (2, 1), (4, 0)), _LINE_RX, (1, 1, 1, 1), "2lane"),
    Board("IWR6843AOP", _BAND_60, ((0, 0), (2, -2), (0, -2)),
          ((1, -1), (1, 0), (0, -1), (0, 0)), (1, -1, 1, -1), "2lane"),
    Board("IWR6843ODS", _BAND_60, ((0, 0), (2, 0), (2, -2)),
          ((0, 0), (0, -1), (1, -1), (1, 0)), (1, -1, -1, 1), "2lane"),
)}
#: Other spellings of the board names (lower case, without "-" / "_" / " ").
_ALIASES = {
    "xwr14xx": "xWR14xx", "awr1443": "xWR14xx", "iwr1443": "xWR14xx", "1443": "xWR14xx",
    "xwr16xx": "xWR16xx", "awr1642": "xWR16xx", "iwr1642": "xWR16xx", "1642": "xWR16xx",
    "xwr18xx": "xWR18xx", "awr1843": "xWR18xx", "iwr1843": "xWR18xx", "1843": "xWR18xx",
    "iwr6843isk": "IWR6843ISK", "6843isk": "IWR6843ISK", "isk": "IWR6843ISK",
    "iwr6843aop": "IWR6843AOP", "6843aop": "IWR6843AOP", "aop": "IWR6843AOP",
    "iwr6843ods": "IWR6843ODS", "iwr6843iskods": "IWR6843ODS", "6843ods": "IWR6843ODS",
    "ods": "IWR6843ODS",
}


def board_names() -> list[str]:
    """The board names :func:`resolve_board` accepts (aliases such as ``AWR1843`` too)."""
    return list(BOARDS)


@dataclass(frozen=True)
class AntennaLayout:
    """Antennas of one capture, in metres.

    Attributes
    ----------
    tx : ndarray, shape ``[tx, 3]``
        TX positions in frame A [m], indexed by TX number.
    rx : ndarray, shape ``[rx, 3]``
        RX positions in frame A [m], indexed by RX number.
    rx_phase : ndarray, shape ``[rx]``
        Feed sign of each RX (+1 / -1).
    name : str
        Board name(s) or the antenna file.
    layout : str or None
        LVDS lanes of the board (None from a file).
    """

    tx: np.ndarray
    rx: np.ndarray
    rx_phase: np.ndarray
    name: str
    layout: str | None = None


def _board(name: str, where: str) -> Board:
    key = "".join(ch for ch in str(name).lower() if ch not in "-_ ")
    if key not in _ALIASES:
        raise ValueError(f"{where}board {name!r} is not known; expected one of "
                         f"{board_names()} (or a part number such as AWR1843, IWR6843AOP)")
    return BOARDS[_ALIASES[key]]


def _metres(b: Board, wavelength: float) -> AntennaLayout:
    h = wavelength / 2.0
    tx = np.array([[x * h, y * h, 0.0] for x, y in b.tx])
    rx = np.array([[x * h, y * h, 0.0] for x, y in b.rx])
    return AntennaLayout(tx, rx, np.asarray(b.rx_phase, dtype=float), b.name, b.layout)


def resolve_board(board: str | None, *, tx_order, rx_enabled, start_freq_hz: float,
                  wavelength: float, where: str = "") -> AntennaLayout:
    """The antenna layout of a configuration: of ``board``, or the one its candidates share.

    Parameters
    ----------
    board : str or None
        Board name (:data:`BOARDS` or an alias); None: infer (module docstring).
    tx_order : sequence of int
        TX number of each TDM slot.
    rx_enabled : sequence of int
        Enabled RX numbers.
    start_freq_hz : float
        ``profileCfg`` start frequency [Hz] (60 or 77 GHz parts).
    wavelength : float
        Centre wavelength [m] the ``lambda/2`` units are scaled with.
    where : str
        Prefix of messages (the configuration file).

    Returns
    -------
    AntennaLayout

    Raises
    ------
    ValueError
        An unknown board, a board that lacks a transmitter the configuration
        fires or whose band misses its frequency, or no board given where the
        boards that fit the configuration have different layouts (the
        message names them and how to choose).
    """
    f_ghz = float(start_freq_hz) / 1e9
    tx_used = sorted(set(int(t) for t in tx_order))
    if board is not None:
        b = _board(board, where)
        if max(tx_used) >= len(b.tx):
            raise ValueError(f"{where}board {b.name} has {len(b.tx)} transmitters (TX0.."
                             f"TX{len(b.tx) - 1}); the configuration fires TX{tx_used}")
        if not b.band_ghz[0] <= f_ghz <= b.band_ghz[1]:
            raise ValueError(f"{where}board {b.name} works in {b.band_ghz[0]:g}-"
                             f"{b.band_ghz[1]:g} GHz; the configuration starts at "
                             f"{f_ghz:.4g} GHz")
        return _metres(b, wavelength)
    fits = [b for b in BOARDS.values() if b.band_ghz[0] <= f_ghz <= b.band_ghz[1]
            and max(tx_used) < len(b.tx)]
    if not fits:
        raise ValueError(f"{where}no TI board fits a start frequency of {f_ghz:.4g} GHz with "
                         f"TX{tx_used}; give the antenna positions (--antenna-positions)")
    groups: dict = {}
    for b in fits:
        virt = tuple((b.tx[t][0] + b.rx[r][0], b.tx[t][1] + b.rx[r][1], b.rx_phase[r])
                     for t in tx_order for r in rx_enabled)
        groups.setdefault(virt, []).append(b)
    if len(groups) > 1:
        names = [b.name for b in fits]
        shapes = "; ".join("/".join(b.name for b in g) + ": TX " + ", ".join(
            str(g[0].tx[t]) for t in tx_used) for g in groups.values())
        raise ValueError(
            f"{where}the configuration (start {f_ghz:.4g} GHz, slots fire TX{list(tx_order)}, "
            f"RX{list(rx_enabled)}) fits boards with different antenna layouts: {names} "
            f"(TX positions in lambda/2: {shapes}); the configuration does not say the board: "
            f"give it (--board / board=, one of {board_names()}) or the antenna positions "
            f"(--antenna-positions FILE)")
    group = next(iter(groups.values()))
    lay = _metres(group[0], wavelength)
    lanes = {b.layout for b in group}
    return AntennaLayout(lay.tx, lay.rx, lay.rx_phase, "/".join(b.name for b in group),
                         lanes.pop() if len(lanes) == 1 else None)


_UNITS = ("wavelength", "m")


def _scale(units, where: str, wavelength: float) -> float:
    u = str(units).strip().lower() if units is not None else None
    if u in ("wavelength", "wavelengths", "lambda"):
        return float(wavelength)
    if u in ("m", "metre", "meter", "metres", "meters"):
        return 1.0
    raise ValueError(f"{where}units must be stated as one of {list(_UNITS)}, got {units!r}")


def _rows(values, name: str, where: str) -> np.ndarray:
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{where}{name} must be a list of [x, y, z] positions, got "
                         f"{values!r}") from None
    if a.ndim != 2 or a.shape[1] not in (2, 3) or a.shape[0] < 1 or not np.all(np.isfinite(a)):
        raise ValueError(f"{where}{name} must be a non-empty list of finite [x, y, z] (or "
                         f"[x, y]) positions, got shape {a.shape}")
    return np.column_stack([a, np.zeros(a.shape[0])]) if a.shape[1] == 2 else a


def read_antenna_positions(path: str | os.PathLike, wavelength: float) -> AntennaLayout:
    """TX and RX positions from a CSV or JSON file (module docstring).

    Parameters
    ----------
    path : str or path-like
        ``.csv`` or ``.json`` file.
    wavelength : float
        Centre wavelength [m] of the configuration (for ``wavelength`` units).

    Returns
    -------
    AntennaLayout
        ``tx [tx, 3]``, ``rx [rx, 3]`` [m], indexed by TX / RX number (file
        order), ``rx_phase [rx]``.

    Raises
    ------
    ValueError
        A missing file, no units stated, unknown units, a row that is not an
        antenna ``txN`` / ``rxN`` with numeric coordinates, numbers missing or
        repeated, or a phase other than +1 / -1.
    """
    p = Path(path)
    where = f"antenna positions {str(p)!r}: "
    if not p.is_file():
        raise ValueError(f"{where}file does not exist")
    text = p.read_text(encoding="utf-8", errors="replace")
    if p.suffix.lower() == ".json":
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{where}not valid JSON ({exc})") from None
        if not isinstance(doc, dict) or "tx" not in doc or "rx" not in doc:
            raise ValueError(f"{where}expected an object with 'units', 'tx' and 'rx'")
        s = _scale(doc.get("units"), where, wavelength)
        tx, rx = _rows(doc["tx"], "tx", where) * s, _rows(doc["rx"], "rx", where) * s
        phase = np.asarray(doc.get("rx_phase", np.ones(rx.shape[0])), dtype=float)
    else:
        units, rows, header = None, [], None
        for line in text.splitlines():
            st = line.strip()
            if not st:
                continue
            if st.startswith("#"):
                body = st.lstrip("#").strip()
                if body.lower().startswith("units"):
                    units = body.split(":", 1)[-1].strip() if ":" in body else body.split()[-1]
                continue
            fields = [f.strip() for f in next(csv.reader([st]))]
            if header is None:
                header = [h.lower() for h in fields]
                continue
            rows.append(fields)
        if header is None or not {"antenna", "x", "y"} <= set(header):
            raise ValueError(f"{where}expected a header with the columns antenna,x,y[,z]"
                             f"[,phase], got {header}")
        if units is None and "units" in header:
            units = rows[0][header.index("units")] if rows else None
        s = _scale(units, where, wavelength)
        ant: dict = {"tx": {}, "rx": {}}
        for n, r in enumerate(rows, 1):
            name = r[header.index("antenna")].lower()
            kind, num = name[:2], name[2:]
            if kind not in ant or not num.isdigit():
                raise ValueError(f"{where}row {n}: antenna {name!r} must be txN or rxN")
            try:
                xyz = [float(r[header.index(c)]) if c in header else 0.0 for c in "xyz"]
                ph = float(r[header.index("phase")]) if "phase" in header else 1.0
            except (ValueError, IndexError):
                raise ValueError(f"{where}row {n}: coordinates must be numbers, got "
                                 f"{r}") from None
            if int(num) in ant[kind]:
                raise ValueError(f"{where}row {n}: antenna {name!r} is given twice")
            ant[kind][int(num)] = (xyz, ph)
        for kind in ("tx", "rx"):
            if sorted(ant[kind]) != list(range(len(ant[kind]))) or not ant[kind]:
                raise ValueError(f"{where}{kind} antennas must be numbered 0..N-1, got "
                                 f"{sorted(ant[kind])}")
        tx = np.array([ant["tx"][k][0] for k in range(len(ant["tx"]))]) * s
        rx = np.array([ant["rx"][k][0] for k in range(len(ant["rx"]))]) * s
        phase = np.array([ant["rx"][k][1] for k in range(len(ant["rx"]))])
    if phase.shape != (rx.shape[0],) or not np.all(np.isin(phase, (-1.0, 1.0))):
        raise ValueError(f"{where}the RX phase must be +1 or -1 for each of the {rx.shape[0]} "
                         f"receivers, got {phase.tolist()}")
    return AntennaLayout(tx, rx, phase, str(p), None)
