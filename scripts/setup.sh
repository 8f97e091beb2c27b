#!/usr/bin/env bash
# Install what raysim needs on a fresh Debian/Ubuntu machine with Python >= 3.11:
# the system libLLVM that Dr.Jit's CPU backend needs (>= 16) and the package itself.
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1; then SUDO="sudo"; fi

have_llvm() {
  ldconfig -p 2>/dev/null | grep -Eq 'libLLVM(-|\.so\.)(1[6-9]|[2-9][0-9])' \
    || [ -n "${DRJIT_LIBLLVM_PATH:-}" ]
}
if ! have_llvm; then
  echo "setup: installing libllvm19 (Dr.Jit's LLVM backend needs libLLVM >= 16)" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libllvm19 >/dev/null
fi

echo "setup: installing raysim and its test dependencies" >&2
python3 -m pip install -q --disable-pip-version-check -e ".[test]"
