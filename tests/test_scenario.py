"""Scenario files: parsing, validation messages naming the key, conversions, examples."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from raysim.pipeline.sources import point_targets
from raysim.scenario import (
    dumps_toml,
    load_scenario,
    loads_scenario,
    parse_assignment,
    scenario_from_case,
    set_key,
    validate_scenario,
)
from raysim.scenario.paper_cases import DEFAULT_LEVER_ARM, PAPER_CASES, get_case

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

SMALL = """
name = "small"
[radar]
num_chirps = 32
chirp_duration_s = 12.8e-6
[array]
nx = 4
ny = 4
[[scene.targets]]
range_m = 15.0
az_deg = 20.0
"""


def test_minimal_file_defaults():
    s = loads_scenario(SMALL)
    cfg = s.radar_config()
    assert (cfg.num_chirps, cfg.num_samples, cfg.carrier_frequency) == (32, 128, 77e9)
    assert s.virtual_array().num_channels == 16
    assert s.scene.kind == "points"
    assert s.trajectory().name == "stationary"
    np.testing.assert_allclose(s.lever_arm, [0, 0, 0.1])


def test_error_names_key_value_and_expectation(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(SMALL.replace("num_chirps = 32", "num_chirps = 32\nsample_rate_hz = -1"))
    with pytest.raises(ValueError) as err:
        load_scenario(bad)
    msg = str(err.value)
    assert str(bad) in msg
    assert "radar.sample_rate_hz: got -1, expected > 0" in msg


@pytest.mark.parametrize("path, value, expected", [
    ("radar.foo", 1, "radar.foo: got 1, expected no such key"),
    ("scene.targets.0.azdeg", 3, "scene.targets.0.azdeg: got 3, expected no such key"),
    ("array.kind", "upb", "array.kind: got \"upb\", expected one of"),
    ("frames", "two", "frames: got \"two\", expected an integer"),
    ("radar.num_chirps", 1.5, "radar.num_chirps: got 1.5, expected an integer"),
    ("motion.case", "nope", "motion.case: got \"nope\", expected a paper case name"),
    ("motion.sinusoids", [{"axis": "pitch", "amplitude_m": 1.0, "frequency_hz": 3.0}],
     "motion.sinusoids.0: axis 'pitch' is an angle: give amplitude_deg"),
    ("imu.preset", "navy", "imu.preset: got \"navy\""),
    ("lever_arm_m", [0.0, 0.0], "lever_arm_m"),
    ("scene.targets.0.range_m", -2.0, "scene.targets.0.range_m: got -2.0, expected > 0"),
])
def test_malformed_files_name_the_offending_key(tmp_path, path, value, expected):
    data = tomllib.loads(SMALL)
    set_key(data, path, value)
    f = tmp_path / "bad.toml"
    f.write_text(dumps_toml(data))
    with pytest.raises(ValueError) as err:
        load_scenario(f)
    assert expected in str(err.value)
    assert str(f) in str(err.value)


def test_missing_required_key_and_bad_toml():
    with pytest.raises(ValueError, match=r"scene.targets.0.range_m: missing"):
        loads_scenario("[[scene.targets]]\naz_deg = 3")
    with pytest.raises(ValueError, match="not valid TOML"):
        loads_scenario("[radar\n")
    with pytest.raises(ValueError, match="cannot read scenario file"):
        load_scenario("/nonexistent/x.toml")


def test_cross_field_radar_check_is_reported():
    with pytest.raises(ValueError, match="radar.*bandwidth"):
        loads_scenario(SMALL.replace("num_chirps = 32", "num_chirps = 32\nbandwidth_hz = 1e12"))


def _problems(text: str, tmp_path) -> list[str]:
    """The lines of the error of a scenario file holding ``text`` (after its head line)."""
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ValueError) as err:
        load_scenario(f)
    head, *lines = str(err.value).splitlines()
    assert head == f"{f}: {len(lines)} invalid value{'s' if len(lines) > 1 else ''}:", head
    return [line.strip() for line in lines]


def test_two_field_errors_in_different_sections_are_both_reported(tmp_path):
    lines = _problems(SMALL.replace("num_chirps = 32", "num_chirps = 32\nsample_rate_hz = -1")
                      + "\n[imu]\npreset = \"navy\"\n", tmp_path)
    assert len(lines) == 2, lines
    assert lines[0] == "radar.sample_rate_hz: got -1, expected > 0"
    assert lines[1].startswith('imu.preset: got "navy", expected one of')


def test_field_error_and_two_cross_section_errors_are_all_reported(tmp_path):
    # a bad key in [scene] used to hide the radar and IMU-rate checks entirely
    text = (SMALL.replace("num_chirps = 32", "num_chirps = 32\nbandwidth_hz = 1e12")
            .replace("range_m = 15.0", "range_m = 15.0\nazdeg = 3")
            + "\n[[motion.sinusoids]]\naxis = \"pitch\"\namplitude_deg = 5.0\n"
              "frequency_hz = 20.0\n\n[imu]\nrate_hz = 30.0\n")
    lines = _problems(text, tmp_path)
    assert len(lines) == 3, lines
    assert lines[0].startswith("scene.targets.0.azdeg: got 3, expected no such key")
    assert "did you mean 'az_deg'" in lines[0]
    assert lines[1].startswith("radar: inconsistent waveform: bandwidth")
    assert lines[2] == ("imu.rate_hz: got 30 Hz, below the Nyquist rate of the motion: the "
                        "pitch sinusoid at 20 Hz needs imu.rate_hz >= 40 Hz")


def test_cross_section_check_of_an_invalid_section_is_not_guessed(tmp_path):
    # [imu] itself is invalid: the IMU-rate check would read a default, so it is left out
    text = (SMALL + "\n[[motion.sinusoids]]\naxis = \"pitch\"\namplitude_deg = 5.0\n"
                    "frequency_hz = 20.0\n\n[imu]\nrate_hz = 30.0\nseed = -1\n")
    lines = _problems(text, tmp_path)
    assert lines == ["imu.seed: got -1, expected >= 0"], lines


def test_every_problem_of_one_table_is_reported(tmp_path):
    # a rotor giving both spin rates and an all-zero axis; then a point scene without
    # targets holding a (valid) rotor, which needs a ray-traced scene
    lines = _problems('[scene]\nkind = "bundled"\n\n[[scene.rotors]]\nhub_m = [0.0, 0.0, 0.0]\n'
                      'blade_length_m = 0.2\nrate_rps = 10.0\nrate_radps = 60.0\n'
                      'axis = [0.0, 0.0, 0.0]\n', tmp_path)
    assert len(lines) == 2, lines
    assert lines[0].startswith("scene.rotors.0: give one of rate_rps"), lines
    assert lines[1].startswith("scene.rotors.0: axis must not be all zero"), lines
    lines = _problems('[scene]\nkind = "points"\n\n[[scene.rotors]]\nhub_m = [0.0, 0.0, 0.0]\n'
                      'blade_length_m = 0.2\nrate_rps = 10.0\n', tmp_path)
    assert len(lines) == 2, lines
    assert lines[0] == "scene: kind 'points' needs at least one [[scene.targets]] entry"
    assert lines[1].startswith("scene: [[scene.rotors]] need a ray-traced scene with "
                               "[scene.clutter] mode = 'field'"), lines


def test_motion_sums_case_sinusoids_velocity_and_jitter():
    s = loads_scenario(SMALL + """
[motion]
case = "rotation_y"
velocity_mps = [0.1, 0.0, 0.0]
[[motion.sinusoids]]
axis = "z"
amplitude_m = 0.05
frequency_hz = 5.0
phase_deg = 90.0
[motion.hover_jitter]
seed = 4
""")
    traj = s.trajectory()
    t = np.array([0.0, 0.01, 0.02])
    q, _, _ = traj.states(t)
    case = scenario_from_case("rotation_y").trajectory().states(t)[0]
    # z: sinusoid at phase 90 deg (value 0.05 at t=0) plus jitter (a few cm)
    assert abs(q[0, 2] - 0.05) < 0.1
    assert traj.name.count("+") == 3
    from raysim.platform.motion import hover_jitter
    jit = hover_jitter(4).states(t)[0]
    np.testing.assert_allclose(q[:, 4], case[:, 4] + jit[:, 4], atol=1e-12)
    np.testing.assert_allclose(q[:, 0], 0.1 * t + jit[:, 0], atol=1e-12)


def test_custom_array_and_ti_slots():
    s = loads_scenario(SMALL.replace('[array]\nnx = 4\nny = 4', '[array]\nkind = "ti_3tx4rx"'))
    assert s.radar_config().num_tx_slots == 3 and s.virtual_array().num_channels == 12
    s = loads_scenario(SMALL.replace('[array]\nnx = 4\nny = 4', '''[array]
kind = "custom"
tx_positions_m = [[0, 0, 0], [0.004, 0, 0]]
rx_positions_m = [[0, 0, 0], [0.002, 0, 0]]'''))
    assert s.radar_config().num_tx_slots == 2 and s.virtual_array().num_channels == 4
    with pytest.raises(ValueError, match="array: kind 'custom' needs"):
        loads_scenario(SMALL.replace('[array]\nnx = 4\nny = 4', '[array]\nkind = "custom"'))


def test_custom_imu_and_targets():
    s = loads_scenario(SMALL + """
[imu]
preset = "custom"
[imu.gyro]
noise_density = 1e-4
""")
    spec = s.imu_spec()
    assert spec.gyro.noise_density == 1e-4 and math.isinf(spec.gyro.full_scale)
    tgt = point_targets(s)[0]
    d = tgt.position - s.lever_arm
    assert np.linalg.norm(d) == pytest.approx(15.0)
    assert math.degrees(math.atan2(d[0], d[2])) == pytest.approx(20.0)


#: The paper's cases: chirps, frames, target (range [m], az [deg], el [deg]), motion
#: (axis, amplitude [deg or m], frequency [Hz]) or None.
CASES = {
    "stationary": (256, 1, (15.0, 20.0, 0.0), None),
    "rotation_y": (256, 1, (15.0, 20.0, 0.0), ("pitch", np.deg2rad(10.0), 20.0)),
    "yaw": (256, 20, (18.0, 25.0, 25.0), ("yaw", np.deg2rad(20.0), 10.0)),
    "translation_y": (512, 1, (15.0, 10.0, 35.0), ("y", 0.05, 5.0)),
    "translation_z": (512, 1, (15.0, 10.0, 10.0), ("z", 0.05, 5.0)),
}


@pytest.mark.parametrize("name", sorted(PAPER_CASES))
def test_paper_case_scenarios_and_examples(name):
    from raysim.echoes.oracle import PointTarget
    from raysim.platform.motion import sinusoid, stationary
    from raysim.radar.config import RadarConfig

    assert sorted(PAPER_CASES) == sorted(CASES)
    chirps, frames, (r, az, el), motion = CASES[name]
    s = scenario_from_case(name)
    case = get_case(name)
    assert s.name == name and s.description == case["description"]
    assert s.radar_config() == RadarConfig(num_chirps=chirps, num_frames=frames,
                                           element_pattern="constant")
    assert s.frames == frames and s.virtual_array().grid_shape == (20, 20)
    np.testing.assert_array_equal(s.lever_arm, DEFAULT_LEVER_ARM)
    want = PointTarget.at(r, np.deg2rad(az), np.deg2rad(el), radar_origin=DEFAULT_LEVER_ARM)
    np.testing.assert_array_equal(point_targets(s)[0].position, want.position)
    t = np.linspace(0.0, 0.05, 7)
    truth = stationary() if motion is None else sinusoid(*motion)
    for got, exp in zip(s.trajectory().states(t), truth.states(t), strict=True):
        np.testing.assert_array_equal(got, exp)
    # the case description is plain data: the scenario keys validate on their own
    assert validate_scenario(case["scenario"]).radar_config() == s.radar_config()
    assert set(case["paper"]) <= {"none", "paper"}
    from raysim.vocabulary import METRICS

    assert all(m in METRICS for vals in case["paper"].values() for m in vals)
    ex = load_scenario(EXAMPLES / f"case_{name}.toml")
    assert ex.radar_config() == s.radar_config()
    assert ex.motion.case == name and ex.scene.targets == s.scene.targets


def test_paper_cases_are_data_files_in_paper_order(tmp_path):
    """The cases are TOML files; the index keeps the paper's order; bad folders are named."""
    from raysim.scenario import paper_cases

    assert list(PAPER_CASES) == ["stationary", "rotation_y", "yaw", "translation_y",
                                 "translation_z"]
    base, cases = paper_cases.load_cases(paper_cases.CASES_DIR)
    assert cases == PAPER_CASES and base == paper_cases.BASE
    for name in PAPER_CASES:
        data = tomllib.loads((paper_cases.CASES_DIR / f"{name}.toml").read_text())
        assert set(data) <= {"description", "scenario", "paper"}
    # a case file the index does not list
    for f in paper_cases.CASES_DIR.glob("*.toml"):
        (tmp_path / f.name).write_text(f.read_text())
    (tmp_path / "roll_x.toml").write_text('description = "x"\n')
    with pytest.raises(ValueError, match="do not match the case files.*roll_x"):
        paper_cases.load_cases(tmp_path)
    (tmp_path / "roll_x.toml").unlink()
    (tmp_path / "yaw.toml").write_text('description = "x"\nfrmes = 3\n')
    with pytest.raises(ValueError, match="yaw.toml: expected keys.*frmes"):
        paper_cases.load_cases(tmp_path)
    (tmp_path / "yaw.toml").write_text("description = \n")
    with pytest.raises(ValueError, match="yaw.toml' is not valid TOML"):
        paper_cases.load_cases(tmp_path)


def test_every_bundled_scene_has_an_example():
    names = {"flat_reflectors", "parking_lot", "rough_terrain"}
    try:
        from raysim.echoes.rt.scenes import SCENES
        names = set(SCENES)
    except ImportError:
        pass
    for name in names:
        s = load_scenario(EXAMPLES / f"scene_{name}.toml")
        assert s.scene.kind == "bundled" and s.scene.name == name


def test_toml_round_trip_and_with_values():
    s = scenario_from_case("yaw")
    assert loads_scenario(s.to_toml()) == s
    assert tomllib.loads(dumps_toml({"a": 7.7e10}))["a"] == 7.7e10
    s2 = s.with_values({"radar.num_chirps": 32, "scene.targets.0.range_m": 10.0})
    assert s2.radar.num_chirps == 32 and s2.scene.targets[0].range_m == 10.0
    with pytest.raises(ValueError, match="radar.num_chirps: got 2, expected >= 4"):
        s.with_values({"radar.num_chirps": 2})
    assert parse_assignment("radar.num_chirps=64") == ("radar.num_chirps", 64)
    assert parse_assignment("imu.preset=tactical") == ("imu.preset", "tactical")
    with pytest.raises(ValueError, match="KEY=VALUE"):
        parse_assignment("radar.num_chirps")
    with pytest.raises(ValueError, match="key path"):
        parse_assignment("radar..x=1")


def test_validate_rejects_non_table():
    with pytest.raises(ValueError, match="expected a table"):
        validate_scenario([1, 2])
