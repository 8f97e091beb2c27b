"""Whether a scatterer's slow-time track is one point's: the slow swing of its amplitude.

The clock fit (:mod:`compensation.clock_offset`, :mod:`compensation.clock_averaged`)
reads the platform's motion from the phase of a stationary scatterer's beam, chirp
by chirp. Where two scatterers share the cell (unresolved in range and angle) the
beam is ``a + b exp(j dphi(t))``, ``dphi`` their differential phase, which the
platform's advance turns by ``2 k (u_a - u_b) . p(t)``: to first order in ``eps =
b / a`` its phase carries ``eps sin dphi`` and its amplitude ``a (1 + eps cos
dphi)``, the same swing in both. The amplitude thus shows the phase's error, and a
phase error that follows the motion is what an offset fit takes for a time shift.
On a 250 Hz boxcar flight with two points 0.1 m apart in range, 4 deg in azimuth
and 10 deg in elevation (one cell of a 3 x 4 array), the amplitude swung by 3-28 %
within each frame and the coarse offset search settled 8.6 ms from the truth at a
misfit a fortieth of the truth's; single points, with ground clutter around them,
swung by 0.1-1 %.

The swing is the amplitude's variance less its chirp-to-chirp part (half the mean
square difference of consecutive chirps, which white noise fills and a beat over
the frame does not), counted only where it stands out of that noise: the thermal
noise of a weak point does not count, and a beat it buries moves the phase less
than the noise does.

What it cannot see: a second scatterer whose differential phase does not move over
the frame (the two along one line of sight, or a platform at rest); its phase
error is then a constant, which the fits' per-track constant takes.
"""

from __future__ import annotations

import warnings

import numpy as np

from .clock_offset import track_arrays
from .guards import CompensationWarning

__all__ = ["MIXED_CELL_SWING", "SWING_SIGNIFICANCE", "amplitude_swing", "clock_scatterers"]

#: Amplitude swing [1] (rms over a frame, relative to the mean; about the rms phase error
#: [rad] it brings) above which a scatterer's cell holds more than one point.
MIXED_CELL_SWING = 0.02
#: Spreads of the white-noise estimate the slow variance must exceed to count [1].
SWING_SIGNIFICANCE = 3.0


def amplitude_swing(weight) -> float:
    """Slow rms swing of a track's amplitude over its mean [1]; 0 where it does not stand
    out of the chirp-to-chirp noise.

    ``weight [chirp]`` is the track's power ``|y|^2``. The slow variance is the
    amplitude's variance less ``s^2``, half the mean square of its chirp-to-chirp
    differences (white noise's variance; a beat over the frame adds little to it); for
    white noise alone it is zero with a spread ``s^2 / sqrt(N)`` over ``N`` chirps
    (measured: 1.00 of it at 16, 64 and 256 chirps, 20 000 draws each), so below
    :data:`SWING_SIGNIFICANCE` such spreads it counts as none.
    """
    a = np.sqrt(np.maximum(np.asarray(weight, dtype=float), 0.0))
    if a.size < 3 or not np.mean(a) > 0:
        return 0.0
    noise = 0.5 * np.mean(np.diff(a) ** 2)
    slow = np.var(a) - noise
    if slow <= SWING_SIGNIFICANCE * noise / np.sqrt(a.size):
        return 0.0
    return float(np.sqrt(slow) / np.mean(a))


def clock_scatterers(tracks, scatterers, search_half_width: float) -> tuple[tuple, float]:
    """The scatterers a clock offset is fitted on, and the spread [s] to state for it.

    Parameters
    ----------
    tracks : sequence of (times, phase, rate, weight)
        :func:`compensation.clock_offset.phase_tracks` of every frame, frame major.
    scatterers : sequence
        The scatterers of the tracks (``len(tracks)`` a multiple of their number).
    search_half_width : float
        Half-width of the offset search [s] (0: none).

    Returns
    -------
    kept : tuple
        The scatterers whose median swing over the frames is at most
        :data:`MIXED_CELL_SWING` (the others warned about); all of them where none is.
    spread : float
        0, or where every scatterer swings (warned) the search's half-width: an offset
        fitted on mixed cells is not trusted to better than the search.
    """
    scatterers = tuple(scatterers)
    n = len(scatterers)
    if n == 0 or len(tracks) % n:
        raise ValueError(f"tracks: {len(tracks)} tracks for {n} scatterers; expected a "
                         f"whole number of frames of them")
    swing = np.array([amplitude_swing(track_arrays(i, tr)[3]) for i, tr in enumerate(tracks)])
    swing = np.median(swing.reshape(-1, n), axis=0)                       # [scatterer]
    mixed = swing > MIXED_CELL_SWING
    if not mixed.any():
        return scatterers, 0.0
    lo, hi = 100 * swing[mixed].min(), 100 * swing[mixed].max()
    what = (f"clock: {int(mixed.sum())} of {n} scatterer(s) (number "
            f"{', '.join(str(j) for j in np.flatnonzero(mixed))}) swing in amplitude by "
            f"{f'{lo:.2g}' if hi - lo < 0.05 else f'{lo:.2g}-{hi:.2g}'} % within a frame "
            f"(median over the frames; one point, by under {100 * MIXED_CELL_SWING:g} %): their "
            f"cells hold more than one scatterer, whose beat moves the phase")
    if mixed.all():
        spread = (f"its spread states the search's half-width {1e3 * search_half_width:g} ms"
                  if search_half_width > 0 else "it may lie beyond its spread")
        warnings.warn(f"{what}; the offset is fitted on them but not trusted: {spread}; give "
                      f"the offset from a time sync (--time-offset, docs/recordings.md)",
                      CompensationWarning, stacklevel=2)
        return scatterers, float(search_half_width)
    warnings.warn(f"{what}; the offset is fitted on the other {int(n - mixed.sum())}",
                  CompensationWarning, stacklevel=2)
    return tuple(s for s, m in zip(scatterers, mixed, strict=True) if not m), 0.0
