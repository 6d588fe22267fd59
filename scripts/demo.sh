#!/usr/bin/env bash
# The main job on the built-in default: a simulated sequence, no download.
# Usage: scripts/demo.sh [BUILD_DIR]   (output in $VIOSFM_DEMO_OUT, default out/demo)
#
# Simulates a 30 s handheld walk in a textured room (images at 10 Hz, IMU at
# 200 Hz, ground truth), reconstructs it with `viosfm run` from the images and
# the IMU alone (viosfm's own VIO, features, VIO-aided verification, batched
# mapping with relative-pose-constrained bundle adjustment, evaluation of the
# VIO and of the result against the ground truth), and writes the HTML report
# of the run.
set -euo pipefail
build_dir=${1:-build}
out=${VIOSFM_DEMO_OUT:-out/demo}
viosfm="$build_dir/src/viosfm/cli/viosfm"
mkdir -p "$out"

echo "== 1/3 simulate: 'room', 30 s, images at 10 Hz, IMU at 200 Hz -> $out/sequence"
"$viosfm" simulate --scenario room --duration 30 --rate 10 --seed 0 --out "$out/sequence"

echo "== 2/3 run: own VIO, features, N1=10 temporal + N2=5 retrieval pairs, VIO-aided"
echo "   verification, batches of 50 frames, BA with relative-pose constraints -> $out/run"
rm -rf "$out/run"
"$viosfm" run "$out/sequence" --out "$out/run" --n1 10 --n2 5 --max-features 1000 --batch-size 50

echo "== 3/3 report -> $out/run/report.html"
"$viosfm" report "$out/run"
echo "== Done: $out/run (model/ for COLMAP, points.ply, trajectory_*.tum, vio/, summary.json, report.html)"
