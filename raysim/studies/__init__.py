"""Studies composed from the pipeline: paper reproduction, stability maps, scene reports, sweeps, benchmarks, reports."""
