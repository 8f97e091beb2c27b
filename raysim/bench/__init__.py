"""Benchmarks, all in one place: the suite of ``raysim bench`` (:mod:`~raysim.bench.suite`),
its workloads, the real-time stream, the speed-versus-accuracy chart, the SBR tube density,
scene re-projection against re-tracing, and the stand-alone scripts
(``python -m raysim.bench.<name>``). Figures are ratios against a baseline of the same run."""
