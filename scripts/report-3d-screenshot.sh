#!/usr/bin/env bash
# Draws the 3D view of a run's report in headless Chromium (WebGL on
# SwiftShader, no GPU) and saves the canvas as a PNG: the page hands the
# canvas back when opened as report.html#viewer-selftest.
#   scripts/report-3d-screenshot.sh RUN/report.html OUT.png
set -euo pipefail
html=$(realpath "$1")
out=$2
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
timeout 120 chromium --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader \
  --no-first-run --user-data-dir="$profile" --dump-dom "file://$html#viewer-selftest" \
  2>/dev/null | python3 -c '
import base64, re, sys
match = re.search(r"data:image/png;base64,([A-Za-z0-9+/=]+)", sys.stdin.read())
if not match:
    sys.exit("no canvas in the page (no 3D view, or no WebGL)")
open(sys.argv[1], "wb").write(base64.b64decode(match.group(1)))
' "$out"
echo "wrote $out"
