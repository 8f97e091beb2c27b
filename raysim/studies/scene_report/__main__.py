"""``python -m raysim.studies.scene_report``: print the re-projection benchmark as JSON."""

from raysim.bench.reprojection import main_bench

if __name__ == "__main__":  # pragma: no cover
    main_bench()
