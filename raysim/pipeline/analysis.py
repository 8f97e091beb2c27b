"""Maps and metrics of frames through one chain (stages 5-6 of the run path).

:func:`analyse` turns IF frames into the maps of :data:`raysim.vocabulary.MAPS`
and the metrics of :data:`raysim.vocabulary.METRICS`, with the beams of one
chain (:func:`raysim.pipeline.chains.project`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from raysim.pipeline.chains import project
from raysim.pipeline.sources import Reference
from raysim.processing.maps import Map, doppler_fft, range_compress, window
from raysim.processing.metrics import (
    angle_error_deg,
    doppler_mainlobe_width,
    parabolic_offset,
    pseudo_velocity,
)
from raysim.synthesis.frame import RadarFrame
from raysim.vocabulary import ChainSpec, parse_chain

__all__ = ["ANALYSIS_METRICS", "ANGLE_LIMIT_DEG", "ANGLE_STEP_DEG", "SINGLE_CHIRP_HALF_WIDTH_DEG",
           "SINGLE_CHIRP_STEP_DEG", "MAX_SNAPSHOTS", "RANGE_SEARCH_M", "angle_chirp",
           "gate_snapshots", "analyse", "angle_apertures", "check_finite_frames"]

#: Metrics returned by :func:`analyse`, in order (units in :data:`raysim.vocabulary.METRICS`).
ANALYSIS_METRICS = ("range_m", "az_deg", "el_deg", "angle_error_deg", "map_az_deg",
                    "map_el_deg", "map_angle_error_deg",
                    "pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
                    "doppler_width_bins", "entropy_ae_nats", "entropy_rd_nats", "peak_power_db")
#: Half-width of the accumulated azimuth / elevation scan of :func:`analyse` [deg].
ANGLE_LIMIT_DEG = 60.0
#: Step of the accumulated azimuth / elevation scan of :func:`analyse` [deg].
ANGLE_STEP_DEG = 1.0
#: Half-width of the single-chirp angle grid around the reference direction [deg].
SINGLE_CHIRP_HALF_WIDTH_DEG = 15.0
#: Step of the single-chirp angle grid [deg].
SINGLE_CHIRP_STEP_DEG = 0.5
#: Chirps beamformed at a time into the coherent AE map (bounds its memory).
MAX_SNAPSHOTS = 256
#: Half-width of the range window searched around a known target range [m].
RANGE_SEARCH_M = 1.5


def angle_chirp(num_chirps: int) -> int:
    """Chirp of the single-chirp angle estimate: ``N/2 - 1`` (the paper's chirp 128 of 256)."""
    return max(num_chirps // 2 - 1, 0)


def local_axis(centre: float, half_deg: float, step_deg: float) -> np.ndarray:
    """Grid axis ``centre + k step`` within ``+-half_deg`` [rad]; ``centre`` [rad]."""
    n = int(round(half_deg / step_deg))
    return centre + np.deg2rad(np.arange(-n, n + 1) * step_deg)


def gate_snapshots(data: np.ndarray, range_bin: float) -> np.ndarray:
    """Hann-windowed range DFT of IF data at one (fractional) range bin.

    Parameters
    ----------
    data : ndarray, shape ``[chirp, channel, sample]``
    range_bin : float
        Range-FFT bin (unpadded FFT of length ``sample``).

    Returns
    -------
    ndarray, shape ``[chirp, channel]``, complex64
        Equal to ``range_compress(data)[..., range_bin]`` for an integer bin.
    """
    k = data.shape[-1]
    w = window("hann", k)
    # a real-sampled cube keeps the positive beat half, doubled (as range_compress)
    gain = 1.0 if np.iscomplexobj(data) else 2.0
    kern = gain * (w / w.sum()) * np.exp(-2j * np.pi * range_bin * np.arange(k) / k)
    return (data @ kern.astype(np.complex64)).astype(np.complex64)


def check_finite_frames(frames: Sequence[RadarFrame], start: int = 0) -> None:
    """Raise if any IF sample is NaN or infinite.

    ``start`` is the position of ``frames[0]`` in the run (for the message).

    Raises
    ------
    ValueError
        Naming the frame (its ``frame_index``), chirp, channel and sample of the
        first bad value.
    """
    for k, fr in enumerate(frames, start):
        data = np.asarray(fr.data)
        ok = np.isfinite(data)
        if not ok.all():
            c, m, s = (int(v) for v in np.argwhere(~ok)[0])
            idx = getattr(fr, "frame_index", k)
            raise ValueError(f"frame {idx} (position {k}): IF data holds a non-finite value "
                             f"{complex(data[c, m, s])} at chirp {c}, channel {m}, sample {s} "
                             f"({int((~ok).sum())} such samples); expected finite samples")


def angle_apertures(positions: np.ndarray, wavelength: float) -> tuple[bool, bool]:
    """Whether the virtual array resolves azimuth and elevation.

    With ``u = (cos el sin az, sin el, cos el cos az)`` azimuth is measured by
    the spread of the positions along x and elevation by their spread along y
    (positions ``[channel, 3]`` in frame A [m]); an axis whose spread is below a
    thousandth of ``wavelength`` [m] (a single channel, a line array) has no
    aperture.
    """
    p = np.asarray(positions, dtype=float).reshape(-1, 3)
    tol = 1e-3 * wavelength
    return bool(np.ptp(p[:, 0]) > tol), bool(np.ptp(p[:, 1]) > tol)


def _parabolic_peak(y: np.ndarray, i: int) -> float:
    if 0 < i < y.size - 1:
        db = 10 * np.log10(np.maximum(y[i - 1: i + 2], 1e-300))
        return i + parabolic_offset(db[0], db[1], db[2])
    return float(i)


def _beamformer(spec: ChainSpec, frame: RadarFrame, motion, warnings: list):
    """``bf(rc, chirps, ranges, az, el, direction) -> [chirp, range, azimuth, elevation]``.

    ``rc`` is ``[chirp, channel, range]`` (the chirps ``chirps`` of ``frame``),
    ``ranges`` the range of each of its bins [m], ``az``/``el`` grid axes
    [rad], ``direction`` the slow-time correction direction of the paper chain.
    Guard warnings of the chain are appended to ``warnings``.
    """
    arr, cfg = frame.array, frame.config
    slots = arr.num_slots
    per_slot = spec.compensated and slots > 1

    def bf(rc, chirps, ranges, az, el, direction=None):
        c = np.asarray(chirps)
        mot, channel_slot = None, None
        if motion is not None and per_slot:           # every TDM slot at its own pose
            mot = motion.select((c[:, None] * slots + np.arange(slots)).ravel())
            channel_slot = arr.tx_slot
        elif motion is not None:                      # one pose per chirp loop (slot 0)
            mot = motion.select(c * slots)
        out = project(spec, rc, arr.virtual_positions, wavelength=cfg.center_wavelength,
                      range_axis=ranges, azimuth=az, elevation=el, motion=mot,
                      direction=direction, grid_shape=arr.grid_shape,
                      channel_slot=channel_slot)
        warnings.extend(w for w in out.warnings if w not in warnings)
        return out.data
    return bf


def analyse(frames: Sequence[RadarFrame], reference: Reference | None = None, *,
            chain: str | ChainSpec = "none", motion=None,
            angle_limit_deg: float = ANGLE_LIMIT_DEG, angle_step_deg: float = ANGLE_STEP_DEG,
            return_maps: bool = False, range_angle_chirps: int = 16,
            warnings: list | None = None):
    """The metrics of :data:`raysim.vocabulary.METRICS` of frames, through one chain.

    Procedure: range profile of frame 0 (Hann, power summed over chirps and
    channels), peak within :data:`RANGE_SEARCH_M` of the reference range (or
    the global peak) refined by a parabola on dB; channel snapshots of every
    frame at that gate. Single-chirp angle: the AE map of chirp
    :func:`angle_chirp` of frame 0 on a grid of :data:`SINGLE_CHIRP_STEP_DEG`
    within :data:`SINGLE_CHIRP_HALF_WIDTH_DEG` of the reference direction
    (of the accumulated peak without one), its interpolated peak
    (``az_deg``, ``el_deg``, ``angle_error_deg``). Accumulated AE map: grid
    ``+-angle_limit_deg`` in steps of ``angle_step_deg``; the beams of each
    frame summed coherently over its chirps (the zero-Doppler beam, the
    paper's yaw metric), their power summed over frames
    (``map_angle_error_deg``, ``entropy_ae_nats``). Slow-time signal of
    frame 0 at the gate in the beam towards the reference (or the
    single-chirp estimate): pseudo-velocity and Doppler width; RD map of the
    same beam and its entropy.

    Parameters
    ----------
    frames : sequence of RadarFrame
        ``data`` of shape ``[chirp, channel, sample]`` each.
    reference : Reference, optional
        Truth target (range window, Doppler beam, angle errors).
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``; the paper
        chain corrects slow time towards its own single-chirp estimate.
    motion : compensation.PlatformMotion, optional
        Pose at every transmit slot of every chirp of all frames, frame after
        frame, chirp major, slot minor (one pose per chirp for a single-slot
        array); required for the compensated chains (see
        :func:`raysim.pipeline.run.motion_times`). The exact chain projects each
        TDM slot's channels with the pose of its own transmit instant; so do
        the paper chain's tilt, slow-time and yaw steps.
    return_maps : bool
        Also return the maps: ``range_profile`` (``range``), ``rd``, ``ae``,
        ``ra``, ``re`` (dimensions of :data:`raysim.vocabulary.MAPS`) as
        :class:`~raysim.processing.maps.Map`, ``slow_time`` (``[chirp]``) and
        ``range_bin``.
    range_angle_chirps : int
        Chirps of frame 0 whose power is summed in the ``ra`` / ``re`` maps.
    warnings : list, optional
        Receives the chain's guard warnings (str), each once.

    Returns
    -------
    dict
        Metric name -> value, units in :data:`raysim.vocabulary.METRICS`
        (angle errors are NaN without a reference; azimuth metrics are NaN for
        an array without aperture along x, elevation metrics for one without
        aperture along y, and the angle errors with either, see
        :func:`angle_apertures`). With ``return_maps``, a tuple
        ``(metrics, maps)``.

    Raises
    ------
    ValueError
        Bad arguments, or a NaN / infinite IF sample (naming its frame, chirp,
        channel and sample).
    """
    if not isinstance(frames, Sequence):
        frames = list(frames)
    if len(frames) == 0:
        raise ValueError("frames is empty: nothing to analyse")
    spec = parse_chain(chain)
    if spec.compensated and motion is None:
        raise ValueError(f"chain {spec.key!r} needs motion (the platform pose at every chirp)")
    if not (0 < angle_step_deg <= angle_limit_deg <= 90):
        raise ValueError(f"need 0 < angle_step_deg <= angle_limit_deg <= 90, got "
                         f"{angle_step_deg!r}, {angle_limit_deg!r}")
    check_finite_frames([frames[0]])        # the others when the frame loop reads them
    cfg = frames[0].config
    n = frames[0].data.shape[0]
    slots = frames[0].array.num_slots
    if motion is not None and motion.num_chirps != n * slots * len(frames):
        raise ValueError(f"motion has {motion.num_chirps} poses, frames need {n * len(frames)} "
                         f"chirps x {slots} TDM slot(s) = {n * slots * len(frames)}")
    found = [] if warnings is None else warnings
    per_frame = n * slots
    bfs = [_beamformer(spec, frames[0], None if motion is None else
                       motion.select(slice(k * per_frame, (k + 1) * per_frame)), found)
           for k in range(len(frames))]
    wl = cfg.center_wavelength

    rc0 = range_compress(frames[0].data)                       # [chirp, channel, range]
    n_range = rc0.shape[-1]
    r_axis = cfg.bin_ranges(n_range)
    profile = np.sum(np.abs(rc0) ** 2, axis=(0, 1))[: r_axis.size]
    search = profile.copy()
    if reference is not None:
        outside = np.abs(r_axis - reference.range_m) > RANGE_SEARCH_M
        if not np.all(outside):
            search[outside] = 0.0
    i = int(np.argmax(search))
    range_m = float(np.interp(_parabolic_peak(profile, i), np.arange(r_axis.size), r_axis))
    gate_r = r_axis[[i]]

    # accumulated AE map over the frames (the paper chain looks towards the truth here)
    grid = np.deg2rad(np.arange(-angle_limit_deg, angle_limit_deg + 1e-9, angle_step_deg))
    all_chirps = np.arange(n)
    power = 0.0
    snaps0 = None
    for k, bf in enumerate(bfs):
        fr = frames[k]                  # lazy frames are rendered once, here
        if k:
            check_finite_frames([fr], start=k)
        snaps = gate_snapshots(fr.data, i)[:, :, None]          # [chirp, channel, 1]
        if k == 0:
            snaps0 = snaps
        power = power + _coherent_power(bf, snaps, all_chirps, gate_r, grid,
                                        reference.direction if reference is not None else None)
    ae = Map(power, ("azimuth", "elevation"), {"azimuth": grid, "elevation": grid})
    pk = ae.peak()
    u_map = _direction(pk["azimuth"], pk["elevation"])

    # single-chirp angle estimate (the paper's chirp 128 metric)
    c = angle_chirp(n)
    if reference is not None:
        look_az, look_el = math.radians(reference.az_deg), math.radians(reference.el_deg)
    else:
        look_az, look_el = pk["azimuth"], pk["elevation"]
    az_a = local_axis(look_az, SINGLE_CHIRP_HALF_WIDTH_DEG, SINGLE_CHIRP_STEP_DEG)
    el_a = local_axis(look_el, SINGLE_CHIRP_HALF_WIDTH_DEG, SINGLE_CHIRP_STEP_DEG)
    one = bfs[0](snaps0[c:c + 1], [c], gate_r, az_a, el_a,
                 reference.direction if reference is not None else u_map)
    single = Map(np.abs(one[0, 0].astype(np.complex128)) ** 2, ("azimuth", "elevation"),
                 {"azimuth": az_a, "elevation": el_a})
    pk1 = single.peak()
    u_hat = _direction(pk1["azimuth"], pk1["elevation"])
    if reference is not None:
        err = angle_error_deg(pk1["azimuth"], pk1["elevation"], look_az, look_el)
        map_err = angle_error_deg(pk["azimuth"], pk["elevation"], look_az, look_el)
    else:
        err = map_err = math.nan

    slow = bfs[0](snaps0, all_chirps, gate_r, [look_az], [look_el], u_hat)[:, 0, 0, 0]
    beam_rc = bfs[0](rc0, all_chirps, r_axis, [look_az], [look_el], u_hat)[:, :, 0, 0]
    spec_rd = doppler_fft(beam_rc, axis=0)                       # [doppler, range]
    rd = Map(np.abs(spec_rd.T) ** 2, ("range", "doppler"),
             {"range": r_axis, "doppler": cfg.velocity_axis(spec_rd.shape[0])})
    width = doppler_mainlobe_width(slow, cfg.chirp_interval)
    pv = pseudo_velocity(slow, cfg.chirp_interval, wl)
    has_az, has_el = angle_apertures(frames[0].array.virtual_positions, cfg.center_wavelength)
    if not (has_az and has_el):
        err = map_err = math.nan
    metrics = {
        "range_m": range_m,
        "az_deg": math.degrees(pk1["azimuth"]) if has_az else math.nan,
        "el_deg": math.degrees(pk1["elevation"]) if has_el else math.nan,
        "angle_error_deg": float(err),
        "map_az_deg": math.degrees(pk["azimuth"]) if has_az else math.nan,
        "map_el_deg": math.degrees(pk["elevation"]) if has_el else math.nan,
        "map_angle_error_deg": float(map_err),
        "pseudo_velocity_mps": pv,
        "pseudo_velocity_bins": pv / cfg.velocity_resolution,
        "doppler_width_hz": width,
        "doppler_width_bins": width / cfg.doppler_resolution,
        "entropy_ae_nats": ae.entropy(),
        "entropy_rd_nats": rd.entropy(),
        "peak_power_db": float(10 * np.log10(max(profile[i] / (n * snaps0.shape[1]),
                                                  1e-300))),
    }
    if not return_maps:
        return metrics
    ra_pick = np.unique(np.linspace(0, n - 1, min(n, range_angle_chirps)).astype(int))
    ra = bfs[0](rc0[ra_pick], ra_pick, r_axis, grid, [look_el], u_hat)[:, :, :, 0]
    re_ = bfs[0](rc0[ra_pick], ra_pick, r_axis, [look_az], grid, u_hat)[:, :, 0, :]
    maps = {
        "range_profile": Map(profile, ("range",), {"range": r_axis}), "rd": rd, "ae": ae,
        "ra": Map(np.sum(np.abs(ra) ** 2, axis=0), ("range", "azimuth"),
                  {"range": r_axis, "azimuth": grid}),
        "re": Map(np.sum(np.abs(re_) ** 2, axis=0), ("range", "elevation"),
                  {"range": r_axis, "elevation": grid}),
        "range_bin": i, "slow_time": slow,
    }
    return metrics, maps


def _coherent_power(bf, snaps: np.ndarray, chirps: np.ndarray, gate_r, grid, direction):
    """AE power of the beams summed coherently over a frame's chirps, ``[azimuth, elevation]``.

    Chirp blocks of :data:`MAX_SNAPSHOTS` bound the memory of the beams.
    """
    total = 0.0
    for c in range(0, chirps.size, MAX_SNAPSHOTS):
        sel = chirps[c:c + MAX_SNAPSHOTS]
        beams = bf(snaps[sel], sel, gate_r, grid, grid, direction)     # [chirp, 1, az, el]
        total = total + beams[:, 0].astype(np.complex128).sum(axis=0)
    return np.abs(total / chirps.size) ** 2


def _direction(az: float, el: float) -> np.ndarray:
    from raysim.echoes.oracle import direction

    return direction(az, el)
