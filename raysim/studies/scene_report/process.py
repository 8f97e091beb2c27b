"""Processing of the report: beams through one chain, maps, entropy, ridge leakage, CFAR.

Chains are applied by :func:`raysim.pipeline.chains.project`, block by block
of range gates (bounds memory). The ``paper`` chain's slow-time phase is
corrected towards one direction; the report has no per-target angle estimate,
so it re-points that correction per beam: every beam ``(az, el)`` is
multiplied by ``exp(-j 4 pi (dR_n(u) - dR_n(u_0)) / lambda)``
(:func:`compensation.range_change`), i.e. the paper's per-target correction
evaluated for every grid direction ``u``. The correction is a per-chirp scalar,
so this equals correcting towards ``u`` before the projection.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from raysim.processing.maps import Map
from raysim.processing.metrics import image_entropy
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig
from raysim.vocabulary import MAPS, REFERENCE, ChainSpec, parse_chain

from .settings import (
    CFAR_GUARD,
    CFAR_THRESHOLD_DB,
    CFAR_TRAIN,
    MAX_DETECTIONS,
    REPORT_MAPS,
    RIDGE_HALF_WIDTH_BINS,
    ReportSettings,
)

__all__ = ["BORESIGHT", "ChainResult", "beam_blocks", "cfar_detect", "chain_result"]

#: Direction in W of the ``paper`` chain's own slow-time correction and tilt
#: check (straight down the radar boresight); re-pointed per beam afterwards.
BORESIGHT = (0.0, 0.0, 1.0)


@dataclass(frozen=True, eq=False)
class ChainResult:
    """Maps, entropies and detections of one chain or of the reference.

    Attributes
    ----------
    key : str
        A chain key (:attr:`raysim.vocabulary.ChainSpec.key`: ``none``,
        ``paper``, ``paper:published``, ``exact``) or
        :data:`raysim.vocabulary.REFERENCE` for the stationary platform.
    maps : dict
        ``"rd"`` (dims ``range, doppler``), ``"ra"`` (``range, azimuth``), ``"ae"``
        (``azimuth, elevation``) -> :class:`raysim.processing.maps.Map` of beam power [W]
        (channel-averaged beams of IF amplitudes in sqrt(W)); axes in m, m/s, rad.
    cube : ndarray, shape ``[range, azimuth, elevation]``
        Coherent (zero-Doppler, Hann-weighted) beam power [W].
    entropy : dict
        Map name -> image entropy [nats].
    detections : list of dict
        CFAR detections, strongest first: ``range_m``, ``az_deg``, ``el_deg``,
        ``velocity_mps`` (range rate at the RD peak of the detection's gate),
        ``power_db`` (relative to the cube's maximum), ``position_m`` (in W).
    ridge_leakage_db : float
        RD power outside the zero-Doppler ridge relative to the total [dB].
    seconds : float
        Processing time [s].
    """

    key: str
    maps: dict
    cube: np.ndarray
    entropy: dict
    detections: list
    ridge_leakage_db: float
    seconds: float

    def metrics(self) -> dict:
        """``{metric name: value}`` with names from :data:`raysim.vocabulary.METRICS`.

        ``entropy_rd_nats``, ``entropy_ra_nats``, ``entropy_ae_nats`` [nats] and
        ``ridge_leakage_db`` [dB].
        """
        out = {f"entropy_{m}_nats": float(self.entropy[m]) for m in REPORT_MAPS}
        out["ridge_leakage_db"] = float(self.ridge_leakage_db)
        return out


def _repointing(spec: ChainSpec, motion, azimuth, elevation, wavelength: float) -> np.ndarray:
    """Per-beam slow-time phase of the ``paper`` chain, shape ``[chirp, 1, az, el]`` complex64.

    ``exp(-j 4 pi (dR_n(u) - dR_n(u_0)) / lambda)`` with ``u`` every grid
    direction and ``u_0`` :data:`BORESIGHT` (the direction
    :func:`raysim.pipeline.chains.project` corrected towards).
    """
    from compensation import range_change
    from compensation.geometry import grid_directions

    u = np.asarray(grid_directions(azimuth, elevation)).reshape(len(azimuth), len(elevation), 3)
    dr0 = range_change(motion, BORESIGHT, rotation_phase=spec.rotation_phase)
    dr = np.stack([np.stack([range_change(motion, u[i, j], rotation_phase=spec.rotation_phase)
                             for j in range(len(elevation))], -1)
                   for i in range(len(azimuth))], -2)                     # [chirp, az, el]
    ddr = dr - dr0[:, None, None]
    return np.exp(-4j * np.pi * ddr / wavelength).astype(np.complex64)[:, None]


def beam_blocks(chain, rc: np.ndarray, positions: np.ndarray, motion, config: RadarConfig,
                range_axis: np.ndarray, gates: np.ndarray, azimuth: np.ndarray,
                elevation: np.ndarray, grid_shape, gate_block: int):
    """Beams of one chain, block by block of range gates.

    Parameters
    ----------
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (complex64, channel taper applied).
    positions : ndarray, shape ``[channel, 3]``
        Virtual element positions [m].
    motion : compensation.PlatformMotion or None
        Pose estimate at the chirps (unused by ``none``).
    config : RadarConfig
    range_axis : ndarray, shape ``[range]``
        Range of every bin of ``rc`` [m].
    gates : ndarray of int, shape ``[gate]``
        Bins of ``rc`` to beamform.
    azimuth, elevation : ndarray
        Global grid [rad].
    grid_shape : (int, int)
        ``(nx, ny)`` of the virtual UPA.
    gate_block : int
        Gates per block.

    Yields
    ------
    (ndarray of int, compensation.BeamCube)
        The block's gates and its beams ``[chirp, gate, azimuth, elevation]``.
    """
    from raysim.pipeline.chains import project

    spec = parse_chain(chain)
    lam = config.center_wavelength
    repoint = (_repointing(spec, motion, azimuth, elevation, lam) if spec.name == "paper"
               else None)
    for g0 in range(0, gates.size, gate_block):
        sel = gates[g0:g0 + gate_block]
        bc = project(spec, rc, positions, wavelength=lam, range_axis=range_axis,
                     azimuth=azimuth, elevation=elevation,
                     motion=motion if spec.compensated else None,
                     direction=BORESIGHT if spec.name == "paper" else None,
                     grid_shape=grid_shape, range_gates=sel)
        if repoint is not None:
            bc = replace(bc, data=bc.data * repoint)
        yield sel, bc


def cfar_detect(cube: np.ndarray, *, train: int = CFAR_TRAIN, guard: int = CFAR_GUARD,
                threshold_db: float = CFAR_THRESHOLD_DB) -> np.ndarray:
    """Cell-averaging CFAR along range plus 3 x 3 x 3 local-maximum test.

    Parameters
    ----------
    cube : ndarray, shape ``[range, azimuth, elevation]``
        Non-negative power.
    train, guard : int
        Training and guard cells on each side along range.
    threshold_db : float
        Detection threshold over the mean of the training cells [dB].

    Returns
    -------
    ndarray of int, shape ``[detection, 3]``
        Indices ``(range, azimuth, elevation)``, strongest first.
    """
    from scipy.ndimage import maximum_filter, uniform_filter1d

    p = np.asarray(cube, dtype=float)
    if p.ndim != 3 or np.any(p < 0):
        raise ValueError(f"cube must be a non-negative [range, azimuth, elevation] array, got "
                         f"shape {p.shape}")
    if train < 1 or guard < 0:
        raise ValueError(f"need train >= 1 and guard >= 0, got train={train!r}, guard={guard!r}")
    big = uniform_filter1d(p, 2 * (train + guard) + 1, axis=0, mode="nearest") * (
        2 * (train + guard) + 1)
    small = uniform_filter1d(p, 2 * guard + 1, axis=0, mode="nearest") * (2 * guard + 1)
    noise = np.maximum((big - small) / (2 * train), np.finfo(float).tiny)
    hit = (p > noise * 10 ** (threshold_db / 10)) & (p == maximum_filter(p, size=3,
                                                                          mode="nearest"))
    idx = np.argwhere(hit)
    order = np.argsort(-p[hit])
    return idx[order]


def chain_result(chain, rc: np.ndarray, motion, settings: ReportSettings,
                 config: RadarConfig, array: VirtualArray) -> ChainResult:
    """Beams, maps, entropies and detections of one chain (or of the reference).

    Parameters
    ----------
    chain : str or ChainSpec
        A chain (``none``, ``paper``, ``paper:published``, ``exact``), or
        :data:`raysim.vocabulary.REFERENCE` for the stationary platform's frame
        (beamformed like ``none``).
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (Hann), channel taper applied.
    motion : compensation.PlatformMotion or None
        Pose estimate at the chirps (needed by ``paper`` and ``exact``).
    settings, config, array
        Report settings, waveform and virtual array.

    Returns
    -------
    ChainResult
    """
    if chain == REFERENCE:
        spec, key = parse_chain("none"), REFERENCE
    else:
        spec = parse_chain(chain)
        key = spec.key
    t = time.perf_counter()
    n_range = rc.shape[-1]
    r_axis = config.bin_ranges(n_range)
    lo, hi = settings.range_window
    gates = np.nonzero((r_axis >= lo) & (r_axis <= hi))[0]
    az, el = settings.grid()
    positions = array.virtual_positions
    rd = np.zeros((gates.size, rc.shape[0]))
    cube = np.zeros((gates.size, az.size, el.size))
    rc_win = np.ascontiguousarray(rc[:, :, gates])               # the window only
    local = np.arange(gates.size)
    for k, bc in beam_blocks(spec, rc_win, positions, motion, config, r_axis[gates], local,
                             az, el, array.grid_shape, settings.gate_block):
        spec_d = bc.doppler()                                # [doppler, g, az, el]
        rd[k] = np.einsum("dgae->gd", np.abs(spec_d.astype(np.complex128)) ** 2)
        cube[k] = bc.coherent_power(window="hann")
    vel = config.velocity_axis(rc.shape[0])
    rng = r_axis[gates]
    maps = {
        "rd": Map(rd, MAPS["rd"], {"range": rng, "doppler": vel}),
        "ra": Map(cube.sum(axis=2), MAPS["ra"], {"range": rng, "azimuth": az}),
        "ae": Map(cube.sum(axis=0), MAPS["ae"], {"azimuth": az, "elevation": el}),
    }
    entropy = {m: image_entropy(maps[m].values) for m in REPORT_MAPS}
    centre = rc.shape[0] // 2
    ridge = rd[:, centre - RIDGE_HALF_WIDTH_BINS: centre + RIDGE_HALF_WIDTH_BINS + 1].sum()
    leak = float(10 * np.log10(max(rd.sum() - ridge, 0.0) / rd.sum() + 1e-300))
    detections = []
    lever = np.asarray(settings.lever_arm, dtype=float)
    from raysim.echoes.oracle import direction

    for gi, ai, ei in cfar_detect(cube)[:MAX_DETECTIONS]:
        u = direction(az[ai], el[ei])
        d = int(np.argmax(rd[gi]))
        detections.append({
            "range_m": float(rng[gi]), "az_deg": float(np.rad2deg(az[ai])),
            "el_deg": float(np.rad2deg(el[ei])), "velocity_mps": float(vel[d]),
            "power_db": float(10 * np.log10(cube[gi, ai, ei] / cube.max())),
            "position_m": (lever + rng[gi] * u).tolist()})
    return ChainResult(key, maps, cube, entropy, detections, leak, time.perf_counter() - t)
