"""Measurements: one module per product, each metric defined once.

* :mod:`raysim.measure.point`: metrics of a point target (range, angles,
  pseudo-velocity, Doppler width, entropies of its maps).
* :mod:`raysim.measure.scene`: maps of a whole scene and its detections.
* :mod:`raysim.measure.ridge`: Doppler ridge leakage of a scene.
* :mod:`raysim.measure.beams`: metrics of a compensated beam cube.

Names and units of every metric are those of :data:`raysim.vocabulary.METRICS`;
their parameters are stated in docs/conventions.md.
"""
