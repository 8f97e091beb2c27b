"""``raysim simulate``: point targets under a platform motion, metrics on stdout.

The scenario comes from a paper case (``--case``), a scenario file
(``--scenario``) or flags (``--target``, ``--motion``, ``--jitter``); ``--set``
changes any scenario key. The frames are rendered in memory and processed
through the chains of :mod:`raysim.vocabulary` (``none``, ``paper``,
``paper:published``, ``exact``; the compensated ones when the
``compensation`` package provides them); the metrics of
:data:`raysim.vocabulary.METRICS` are printed as a table or, with ``--json``,
as one JSON object. A progress bar on stderr counts the frames rendered
(``--no-progress``: none). The compensation's guard warnings are printed on stderr
(``warning: <chain>: <text>``) and, with ``--json``, listed per chain under
``warnings``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from raysim.vocabulary import CHAINS

EPILOG = """\
examples:
  raysim simulate --case stationary
  raysim simulate --case rotation_y --json
  raysim simulate --case rotation_y --set radar.num_chirps=64 --set array.nx=8 --set array.ny=8
  raysim simulate --target 15,20,0 --motion pitch:10:20 --motion y:0.05:5
  raysim simulate --scenario examples/case_yaw.toml --chains none
  raysim simulate --case rotation_y --chains none,paper,paper:published,exact

chains: none (no compensation), paper (the published chain; paper:published
with the paper's rotation phase v_r(nT) nT), exact (rigid-body projection).
Guard warnings of a chain go to stderr as "warning: CHAIN: TEXT" (and into
the "warnings" object of --json).

motion flags: AXIS:AMPLITUDE:FREQ_HZ[:PHASE_DEG], amplitude in degrees for
roll/pitch/yaw and metres for x/y/z; several --motion flags add up.

exit status: 0 success, 1 the simulation could not run here (missing optional
component), 2 invalid input (the message names the offending key or flag).
"""


def register(subparsers) -> None:
    """Add the ``simulate`` subcommand."""
    from raysim.cli.options import chains_help

    p = subparsers.add_parser(
        "simulate", help="simulate point targets under a motion and print metrics",
        description="Simulate point targets seen from a moving drone and print range, "
        "azimuth/elevation, pseudo-velocity, Doppler mainlobe width and entropies through "
        "each chain (none, paper, exact).",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group()
    src.add_argument("--case", metavar="NAME",
                     help="paper case: stationary, rotation_y, yaw, translation_y, translation_z")
    src.add_argument("--scenario", metavar="FILE.toml", help="scenario file (see examples/)")
    p.add_argument("--target", action="append", default=[], metavar="R,AZ_DEG,EL_DEG[,RCS]",
                   help="point target: range [m], azimuth and elevation [deg], RCS [dBsm] "
                   "(repeatable; replaces the scenario's targets)")
    p.add_argument("--motion", action="append", default=[], metavar="AXIS:AMP:FREQ[:PHASE]",
                   help="add a sinusoid (repeatable)")
    p.add_argument("--jitter", type=int, metavar="SEED",
                   help="add seeded stochastic hover jitter")
    p.add_argument("--lever-arm", metavar="X,Y,Z", help="radar phase centre in body frame [m]")
    p.add_argument("--imu", metavar="PRESET", help="IMU preset: ideal, tactical, consumer_mems")
    p.add_argument("--frames", type=int, metavar="N", help="frames to render")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a scenario key, e.g. radar.num_chirps=64 (repeatable)")
    p.add_argument("--chains", default=",".join(CHAINS),
                   help=chains_help(",".join(CHAINS)))
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _floats(text: str, n: tuple[int, ...], flag: str) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) not in n or not all(math.isfinite(v) for v in vals):
        raise ValueError(f"{flag}: got {text!r}, expected {' or '.join(map(str, n))} "
                         f"comma-separated numbers")
    return vals


def _sinusoid(text: str) -> dict:
    from raysim.scenario import ANGLE_AXES, TRANSLATION_AXES

    parts = text.split(":")
    axis = parts[0]
    if axis not in ANGLE_AXES + TRANSLATION_AXES or len(parts) not in (3, 4):
        raise ValueError(f"--motion: got {text!r}, expected AXIS:AMPLITUDE:FREQ_HZ[:PHASE_DEG] "
                         f"with AXIS one of {list(TRANSLATION_AXES + ANGLE_AXES)}")
    try:
        nums = [float(v) for v in parts[1:]]
    except ValueError:
        raise ValueError(f"--motion: got {text!r}, expected numbers after the axis") from None
    unit = "amplitude_deg" if axis in ANGLE_AXES else "amplitude_m"
    out = {"axis": axis, unit: nums[0], "frequency_hz": nums[1]}
    if len(nums) == 3:
        out["phase_deg"] = nums[2]
    return out


def build_scenario(args):
    """The :class:`~raysim.scenario.Scenario` described by parsed arguments."""
    from raysim.scenario import (
        load_scenario,
        parse_assignment,
        scenario_from_case,
        validate_scenario,
    )

    if args.scenario:
        base = load_scenario(args.scenario)
    elif args.case:
        base = scenario_from_case(args.case)
    else:
        base = None
    data = base.model_dump(mode="json") if base is not None else {
        "name": "custom", "scene": {"kind": "points",
                                    "targets": [{"range_m": 15.0, "az_deg": 20.0}]}}
    if args.target:
        targets = []
        for t in args.target:
            v = _floats(t, (3, 4), "--target")
            d = {"range_m": v[0], "az_deg": v[1], "el_deg": v[2]}
            if len(v) == 4:
                d["rcs_dbsm"] = v[3]
            targets.append(d)
        data["scene"] = {"kind": "points", "targets": targets}
    motion = data.setdefault("motion", {})
    if args.motion:
        motion["sinusoids"] = list(motion.get("sinusoids") or []) + [
            _sinusoid(m) for m in args.motion]
    if args.jitter is not None:
        if args.jitter < 0:
            raise ValueError(f"--jitter: got {args.jitter}, expected a seed >= 0")
        motion["hover_jitter"] = {"seed": args.jitter}
    if args.lever_arm:
        data["lever_arm_m"] = _floats(args.lever_arm, (3,), "--lever-arm")
    if args.imu:
        data.setdefault("imu", {})["preset"] = args.imu
    if args.frames is not None:
        data["frames"] = args.frames
    from raysim.scenario import set_key

    for item in args.set:
        key, value = parse_assignment(item)
        set_key(data, key, value)
    return validate_scenario(data, source="simulate options")


def _clean(obj):
    if isinstance(obj, float):
        return None if not math.isfinite(obj) else obj
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    return obj


def print_warnings(warnings: dict, file=None) -> int:
    """Print ``warning: <chain>: <text>`` for every guard warning; returns their number.

    ``warnings`` maps a chain key to its warning strings (``evaluate``'s
    ``result["warnings"]``); lines go to ``file`` (default stderr).
    """
    file = sys.stderr if file is None else file
    n = 0
    for chain, texts in warnings.items():
        for text in texts:
            print(f"warning: {chain}: {text}", file=file)
            n += 1
    return n


def run(args) -> int:
    """Run ``raysim simulate``; returns the exit code."""
    from raysim.cli.options import chains_option
    from raysim.measure.point import POINT_METRICS
    from raysim.pipeline.run import evaluate
    from raysim.pipeline.sources import FeatureUnavailable
    from raysim.report.html import counted_frames, progress_bar
    from raysim.vocabulary import metric_unit

    chains = chains_option(args.chains)
    scenario = build_scenario(args)
    # the report's bar: one step per frame rendered, then the chains being measured
    bar = progress_bar(scenario.frames, "simulate", not args.no_progress)
    try:
        frames = counted_frames(scenario, scenario.trajectory(), bar,
                                lambda: f"measuring chains {', '.join(chains)}")
        result = evaluate(scenario, chains=chains, frames=frames, reference=frames.reference)
    except FeatureUnavailable as exc:
        print(f"raysim simulate: {exc}", file=sys.stderr)
        return 1
    finally:
        bar.close()
    ref = result["reference"]
    paper = {}
    if scenario.motion.case is not None:
        from raysim.scenario.paper_cases import get_case

        paper = get_case(scenario.motion.case)["paper"]
    out = {
        "scenario": scenario.name,
        "motion": scenario.trajectory().name,
        "reference": None if ref is None else {"range_m": ref.range_m, "az_deg": ref.az_deg,
                                               "el_deg": ref.el_deg},
        "radar": {"num_chirps": scenario.radar.num_chirps,
                  "num_samples": scenario.radar_config().num_samples,
                  "num_channels": scenario.virtual_array().num_channels,
                  "frames": scenario.frames},
        "units": {m: metric_unit(m) for m in POINT_METRICS},
        "chains": result["chains"],
        "warnings": result["warnings"],
        "paper": paper,
        "notes": result["notes"],
    }
    print_warnings(result["warnings"])
    if args.json:
        print(json.dumps(_clean(out), indent=2, sort_keys=False))
        return 0
    print(f"scenario: {scenario.name}   motion: {out['motion']}")
    r = out["radar"]
    print(f"radar: {r['num_chirps']} chirps x {r['num_channels']} channels x "
          f"{r['num_samples']} samples, {r['frames']} frame(s)")
    if ref is not None:
        print(f"target: range {ref.range_m:.3f} m, az {ref.az_deg:.2f} deg, "
              f"el {ref.el_deg:.2f} deg")
    names = list(result["chains"])
    print()
    print(f"{'metric':<24}" + "".join(f"{n:>16}" for n in names))
    for key, unit in ((m, metric_unit(m)) for m in POINT_METRICS):
        row = f"{key + ' [' + unit + ']':<24}"
        for n in names:
            v = result["chains"][n][key]
            row += f"{v:>16.4f}" if math.isfinite(v) else f"{'-':>16}"
        print(row)
    if paper:
        print("\npaper reports: " + "; ".join(
            f"{chain}: " + ", ".join(f"{k}={v}" for k, v in vals.items())
            for chain, vals in paper.items()))
    for note in result["notes"]:
        print(f"note: {note}")
    return 0
