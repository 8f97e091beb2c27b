"""Figures of maps: one way to draw RD, RA, RE and AE maps in every report.

Axes follow :data:`raysim.vocabulary.FIGURE_AXES` (azimuth on x wherever a
map has it, range on y), labels :data:`raysim.vocabulary.AXIS_LABELS`,
titles :data:`raysim.vocabulary.MAP_TITLES`; angles are drawn in degrees.
"""

from __future__ import annotations

import numpy as np

from raysim.processing.maps import Map
from raysim.vocabulary import AXIS_LABELS, FIGURE_AXES, MAP_TITLES

__all__ = ["ANGLE_AXES", "map_image", "plot_map", "map_name"]

#: Axes whose coordinates are angles [rad in a Map, deg in a figure].
ANGLE_AXES = ("azimuth", "elevation")


def map_name(m: Map) -> str:
    """The :data:`~raysim.vocabulary.MAPS` name of a map from its dimensions."""
    for name, (x, y) in FIGURE_AXES.items():
        if set(m.dims) == {x, y}:
            return name
    raise ValueError(f"map dims {m.dims} are not those of a known map {list(FIGURE_AXES)}")


def _shown(axis: str, values) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    return np.rad2deg(v) if axis in ANGLE_AXES else v


def map_image(m: Map, *, reference_power: float | None = None):
    """``(x, y, db)`` of a map oriented for a figure.

    Parameters
    ----------
    m : Map
        Two-dimensional map.
    reference_power : float, optional
        Power of 0 dB (default: the map's peak).

    Returns
    -------
    x : ndarray, shape ``[nx]``
        Coordinates of the x axis (degrees for angles).
    y : ndarray, shape ``[ny]``
        Coordinates of the y axis.
    db : ndarray, shape ``[ny, nx]``
        Power in dB relative to ``reference_power``.
    """
    name = map_name(m)
    xa, ya = FIGURE_AXES[name]
    values = np.asarray(m.values, dtype=float)
    if m.dims.index(xa) == 0:                       # array order (x, y): transpose for (y, x)
        values = values.T
    ref = float(values.max()) if reference_power is None else float(reference_power)
    db = 10 * np.log10(np.maximum(values / max(ref, 1e-300), 1e-30))
    return _shown(xa, m.coords[xa]), _shown(ya, m.coords[ya]), db


def plot_map(ax, m: Map, *, title: str | None = None, reference_power: float | None = None,
             dynamic_range_db: float = 50.0, xlim=None, ylim=None):
    """Draw a map on a matplotlib axis; returns the image artist (for a colour bar).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    m : Map
    title : str, optional
        Panel title (default: the map's title from :data:`MAP_TITLES`).
    reference_power : float, optional
        Power of 0 dB (default: the map's peak).
    dynamic_range_db : float
        Colour scale from ``-dynamic_range_db`` to 0 dB.
    xlim, ylim : (float, float), optional
        Zoom (figure units: degrees for angles).
    """
    name = map_name(m)
    x, y, db = map_image(m, reference_power=reference_power)
    im = ax.pcolormesh(x, y, db, vmin=-dynamic_range_db, vmax=0.0, shading="auto",
                       cmap="viridis")
    xa, ya = FIGURE_AXES[name]
    ax.set_xlabel(AXIS_LABELS[xa])
    ax.set_ylabel(AXIS_LABELS[ya])
    # y given: no search of the axes' top tick labels for room (none are drawn there);
    # the title sits where that search puts it, at the top plus its pad
    ax.set_title(MAP_TITLES[name] if title is None else title, fontsize=10, y=1.0)
    if xlim is not None:
        ax.set_xlim(*xlim)
    if ylim is not None:
        ax.set_ylim(*ylim)
    return im
