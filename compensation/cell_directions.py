"""Where a beam cell's scatterer lies between the beams, and the Doppler that leaves it.

A compensation removes the motion at each beam's own direction ``u_c``; a
stationary scatterer at ``u_s`` between two beams of the grid keeps the rest:
with the phase growing with range (docs/conventions.md) the radar's advance
``p(t)`` leaves the cell ``-2 k (u_s - u_c) . p(t)``, the phase of a velocity
``(u_s - u_c) . v`` along ``u_s`` that is no velocity error. On a 5 deg
elevation grid at 0.3 m/s across it, 1.9 deg off the beam: 10 mm/s. A fit that
takes the cells for stationary scatterers must take it off first
(:func:`compensation.autofocus_displacement.estimate_displacement`, whose
``2 k u . d`` phase convention makes it ``-2 k (u_s - u_c) . v`` of each cell's slope).

The scatterer's direction is the vertex of the parabola through the cell's beam
power and its two neighbours along each grid axis (in dB, the main lobe's peak;
at the grid's edge the three nearest beams, so that a scatterer beyond the last
beam is reached; within a grid step of the beam). Along an axis the array spans
no extent, or with fewer than three beams, the beam's own angle is kept.
"""

from __future__ import annotations

import numpy as np

from .geometry import direction

__all__ = ["beam_offset_doppler", "parabola_vertex", "refined_directions"]


def parabola_vertex(lo: np.ndarray, mid: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Offset [steps] of the vertex of the parabola through three equally spaced samples
    from the middle one (0 where the three do not bend down)."""
    den = lo - 2 * mid + hi
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den < 0, 0.5 * (lo - hi) / den, 0.0)


def _refine(db_line: np.ndarray, idx: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Angles [rad] of the power peaks near beams ``idx`` of ``db_line [cell, beam]``: the
    parabola through the beam and its neighbours (at the grid's edge the three nearest,
    so a peak beyond the last beam is reached), within a step of the beam."""
    mid = np.clip(idx, 1, grid.size - 2)
    rows = np.arange(idx.size)
    f = parabola_vertex(db_line[rows, mid - 1], db_line[rows, mid], db_line[rows, mid + 1])
    step = np.where(f >= 0, grid[mid + 1] - grid[mid], grid[mid] - grid[mid - 1])
    pitch = np.abs(np.diff(grid)).max()
    return np.clip(grid[mid] + f * step, grid[idx] - pitch, grid[idx] + pitch)


def refined_directions(beams, cells, spans=(True, True)) -> np.ndarray:
    """Unit vectors ``[cell, 3]`` of the scatterers of beam cells, between the beams.

    Parameters
    ----------
    beams : compensation.BeamCube
        ``data [chirp, range, azimuth, elevation]``, ``azimuth`` and ``elevation`` [rad].
    cells : array_like of int, shape ``[cell]``
        Flat indices into ``data.shape[1:]``.
    spans : (bool, bool)
        Whether the array has extent along its azimuth and elevation axes (else that
        angle is not refined).
    """
    shape = beams.data.shape[1:]
    power = np.mean(np.abs(beams.data) ** 2, axis=0)                   # [range, az, el]
    db = 10 * np.log10(np.maximum(power, np.finfo(float).tiny))
    ir, ia, ie = np.unravel_index(np.asarray(cells, dtype=int), shape)
    az, el = (np.asarray(a, dtype=float) for a in (beams.azimuth, beams.elevation))
    out_az = _refine(db[ir, :, ie], ia, az) if spans[0] and az.size >= 3 else az[ia]
    out_el = _refine(db[ir, ia, :], ie, el) if spans[1] and el.size >= 3 else el[ie]
    return direction(out_az, out_el)


def beam_offset_doppler(beams, cells, beam_directions, radar_velocity, spans=(True, True)
                        ) -> np.ndarray:
    """``(u_s - u_c) . v`` of each cell [m/s], ``[cell]``: the velocity whose phase the
    grid's miss leaves it (see the module docstring).

    Parameters
    ----------
    beams, cells, spans
        As :func:`refined_directions`.
    beam_directions : array_like, shape ``[cell, 3]``
        The cells' beam directions ``u_c`` (with the components the array does not
        span zeroed, as the fit uses them).
    radar_velocity : array_like, shape ``[3]``
        Mean radar velocity over the frame in the beams' frame [m/s].
    """
    u_s = refined_directions(beams, cells, spans)
    u_s[:, :2] *= np.asarray(spans, dtype=bool)
    return (u_s - np.asarray(beam_directions, dtype=float)) @ np.asarray(radar_velocity, float)
