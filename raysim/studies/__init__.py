"""Experiments composed from the pipeline: each a configuration of the one run path.

Paper reproduction (``reproduce``), stability maps (``stability/``), scene
reports (``scene_report/``) and self-calibration on a scene
(``scene_calibration``). Products live elsewhere: the HTML report and figures
in :mod:`raysim.report`, sweeps and simulated flights in :mod:`raysim.pipeline`,
benchmarks in :mod:`raysim.bench`.
"""
