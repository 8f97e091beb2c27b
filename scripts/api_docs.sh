#!/usr/bin/env bash
# Write the HTML API reference of raysim and compensation, generated from the docstrings by pdoc,
# into a folder (default out/api). Fails (exit status 1) on any warning pdoc or an import emits,
# so the reference is built without warnings or not at all.
#   bash scripts/api_docs.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/api}"
export DRJIT_CACHE_DIR="${DRJIT_CACHE_DIR:-$HOME/.cache/raysim-drjit}"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
exec python3 - "$out" <<'PY'
import pathlib
import sys
import warnings

import pdoc
import pdoc.extract
import pdoc.render

out = pathlib.Path(sys.argv[1])
# Every public module, found on disk (private "_x" modules and __main__ scripts left out).
modules = []
for package in ("raysim", "compensation"):
    for file in sorted(pathlib.Path(package).rglob("*.py")):
        parts = list(file.with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if not any(part.startswith("_") for part in parts):
            modules.append(".".join(parts))

with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    # A package's __all__ lists its entry points, not its submodules, so pdoc would stop there:
    # name each module that no earlier name already reaches (naming one twice makes pdoc warn).
    specs, reached = [], set()
    for module in modules:
        if module not in reached:
            reached.update(pdoc.extract.walk_specs([module]))
            specs.append(module)
    pdoc.render.configure(docformat="numpy")
    pdoc.pdoc(*specs, r"!.*\._", output_directory=out)

for warning in caught:
    print(f"api_docs: {warning.category.__name__}: {warning.message} "
          f"({warning.filename}:{warning.lineno})", file=sys.stderr)
if caught:
    print(f"api_docs: {len(caught)} warning(s); the reference in {out} is incomplete",
          file=sys.stderr)
    sys.exit(1)
print(f"api_docs: {len(list(out.rglob('*.html')))} pages written to {out}/ "
      f"(open {out}/index.html)", file=sys.stderr)
PY
