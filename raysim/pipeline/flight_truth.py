"""The truth of a simulated flight, kept beside its files, and the score of a compensation.

``raysim flight`` writes ``truth.json`` (:meth:`FlightFiles.truth`) next to the
capture, the log and the cfg: everything :class:`raysim.pipeline.flight.FlightFiles`
holds (targets, clock offset and drift, per-frame velocity, attitude and position,
lever arm, board, mounting, log rate, gaps), so that a compensation run later, by
any tool, can be scored against what was simulated: :func:`score_flight` measures
every target in every frame of a compensated store
(:func:`raysim.pipeline.flight.measure_targets`) against the stated limits
:data:`LIMITS`.

The file is JSON (``format`` :data:`TRUTH_FORMAT`); paths are stored relative to
the flight's folder, so a folder moved or copied keeps its truth.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from raysim.pipeline.flight import TRUTH_FILE, TRUTH_FORMAT, FlightFiles

__all__ = ["LIMITS", "TRUTH_FILE", "TRUTH_FORMAT", "read_truth", "score_flight"]

#: Stated limits of a compensated flight, on every target and frame:
#: ``beam_angle_error_deg`` [deg], ``|beam_pseudo_velocity_bins|`` [bin],
#: ``doppler_leakage_db`` [dB], and ``|offset_error_ms|`` [ms] of the store's clock offset.
LIMITS = {"beam_angle_error_deg": 0.2, "beam_pseudo_velocity_bins": 0.05,
          "doppler_leakage_db": -35.0, "offset_error_ms": 0.5}
_ARRAYS = ("frame_starts", "initial_velocity", "initial_attitude_deg", "initial_position",
           "lever_arm", "log_attitude_deg")
_PATHS = ("capture", "radar_config", "imu_log")
#: Shape of each numeric field of the truth (-1: any length >= 1); None where it may be.
_SHAPES = {"start": (), "time_offset": (), "imu_rate": (), "clock_drift_ppm": (),
           "frame_starts": (-1,), "initial_velocity": (-1, 3), "initial_attitude_deg": (-1, 3),
           "initial_position": (-1, 3), "lever_arm": (3,), "log_attitude_deg": (-1, 3),
           "target": (3,), "targets": (-1, 3), "mounting_deg": (3,), "gaps": (-1, 2)}
_OPTIONAL = ("log_attitude_deg",)
_TEXT = ("imu", "board")
_FLAGS = ("imu_boxcar", "attitude")


def _checked(path: Path, data: dict) -> dict:
    """The truth's fields, each checked against its kind and shape; a ValueError names
    the file, the field and what was expected."""
    from dataclasses import MISSING, fields

    known = {f.name: f for f in fields(FlightFiles)}
    extra = sorted(set(data) - set(known) - {"format"})
    missing = [k for k, f in known.items() if k not in data and f.default is MISSING]
    if extra or missing:
        raise ValueError(f"{str(path)!r}: " + "; ".join(
            ([f"unknown field(s) {extra}"] if extra else [])
            + ([f"missing field(s) {missing}"] if missing else []))
            + ": expected a flight truth written by `raysim flight`")
    kw = {}
    for k, v in data.items():
        if k == "format":
            continue
        bad = None
        if k in _PATHS or k in _TEXT:
            bad = None if isinstance(v, str) and v else "a non-empty string"
        elif k in _FLAGS:
            bad = None if isinstance(v, bool) else "true or false"
        elif not (v is None and k in _OPTIONAL):
            shape = _SHAPES[k]
            try:
                a = np.asarray(v, dtype=float)
            except (TypeError, ValueError):
                a = None
            fits = (a is not None and a.ndim == len(shape) and np.all(np.isfinite(a))
                    and all(n == m or (m == -1 and n >= 1)
                            for n, m in zip(a.shape, shape, strict=True))
                    and not isinstance(v, bool))
            if k == "gaps" and a is not None and a.size == 0:
                fits = True                             # no logger gaps
            dims = "x".join("N" if m == -1 else str(m) for m in shape)
            bad = None if fits else ("a finite number" if not shape else
                                     f"finite numbers of shape [{dims}]")
        if bad:
            raise ValueError(f"{str(path)!r}: field {k!r} is {v!r}, expected {bad}")
        kw[k] = v
    return kw


def read_truth(folder: str | Path):
    """The ``FlightFiles`` of a flight folder written by ``raysim flight``.

    Raises
    ------
    ValueError
        The folder has no :data:`TRUTH_FILE`, or it is not a flight truth of this format.
    """
    folder = Path(folder)
    path = folder / TRUTH_FILE
    if not path.is_file():
        raise ValueError(f"{str(folder)!r} holds no {TRUTH_FILE}: expected the folder of a "
                         f"flight written by `raysim flight`")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{str(path)!r} is not readable JSON ({exc}); expected a flight "
                         f"truth written by `raysim flight`") from None
    if not isinstance(data, dict) or data.get("format") != TRUTH_FORMAT:
        got = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise ValueError(f"{str(path)!r} has format {got!r}; expected {TRUTH_FORMAT!r}")
    kw = _checked(path, data)
    for k in _PATHS:
        kw[k] = folder / kw[k]
    for k in _ARRAYS:
        if kw.get(k) is not None:
            kw[k] = np.asarray(kw[k], dtype=float)
    for k in ("target", "mounting_deg"):
        kw[k] = tuple(kw[k])
    kw["targets"] = tuple(tuple(t) for t in kw["targets"])
    kw["gaps"] = tuple(tuple(g) for g in kw["gaps"])
    try:
        return FlightFiles(**kw)
    except TypeError as exc:
        raise ValueError(f"{str(path)!r} does not hold a flight's truth ({exc})") from None


def _check_same_capture(ds, flight) -> None:
    """A ValueError where the store was compensated from another capture than the flight's
    (both files present and their bytes differ); a copied or moved folder passes."""
    import filecmp

    try:
        source = Path(json.loads(ds.attrs.get("source", "{}")).get("capture", ""))
    except (ValueError, AttributeError, TypeError):
        return
    ours = Path(flight.capture)
    if not source.name or not source.is_file() or not ours.is_file():
        return
    if source.resolve() != ours.resolve() and not filecmp.cmp(source, ours, shallow=False):
        raise ValueError(f"the store was compensated from the capture {str(source)!r}, not "
                         f"this flight's {str(ours)!r}; expected a store of this flight")


def score_flight(folder: str | Path, store, first: int | None = None) -> dict:
    """Score a compensated store of a flight against the flight's truth and :data:`LIMITS`.

    Parameters
    ----------
    folder : path
        The flight's folder (with :data:`TRUTH_FILE`).
    store : path or xarray.Dataset
        The compensated store (``raysim compensate --out``) with a ``range`` axis
        covering every target and an ``azimuth`` axis around each.
    first : int, optional
        Flight frame of the store's first frame (``--frames K:...``); None: the store's
        first ``frame`` coordinate (``raysim compensate`` writes the capture's frame
        numbers there), 0 where it has none.

    Returns
    -------
    dict
        ``targets [target, frame, 3]`` (angle error [deg], pseudo-velocity [bin],
        leakage [dB]), ``worst`` (per metric of :data:`LIMITS`; ``offset_error_ms``
        None where the store has no clock offset), ``limits`` and ``passed``
        (per metric, and ``all``).
    """
    from raysim.io.zarr_store import open_store
    from raysim.pipeline.flight import measure_targets

    flight = read_truth(folder)
    ds = store if hasattr(store, "data_vars") else open_store(store)
    _check_same_capture(ds, flight)
    if first is None:
        first = int(ds["frame"].values[0]) if "frame" in ds.coords else 0
    if not 0 <= first < len(flight.frame_starts):
        raise ValueError(f"first frame {first} is not a frame of the flight (0.."
                         f"{len(flight.frame_starts) - 1})")
    m = measure_targets(ds, flight, first=first)                # [target, frame, 3]
    offset = ds.attrs.get("time_offset_s")
    worst = {"beam_angle_error_deg": float(m[..., 0].max()),
             "beam_pseudo_velocity_bins": float(np.abs(m[..., 1]).max()),
             "doppler_leakage_db": float(m[..., 2].max()),
             "offset_error_ms": None if offset is None
             else 1e3 * (float(offset) - flight.time_offset)}
    passed = {k: None if v is None else bool(
        abs(v) <= LIMITS[k] if k != "doppler_leakage_db" else v <= LIMITS[k])
        for k, v in worst.items()}
    passed["all"] = all(v is not False for v in passed.values())
    return {"targets": m.tolist(), "worst": worst, "limits": dict(LIMITS), "passed": passed}
