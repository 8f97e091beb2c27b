"""Metrics of a point target through one chain, each defined once.

Every command and study that reports a point metric (``simulate``, ``render`` +
``report``, ``sweep``, ``reproduce``, the stability study) measures it here,
with the parameters of this module's constants; docs/conventions.md states
them. Names and units are those of :data:`raysim.vocabulary.METRICS`.

Two stages:

* :func:`point_cells` reads IF frames once: the range profile of frame 0, the
  target's range gate (:data:`RANGE_SEARCH_M` around the reference, parabolic
  peak) and the gate's channel snapshots of every frame (:func:`gate_snapshots`),
  a :class:`PointGate`.
* :func:`gate_metrics` measures a :class:`PointGate` through one chain (the
  metrics of :data:`GATE_METRICS`). A gate from any source works: the
  stability study builds one from :func:`raysim.echoes.gated.gated_cube`.

:func:`measure` composes both and adds the metrics that need the whole range
axis (``range_m``, ``entropy_rd_nats``, ``peak_power_db``) and the maps.
All beams come from :class:`raysim.pipeline.beams.Beamformer`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from raysim.pipeline.beams import Beamformer, common_subaperture
from raysim.pipeline.sources import Reference
from raysim.processing.maps import Map, doppler_fft, range_compress, window
from raysim.processing.metrics import (
    angle_error_deg,
    doppler_mainlobe_width,
    parabolic_offset,
    pseudo_velocity,
)
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig
from raysim.synthesis.frame import RadarFrame
from raysim.vocabulary import ChainSpec, parse_chain

__all__ = ["POINT_METRICS", "GATE_METRICS", "ANGLE_LIMIT_DEG", "ANGLE_STEP_DEG",
           "SINGLE_CHIRP_HALF_WIDTH_DEG", "SINGLE_CHIRP_STEP_DEG", "MAX_SNAPSHOTS",
           "RANGE_SEARCH_M", "RANGE_WINDOW", "RANGE_ANGLE_CHIRPS", "PointGate", "PointCells",
           "angle_chirp", "local_axis", "map_grid", "gate_snapshots", "check_finite_frames",
           "angle_apertures", "point_cells", "gate_metrics", "measure"]

#: Metrics returned by :func:`measure`, in order (units in :data:`raysim.vocabulary.METRICS`).
POINT_METRICS = ("range_m", "az_deg", "el_deg", "angle_error_deg", "map_az_deg",
                 "map_el_deg", "map_angle_error_deg",
                 "pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
                 "doppler_width_bins", "entropy_ae_nats", "entropy_rd_nats", "peak_power_db")
#: Metrics of :func:`gate_metrics`: those of :data:`POINT_METRICS` a range gate alone gives.
GATE_METRICS = ("az_deg", "el_deg", "angle_error_deg", "map_az_deg", "map_el_deg",
                "map_angle_error_deg", "pseudo_velocity_mps", "pseudo_velocity_bins",
                "doppler_width_hz", "doppler_width_bins", "entropy_ae_nats")
#: Half-width of the accumulated azimuth-elevation map (``entropy_ae_nats``, ``map_*``) [deg].
ANGLE_LIMIT_DEG = 60.0
#: Step of the accumulated azimuth-elevation map [deg].
ANGLE_STEP_DEG = 1.0
#: Half-width of the single-chirp angle grid around the reference direction [deg].
SINGLE_CHIRP_HALF_WIDTH_DEG = 15.0
#: Step of the single-chirp angle grid [deg].
SINGLE_CHIRP_STEP_DEG = 0.5
#: Chirps beamformed at a time into the accumulated AE map (bounds its memory).
MAX_SNAPSHOTS = 256
#: Half-width of the range window searched around a known target range [m].
RANGE_SEARCH_M = 1.5
#: Fast-time window of the range DFT (normalised by its sum).
RANGE_WINDOW = "hann"
#: Chirps of frame 0 (evenly spread) whose power is summed in the ``ra`` / ``re`` maps.
RANGE_ANGLE_CHIRPS = 16


def angle_chirp(num_chirps: int) -> int:
    """Chirp of the single-chirp angle estimate: ``N/2 - 1`` (the paper's chirp 128 of 256)."""
    return max(num_chirps // 2 - 1, 0)


def local_axis(centre: float, half_deg: float, step_deg: float) -> np.ndarray:
    """Grid axis ``centre + k step`` within ``+-half_deg`` [rad]; ``centre`` [rad]."""
    n = int(round(half_deg / step_deg))
    return centre + np.deg2rad(np.arange(-n, n + 1) * step_deg)


def map_grid() -> np.ndarray:
    """Azimuth (and elevation) axis of the accumulated AE map, shape ``[azimuth]`` [rad].

    ``-ANGLE_LIMIT_DEG .. +ANGLE_LIMIT_DEG`` in steps of :data:`ANGLE_STEP_DEG`.
    """
    return np.deg2rad(np.arange(-ANGLE_LIMIT_DEG, ANGLE_LIMIT_DEG + 1e-9, ANGLE_STEP_DEG))


def gate_snapshots(data: np.ndarray, range_bin: float) -> np.ndarray:
    """Windowed range DFT of IF data at one (fractional) range bin.

    Parameters
    ----------
    data : ndarray, shape ``[chirp, channel, sample]``
    range_bin : float
        Range-FFT bin (unpadded FFT of length ``sample``).

    Returns
    -------
    ndarray, shape ``[chirp, channel]``, complex64
        Equal to ``range_compress(data)[..., range_bin]`` for an integer bin
        (window :data:`RANGE_WINDOW`).
    """
    k = data.shape[-1]
    w = window(RANGE_WINDOW, k)
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


@dataclass(frozen=True, eq=False)
class PointGate:
    """The target's range gate in every frame: what :func:`gate_metrics` measures.

    Attributes
    ----------
    snapshots : ndarray, shape ``[frame, chirp, channel]``, complex
        Range-compressed samples of the gate [sqrt(W)].
    range_m : float
        Range of the gate's bin [m] (the beamformer's range axis).
    config : RadarConfig
        Waveform of the frames.
    array : VirtualArray
        Virtual array of the frames.
    """

    snapshots: np.ndarray
    range_m: float
    config: RadarConfig
    array: VirtualArray

    def __post_init__(self) -> None:
        s = np.asarray(self.snapshots)
        if s.ndim != 3 or 0 in s.shape:
            raise ValueError(f"snapshots: got shape {s.shape}, expected [frame, chirp, channel] "
                             f"with every axis non-empty")
        if s.shape[2] != self.array.num_channels:
            raise ValueError(f"snapshots: got {s.shape[2]} channels, the array has "
                             f"{self.array.num_channels}")
        if not np.all(np.isfinite(s)):
            raise ValueError("snapshots hold a non-finite value; expected finite samples")
        if not (math.isfinite(self.range_m) and self.range_m >= 0):
            raise ValueError(f"range_m: got {self.range_m!r}, expected a range >= 0 [m]")
        object.__setattr__(self, "snapshots", s)

    @property
    def num_frames(self) -> int:
        """Frames of the gate."""
        return int(self.snapshots.shape[0])

    @property
    def num_chirps(self) -> int:
        """Chirps per frame."""
        return int(self.snapshots.shape[1])


@dataclass(frozen=True, eq=False)
class PointCells:
    """What :func:`measure` reads of IF frames: the gate and frame 0's range cube.

    Attributes
    ----------
    gate : PointGate
    range_bin : int
        Bin of the gate in ``cube``.
    cube : ndarray, shape ``[chirp, channel, range]``
        Range-compressed frame 0 [sqrt(W)].
    range_axis : ndarray, shape ``[range]``
        Range of every bin of ``cube`` [m].
    profile : ndarray, shape ``[range]``
        Frame 0's power summed over chirps and channels [W].
    """

    gate: PointGate
    range_bin: int
    cube: np.ndarray
    range_axis: np.ndarray
    profile: np.ndarray


def _parabolic_peak(y: np.ndarray, i: int) -> float:
    if 0 < i < y.size - 1:
        db = 10 * np.log10(np.maximum(y[i - 1: i + 2], 1e-300))
        return i + parabolic_offset(db[0], db[1], db[2])
    return float(i)


def point_cells(frames: Sequence[RadarFrame], reference: Reference | None = None) -> PointCells:
    """Read frames once: frame 0's range profile, the target's gate, its snapshots per frame.

    The gate is the peak of frame 0's range profile (window
    :data:`RANGE_WINDOW`, power summed over chirps and channels) within
    :data:`RANGE_SEARCH_M` of the reference range (the global peak without a
    reference, or when no bin lies that close).

    Parameters
    ----------
    frames : sequence of RadarFrame
        ``data`` of shape ``[chirp, channel, sample]`` each; a lazy sequence is
        read once, frame after frame.
    reference : Reference, optional
        Truth target.

    Returns
    -------
    PointCells

    Raises
    ------
    ValueError
        No frames, or a NaN / infinite IF sample (naming its frame, chirp,
        channel and sample).
    """
    if not isinstance(frames, Sequence):
        frames = list(frames)
    if len(frames) == 0:
        raise ValueError("frames is empty: nothing to measure")
    fr0 = frames[0]
    check_finite_frames([fr0])
    cfg = fr0.config
    rc0 = range_compress(fr0.data)                              # [chirp, channel, range]
    r_axis = cfg.bin_ranges(rc0.shape[-1])
    profile = np.sum(np.abs(rc0) ** 2, axis=(0, 1))[: r_axis.size]
    search = profile.copy()
    if reference is not None:
        outside = np.abs(r_axis - reference.range_m) > RANGE_SEARCH_M
        if not np.all(outside):
            search[outside] = 0.0
    i = int(np.argmax(search))
    snaps = [gate_snapshots(fr0.data, i)]
    for k in range(1, len(frames)):
        fr = frames[k]                  # lazy frames are rendered once, here
        check_finite_frames([fr], start=k)
        snaps.append(gate_snapshots(fr.data, i))
        del fr
    gate = PointGate(np.stack(snaps), float(r_axis[i]), cfg, fr0.array)
    return PointCells(gate, i, rc0, r_axis, profile)


def _beamformers(spec: ChainSpec, gate: PointGate, motion, found: list) -> list[Beamformer]:
    """One :class:`Beamformer` per frame of the gate; ``dpca`` keeps one sub-aperture size
    for every frame (:func:`raysim.pipeline.beams.common_subaperture`), so the frames'
    beams add up on one resolution."""
    arr, wl = gate.array, gate.config.center_wavelength
    motions = _split_motion(motion if spec.compensated else None, gate)
    sub = None
    if spec.name == "dpca" and len(motions) > 1:
        sub, _ = common_subaperture(arr.virtual_positions, motions, wl,
                                    grid_shape=arr.grid_shape,
                                    channel_slot=arr.tx_slot if arr.num_slots > 1 else None)
    return [Beamformer(spec, arr, wl, motion=m, warnings=found, subaperture=sub)
            for m in motions]


def _split_motion(motion, gate: PointGate) -> list:
    """Per-frame motion (poses at every TDM slot of every chirp), or Nones."""
    if motion is None:
        return [None] * gate.num_frames
    per_frame = gate.num_chirps * gate.array.num_slots
    total = per_frame * gate.num_frames
    if motion.num_chirps != total:
        raise ValueError(f"motion has {motion.num_chirps} poses, the gate needs "
                         f"{gate.num_frames} frame(s) x {gate.num_chirps} chirps x "
                         f"{gate.array.num_slots} TDM slot(s) = {total}")
    return [motion.select(slice(k * per_frame, (k + 1) * per_frame))
            for k in range(gate.num_frames)]


def _coherent_power(bf: Beamformer, snaps: np.ndarray, gate_r, grid, direction) -> np.ndarray:
    """AE power of the beams summed coherently over a frame's chirps, ``[azimuth, elevation]``.

    ``none`` is linear: its beams of the chirp mean are the mean of its beams.
    A compensated chain beamforms blocks of :data:`MAX_SNAPSHOTS` chirps.
    """
    n = snaps.shape[0]
    if not bf.compensated:
        mean = snaps.astype(np.complex128).mean(axis=0, keepdims=True)
        beams = bf(mean.astype(np.complex64), [0], gate_r, grid, grid, direction)
        return np.abs(beams[0, 0].astype(np.complex128)) ** 2
    total = 0.0
    for c in range(0, n, MAX_SNAPSHOTS):
        sel = np.arange(c, min(c + MAX_SNAPSHOTS, n))
        beams = bf(snaps[sel], sel, gate_r, grid, grid, direction)     # [chirp, 1, az, el]
        total = total + beams[:, 0].astype(np.complex128).sum(axis=0)
    return np.abs(total / n) ** 2


def _direction(az: float, el: float) -> np.ndarray:
    from compensation.geometry import direction

    return direction(az, el)


def gate_metrics(gate: PointGate, reference: Reference | None = None, *,
                 chain: str | ChainSpec = "none", motion=None, warnings: list | None = None,
                 maps: dict | None = None, accumulate: bool = True) -> dict:
    """The metrics of :data:`GATE_METRICS` of a range gate through one chain.

    Definitions (parameters are this module's constants):

    * accumulated AE map: grid ``+-ANGLE_LIMIT_DEG`` in steps of
      ``ANGLE_STEP_DEG`` in azimuth and elevation (:func:`map_grid`); the
      beams of each frame summed coherently over all its chirps (the
      zero-Doppler beam, the paper's yaw metric; the paper chain corrects slow
      time towards the reference direction), their power summed over frames.
      Its interpolated peak gives ``map_az_deg``, ``map_el_deg`` and
      ``map_angle_error_deg``; its image entropy ``entropy_ae_nats``.
    * single-chirp angle: the AE map of chirp :func:`angle_chirp` of frame 0
      on a grid of ``SINGLE_CHIRP_STEP_DEG`` within
      ``SINGLE_CHIRP_HALF_WIDTH_DEG`` of the reference direction (of the
      accumulated peak without one), its interpolated peak: ``az_deg``,
      ``el_deg``, ``angle_error_deg``.
    * slow time: frame 0's gate in the beam towards the reference (the
      single-chirp estimate without one), every chirp, the paper chain
      correcting towards its single-chirp estimate: ``pseudo_velocity_mps``
      (and ``_bins``), ``doppler_width_hz`` (and ``_bins``).

    Parameters
    ----------
    gate : PointGate
    reference : Reference, optional
        Truth target (angle errors are NaN without one).
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    motion : compensation.PlatformMotion, optional
        Pose at every transmit slot of every chirp of all frames, frame after
        frame, chirp major, slot minor; required by the compensated chains.
    warnings : list, optional
        Receives the chain's guard warnings (str), each once.
    accumulate : bool
        Form the accumulated AE map (False leaves ``map_*`` and
        ``entropy_ae_nats`` NaN and needs a reference).
    maps : dict, optional
        Receives ``ae`` (accumulated AE :class:`~raysim.processing.maps.Map`,
        None without ``accumulate``),
        ``slow_time`` (``[chirp]``) and the look direction ``look`` (az, el)
        [rad] and slow-time correction direction ``u_hat`` of the chain.

    Returns
    -------
    dict
        Metric name -> value, units in :data:`raysim.vocabulary.METRICS`
        (azimuth metrics are NaN for an array without aperture along x,
        elevation metrics for one without aperture along y, and the angle
        errors with either, see :func:`angle_apertures`).

    Raises
    ------
    ValueError
        A compensated chain without motion, motion of the wrong length, or
        ``accumulate=False`` without a reference.
    """
    spec = parse_chain(chain)
    if spec.compensated and motion is None:
        raise ValueError(f"chain {spec.key!r} needs motion (the platform pose at every chirp)")
    if not accumulate and reference is None:
        raise ValueError("accumulate=False needs a reference (the look direction of the "
                         "single-chirp estimate is the accumulated peak without one)")
    cfg, arr = gate.config, gate.array
    found = [] if warnings is None else warnings
    bfs = _beamformers(spec, gate, motion, found)
    gate_r = [gate.range_m]
    snaps = gate.snapshots[:, :, :, None]                       # [frame, chirp, channel, 1]
    toward = reference.direction if reference is not None else None

    ae, pk = None, {"azimuth": math.nan, "elevation": math.nan}
    if accumulate:
        grid = map_grid()
        power = 0.0
        for k, bf in enumerate(bfs):
            power = power + _coherent_power(bf, snaps[k], gate_r, grid, toward)
        ae = Map(power, ("azimuth", "elevation"), {"azimuth": grid, "elevation": grid})
        pk = ae.peak()

    n = gate.num_chirps
    c = angle_chirp(n)
    if reference is not None:
        look_az, look_el = math.radians(reference.az_deg), math.radians(reference.el_deg)
    else:
        look_az, look_el = pk["azimuth"], pk["elevation"]
    az_a = local_axis(look_az, SINGLE_CHIRP_HALF_WIDTH_DEG, SINGLE_CHIRP_STEP_DEG)
    el_a = local_axis(look_el, SINGLE_CHIRP_HALF_WIDTH_DEG, SINGLE_CHIRP_STEP_DEG)
    one = bfs[0](snaps[0, c:c + 1], [c], gate_r, az_a, el_a,
                 toward if toward is not None else _direction(pk["azimuth"], pk["elevation"]))
    single = Map(np.abs(one[0, 0].astype(np.complex128)) ** 2, ("azimuth", "elevation"),
                 {"azimuth": az_a, "elevation": el_a})
    pk1 = single.peak()
    u_hat = _direction(pk1["azimuth"], pk1["elevation"])
    if reference is not None:
        err = angle_error_deg(pk1["azimuth"], pk1["elevation"], look_az, look_el)
        map_err = angle_error_deg(pk["azimuth"], pk["elevation"], look_az, look_el)
    else:
        err = map_err = math.nan

    slow = bfs[0](snaps[0], np.arange(n), gate_r, [look_az], [look_el], u_hat)[:, 0, 0, 0]
    width = doppler_mainlobe_width(slow, cfg.chirp_interval)
    pv = pseudo_velocity(slow, cfg.chirp_interval, cfg.center_wavelength)
    has_az, has_el = angle_apertures(arr.virtual_positions, cfg.center_wavelength)
    if not (has_az and has_el):
        err = map_err = math.nan
    if maps is not None:
        maps.update(ae=ae, slow_time=slow, look=(look_az, look_el), u_hat=u_hat)
    return {
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
        "entropy_ae_nats": ae.entropy() if ae is not None else math.nan,
    }


def measure(frames: Sequence[RadarFrame] | PointCells, reference: Reference | None = None, *,
            chain: str | ChainSpec = "none", motion=None, return_maps: bool = False,
            warnings: list | None = None):
    """The metrics of :data:`POINT_METRICS` of frames through one chain.

    :func:`point_cells` reads the frames (pass its :class:`PointCells` to
    measure several chains on one read), :func:`gate_metrics` measures the
    gate; the metrics of the whole range axis are added here:
    ``range_m`` (frame 0's range-profile peak refined by a parabola on dB),
    ``peak_power_db`` (that bin's power per chirp and channel) and
    ``entropy_rd_nats`` (RD map of frame 0's cube in the slow-time beam of
    :func:`gate_metrics`).

    Parameters
    ----------
    frames : sequence of RadarFrame, or PointCells
        ``data`` of shape ``[chirp, channel, sample]`` each.
    reference : Reference, optional
        Truth target (range window, look direction, angle errors).
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    motion : compensation.PlatformMotion, optional
        Pose at every transmit slot of every chirp of all frames, frame after
        frame, chirp major, slot minor (one pose per chirp for a single-slot
        array); required for the compensated chains (see
        :func:`raysim.pipeline.run.motion_times`).
    return_maps : bool
        Also return the maps: ``range_profile`` (``range``), ``rd``, ``ae``,
        ``ra``, ``re`` (dimensions of :data:`raysim.vocabulary.MAPS`) as
        :class:`~raysim.processing.maps.Map`, ``slow_time`` (``[chirp]``) and
        ``range_bin``.
    warnings : list, optional
        Receives the chain's guard warnings (str), each once.

    Returns
    -------
    dict
        Metric name -> value (units in :data:`raysim.vocabulary.METRICS`); with
        ``return_maps``, a tuple ``(metrics, maps)``.

    Raises
    ------
    ValueError
        Bad arguments, or a NaN / infinite IF sample (naming its frame, chirp,
        channel and sample).
    """
    spec = parse_chain(chain)
    if spec.compensated and motion is None:
        raise ValueError(f"chain {spec.key!r} needs motion (the platform pose at every chirp)")
    cells = frames if isinstance(frames, PointCells) else point_cells(frames, reference)
    gate, cfg = cells.gate, cells.gate.config
    found = [] if warnings is None else warnings
    extra: dict = {}
    metrics = gate_metrics(gate, reference, chain=spec, motion=motion, warnings=found,
                           maps=extra)
    profile, r_axis, i = cells.profile, cells.range_axis, cells.range_bin
    bf = _beamformers(spec, gate, motion, found)[0]
    look_az, look_el = extra["look"]
    n = gate.num_chirps
    all_chirps = np.arange(n)
    beam_rc = bf(cells.cube, all_chirps, r_axis, [look_az], [look_el],
                 extra["u_hat"])[:, :, 0, 0]
    spec_rd = doppler_fft(beam_rc, axis=0)                       # [doppler, range]
    rd = Map(np.abs(spec_rd.T) ** 2, ("range", "doppler"),
             {"range": r_axis, "doppler": cfg.velocity_axis(spec_rd.shape[0])})
    out = {"range_m": float(np.interp(_parabolic_peak(profile, i), np.arange(r_axis.size),
                                      r_axis))}
    out.update(metrics)
    out["entropy_rd_nats"] = rd.entropy()
    out["peak_power_db"] = float(10 * np.log10(max(profile[i] / (n * gate.array.num_channels),
                                                    1e-300)))
    out = {k: out[k] for k in POINT_METRICS}
    if not return_maps:
        return out
    grid = map_grid()
    pick = np.unique(np.linspace(0, n - 1, min(n, RANGE_ANGLE_CHIRPS)).astype(int))
    ra = bf(cells.cube[pick], pick, r_axis, grid, [look_el], extra["u_hat"])[:, :, :, 0]
    re_ = bf(cells.cube[pick], pick, r_axis, [look_az], grid, extra["u_hat"])[:, :, 0, :]
    maps = {
        "range_profile": Map(profile, ("range",), {"range": r_axis}), "rd": rd,
        "ae": extra["ae"],
        "ra": Map(np.sum(np.abs(ra) ** 2, axis=0), ("range", "azimuth"),
                  {"range": r_axis, "azimuth": grid}),
        "re": Map(np.sum(np.abs(re_) ** 2, axis=0), ("range", "elevation"),
                  {"range": r_axis, "elevation": grid}),
        "range_bin": i, "slow_time": extra["slow_time"],
    }
    return out, maps
