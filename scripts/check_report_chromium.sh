#!/usr/bin/env bash
# Check that a raysim HTML report renders in headless Chromium.
#
# 1. installs Chromium if it is missing (Debian package `chromium`, needs root
#    and network; skip with NO_INSTALL=1),
# 2. writes a small report (paper case rotation_y on a reduced radar),
# 3. takes a headless screenshot and checks that it is not blank,
# 4. runs the pytest check tests/test_report.py::test_report_renders_in_chromium.
#
# Usage: scripts/check_report_chromium.sh [OUTDIR]     (default: a temporary folder)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-$(mktemp -d)}"
mkdir -p "$OUT"

find_chromium() { command -v chromium || command -v chromium-browser || command -v google-chrome || true; }
CHROME="$(find_chromium)"
if [[ -z "$CHROME" && "${NO_INSTALL:-0}" != "1" ]]; then
    echo "installing chromium (apt-get)..."
    SUDO=""; [[ "$(id -u)" != "0" ]] && SUDO="sudo"
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq chromium
    CHROME="$(find_chromium)"
fi
if [[ -z "$CHROME" ]]; then
    echo "chromium not found and not installed (NO_INSTALL=1?)" >&2
    exit 1
fi
echo "chromium: $CHROME ($("$CHROME" --version 2>/dev/null || echo unknown version))"

python -m raysim report --case rotation_y --set radar.num_chirps=32 --set array.nx=4 \
    --set array.ny=4 --set radar.chirp_duration_s=12.8e-6 --out "$OUT/report.html"
"$CHROME" --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1280,2400 \
    --screenshot="$OUT/report.png" "file://$(realpath "$OUT/report.html")" >/dev/null 2>&1
python - "$OUT/report.png" <<'PY'
import sys
import matplotlib.image as mpimg
import numpy as np
img = mpimg.imread(sys.argv[1])[..., :3]
frac = float(np.mean(np.any(np.abs(img - img[0, 0]) > 0.05, axis=-1)))
print(f"screenshot {img.shape[1]}x{img.shape[0]}, {100 * frac:.1f} % non-background pixels")
if img.std() < 0.02 or frac < 0.05:
    sys.exit("screenshot looks blank")
PY
RAYSIM_CHROMIUM="$CHROME" python -m pytest -q tests/test_report.py -k chromium
echo "ok: report and screenshot in $OUT"
