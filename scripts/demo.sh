#!/usr/bin/env bash
# The main job on the built-in default: a simulated sequence, no download.
# Usage: scripts/demo.sh [BUILD_DIR]   (output in $VIOSFM_DEMO_OUT, default out/demo)
set -euo pipefail
build_dir=${1:-build}
out=${VIOSFM_DEMO_OUT:-out/demo}
viosfm="$build_dir/src/viosfm/cli/viosfm"

echo "== viosfm demo: simulated 'room' sequence, 60 s at 20 Hz with IMU, into $out"
"$viosfm" simulate --scenario room --duration 60 --seed 0 --out "$out/sequence"

echo "== Emulated VIO trajectory against ground truth (Sim(3)-aligned ATE, RPE over 1 m)"
"$viosfm" eval --est "$out/sequence/vio_emulated.tum" \
  --ref "$out/sequence/mav0/state_groundtruth_estimate0/data.csv" \
  --align sim3 --rpe-delta-m 1.0 --json "$out/eval_vio.json"
echo "== Done. Results: $out (eval_vio.json)"
