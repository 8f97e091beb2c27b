"""Target-ground multipath of geometry targets: PO + SBR with a ground apron vs the image method.

A metal trihedral (edge 0.1 m, apex 0.5 m above a flat ground, its symmetry axis
horizontal towards the radar and one mirror plane horizontal, so that it looks
the same from above and below) is traced from a radar 1.5 m high, 6 m away,
with a square apron of the ground under it. The image method (Balanis,
Advanced Engineering Electromagnetics, sec. 7.4; the radar's image ``x'`` in the
ground plane) gives the ghosts of a point target at ``p``:

* ground-target-ground: the target seen from ``x'``, at range ``R2 = |p - x'|``,
  power ``|Gamma chi|^4 (R1 / R2)^4 sigma(x') / sigma(x)`` relative to the direct
  return at ``R1 = |p - x|``;
* target-ground and ground-target: range ``(R1 + R2) / 2`` (bistatic, weak for a
  retro-reflector: its bistatic lobe ``lambda / a`` is 2 deg wide, the legs 28 deg apart);

with ``Gamma`` the Fresnel coefficient at the bounce's incidence (TE for a
horizontal radar polarisation, TM for a vertical one) and ``chi`` the Ament factor of the material.
``sigma(x')`` is the trihedral's free-space PO + SBR RCS seen from ``x'``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

FREQUENCY = 77e9
EDGE, APEX_HEIGHT, RADAR_HEIGHT, DISTANCE = 0.1, 0.5, 1.5, 6.0
#: Ghost centre vs the image-method range [range bins]: the retro-reflected
#: length is exact for a trihedral (``2 |apex - x'|``), this bounds the clustering.
RANGE_TOL_BINS = 0.1
#: Ghost-to-direct power vs the image-method closed form [dB]: the ghost is the
#: same triple bounce as the free-space trace from ``x'``, sampled by other tubes
#: (those reflected by the ground, on a launch grid normal to the radar's line of
#: sight): the trihedral's tube-sampling error is up to 0.4 dB at the default
#: density (``raysim.bench.tube_density``), on each of the two traces.
GHOST_TOL_DB = 1.0
#: The apron lies below the target and must leave its direct return unchanged [dB].
DIRECT_TOL_DB = 0.05
#: Radar polarisation in the test frame (x from the target to the radar, z up): horizontal is
#: TE at the ground bounce, vertical TM (near the Brewster angle of asphalt).
POLARISATION = {"HH": (0.0, 1.0, 0.0), "VV": (0.0, 0.0, 1.0)}


def _setup():
    from raysim.echoes.po.mesh import TriangleMesh
    from raysim.echoes.po.targets import trihedral

    # trihedral axis (+z local) -> +x (towards the radar), local x (normal of its
    # mirror plane) -> vertical: the same from above and below its apex
    rot = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]).T
    apex = np.array([0.0, 0.0, APEX_HEIGHT])
    m = trihedral(EDGE)
    target = TriangleMesh(m.vertices @ rot.T + apex, m.faces)
    half = 4.0
    apron = TriangleMesh(np.array([[-half, -half, 0.0], [half + DISTANCE / 2, -half, 0.0],
                                   [half + DISTANCE / 2, half, 0.0], [-half, half, 0.0]]),
                         np.array([[0, 1, 2], [0, 2, 3]]))
    radar = np.array([DISTANCE, 0.0, RADAR_HEIGHT])
    return target, apron, apex, radar


@pytest.fixture(scope="module")
def free_space(rt_backend):
    """The trihedral alone, seen from the radar and from its image (terms), per polarisation."""
    from raysim.echoes.po.paths import scattering_terms

    target, _, apex, radar = _setup()
    image = radar * [1.0, 1.0, -1.0]
    out = {}
    for pol, vec in POLARISATION.items():
        kw = {"frequency": FREQUENCY, "polarisation_w": vec}
        out[pol] = (scattering_terms(target, "metal", radar, apex, **kw),
                    scattering_terms(target, "metal", image, apex, **kw))
    return out


@pytest.mark.parametrize("ground, pol", [("pec", "HH"), ("asphalt-77ghz", "HH"),
                                         ("asphalt-77ghz", "VV")])
def test_trihedral_ghosts_follow_the_image_method(free_space, ground, pol):
    from raysim.echoes.ground.sigma0 import ament_factor, fresnel_coefficient
    from raysim.echoes.po.paths import cluster_terms, scattering_terms

    direct_free, image_free = free_space[pol]
    target, apron, apex, radar = _setup()
    terms = scattering_terms(target, "metal", radar, apex, frequency=FREQUENCY,
                             polarisation_w=POLARISATION[pol], ground=(apron, ground))
    wavelength = SPEED_OF_LIGHT / FREQUENCY
    r1 = float(np.linalg.norm(radar - apex))
    r2 = float(np.linalg.norm(radar * [1.0, 1.0, -1.0] - apex))
    cos_i = (RADAR_HEIGHT + APEX_HEIGHT) / r2
    if ground == "pec":
        gamma, chi = 1.0, 1.0
    else:
        gamma = abs(complex(fresnel_coefficient(ground, cos_i, pol)))
        chi = float(ament_factor(ground, math.acos(cos_i), wavelength))
        assert chi < 0.9                                # the roughness is felt
    closed_db = 10 * math.log10((gamma * chi) ** 4 * (r1 / r2) ** 4
                                * image_free.rcs_m2 / direct_free.rcs_m2)

    on_first = np.abs(terms.first[:, 2]) < 1e-6
    on_last = np.abs(terms.last[:, 2]) < 1e-6
    # no ground-only path: the apron's own single bounce and ground-ground pairs are absent
    assert not np.any((terms.bounces == 1) & on_first)
    assert not np.any((terms.bounces == 2) & on_first & on_last)

    def power(sel):
        return abs(np.sum(terms.amplitude[sel])) ** 2

    direct = ~on_first & ~on_last
    assert abs(10 * math.log10(power(direct) / (direct_free.rcs_m2 / (4 * math.pi)))) \
        < DIRECT_TOL_DB
    double = on_first & on_last
    ghost_db = 10 * math.log10(power(double) / power(direct))
    print(f"{ground} {pol}: ground-target-ground {ghost_db:.2f} dB, closed {closed_db:.2f} dB")
    assert abs(ghost_db - closed_db) < GHOST_TOL_DB

    bin_m = RadarConfig().range_resolution
    centre, amp, _ = cluster_terms(terms, bin_m)
    ranges = np.linalg.norm(centre - radar, axis=1)
    order = np.argsort(-np.abs(amp))
    assert abs(ranges[order[0]] - r1) < RANGE_TOL_BINS * bin_m           # the direct return
    assert abs(ranges[order[1]] - r2) < RANGE_TOL_BINS * bin_m           # its ground image
    assert abs(20 * math.log10(abs(amp[order[1]] / amp[order[0]])) - closed_db) < GHOST_TOL_DB
    # the bistatic ghosts (one ground bounce) sit at (R1 + R2) / 2
    single = on_first ^ on_last
    assert single.any()
    w = np.abs(terms.amplitude[single])
    mean_range = np.sum(w * terms.length[single]) / np.sum(w) / 2
    assert abs(mean_range - (r1 + r2) / 2) < RANGE_TOL_BINS * bin_m


def test_without_apron_there_are_no_ghosts(free_space):
    """The same trace without ground has no term beyond the target's own range extent."""
    direct_free, _ = free_space["HH"]
    _, _, apex, radar = _setup()
    r1 = float(np.linalg.norm(radar - apex))
    assert np.all(direct_free.length / 2 < r1 + EDGE)


def test_ground_apron_lies_in_the_local_ground_plane():
    """The apron of a target over a flat ground (W, NED: ground 15 m below the radar) is
    in the ground plane, centred under the target, as wide as its shadow plus two
    Fresnel lengths, of the ground's material; none off the ground or under the radar."""
    from raysim.echoes.ground.surface import GroundSurface
    from raysim.echoes.po.mesh import TriangleMesh
    from raysim.echoes.po.paths import APRON_MAX_HALF_SIDE, ground_apron

    ground = TriangleMesh(np.array([[-50.0, -50.0, 15.0], [50.0, -50.0, 15.0],
                                    [50.0, 50.0, 15.0], [-50.0, 50.0, 15.0]]),
                          np.array([[0, 1, 2], [0, 2, 3]]))
    surface = GroundSurface.from_meshes([(ground, "asphalt-77ghz")])
    wavelength = SPEED_OF_LIGHT / FREQUENCY
    target, radar, radius = np.array([10.0, 5.0, 14.0]), np.zeros(3), 0.5
    mesh, material = ground_apron(surface, target, radar, radius, wavelength)
    assert material == "asphalt-77ghz"
    assert np.allclose(mesh.vertices[:, 2], 15.0)
    assert np.allclose(mesh.vertices.mean(axis=0)[:2], target[:2])
    half = np.abs(mesh.vertices[:, :2] - target[:2]).max()
    shadow = 2 * radius * math.hypot(10.0, 5.0) / 15.0
    expected = radius + shadow + 2 * math.sqrt(wavelength * math.hypot(10.0, 5.0, 15.0))
    assert abs(half - min(expected, APRON_MAX_HALF_SIDE)) < 1e-9
    assert ground_apron(surface, np.array([80.0, 0.0, 14.0]), radar, radius, wavelength) is None
    assert ground_apron(surface, target, np.array([0.0, 0.0, 16.0]), radius, wavelength) is None
