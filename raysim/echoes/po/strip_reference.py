"""The engine's PO and PO + PTD on long plates and boxes against the 2-D method of moments.

A flat plate ``width`` wide (along ``x``) and ``length`` long (along ``y``,
``length >> lambda``) in ``z = 0``, rotated in azimuth about its long edges, is
the 3-D counterpart of a strip: seen normal to its length its RCS is the strip's
echo width times ``2 L^2 / lambda`` (Knott, Shaeffer & Tuley, *Radar Cross
Section*, 2nd ed., 1993: the 2-D to 3-D relation), up to the short edges' own terms, which are
``O(lambda / L)`` of the long edges'. The engine's azimuth is the strip's
``phi`` (:mod:`~raysim.echoes.po.mom2d`); VV (electric field along the long edges)
is the strip's TM, HH its TE. A long box of square cross-section (right-angle
wedges, ``n = 3/2``) is compared in the same way with the square cylinder.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.echoes.po.mesh import TriangleMesh, po_material
from raysim.echoes.po.mom2d import SEGMENTS_PER_WAVELENGTH, echo_width, polyline, strip
from raysim.echoes.po.rcs import DEFAULT_FREQUENCY, monostatic_rcs
from raysim.radar.config import SPEED_OF_LIGHT

__all__ = ["StripComparison", "long_plate", "long_box", "compare_long_plate",
           "LENGTH_WAVELENGTHS", "ENGINE_POLARISATION", "SHAPES"]

#: Default plate length [wavelengths]: the short edges' terms, ``O(lambda / L)`` of the
#: long edges', stay below 0.02 dB.
LENGTH_WAVELENGTHS = 200.0
#: The engine's channel for each 2-D polarisation (plate rotated about its long edges).
ENGINE_POLARISATION = {"TM": "VV", "TE": "HH"}
#: Cross-sections :func:`compare_long_plate` knows: a zero-thickness strip, a square.
SHAPES = ("plate", "box")


def long_plate(width: float, length: float) -> TriangleMesh:
    """Rectangular plate in ``z = 0``, centred: ``width`` [m] along x, ``length`` [m] along y."""
    for value, name in ((width, "width"), (length, "length")):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive length [m], got {value!r}")
    w, h = width / 2, length / 2
    v = np.array([[-w, -h, 0.0], [w, -h, 0.0], [w, h, 0.0], [-w, h, 0.0]])
    return TriangleMesh(v, np.array([[0, 1, 2], [0, 2, 3]]))


def long_box(width: float, length: float) -> TriangleMesh:
    """Closed box, ``width`` [m] along ``x`` and ``z``, ``length`` [m] along ``y``, centred."""
    import trimesh

    long_plate(width, length)                  # the same checks
    box = trimesh.creation.box((width, length, width))
    return TriangleMesh(box.vertices, box.faces)


@dataclass(frozen=True)
class StripComparison:
    """Echo width of a strip: the engine's PO and PO + PTD against the method of moments.

    Attributes
    ----------
    phi_deg : ndarray, shape ``[phi]``
        Aspect from broadside [deg] (the engine's azimuth, the strip's ``phi``).
    shape : str
        ``"plate"`` (strip) or ``"box"`` (square cylinder).
    width, wavelength, length : float
        Strip width (square side), wavelength and the engine's length [m].
    mom, po, ptd, multiple : dict of str to ndarray, shape ``[phi]``
        ``sigma_2D / lambda`` [dB] per polarisation ``"TM"``, ``"TE"``: the
        method of moments, the engine's PO, its PO + PTD and PO + PTD with
        the multiple diffraction of facing edges (``sigma_3D lambda / (2 L^2)``).
    seconds : dict of str to float
        Wall-clock time of the moment solves (``"mom"``) and the engine runs (``"engine"``).
    """

    phi_deg: np.ndarray
    shape: str
    width: float
    wavelength: float
    length: float
    mom: dict
    po: dict
    ptd: dict
    multiple: dict
    seconds: dict

    def table(self) -> str:
        """The comparison as a Markdown table [dB relative to lambda]."""
        head = ("| phi [deg] | TM: MoM | PO | PO + PTD | TE: MoM | PO | PO + PTD "
                "| PO + PTD + multiple |\n|---|---|---|---|---|---|---|---|\n")
        rows = []
        for i, p in enumerate(self.phi_deg):
            vals = [self.mom["TM"][i], self.po["TM"][i], self.ptd["TM"][i],
                    self.mom["TE"][i], self.po["TE"][i], self.ptd["TE"][i],
                    self.multiple["TE"][i]]
            rows.append(f"| {p:g} | " + " | ".join(
                "-inf" if v < -200 else f"{v:.2f}" for v in vals) + " |")
        return head + "\n".join(rows)


def compare_long_plate(width: float, phi_deg, *, frequency: float = DEFAULT_FREQUENCY,
                       length: float | None = None, shape: str = "plate",
                       segments_per_wavelength: float = SEGMENTS_PER_WAVELENGTH
                       ) -> StripComparison:
    """Echo width of a strip (or a square cylinder) from the moment method and the engine.

    Parameters
    ----------
    width : float
        Strip (plate) width or the square's side [m].
    phi_deg : array_like, shape ``[phi]``
        Aspects from broadside [deg], in ``[0, 90]``.
    frequency : float
        [Hz].
    length : float, optional
        The engine's plate length [m]; default ``LENGTH_WAVELENGTHS`` wavelengths.
    shape : {"plate", "box"}
        A zero-thickness strip (:func:`long_plate`) or a square cylinder
        (:func:`long_box`; avoid the square's interior resonances,
        ``2 width / lambda = sqrt(m^2 + n^2)``, where the closed-contour EFIE fails).
    segments_per_wavelength : float
        Moment-method segment density.

    Returns
    -------
    StripComparison
    """
    import time

    if not (math.isfinite(frequency) and frequency > 0):
        raise ValueError(f"frequency must be a positive number of Hz, got {frequency!r}")
    phi = np.atleast_1d(np.asarray(phi_deg, dtype=float))
    if phi.ndim != 1 or len(phi) == 0 or not (np.all(phi >= 0) and np.all(phi <= 90)):
        raise ValueError(f"phi_deg must be angles in [0, 90] deg, got {phi_deg!r}")
    lam = SPEED_OF_LIGHT / frequency
    length = LENGTH_WAVELENGTHS * lam if length is None else length
    if not (math.isfinite(segments_per_wavelength) and segments_per_wavelength > 0):
        raise ValueError(f"segments_per_wavelength must be > 0, got {segments_per_wavelength!r}")
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {SHAPES}, got {shape!r}")
    seg = lam / segments_per_wavelength
    if shape == "plate":
        mesh, contour = long_plate(width, length), strip(width, seg)
    else:
        h = width / 2
        mesh = long_box(width, length)
        contour = polyline([[-h, -h], [h, -h], [h, h], [-h, h]], seg, closed=True)
    t0 = time.perf_counter()
    mom = {pol: echo_width(contour, lam, phi, pol).echo_width_db_lambda for pol in ("TM", "TE")}
    t1 = time.perf_counter()
    metal = po_material("pec", frequency)
    to_2d = 10 * math.log10(lam / (2 * length**2) / lam)
    po, ptd, multiple = {}, {}, {}
    for pol, channel in ENGINE_POLARISATION.items():
        for out, order in ((po, 0), (ptd, 1), (multiple, 2)):
            res = monostatic_rcs(mesh, metal, phi, [0.0], frequency=frequency,
                                 polarisation=channel, max_bounces=1, diffraction=order > 0,
                                 multiple_diffraction=order > 1)
            out[pol] = res.rcs_dbsm[:, 0] + to_2d
    t2 = time.perf_counter()
    return StripComparison(phi, shape, float(width), lam, float(length), mom, po, ptd, multiple,
                           {"mom": t1 - t0, "engine": t2 - t1})
