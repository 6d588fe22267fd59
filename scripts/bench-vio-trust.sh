#!/usr/bin/env bash
# How far viosfm trusts the VIO: the default run against its
# ablations on sequences with the realistic emulated VIO (drift in time,
# distance and rotation, a 2 % scale error, correlated noise).
#
# Usage: scripts/bench-vio-trust.sh OUT [CASE...]
#   CASE = NAME:SCENARIO:DURATION_S:MODE[:EXTRA_SIMULATE_FLAGS]
#   MODE = kf (keyframe-like frames, gaps 0.05-7 s, every keyframe used) or
#          a frame rate in Hz (every frame of the grid, used at that rate)
# Default cases: room, two_floors and corridor as keyframes over 144 s (as
# EuRoC V1_01's 100 keyframes in 144 s) and at 10 Hz over 40 s.
#
# For each case: `viosfm simulate --vio-profile realistic`, then
#   default      viosfm run (covariance-weighted priors, verified registration)
#   no_rpc       --no-rpc (no relative-pose term)
#   paper        --prior-weighting paper (the paper's w = alpha exp(-beta c))
#   no_bridging  --no-bridging (consecutive priors only)
# The variants map the default run's stored features and verified matches
# (a copy of its database), so they differ in the mapping only. Settings of
# the sweeps of docs/benchmarks.md: N1 10, N2 5, 1500 SIFT features.
# SEED (environment, default 0) seeds the simulated sequences (scene, motion,
# images, IMU and the emulated VIO's errors).
# Prints one table row per case (ATE after Sim(3), mm) and writes OUT/table.md.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
# shellcheck source=lib/prior-variants.sh
. "$here/scripts/lib/prior-variants.sh"
# shellcheck source=lib/trust-cases.sh
. "$here/scripts/lib/trust-cases.sh"
out=${1:?usage: scripts/bench-vio-trust.sh OUT [CASE...]}
shift
cases=("$@")
if [ ${#cases[@]} = 0 ]; then cases=("${TRUST_CASES[@]}"); fi
mkdir -p "$out"
run_flags=(--n1 10 --n2 5 --max-features 1500 --no-progress)


for case in "${cases[@]}"; do
  IFS=: read -r name scenario duration mode extra <<< "$case"
  seq=$out/seq/$name
  simulate_trust_case "$out" "$name" "$scenario" "$duration" "$mode" "$extra"
  read -r -a rate_flags <<< "$(trust_rate_flags "$mode")"
  map_prior_variants "$out/runs/$name" "$seq" --vio-trajectory "$seq/vio_emulated.tum" \
    "${rate_flags[@]}" "${run_flags[@]}"
done

{
  echo "| sequence | frames (registered / VIO only / unposed) | input VIO | **default** | --no-rpc | --prior-weighting paper | --no-bridging | default / VIO | SE(3) ATE default (VIO) | scale default (VIO) |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  for case in "${cases[@]}"; do
    IFS=: read -r name _ <<< "$case"
    runs=$out/runs/$name
    vio=$(metric "$runs/default" .eval.vio_metric.ate_sim3_rmse_m)
    d=$(metric "$runs/default" .eval.metric.ate_sim3_rmse_m)
    frames="$(metric "$runs/default" .frames.registered) / $(metric "$runs/default" .frames.vio_only) / $(metric "$runs/default" .frames.unposed) of $(metric "$runs/default" .frames.selected)"
    ratio=$(awk -v a="$d" -v b="$vio" 'BEGIN { if (a == "-" || b == "-") print "-"; else printf "1/%.0f", b / a }')
    se3="$(mm "$(metric "$runs/default" .eval.metric.ate_se3_rmse_m)") ($(mm "$(metric "$runs/default" .eval.vio_metric.ate_se3_rmse_m)"))"
    scale="$(metric "$runs/default" .eval.metric.scale | cut -c1-6) ($(metric "$runs/default" .eval.vio_metric.scale | cut -c1-6))"
    echo "| $name | $frames | $(mm "$vio") | **$(mm "$d")** | $(mm "$(metric "$runs/no_rpc" .eval.metric.ate_sim3_rmse_m)") | $(mm "$(metric "$runs/paper" .eval.metric.ate_sim3_rmse_m)") | $(mm "$(metric "$runs/no_bridging" .eval.metric.ate_sim3_rmse_m)") | $ratio | $se3 | $scale |"
  done
} | tee "$out/table.md"
