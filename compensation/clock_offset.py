"""IMU-radar clock offset and drift from the residual slow-time phase of stationary scatterers.

When the motion is integrated with a clock offset wrong by ``delta`` (the IMU
record shifted against the chirps), the phase the compensation removes from a
scatterer in the direction ``u`` is that of the displacement at the wrong
time. To first order the residual phase is ``phi(t) = r(t) delta`` with the
predicted phase rate ``r(t) = -(4 pi / lambda) u . v_R(t)`` (``v_R`` the radar
phase-centre velocity in W): motion compensated out of phase. A clock drift
``rho`` (IMU rate error) makes the shift ``delta + rho t``.

The linearisation holds for offset errors below about a quarter of the
vibration period (1 ms at 100-200 Hz); :func:`phase_misfit` is the cost of a
coarse search that brings the offset within that reach first.

Each track (one scatterer in one frame) also carries an unknown phase and an
unknown range rate (the velocity error), so a line ``a + b t`` per track is a
nuisance: only the part of ``r(t)`` that is not a line informs ``delta``. Rotor
vibration (tens to hundreds of hertz) bends the radar velocity within a frame
and makes the offset observable to a fraction of a millisecond; a platform
that moves at constant velocity gives no information (the uncertainty says so).

A log of interval averages (a flight controller's 200-250 Hz boxcar) does not
resolve that vibration: what the spline through its averages misses correlates
with the spline's bending and moves this fit by up to 0.5 ms;
:mod:`compensation.clock_averaged` compares the radar with such a log over its
intervals instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._checks import finite_array

#: Share of the predicted phase-rate energy left after removing a line per track
#: below which the offset counts as unobservable [1].
UNOBSERVABLE_FRACTION = 1e-10


@dataclass(frozen=True)
class ClockOffset:
    """Estimate of a time shift ``delta + rho (t - t_ref)`` of the IMU record.

    Attributes
    ----------
    offset : float
        ``delta`` [s] at the reference time.
    offset_sigma : float
        Its one-sigma spread [s].
    drift : float
        ``rho`` [s/s] (0 when not fitted).
    drift_sigma : float
        Its one-sigma spread [s/s] (``inf`` when not fitted).
    reference_time : float
        ``t_ref`` [s].
    stamp_sigma : float
        Spread the log's time stamps add to any offset estimated from that log [s],
        not in ``offset_sigma`` (the placement of an average within its interval,
        :mod:`compensation.clock_averaged`), and the search's ambiguities
        (:func:`compensation.clock_averaged.coarse_offset`, :meth:`beyond_search`); 0 for
        instantaneous samples found unambiguously.
    """

    offset: float
    offset_sigma: float
    drift: float = 0.0
    drift_sigma: float = float("inf")
    reference_time: float = 0.0
    stamp_sigma: float = 0.0

    @property
    def total_sigma(self) -> float:
        """``offset_sigma`` and ``stamp_sigma`` in quadrature [s]."""
        return float(np.hypot(self.offset_sigma, self.stamp_sigma))

    def beyond_search(self, moved: float, half_width: float, step: float) -> ClockOffset:
        """This estimate, or, where the fits carried the offset ``moved`` [s] from the
        search's centre more than a grid ``step`` [s] past its ``half_width`` [s] (the
        search found its minimum inside), one whose spread holds that distance (warned):
        the radar did not pin the offset there (a 50 Hz log, or no lever arm on one frame)."""
        if abs(moved) <= half_width + step:
            return self
        import warnings
        from dataclasses import replace

        from .guards import CompensationWarning

        warnings.warn(f"clock: the fit moved the offset {1e3 * moved:+.2f} ms from the "
                      f"search's centre, past the +-{1e3 * half_width:g} ms searched, where the "
                      f"search found no minimum: the radar does not pin it; its spread states "
                      f"that distance; widen --time-offset-search or give the offset from a "
                      f"time sync (--time-offset, docs/recordings.md)", CompensationWarning,
                      stacklevel=2)
        return replace(self, stamp_sigma=float(np.hypot(self.stamp_sigma, moved)))


def _detrend(t: np.ndarray, w: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``x [chirp, k]`` minus its weighted least-squares line in ``t``."""
    basis = np.column_stack([np.ones_like(t), t - t.mean()]) * np.sqrt(w)[:, None]
    xs = x * np.sqrt(w)[:, None]
    coef, *_ = np.linalg.lstsq(basis, xs, rcond=None)
    return (xs - basis @ coef) / np.sqrt(w)[:, None]


def track_arrays(i: int, item) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(times, phase, rate, weight)`` of ``tracks[i]`` as float arrays; a ValueError
    naming the track otherwise."""
    try:
        t, phi, r, w = (np.asarray(v, dtype=float) for v in item)
    except (TypeError, ValueError):
        raise ValueError(f"tracks[{i}] must be (times, phase, rate, weight) arrays, "
                         f"got {item!r}") from None
    return t, phi, r, w


def fit_time_shift(tracks, *, drift: bool = False, reference_time: float | None = None
                   ) -> ClockOffset:
    """Least-squares time shift from residual phases against predicted phase rates.

    Parameters
    ----------
    tracks : sequence of (times, phase, rate, weight)
        One entry per scatterer and frame: ``times [chirp]`` [s], the
        unwrapped residual phase ``[chirp]`` [rad], the predicted phase rate
        ``r(t) [chirp]`` [rad/s] and the weight of each chirp ``[chirp]``
        (e.g. ``|y|^2``, any scale) [1].
    drift : bool
        Also fit the drift ``rho`` (needs tracks spread over time).
    reference_time : float, optional
        ``t_ref`` of the drift [s]; default the mean track time.

    Returns
    -------
    ClockOffset
        ``delta`` such that integrating with ``time_offset + delta`` removes
        the residual; spreads from the weighted residual (Gauss-Markov), or
        the cluster-robust sandwich over tracks where larger (White 1980;
        Cameron & Miller, J. Human Resources 50(2), 2015, eq. 11).

    Raises
    ------
    ValueError
        No track with at least 4 chirps, or rates that bend nowhere (the
        offset is unobservable).
    """
    rows, ys, ws = [], [], []
    for i, item in enumerate(tracks):
        t, phi, r, w = track_arrays(i, item)
        n = t.size
        for name, v in (("phase", phi), ("rate", r), ("weight", w)):
            if v.shape != (n,) or not np.all(np.isfinite(v)):
                raise ValueError(f"tracks[{i}] {name} must be finite with shape [{n}], got "
                                 f"shape {v.shape}")
        if n < 4 or not np.any(w > 0):
            continue
        w = np.maximum(w, 0.0) / w.max()
        w = np.where(w > 0, w, 1e-12)
        rows.append((t, w, r))
        ys.append(phi)
        ws.append(w)
    if not rows:
        raise ValueError("tracks: no track with at least 4 chirps and a positive weight")
    t_all = np.concatenate([r[0] for r in rows])
    t_ref = float(t_all.mean()) if reference_time is None else float(
        finite_array("reference_time", reference_time, shape=()))
    cols, y, w = [], [], []
    for (t, wt, r), phi in zip(rows, ys, strict=True):
        x = np.column_stack([r, r * (t - t_ref)]) if drift else r[:, None]
        both = _detrend(t, wt, np.column_stack([x, phi]))
        cols.append(both[:, :-1])
        y.append(both[:, -1])
        w.append(wt)
    x = np.vstack(cols)
    yv = np.concatenate(y)
    wv = np.concatenate(w)
    normal = x.T @ (x * wv[:, None])
    raw = sum(float(np.sum(wt * r ** 2)) for t, wt, r in rows)
    if np.linalg.cond(normal) > 1e12 or np.trace(normal) <= UNOBSERVABLE_FRACTION * raw:
        raise ValueError("the predicted phase rates are straight lines in every track: the "
                         "clock offset is unobservable (no vibration or acceleration change "
                         "within a frame)")
    coef = np.linalg.solve(normal, x.T @ (wv * yv))
    res = yv - x @ coef
    dof = max(yv.size - 2 * len(rows) - coef.size, 1)
    inv = np.linalg.inv(normal)
    cov = inv * float(np.sum(wv * res ** 2) / dof)
    if len(rows) > 1:
        # residuals correlate along a track (model errors, not white noise): the
        # cluster-robust sandwich with tracks as clusters, kept when larger
        edges = np.cumsum([0] + [len(c) for c in cols])
        score = np.stack([x[a:b].T @ (wv[a:b] * res[a:b]) for a, b in
                          zip(edges[:-1], edges[1:], strict=True)])
        robust = inv @ (score.T @ score) @ inv * len(rows) / (len(rows) - 1)
        cov = np.where(np.diag(robust)[:, None] > np.diag(cov)[:, None], robust, cov)
    sig = np.sqrt(np.diag(cov))
    if drift:
        return ClockOffset(float(coef[0]), float(sig[0]), float(coef[1]), float(sig[1]), t_ref)
    return ClockOffset(float(coef[0]), float(sig[0]), reference_time=t_ref)


def phase_misfit(tracks) -> float:
    """Weighted mean square of the residual phases about a line per track [rad^2].

    The cost of a coarse search over clock offsets: smallest where the
    compensation follows the motion in phase. ``tracks`` as for
    :func:`fit_time_shift` (the rates are not used).
    """
    total = weight = 0.0
    for t, phi, _, w in tracks:
        t, phi, w = (np.asarray(v, dtype=float) for v in (t, phi, w))
        if t.size < 4 or not np.any(w > 0):
            continue
        w = np.where(w > 0, w / w.max(), 1e-12)
        r = _detrend(t, w, phi[:, None])[:, 0]
        total += float(np.sum(w * r ** 2))
        weight += float(np.sum(w))
    if weight == 0:
        raise ValueError("tracks: no track with at least 4 chirps and a positive weight")
    return total / weight


def phase_tracks(y, motions, scatterers, wavelength: float) -> list:
    """Residual phase tracks of stationary scatterers, the input of :func:`fit_time_shift`.

    Parameters
    ----------
    y : ndarray, shape ``[frame, scatterer, chirp]``
        Compensated beam of each scatterer at every chirp loop.
    motions : sequence of PlatformMotion
        The motion of each frame the beams were compensated with (every slot; the
        first slot of each loop stamps the track).
    scatterers : sequence
        Each with a unit ``direction [3]`` in the motion's frame.
    wavelength : float
        [m].

    Returns
    -------
    list of (times, phase, rate, weight)
        One per frame and scatterer, frame major: chirp times [s], the unwrapped
        phase [rad] (its residual Doppler removed so that it unwraps chirp to
        chirp), the predicted phase rate ``-(4 pi / lambda) u . v_R`` [rad/s] and
        ``|y|^2``.
    """
    tracks = []
    for k, m in enumerate(motions):
        mo = m.select(slice(0, None, m.num_chirps // y.shape[2]))
        t = mo.time
        for j, s in enumerate(scatterers):
            yk = y[k, j]
            f0 = np.fft.fftfreq(t.size * 16, d=float(np.median(np.diff(t))))[
                int(np.argmax(np.abs(np.fft.fft(yk, t.size * 16))))]
            z = yk * np.exp(-2j * np.pi * f0 * (t - t[0]))
            rate = -(4 * np.pi / wavelength) * (mo.radar_velocity @ s.direction)
            tracks.append((t, np.unwrap(np.angle(z)), rate, np.abs(yk) ** 2))
    return tracks
