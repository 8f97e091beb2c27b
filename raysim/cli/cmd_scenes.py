"""``raysim scenes``: list and describe the bundled ray-tracing scenes."""

from __future__ import annotations

import argparse
import json
import sys


def register(subparsers) -> None:
    """Add the ``scenes`` subcommand with ``list`` and ``describe``."""
    p = subparsers.add_parser(
        "scenes", help="list or describe the bundled ray-tracing scenes",
        description="Bundled Sionna RT scenes usable as scene.name in scenario files.",
        epilog="examples:\n  raysim scenes list\n  raysim scenes describe parking_lot\n"
        "  raysim scenes describe parking_lot --json\n\nexit status: 0 ok, 1 the scene "
        "registry is unavailable, 2 unknown scene name.",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    raw = argparse.RawDescriptionHelpFormatter
    ls = sub.add_parser("list", help="names and one-line descriptions",
                        epilog="examples:\n  raysim scenes list\n  raysim scenes list --json",
                        formatter_class=raw)
    ls.add_argument("--json", action="store_true", help="print JSON")
    ls.set_defaults(func=run_list)
    de = sub.add_parser("describe", help="details of one scene (targets, altitude, materials)",
                        epilog="examples:\n  raysim scenes describe parking_lot\n"
                        "  raysim scenes describe flat_reflectors --json", formatter_class=raw)
    de.add_argument("name", help="scene name (see `raysim scenes list`)")
    de.add_argument("--json", action="store_true", help="print JSON")
    de.set_defaults(func=run_describe)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])


#: The one frame ``scenes describe`` gives positions in: the one ``[[scene.meshes]]`` uses.
FRAME = ("world frame W, NED: north, east, down [m] from the hover point (the frame of "
         "[[scene.meshes]] position_m; docs/conventions.md)")


def _in_world(target: dict, hover_altitude) -> dict:
    """A sidecar target with its scene-frame (ENU, ground at z = 0) ``position`` as
    ``position_m`` in W (NED from the hover point) [m], ``[3]``."""
    import numpy as np

    from raysim.echoes.rt.scenes import ENU_FROM_NED

    out = {k: v for k, v in target.items() if k != "position"}
    pos = target.get("position")
    if pos is None or hover_altitude is None:
        out["position_m"] = None
        return out
    p = np.asarray(pos, dtype=float) - np.array([0.0, 0.0, float(hover_altitude)])
    out["position_m"] = (p @ ENU_FROM_NED.T).tolist()
    return out


def _registry():
    try:
        from raysim.echoes.rt.scenes import SCENES
    except ImportError as exc:
        print(f"raysim scenes: the scene registry (raysim.echoes.rt.scenes) is not "
              f"available: {exc}",
              file=sys.stderr)
        return None
    return SCENES


def run_list(args) -> int:
    """Print the registered scenes."""
    scenes = _registry()
    if scenes is None:
        return 1
    rows = [{"name": n, "description": d.description, "path": str(d.path),
             "present": d.path.exists()} for n, d in sorted(scenes.items())]
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    for r in rows:
        flag = "" if r["present"] else "  (files missing: run python scenes/generate.py)"
        print(f"{r['name']:<18} {r['description']}{flag}")
    return 0


def run_describe(args) -> int:
    """Print one scene's sidecar information."""
    scenes = _registry()
    if scenes is None:
        return 1
    if args.name not in scenes:
        from raysim.cli.options import did_you_mean

        raise ValueError(f"scene name: got {args.name!r}, expected one of {sorted(scenes)}"
                         f"{did_you_mean(args.name, scenes)}")
    d = scenes[args.name]
    meta = d.metadata()
    info = {"name": d.name, "description": d.description, "path": str(d.path),
            "present": d.path.exists(), "hover_altitude_m": meta.get("hover_altitude"),
            "frame": FRAME,
            "targets": [_in_world(t, meta.get("hover_altitude")) for t in
                        meta.get("targets", [])],
            "materials": meta.get("materials", {})}
    if args.json:
        print(json.dumps(info, indent=2, default=str))
        return 0
    print(f"{d.name}: {d.description}")
    print(f"file: {d.path}{'' if d.path.exists() else ' (missing: run python scenes/generate.py)'}")
    if info["hover_altitude_m"] is not None:
        print(f"hover altitude: {info['hover_altitude_m']} m")
    if info["targets"]:
        print(f"positions: {FRAME}")
    for t in info["targets"]:
        pos = t.get("position_m")
        where = ("?" if pos is None else
                 "(" + ", ".join(f"{v:.2f}" for v in pos) + ")")
        print(f"target {t.get('name')}: position (north, east, down) {where} m, "
              f"{t.get('rcs_dbsm', float('nan')):.1f} dBsm")
    mats = info["materials"]
    if mats:
        names = mats if isinstance(mats, list) else list(mats)
        labels = [str(m if isinstance(m, str) else m.get("id", m)) for m in names]
        print(f"materials: {', '.join(labels)}")
    print(f"use in a scenario file:  [scene]\\n  name = \"{d.name}\"".replace("\\n", "\n"))
    return 0
