"""The one run path from a scenario to products.

::

    scenario ─▶ sources ─▶ IF frames ─▶ sensors ─▶ IMU log ─▶ estimate ─▶ motion
                                │                                         │
                                └────────────▶ chains ◀───────────────────┘
                                                 │
                                          beams ─▶ raysim.measure.point: metrics, maps

* :mod:`~raysim.pipeline.sources`: echo source (point-target oracle or a
  ray-traced scene) -> :class:`~raysim.synthesis.frame.RadarFrame`.
* :mod:`~raysim.pipeline.sensors`: the scenario's IMU log.
* :mod:`~raysim.pipeline.estimate`: IMU samples -> platform pose per chirp.
* :mod:`~raysim.pipeline.chains`: ``none`` / ``paper`` / ``exact`` beams.
* :mod:`~raysim.pipeline.beams`: the beamformer of one chain over a frame's TDM slots;
  :mod:`raysim.measure.point` measures the point metrics through it.
* :mod:`~raysim.pipeline.run`: the stages composed (``render``, ``evaluate``).
* :mod:`~raysim.pipeline.self_calibration`: velocity, clock offset and gyro
  bias estimated from the frames.
* :mod:`~raysim.pipeline.compensate`: stored cubes and captures plus an IMU
  log -> compensated beams (behind ``raysim compensate``).

Every command and study is a composition of these stages.
"""
