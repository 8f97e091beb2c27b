"""The clutter field's density: scatterers per radar resolution cell at every incidence.

The field is built (no synthesis) over each bundled scene's ground from the
hover point, and its scatterers are counted in the radar's range x azimuth
resolution cells, zeros included: range bin ``k`` (``dR``) times an azimuth
sector of ring ``k``, the ring cut into ``ceil(2 pi sin(theta_k) / sqrt(du dv))``
equal sectors, so no sector is wider than the radar's cross-range cell
``R sqrt(du dv)`` (the cell grows with range; ``theta_k`` the incidence of ring
``k`` over flat ground at the hover height). Cells cut by the scene's edge or
the range window are left out.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.echoes.ground.field import ClutterField, FieldCapped, FieldSettings
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.rt.scenes import SCENES, RadarScene
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Smallest median count of scatterers per resolution cell accepted in any incidence band.
MIN_PER_CELL = 5
#: Largest share of a band's cells holding fewer than MIN_PER_CELL scatterers (Poisson
#: with mean 10 gives 2.9 %; the sectors are at most one cell wide, so a little more).
MAX_SPARSE_SHARE = 0.10
#: Incidence bands [deg] (nominal incidence of each range ring over flat ground).
BANDS_DEG = ((0.0, 30.0), (30.0, 56.0), (56.0, 70.0), (70.0, 85.0))
#: Margin kept from the scene's edge for a cell to count as whole [m] (rough terrain's relief).
EDGE_MARGIN_M = 2.0


def _ground(name: str) -> tuple[GroundSurface, float]:
    """The bundled scene's ground without Sionna (its meshes read from the XML)."""
    d = SCENES[name]
    alt = float(d.metadata()["hover_altitude"])
    return GroundSurface.from_scene(RadarScene(d, None, alt, [])), alt


def cell_counts(field: ClutterField, radar_w: np.ndarray, height: float, dr: float,
                width: float, max_range: float, extent: np.ndarray) -> dict:
    """Scatterers per whole resolution cell by incidence band, ``{band: counts [cell]}``.

    ``width`` is the cross-range cell in direction cosines, ``extent`` the
    ground's ``[[x_min, y_min], [x_max, y_max]]`` in W [m].
    """
    d = field.positions - radar_w
    r = np.linalg.norm(d, axis=1)
    k = np.floor(r / dr).astype(int)
    phi = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2 * math.pi)
    out = {band: [] for band in BANDS_DEG}
    for ring in range(int(math.ceil(height / dr)), int(max_range / dr)):
        r0, r1 = ring * dr, (ring + 1) * dr
        if r0 < height:
            continue
        rc = 0.5 * (r0 + r1)
        sin_t = math.sqrt(1 - (height / rc) ** 2)
        theta = math.degrees(math.asin(sin_t))
        band = next((b for b in BANDS_DEG if b[0] <= theta < b[1]), None)
        if band is None:
            continue
        n_sec = max(1, math.ceil(2 * math.pi * sin_t / width))
        edges = np.linspace(0.0, 2 * math.pi, n_sec + 1)
        # a sector is whole when its outer corners and mid-arc lie on the ground
        rho_out = math.sqrt(r1**2 - height**2)
        a = np.stack([edges[:-1], edges[1:], 0.5 * (edges[:-1] + edges[1:])])
        xy = radar_w[:2, None, None] + rho_out * np.stack([np.cos(a), np.sin(a)])
        whole = np.all((xy[0] > extent[0, 0] + EDGE_MARGIN_M)
                       & (xy[0] < extent[1, 0] - EDGE_MARGIN_M)
                       & (xy[1] > extent[0, 1] + EDGE_MARGIN_M)
                       & (xy[1] < extent[1, 1] - EDGE_MARGIN_M), axis=0)
        sel = k == ring
        counts = np.bincount(np.minimum((phi[sel] / (2 * math.pi) * n_sec).astype(int),
                                        n_sec - 1), minlength=n_sec)
        out[band].extend(counts[whole].tolist())
    return {b: np.asarray(c) for b, c in out.items()}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_every_incidence_band_holds_the_asked_scatterers_per_cell(name):
    """At least MIN_PER_CELL scatterers per range x azimuth cell (median) at every incidence,
    the 70-85 deg band included, on every bundled scene's ground (8 x 8 UPA, 90 m window)."""
    ground, height = _ground(name)
    config = RadarConfig()
    array = upa(8, 8, wavelength=config.wavelength)
    radar_w = np.zeros(3)
    field = ClutterField.build(ground, config, array, radar_w, np.eye(3),
                               FieldSettings(shadowing=False, walls=False, seed=42))
    rep = field.report
    assert rep["density_scale"] == 1.0 and rep["wall_scatterers"] == 0
    dr, du, dv = rep["resolution"]
    extent = np.stack([ground.triangles[..., :2].min(axis=(0, 1)),
                       ground.triangles[..., :2].max(axis=(0, 1))])
    counts = cell_counts(field, radar_w, height, dr, math.sqrt(du * dv), config.max_range,
                         extent)
    for band, c in counts.items():
        sparse = float(np.mean(c < MIN_PER_CELL))
        print(f"{name} {band[0]:.0f}-{band[1]:.0f} deg: {c.size} cells, median "
              f"{np.median(c):.0f}, mean {c.mean():.2f}, below {MIN_PER_CELL}: {sparse:.3f}")
        assert c.size >= 20
        assert np.median(c) >= MIN_PER_CELL
        assert sparse <= MAX_SPARSE_SHARE


def test_a_capped_field_warns_and_says_its_density():
    """Past max_scatterers the density is scaled down with a FieldCapped warning that
    names the expected count, the cap and the scatterers per cell left."""
    ground, _ = _ground("flat_reflectors")
    config = RadarConfig()
    array = upa(8, 8, wavelength=config.wavelength)
    with pytest.warns(FieldCapped, match=r"exceed max_scatterers = 2000; density scaled"):
        field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                                   FieldSettings(shadowing=False, max_scatterers=2000))
    assert field.report["density_scale"] < 0.1
    assert abs(field.num_scatterers - 2000) < 5 * math.sqrt(2000)
