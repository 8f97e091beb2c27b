#!/usr/bin/env bash
# Set everything up, then run the whole test suite on the CPU.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export DRJIT_CACHE_DIR="${DRJIT_CACHE_DIR:-$HOME/.cache/raysim-drjit}"
exec python3 -m pytest -q "$@"
