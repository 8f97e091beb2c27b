"""Layout rules of docs/architecture.md: an import DAG, one definition per name, small modules."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("raysim", "compensation")
#: Largest module [lines] (docs/architecture.md: a module over this is two).
MAX_MODULE_LINES = 700


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _imports(path: Path, name: str, modules: dict, type_only: bool = True) -> set[str]:
    """Project modules imported anywhere in a module (functions too).

    Imports under ``if TYPE_CHECKING:`` are edges too (``type_only``): a cycle
    of annotations is still a cycle of the design.
    """
    tree = ast.parse(path.read_text(), str(path))
    is_pkg = path.name == "__init__.py"
    found: set[str] = set()

    def resolve(mod: str | None, level: int) -> str:
        if level == 0:
            return mod or ""
        base = name.split(".")
        base = base if is_pkg else base[:-1]
        base = base[: len(base) - (level - 1)]
        return ".".join(base + ([mod] if mod else []))

    def visit(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child) and not type_only:
                for sub in child.orelse:
                    visit(sub)
                continue
            if isinstance(child, ast.Import):
                for a in child.names:
                    found.add(a.name)
            elif isinstance(child, ast.ImportFrom):
                base = resolve(child.module, child.level)
                found.add(base)
                for a in child.names:
                    found.add(f"{base}.{a.name}")
            visit(child)

    visit(tree)
    # keep the deepest project module each import names (a.b.c -> a.b.c if a module, else a.b)
    out = set()
    for imp in found:
        while imp and imp not in modules:
            imp = imp.rpartition(".")[0]
        if imp and imp != name:
            out.add(imp)
    return out


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    graph = {name: _imports(path, name, modules) for name, path in modules.items()}
    # a package's __init__ is imported with any of its modules: it may re-export them,
    # so edges into a package are not edges out of its modules (no cycle through parents)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def strong(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return out


def test_reference_cycle_is_found():
    """The checker itself finds a two-module cycle and ignores a DAG."""
    assert _cycles({"a": {"b"}, "b": {"a"}, "c": {"a"}}) == [["a", "b"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_type_only_imports_are_edges(tmp_path):
    """An import under ``if TYPE_CHECKING:`` is an edge like any other."""
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    from b import X\n")
    b.write_text("import typing\n\nif typing.TYPE_CHECKING:\n    import a\nelse:\n    X = 1\n")
    modules = {"a": a, "b": b}
    graph = {n: _imports(p, n, modules) for n, p in modules.items()}
    assert graph == {"a": {"b"}, "b": {"a"}}
    assert _cycles(graph) == [["a", "b"]]
    assert _imports(a, "a", modules, type_only=False) == set()


def test_no_import_cycles():
    """Module imports (top level, inside functions and type-only) form a DAG."""
    graph = _graph()
    # package __init__ modules only re-export; drop edges from a package to its own modules
    for name in list(graph):
        graph[name] = {m for m in graph[name] if not m.startswith(name + ".")}
    assert _cycles(graph) == []


def test_compensation_never_imports_raysim():
    graph = _graph()
    bad = {m: sorted(i for i in imps if i.startswith("raysim"))
           for m, imps in graph.items() if m.startswith("compensation")}
    assert {m: i for m, i in bad.items() if i} == {}


#: What the scenario model may never reach: it describes a run, others build and run it.
SCENARIO_NEVER = ("raysim.studies", "raysim.echoes", "raysim.pipeline", "raysim.synthesis",
                  "raysim.processing", "raysim.cli")


def _reach(graph: dict[str, set[str]], start: list[str]) -> set[str]:
    """Modules reachable from ``start`` through imports (``start`` itself aside)."""
    seen: set[str] = set()
    todo = list(start)
    while todo:
        for nxt in graph.get(todo.pop(), ()):
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


def test_scenario_model_imports_no_study_and_no_echo_builder():
    """``raysim.scenario`` reaches radar, platform and io helpers, never studies, echoes or
    the pipeline (directly or through another module, type-only imports included)."""
    graph = _graph()
    scenario = [m for m in graph if m == "raysim.scenario" or m.startswith("raysim.scenario.")]
    assert "raysim.scenario.model" in scenario
    bad = sorted(m for m in _reach(graph, scenario)
                 if any(m == p or m.startswith(p + ".") for p in SCENARIO_NEVER))
    assert bad == []
    assert _reach({"a": {"b"}, "b": {"c"}}, ["a"]) == {"b", "c"}


def test_no_public_class_defined_twice():
    where = defaultdict(list)
    for name, path in _modules().items():
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                where[node.name].append(name)
    assert {k: v for k, v in where.items() if len(v) > 1} == {}


def test_modules_are_small():
    sizes = {name: len(path.read_text().splitlines()) for name, path in _modules().items()}
    assert {k: v for k, v in sizes.items() if v > MAX_MODULE_LINES} == {}


def test_stage_packages_exist():
    """The folders show the data flow (docs/architecture.md)."""
    for stage in ("radar", "platform", "echoes", "synthesis", "processing", "scenario", "io",
                  "pipeline", "studies", "cli"):
        assert (ROOT / "raysim" / stage / "__init__.py").is_file(), stage


#: Modules and names that integrate an IMU log or project beams: the CLI calls stages
#: (raysim.pipeline.compensate, run, ...) and never these (docs/architecture.md).
MOTION_AND_PROJECTION_MODULES = (
    "compensation.strapdown", "compensation.projection", "compensation.exact",
    "compensation.paper", "compensation.realtime", "compensation.multiframe",
    "compensation.calibration", "raysim.pipeline.estimate", "raysim.pipeline.chains",
    "raysim.pipeline.self_calibration")
MOTION_AND_PROJECTION_NAMES = (
    "integrate_imu", "integrate_record", "estimate_motion", "estimate_record",
    "scenario_motion", "rigid_body_projection", "beam_projection", "paper_chain",
    "project", "project_record", "RealtimeProjector", "self_calibrate",
    "calibrate_frames", "calibrate_record")


def _motion_or_projection_uses(tree: ast.AST) -> list[str]:
    """Imports of :data:`MOTION_AND_PROJECTION_MODULES` and imports, calls or attribute
    uses of :data:`MOTION_AND_PROJECTION_NAMES` in a module's AST."""
    mods, names = MOTION_AND_PROJECTION_MODULES, set(MOTION_AND_PROJECTION_NAMES)

    def banned_module(m: str) -> bool:
        return any(m == b or m.startswith(b + ".") for b in mods)

    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [f"import {a.name}" for a in node.names if banned_module(a.name)]
        elif isinstance(node, ast.ImportFrom) and node.module:
            if banned_module(node.module):
                found.append(f"from {node.module} import ...")
            found += [f"from {node.module} import {a.name}" for a in node.names
                      if a.name in names or banned_module(f"{node.module}.{a.name}")]
        elif isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(
                f, ast.Attribute) else None
            if name in names:
                found.append(f"call {name}(...) line {node.lineno}")
        elif isinstance(node, ast.Attribute) and node.attr in names:
            found.append(f"attribute .{node.attr} line {node.lineno}")
    return found


def test_checker_finds_motion_and_projection_uses():
    """The checker itself: imports, calls and module attributes are found."""
    src = ("from compensation import integrate_imu\nimport compensation.exact as ex\n"
           "from raysim.pipeline import chains\nchains.project(1)\n"
           "from raysim.pipeline.compensate import compensate\ncompensate(1)\n")
    found = _motion_or_projection_uses(ast.parse(src))
    assert "from compensation import integrate_imu" in found
    assert "import compensation.exact" in found
    assert "from raysim.pipeline import chains" in found
    assert any(f.startswith("call project(") for f in found)
    assert not any("compensate" in f for f in found)


def test_cli_holds_no_strapdown_or_projection():
    """Every module under raysim/cli/ parses, calls stages and prints: none imports or calls
    a strapdown, self-calibration or projection function (the stages do)."""
    bad = {}
    for path in sorted((ROOT / "raysim" / "cli").rglob("*.py")):
        found = _motion_or_projection_uses(ast.parse(path.read_text(), str(path)))
        if found:
            bad[str(path.relative_to(ROOT))] = found
    assert bad == {}


#: Packages below the echo models: they may not import ``raysim.echoes``.
BELOW_ECHOES = ("raysim.radar", "raysim.platform", "raysim.synthesis", "raysim.processing",
                "raysim.measure", "raysim.scenario")


def test_lower_stages_import_no_echo_model():
    """Timing, synthesis, processing and measurement never import an echo model."""
    graph = _graph()
    bad = {m: sorted(i for i in imps if i.startswith("raysim.echoes"))
           for m, imps in graph.items() if m.startswith(BELOW_ECHOES)}
    assert {m: i for m, i in bad.items() if i} == {}
