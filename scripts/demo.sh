#!/usr/bin/env bash
# The main job on the built-in default: a simulated sequence, no download.
# Usage: scripts/demo.sh [BUILD_DIR]   (output in $VIOSFM_DEMO_OUT, default out/demo)
#
# Runs every stage that exists so far: simulate a 20 s handheld walk in a
# textured room (images at 10 Hz, IMU at 200 Hz, ground truth, an emulated
# drifting VIO), extract features into a COLMAP database, verify candidate
# pairs with the VIO-aided two-step check, and evaluate the VIO trajectory.
set -euo pipefail
build_dir=${1:-build}
out=${VIOSFM_DEMO_OUT:-out/demo}
viosfm="$build_dir/src/viosfm/cli/viosfm"
rm -rf "$out/database.db" "$out/database.db-wal" "$out/database.db-shm" "$out/verification"
mkdir -p "$out"

echo "== 1/4 simulate: 'room', 20 s, images at 10 Hz, IMU at 200 Hz -> $out/sequence"
"$viosfm" simulate --scenario room --duration 20 --rate 10 --seed 0 --out "$out/sequence"

echo "== 2/4 features: SIFT (at most 1500 a frame) -> $out/database.db (COLMAP format)"
"$viosfm" features "$out/sequence" --database "$out/database.db" --max-features 1500

echo "== 3/4 match: N1=6 temporal + N2=4 retrieval neighbours, VIO-aided verification, RANSAC"
"$viosfm" match "$out/sequence" --database "$out/database.db" \
  --vio-trajectory "$out/sequence/vio_emulated.tum" --n1 6 --n2 4 --report "$out/verification"

echo "== 4/4 eval: emulated VIO against ground truth (Sim(3)-aligned ATE, RPE over 1 m)"
"$viosfm" eval --est "$out/sequence/vio_emulated.tum" \
  --ref "$out/sequence/mav0/state_groundtruth_estimate0/data.csv" \
  --align sim3 --rpe-delta-m 1.0 --json "$out/eval_vio.json"
echo "== Done: $out (sequence/, database.db: open with 'colmap gui', verification/pairs.csv, eval_vio.json)"
