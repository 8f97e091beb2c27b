"""The sedan's headlamp reflector seen by the PO engine: its single bounce against the
geometric-optics RCS of its vertex."""

from __future__ import annotations

import math

#: Geometric optics at a specular point of principal radii R1, R2: sigma = pi R1 R2
#: (geometric optics of a doubly curved surface; Knott, Shaeffer & Tuley, *Radar Cross
#: Section*, 2nd ed., 1993); at a paraboloid's
#: vertex R1 = R2 = 2 F. The truncated reflector's rim adds an edge wave (for a round rim
#: at one depth d the physical-optics RCS is 4 pi F^2 |1 - exp(-2jkd)|^2, 0 to 4 times the
#: vertex's); this rim lies at depths 3-19 cm, many wavelengths apart, so its edge wave
#: mostly cancels and the single bounce stays within this of the vertex's [dB].
RIM_EDGE_TOL_DB = 3.0
#: Radar range of the check [m]: the 24 x 14 cm reflector's far field (2 D^2 / lambda)
#: begins at about 40 m.
RANGE_M = 50.0


def test_headlamp_reflector_single_bounce_is_its_vertex(rt_backend):
    """Facet PO (one bounce) of the left reflector, seen along its axis: pi (2F)^2."""
    from raysim.echoes.po.mesh import TriangleMesh
    from raysim.echoes.po.sedan import HEADLAMP_FOCAL, sedan_parts
    from raysim.studies.car_rcs import car_rcs

    lamps = {n: m for n, m, _ in sedan_parts(openings=True)}["headlamps"]
    left = lamps.faces[lamps.vertices[lamps.faces][:, :, 1].mean(axis=1) > 0]
    reflector = TriangleMesh(lamps.vertices, left)
    r = car_rcs([("headlamp", reflector, "metal")], [0.0], [0.0], range_m=RANGE_M,
                max_bounces=1)
    got_db = 10 * math.log10(float(r.po_m2[0, 0]))
    ref_db = 10 * math.log10(math.pi * (2 * HEADLAMP_FOCAL) ** 2)
    print(f"reflector single bounce {got_db:.1f} dBsm, vertex GO {ref_db:.1f} dBsm")
    assert abs(got_db - ref_db) < RIM_EDGE_TOL_DB
