"""Studies composed from the pipeline.

Paper reproduction, stability maps, scene reports, sweeps, benchmarks, reports.
"""
