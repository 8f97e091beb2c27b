"""The bad-input catalogue, part 2: the command line and scenario files.

Each case runs ``raysim`` in-process (or reads a scenario file) and expects a
clear error: exit 2 with a one-line message on stderr naming the option, key,
value or file (and, for unknown names, the closest valid one), never a
traceback. Output paths are checked before any computation. The tests after
the catalogue cover what a user must be able to rely on around it: negative
option values, examples in every ``--help``, bench results on stdout, and the
size of the whole catalogue (tests/test_bad_input*.py, at least 100 cases).
"""

from __future__ import annotations

import argparse
import io
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from bad_input_common import ARR, SMALL, Bad, CliError, cli, scenario_data, validate

from raysim.echoes.oracle import PointTarget, simulate_point_targets

CASE_TOML = Path(__file__).resolve().parents[1] / "examples" / "case_rotation_y.toml"


def _file(tmp: Path, name: str = "afile") -> Path:
    """An existing plain file in ``tmp``."""
    p = tmp / name
    p.write_text("not a folder\n")
    return p


def _load(path: Path):
    from raysim.scenario import load_scenario

    return load_scenario(path)


def _scenario_bytes(tmp: Path, data: bytes, name: str = "s.toml"):
    (tmp / name).write_bytes(data)
    return _load(tmp / name)


def _with(**changes):
    from raysim.scenario import scenario_from_case

    return scenario_from_case("rotation_y").with_values(changes)


def _cube(tmp: Path) -> Path:
    """A one-frame ``.npz`` cube of the small radar (8 chirps, 2 x 2 array)."""
    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, -0.2, -0.1)])
    path = tmp / "c.npz"
    np.savez(path, data=fr.data, chirp_times=fr.chirp_times,
             element_positions=ARR.virtual_positions, carrier_frequency=SMALL.carrier_frequency,
             bandwidth=SMALL.bandwidth, chirp_duration=SMALL.chirp_duration,
             sample_rate=SMALL.sample_rate)
    return path


def _folder(path: Path) -> Path:
    path.mkdir()
    return path


def _binary(tmp: Path, name: str) -> Path:
    """A file of binary bytes (a ULog's magic and a few non-UTF-8 bytes) named ``name``."""
    p = tmp / name
    p.write_bytes(b"ULog\x01\x12\x35\x01\xb8\xff\xfe\x00" * 4)
    return p


def _plate_mm(tmp: Path, side: float) -> Path:
    """A square plate of ``side`` file units (STL), as a CAD tool in millimetres writes it."""
    import trimesh

    h = side / 2
    v = np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])
    path = tmp / "plate.stl"
    trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3]]).export(path)
    return path


def _with_memory(available: int, fn):
    """Run ``fn()`` as if ``available`` bytes of memory were left."""
    from raysim import resources

    real = resources.available_memory
    resources.available_memory = lambda: available
    try:
        return fn()
    finally:
        resources.available_memory = real


#: A path whose nearest existing folder cannot be written, even by root.
UNWRITABLE = "/proc/raysim-no-such-dir/out"

CLI_CASES = [
    # ---------------------------------------------------------- scenario files
    Bad("scenario-negative-sample-rate", lambda _: validate(scenario_data(sample_rate_hz=-1)),
        ValueError, ("radar.sample_rate_hz", "-1")),
    Bad("scenario-unknown-key", lambda _: validate(scenario_data(samplerate=1)), ValueError,
        ("radar.samplerate", "unknown keys")),
    Bad("scenario-missing-file",
        lambda t: __import__("raysim.scenario", fromlist=["x"]).load_scenario(t / "no.toml"),
        ValueError, ("no.toml", "cannot read")),
    Bad("scenario-not-utf8", lambda t: _scenario_bytes(t, 'name = "caf\xe9"\n'.encode("latin-1")),
        ValueError, ("s.toml", "not UTF-8", "offset")),
    Bad("scenario-tx-power-overflow", lambda _: _with(**{"radar.tx_power_dbm": 1e6}), ValueError,
        ("radar.tx_power_dbm", "1000000.0", "[-100, 60] dBm")),
    Bad("scenario-rcs-900", lambda _: _with(**{"scene.targets.0.rcs_dbsm": 900}), ValueError,
        ("scene.targets.0.rcs_dbsm", "900", "[-250, 100] dBsm")),
    Bad("scenario-noise-figure-negative", lambda _: _with(**{"radar.noise_figure_db": -3}),
        ValueError, ("radar.noise_figure_db", "-3", "[0, 50] dB")),
    Bad("scenario-imu-below-motion-nyquist", lambda _: _with(**{"imu.rate_hz": 30.0}),
        ValueError, ("imu.rate_hz", "30 Hz", "pitch sinusoid", "20 Hz", ">= 40 Hz")),
    Bad("scenario-imu-below-rotor-band",
        lambda _: _with(**{"motion.hover_jitter": {"seed": 1}, "imu.rate_hz": 200.0}),
        ValueError, ("imu.rate_hz", "200 Hz", "rotor vibration", "160 Hz", ">= 320 Hz")),
    Bad("scenario-set-under-a-value", lambda _: _with(**{"radar.num_chirps.x": 1}), ValueError,
        ("radar.num_chirps.x", "radar.num_chirps is a value", "256")),
    Bad("scenario-unknown-key-suggests", lambda _: validate(scenario_data(num_chrips=64)),
        ValueError, ("radar.num_chrips", "did you mean 'num_chirps'")),
    Bad("scenario-unknown-case-suggests",
        lambda _: __import__("raysim.scenario", fromlist=["x"]).scenario_from_case("rotaton_y"),
        ValueError, ("'rotaton_y'", "did you mean 'rotation_y'")),
    Bad("scenario-imu-preset-suggests", lambda _: _with(**{"imu.preset": "tactcal"}), ValueError,
        ("imu.preset", "tactcal", "did you mean 'tactical'")),
    # ---------------------------------------------------------------------- CLI
    Bad("cli-stability-unknown-map",
        lambda t: cli(["stability", "--out", t / "o", "--maps", "wind"]), CliError,
        ("exit 2", "--maps", "'wind'")),
    Bad("cli-stability-missing-out", lambda _: cli(["stability"]), CliError,
        ("exit 2", "--out")),
    Bad("cli-stability-bad-executor",
        lambda t: cli(["stability", "--out", t / "o", "--executor", "mpi"]), CliError,
        ("exit 2", "'mpi'")),
    Bad("cli-unknown-subcommand", lambda _: cli(["levitate"]), CliError,
        ("exit 2", "'levitate'")),
    Bad("cli-simulate-unknown-case", lambda _: cli(["simulate", "--case", "roll_x"]), CliError,
        ("exit 2", "'roll_x'", "rotation_y")),
    Bad("cli-simulate-unknown-imu",
        lambda _: cli(["simulate", "--case", "rotation_y", "--imu", "navigation_grade"]),
        CliError, ("exit 2", "navigation_grade", "consumer_mems")),
    Bad("cli-simulate-bad-motion",
        lambda _: cli(["simulate", "--case", "rotation_y", "--motion", "pitch:abc:20"]),
        CliError, ("exit 2", "--motion", "pitch:abc:20")),
    Bad("cli-render-missing-scenario",
        lambda t: cli(["render", t / "none.toml", "--out", t / "x.zarr"]), CliError,
        ("exit 2", "none.toml")),
    Bad("cli-compensate-missing-cube",
        lambda t: cli(["compensate", t / "none.npz", t / "none.csv", "--out", t / "o.npz"]),
        CliError, ("exit 2", "none.npz", "does not exist")),
    Bad("cli-scenes-unknown-scene", lambda _: cli(["scenes", "describe", "moon"]), CliError,
        ("exit 2", "'moon'", "flat_reflectors")),
    # ---------------------------------------------------- output paths, checked first
    Bad("cli-render-out-under-file",
        lambda t: cli(["render", CASE_TOML, "--out", _file(t) / "x.zarr"]), CliError,
        ("exit 2", "--out", "afile", "is a file, not a folder")),
    Bad("cli-render-out-is-file", lambda t: cli(["render", CASE_TOML, "--out", _file(t)]),
        CliError, ("exit 2", "--out", "afile", "existing file")),
    Bad("cli-render-out-unwritable", lambda _: cli(["render", CASE_TOML, "--out", UNWRITABLE]),
        CliError, ("exit 2", "--out", UNWRITABLE, "not writable")),
    Bad("cli-render-netcdf-is-dir",
        lambda t: cli(["render", CASE_TOML, "--out", t / "s.zarr", "--netcdf", t]), CliError,
        ("exit 2", "--netcdf", "existing directory")),
    Bad("cli-report-out-is-dir", lambda t: cli(["report", "--case", "rotation_y", "--out", t]),
        CliError, ("exit 2", "--out", "existing directory")),
    Bad("cli-report-out-under-file",
        lambda t: cli(["report", "--case", "rotation_y", "--out", _file(t) / "r.html"]),
        CliError, ("exit 2", "--out", "afile", "is a file, not a folder")),
    Bad("cli-reproduce-out-is-file", lambda t: cli(["reproduce", "--out", _file(t)]), CliError,
        ("exit 2", "--out", "afile", "existing file")),
    Bad("cli-stability-out-unwritable", lambda _: cli(["stability", "--out", UNWRITABLE]),
        CliError, ("exit 2", "--out", "not writable")),
    Bad("cli-scene-report-out-is-file",
        lambda t: cli(["scene-report", "--quick", "--out", _file(t)]), CliError,
        ("exit 2", "--out", "afile", "existing file")),
    Bad("cli-sweep-out-is-file",
        lambda t: cli(["sweep", "--case", "rotation_y", "--param", "radar.num_chirps=64",
                       "--out", _file(t)]), CliError, ("exit 2", "--out", "existing file")),
    Bad("cli-bench-out-is-dir", lambda t: cli(["bench", "--quick", "--out", t]), CliError,
        ("exit 2", "--out", "existing directory")),
    Bad("cli-bench-chart-under-file",
        lambda t: cli(["bench", "--chart-only", "--chart", _file(t) / "c.png"]), CliError,
        ("exit 2", "--chart", "afile")),
    Bad("cli-compensate-out-is-dir",
        lambda t: cli(["compensate", t / "none.npz", "--out", t]), CliError,
        ("exit 2", "--out", "existing directory")),
    # ------------------------------------------------------- values and names
    Bad("cli-set-under-a-value",
        lambda _: cli(["simulate", "--case", "rotation_y", "--set", "radar.num_chirps.x=1"]),
        CliError, ("exit 2", "radar.num_chirps.x", "not a table")),
    Bad("cli-set-unknown-key-suggests",
        lambda _: cli(["simulate", "--case", "rotation_y", "--set", "radar.numchirps=3"]),
        CliError, ("exit 2", "radar.numchirps", "did you mean 'num_chirps'")),
    Bad("cli-tx-power-overflow",
        lambda _: cli(["simulate", "--case", "rotation_y", "--set", "radar.tx_power_dbm=1e6"]),
        CliError, ("exit 2", "radar.tx_power_dbm", "physical range")),
    Bad("cli-target-rcs-900", lambda _: cli(["simulate", "--target", "15,20,0,900"]), CliError,
        ("exit 2", "rcs_dbsm", "900", "physical range")),
    Bad("cli-imu-rate-below-nyquist",
        lambda _: cli(["simulate", "--case", "rotation_y", "--set", "imu.rate_hz=25"]), CliError,
        ("exit 2", "imu.rate_hz", "20 Hz")),
    Bad("cli-case-suggests", lambda _: cli(["simulate", "--case", "rotaton_y"]), CliError,
        ("exit 2", "did you mean 'rotation_y'")),
    Bad("cli-imu-preset-suggests",
        lambda _: cli(["simulate", "--case", "rotation_y", "--imu", "consumer_mem"]), CliError,
        ("exit 2", "did you mean 'consumer_mems'")),
    Bad("cli-chain-suggests",
        lambda _: cli(["simulate", "--case", "rotation_y", "--chains", "none,exat"]), CliError,
        ("exit 2", "--chains", "'exat'", "did you mean 'exact'")),
    Bad("cli-map-suggests", lambda t: cli(["stability", "--out", t / "o", "--maps", "clok"]),
        CliError, ("exit 2", "--maps", "did you mean 'clock'")),
    Bad("cli-scene-suggests", lambda _: cli(["scenes", "describe", "parkinglot"]), CliError,
        ("exit 2", "did you mean 'parking_lot'")),
    Bad("cli-scene-report-scene-suggests",
        lambda t: cli(["scene-report", "--scenes", "flat_reflector", "--out", t]), CliError,
        ("exit 2", "--scenes", "did you mean 'flat_reflectors'")),
    Bad("cli-reproduce-imu-suggests",
        lambda t: cli(["reproduce", "--imu", "tactcal", "--out", t / "r"]), CliError,
        ("exit 2", "--imu", "did you mean 'tactical'")),
    Bad("cli-reproduce-case-suggests",
        lambda t: cli(["reproduce", "--cases", "yaw,rotation", "--out", t / "r"]), CliError,
        ("exit 2", "--cases", "'rotation'", "rotation_y")),
    Bad("cli-compensate-chain-suggests",
        lambda t: cli(["compensate", t / "c.npz", "--chain", "exakt", "--out", t / "o.npz"]),
        CliError, ("exit 2", "--chain", "did you mean 'exact'")),
    # ------------------------------------------ every job sized before allocating
    Bad("size-compensate-beams",
        lambda t: cli(["compensate", _cube(t), "--chain", "none", "--range-m", "0:100",
                       "--az-deg", "-90:90:0.002", "--el-deg", "-60:60:0.002",
                       "--out", t / "b.zarr"]),
        CliError, ("exit 2", "compensate beams", "of memory", "--range-m", "--az-deg")),
    Bad("size-rcs-directions",
        lambda _: cli(["rcs", "plate:0.1", "--az-deg", "0:360:0.01", "--el-deg", "-90:90:0.01"]),
        CliError, ("exit 2", "648054001 directions", "evaluations", "--az-deg / --el-deg")),
    Bad("size-rcs-directions-single-bounce",      # few facets: each direction's own cost
        lambda _: cli(["rcs", "plate:0.1", "--az-deg", "0:360:0.01", "--el-deg", "0:90:0.01",
                       "--max-bounces", "1"]),
        CliError, ("exit 2", "324045001 directions", "for the direction itself")),
    Bad("size-compensate-infinite-angles",
        lambda t: cli(["compensate", _cube(t), "--az-deg=-inf:inf:1", "--out", t / "b.zarr"]),
        CliError, ("exit 2", "--az-deg", "finite")),
    Bad("compensate-angles-beyond-90-deg",
        lambda t: cli(["compensate", _cube(t), "--az-deg", "-200:200:1", "--out",
                       t / "b.zarr"]), CliError, ("exit 2", "--az-deg", "degrees within +-90")),
    Bad("size-rcs-facets",
        lambda _: __import__("raysim.echoes.po.rcs", fromlist=["x"]).rcs_job_size(
            __import__("types").SimpleNamespace(faces=range(10_000_000), radius=1.0), 1,
            3.9e-4, 1), ValueError, ("10000000 facets", "at most 2000000", "decimate")),
    Bad("size-rcs-millimetres",
        lambda t: cli(["rcs", _plate_mm(t, 1000.0), "--az-deg", "0", "--el-deg", "0"]),
        CliError, ("exit 2", "plate.stl", "looks like millimetres", "--scale 0.001")),
    Bad("size-rcs-scale-on-canonical",
        lambda _: cli(["rcs", "plate:0.1", "--scale", "0.001", "--az-deg", "0", "--el-deg",
                       "0"]), CliError, ("exit 2", "--scale", "plate:0.1")),
    Bad("size-rcs-scale-negative",
        lambda t: cli(["rcs", _plate_mm(t, 100.0), "--scale", "-1", "--az-deg", "0",
                       "--el-deg", "0"]), CliError, ("exit 2", "--scale", "-1.0")),
    Bad("size-flight-frames",
        lambda t: cli(["flight", t / "f", "--frames", "1000000000"]), CliError,
        ("exit 2", "1000000000 frame(s)", "--frames")),
    Bad("flight-seed-named-as-typed",
        lambda t: cli(["flight", t / "f", "--seed", "-1"]), CliError,
        ("exit 2", "--seed", "non-negative integer")),
    Bad("flight-time-offset-named-as-typed",
        lambda t: cli(["flight", t / "f", "--time-offset", "nan"]), CliError,
        ("exit 2", "--time-offset", "finite number")),
    Bad("flight-decimate-tolerance-named-as-typed",
        lambda t: cli(["flight", t / "f", "--decimate-tolerance", "5"]), CliError,
        ("exit 2", "--decimate-tolerance", "(0, 0.1]")),
    Bad("flight-imu-fast-rate-named-as-typed",
        lambda t: cli(["flight", t / "f", "--imu-boxcar", "--imu-fast-rate", "2500"]),
        CliError, ("exit 2", "--imu-fast-rate", "whole multiple of --imu-rate")),
    Bad("compensate-frame-of-a-one-frame-cube",
        lambda t: cli(["compensate", _cube(t), "--frame", "2", "--out", t / "b.zarr"]),
        CliError, ("exit 2", "--frame 2", "holds one frame")),
    Bad("compensate-frame-and-frames",
        lambda t: cli(["compensate", _cube(t), "--frame", "0", "--frames", "1:2", "--out",
                       t / "b.zarr"]), CliError, ("exit 2", "--frame 0 and --frames", "one")),
    Bad("compensate-out-names-another-format",
        lambda t: cli(["compensate", _cube(t), "--out", t / "beams.nc"]), CliError,
        ("exit 2", "--out", "'.nc'", "Zarr store (.zarr")),
    Bad("compensate-capture-is-a-folder",
        lambda t: cli(["compensate", _folder(t / "capture"), "--radar-config", t / "r.cfg",
                       "--imu", t / "f.ulg", "--out", t / "b.zarr"]), CliError,
        ("exit 2", "capture", "is a folder")),
    Bad("compensate-binary-log-named-csv",
        lambda t: cli(["compensate", _cube(t), "--imu", _binary(t, "log.csv"), "--out",
                       t / "b.zarr"]), CliError,
        ("exit 2", "log.csv", "not a text CSV", ".ulg")),
    Bad("size-flight-target-behind",
        lambda t: cli(["flight", t / "f", "--target", "15,100,0"]), CliError,
        ("exit 2", "--target", "azimuth 100", "[-90, 90] deg")),
    Bad("size-flight-target-beyond-range",
        lambda t: cli(["flight", t / "f", "--target", "500,0,0"]), CliError,
        ("exit 2", "--target", "range 500 m", "maximum range")),
    Bad("size-intra-chirp-paper-case",
        lambda t: _with_memory(2 << 30, lambda: cli(
            ["render", CASE_TOML, "--set", "intra_chirp=true", "--out", t / "s.zarr"])),
        CliError, ("exit 2", "[256, 400, 600] with intra-chirp motion", "GiB",
                   "radar.num_chirps")),
    Bad("cli-render-scenario-not-utf8",
        lambda t: (t / "l.toml").write_bytes(b'name = "\xe9t\xe9"\n')
        and cli(["render", t / "l.toml", "--out", t / "x.zarr"]), CliError,
        ("exit 2", "l.toml", "not UTF-8")),
]


@pytest.mark.parametrize("case", CLI_CASES, ids=[c.id for c in CLI_CASES])
def test_bad_cli_input(case: Bad, tmp_path, capsys):
    """Each bad input gives the documented error naming the offending option, key or file."""
    with pytest.raises(case.exc) as info:
        case.call(tmp_path)
    msg = str(info.value)
    for needle in case.needles:
        assert needle in msg, f"message {msg!r} does not name {needle!r}"
    if case.exc is CliError:
        assert "Traceback" not in msg
        assert capsys.readouterr().out == ""                   # nothing computed, nothing shown


def test_catalogue_holds_at_least_100_cases():
    """tests/test_bad_input*.py together list at least 100 ``Bad(`` cases, all ids unique."""
    from test_bad_input import CASES
    from test_bad_input_writes import GUARD_CASES

    files = sorted(Path(__file__).parent.glob("test_bad_input*.py"))
    written = sum(len(re.findall(r"^\s*Bad\(", p.read_text(), re.M)) for p in files)
    ids = [c.id for c in CASES + CLI_CASES + GUARD_CASES]
    assert len(ids) == len(set(ids))
    assert written == len(ids)
    assert written >= 100, f"only {written} bad-input cases"


def test_cli_errors_name_the_value(tmp_path, capsys):
    """The CLI turns ValueError into exit code 2 and prints the offending value on stderr."""
    from raysim.cli import main

    assert main(["stability", "--out", str(tmp_path / "o"), "--maps", "wind"]) == 2
    err = capsys.readouterr().err
    assert "'wind'" in err and "--maps" in err


def test_sweep_out_file_is_not_a_scheduler_problem(tmp_path, capsys):
    from raysim.cli import main

    out = _file(tmp_path)
    assert main(["sweep", "--case", "rotation_y", "--param", "radar.num_chirps=64",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "scheduler" not in err and "--out" in err and str(out) in err
    assert out.read_text() == "not a folder\n"


def test_scenario_with_byte_order_mark_is_read(tmp_path):
    """A scenario saved with a UTF-8 BOM (Windows editors) reads like one without."""
    text = CASE_TOML.read_text(encoding="utf-8")
    plain = _scenario_bytes(tmp_path, text.encode("utf-8"), "plain.toml")
    bom = _scenario_bytes(tmp_path, text.encode("utf-8-sig"), "bom.toml")
    assert bom == plain


def test_imu_rate_at_nyquist_is_accepted():
    s = _with(**{"imu.rate_hz": 40.0})                        # pitch 20 Hz: 2 x 20 Hz is enough
    assert s.fastest_motion() == (20.0, "the pitch sinusoid")


# ------------------------------------------------------- negative option values
NEGATIVE_VALUES = ["-30:30:1", "-30,0,30", "-1e-3", "-.5", "-0.1,0,0.2", "-10:10:0.5"]


@pytest.mark.parametrize("value", NEGATIVE_VALUES)
def test_negative_values_are_values(value):
    """Every raysim parser reads ``-30:30:1``-like values as values, not as options."""
    from raysim.cli import build_parser

    for _, parser in _parsers(build_parser(), "raysim"):
        assert parser._negative_number_matcher.match(value), parser.prog
    args = build_parser().parse_args(["compensate", "c.npz", "--az-deg", value, "--el-deg",
                                      value, "--out", "o.npz"])
    assert args.az_deg == value and args.el_deg == value


def test_options_are_still_options():
    from raysim.cli import build_parser

    with pytest.raises(SystemExit):                            # "--out" is not a value
        build_parser().parse_args(["compensate", "c.npz", "--az-deg", "--out", "o.npz"])


def test_compensate_with_negative_ranges(tmp_path, capsys):
    """The documented ``--az-deg -30:30:1`` form runs end to end (chain none, .npz cube)."""
    from raysim.cli import main

    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, -0.2, -0.1)])
    cube = tmp_path / "c.npz"
    np.savez(cube, data=fr.data, chirp_times=fr.chirp_times,
             element_positions=ARR.virtual_positions, carrier_frequency=SMALL.carrier_frequency,
             bandwidth=SMALL.bandwidth, chirp_duration=SMALL.chirp_duration,
             sample_rate=SMALL.sample_rate)
    out = tmp_path / "b.npz"
    assert main(["compensate", str(cube), "--chain", "none", "--range-m", "5:15",
                 "--az-deg", "-30:30:1", "--el-deg", "-10:10:0.5", "--out", str(out)]) == 0
    with np.load(out) as z:
        az, el = z["azimuth_deg"], z["elevation_deg"]
        assert az.size == 61 and el.size == 41
        assert (az[0], az[-1], el[0]) == pytest.approx((-30.0, 30.0, -10.0), abs=1e-9)
    assert "wrote" in capsys.readouterr().out


# ------------------------------------------------------------ help and examples
def _parsers(parser, name):
    yield name, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub, p in action.choices.items():
                yield from _parsers(p, f"{name} {sub}")


def test_every_command_help_has_examples(capsys):
    """Each command's ``--help`` ends with an examples section whose lines run raysim."""
    from raysim.cli import build_parser, main

    names = [n for n, _ in _parsers(build_parser(), "raysim")]
    for cmd in ("render", "report", "simulate", "sweep", "bench", "scenes", "compensate",
                "stability", "reproduce", "scene-report", "scenes list", "scenes describe"):
        assert f"raysim {cmd}" in names
    for name in names:
        with pytest.raises(SystemExit) as info:
            main(name.split()[1:] + ["--help"])
        assert info.value.code == 0
        text = capsys.readouterr().out
        assert "examples:" in text, f"`{name} --help` has no examples"
        examples = text.split("examples:", 1)[1].strip().splitlines()
        assert examples[0].strip().startswith("raysim"), name


# ----------------------------------------------------------------- bench output
def test_bench_prints_a_table_with_out(tmp_path, capsys, monkeypatch):
    """``raysim bench --out`` writes the JSON and still shows the results on stdout."""
    from raysim.bench import suite as bench
    from raysim.cli import main

    fake = {"schema": bench.SCHEMA, "quick": True, "machine": {"cpus": 2},
            "memory": {"peak_rss_gb": 1.25}, "oracle": {"oracle_s": 0.5, "floor_s": 0.1},
            "seconds": 3.0}
    monkeypatch.setattr(bench, "run", lambda **_: dict(fake))
    out = tmp_path / "b.json"
    assert main(["bench", "--quick", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert json.loads(out.read_text())["oracle"] == fake["oracle"]
    assert "peak_rss_gb" in captured.out and "oracle_s" in captured.out
    assert "1.25" in captured.out and "results written" in captured.err


@pytest.mark.skipif(not hasattr(__import__("os"), "geteuid") or __import__("os").geteuid() == 0,
                    reason="root writes into read-only folders; /proc covers it in the catalogue")
def test_read_only_folder_is_refused_before_computing(tmp_path, capsys):
    from raysim.cli import main

    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        assert main(["report", "--case", "rotation_y", "--out", str(ro / "r.html")]) == 2
    finally:
        ro.chmod(0o755)
    err = capsys.readouterr().err
    assert "--out" in err and "not writable" in err and str(ro) in err


def test_millimetre_plate_is_reported_and_scaled(tmp_path, capsys):
    """A 100 mm plate written in millimetres: a note without --scale, its true RCS with it."""
    from raysim.cli import main

    path = _plate_mm(tmp_path, 100.0)
    assert main(["rcs", str(path), "--az-deg", "0", "--el-deg", "0", "--max-bounces", "1",
                 "--json"]) == 0
    out = capsys.readouterr()
    assert "100 m across" in out.err and "--scale 0.001" in out.err
    assert main(["rcs", str(path), "--scale", "0.001", "--az-deg", "0", "--el-deg", "0",
                 "--json"]) == 0
    scaled = json.loads(capsys.readouterr().out)["rcs_dbsm"][0][0]
    assert main(["rcs", "plate:0.1", "--az-deg", "0", "--el-deg", "0", "--json"]) == 0
    assert scaled == pytest.approx(json.loads(capsys.readouterr().out)["rcs_dbsm"][0][0],
                                   abs=0.05)


def test_compensate_default_window_is_sized(tmp_path, capsys):
    """Without --range-m: every cell when the job fits, else the cells around the strongest
    return that fit the budget, with a note saying which."""
    from raysim.cli import main
    from raysim.pipeline import compensate_size

    cube = _cube(tmp_path)
    assert main(["compensate", str(cube), "--chain", "none", "--out",
                 str(tmp_path / "all.npz")]) == 0
    with np.load(tmp_path / "all.npz") as z:
        assert z["range_m"].size == SMALL.num_samples            # all cells fit
    assert "note" not in capsys.readouterr().err
    budget = compensate_size.job_bytes(1, 8, 4, SMALL.num_samples, 5, 121 * 121)
    real = compensate_size.AUTO_BUDGET_BYTES
    compensate_size.AUTO_BUDGET_BYTES = budget
    try:
        from raysim.pipeline.compensate import compensate

        res = compensate(cube, chain="none", out=tmp_path / "win.npz")
    finally:
        compensate_size.AUTO_BUDGET_BYTES = real
    cells = res.beams[0].range
    assert cells.size == 5 and cells[0] < 10.0 < cells[-1]       # around the 10 m target
    assert "strongest return" in res.notes[0] and "--range-m" in res.notes[0]


def test_user_guide_compensate_example_runs_within_2_gb(tmp_path):
    """``raysim compensate rotation_y.zarr --out beams.npz`` (docs/user_guide.md) on the
    paper case: the default window keeps the process under 2 GB of memory (peak RSS)."""
    import os
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(root)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    # The child's own high-water mark (VmHWM): ru_maxrss would also hold the RSS of the
    # pytest process it was forked from, which Linux carries across exec.
    run = ("import sys\nfrom raysim.bench.suite import peak_rss\nfrom raysim.cli import main\n"
           "code = main(sys.argv[1:])\n"
           "print('peak_bytes', peak_rss()[1], file=sys.stderr)\nsys.exit(code)\n")

    def raysim(*argv):
        return subprocess.run([sys.executable, "-c", run, *map(str, argv)], cwd=tmp_path,
                              env=env, capture_output=True, text=True, timeout=600)

    r = raysim("render", CASE_TOML, "--out", "rotation_y.zarr", "--no-progress")
    assert r.returncode == 0, r.stderr
    c = raysim("compensate", "rotation_y.zarr", "--out", "beams.npz", "--no-progress")
    assert c.returncode == 0, c.stderr
    peak = int(c.stderr.split("peak_bytes")[1].split()[0])
    assert peak < 2e9, f"compensate peaked at {peak / 1e9:.2f} GB"
    assert "strongest return" in c.stderr
    with np.load(tmp_path / "beams.npz") as z:
        assert z["beams"].shape[1] >= 3 and 14.0 < float(np.mean(z["range_m"])) < 16.0


class _ClosedPipe(io.StringIO):
    """A standard output whose reader has gone (``raysim ... | head -1``)."""

    def write(self, text):
        raise BrokenPipeError(32, "Broken pipe")


def test_a_reader_that_left_ends_the_command_quietly(monkeypatch, capsys):
    from raysim.cli import PIPE_CLOSED, main

    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    assert main(["scenes", "list"]) == PIPE_CLOSED
    assert "error" not in capsys.readouterr().err
