"""A mounted radar in a traced scene: tracer, clutter field and re-projection take the pose
of the radar frame A (``[radar] mounting_deg``), so the paths lie where it points."""

from __future__ import annotations

import numpy as np

from raysim.platform.mounting import mounting_matrix
from raysim.scenario import loads_scenario

#: Float round-off of the reference direction [deg].
EXACT_DEG = 1e-9
#: An oblique radar (45 deg down, looking forward) draws its paths around its boresight:
#: at least this share lies ahead of the radar (a down-looking one: half, measured 0.50;
#: the oblique one measured 0.96).
AHEAD_SHARE = 0.9

OBLIQUE = """
name = "oblique"
seed = 3

[radar]
num_chirps = 16
mounting_deg = "oblique"

[array]
nx = 4
ny = 4

[scene]
name = "flat_reflectors"
max_depth = 1

[scene.clutter]
max_scatterers = 2000
"""


def test_oblique_radar_traces_the_ground_ahead(warm_kernels):
    from raysim.pipeline.sources import hover_twin
    from raysim.platform.motion import stationary

    s = loads_scenario(OBLIQUE)
    out = hover_twin(s, stationary(), samples_per_src=2000)
    d = out["paths"].first_vertex - s.lever_arm                   # [path, 3] in W
    assert out["path_kinds"]["diffuse"] > 0
    assert np.mean(d[:, 0] > 0) >= AHEAD_SHARE
    # every path in front of the oblique radar (its forward half-space)
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    assert np.all(u @ mounting_matrix("oblique")[:, 2] > 0)
    # the reflector below the radar: straight down is 45 deg in elevation of N, azimuth 0
    ref = out["reference"]
    assert abs(ref.el_deg - 45.0) < EXACT_DEG and abs(ref.az_deg) < EXACT_DEG
    assert np.array_equal(out["hover"].lever_arm, s.lever_arm)   # the frame keeps r_IR in B


def test_scene_report_of_an_oblique_scenario(tmp_path, capsys, warm_kernels):
    """`scene-report --scenario` with an oblique mounting: the reflector under the radar is
    listed at 45 deg elevation of N and found where it is (detections placed along
    ``R_BA u`` in W)."""
    import json

    from raysim.cli import main

    (tmp_path / "s.toml").write_text(OBLIQUE, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["scene-report", "--scenario", str(tmp_path / "s.toml"), "--quick",
                 "--chains", "none,exact", "--out", str(out), "--no-progress",
                 "--threads", "2"]) == 0
    capsys.readouterr()
    data = json.loads((out / "oblique.json").read_text())
    nadir = next(t for t in data["targets"] if t["name"] == "cr-nadir")
    assert abs(nadir["el_deg"] - 45.0) < EXACT_DEG and abs(nadir["az_deg"]) < EXACT_DEG
    assert nadir["match"]["exact"]["detected"] and nadir["match"]["none"]["detected"]
