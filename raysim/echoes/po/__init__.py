"""Physical-optics scattering: facet PO integrals and shooting-and-bouncing rays (SBR).

Modules: :mod:`~raysim.echoes.po.mesh` (meshes, materials, Fresnel),
:mod:`~raysim.echoes.po.integral` (Gordon's closed-form facet integral, PO
currents), :mod:`~raysim.echoes.po.edges` (edge diffraction: the PTD fringe
wave of the mesh wedges), :mod:`~raysim.echoes.po.rays` (Mitsuba ray intersection),
:mod:`~raysim.echoes.po.sbr` (ray tubes), :mod:`~raysim.echoes.po.rcs`
(monostatic RCS driver), :mod:`~raysim.echoes.po.targets` (canonical meshes and
closed forms), :mod:`~raysim.echoes.po.paths` (geometry targets as frozen
scattering-centre paths for the tracer), :mod:`~raysim.echoes.po.fidelity` (the
cheapest echo model per object: point, reduced centres or mesh),
:mod:`~raysim.echoes.po.car` (a car mesh), :mod:`~raysim.echoes.po.sedan` (the
detailed car: docs/cars.md), :mod:`~raysim.echoes.po.mom2d` (the 2-D method of
moments, a full-wave reference) and :mod:`~raysim.echoes.po.strip_reference` (the
engine against it on a long plate). See ``docs/rcs.md`` and ``docs/scattering.md``.
"""

from raysim.echoes.po.mesh import PoMaterial, TriangleMesh, po_material
from raysim.echoes.po.rcs import RcsResult, monostatic_rcs
from raysim.echoes.po.targets import canonical_target

__all__ = ["PoMaterial", "TriangleMesh", "po_material", "RcsResult", "monostatic_rcs",
           "canonical_target"]
