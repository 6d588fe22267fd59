#!/usr/bin/env bash
# The defaults (`--preset realtime`) against the paper's settings (`--preset
# paper`) on the simulated sequences with the realistic emulated VIO of
# scripts/bench-vio-trust.sh: each sequence simulated once, then run with each
# preset from scratch, the emulated VIO as input.
#
# Usage: scripts/bench-presets.sh OUT [CASE...]
#   CASE = NAME:SCENARIO:DURATION_S:MODE as in scripts/bench-vio-trust.sh
#   (default: its six cases). SEED (environment, default 0) seeds the sequences.
# Prints one table row per case (Sim(3) and SE(3) ATE in mm, frames registered
# of selected, the process's CPU seconds) and writes OUT/table.md.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
# shellcheck source=lib/trust-cases.sh
. "$here/scripts/lib/trust-cases.sh"
out=${1:?usage: scripts/bench-presets.sh OUT [CASE...]}
shift
cases=("$@")
if [ ${#cases[@]} = 0 ]; then cases=("${TRUST_CASES[@]}"); fi
mkdir -p "$out"


for case in "${cases[@]}"; do
  IFS=: read -r name scenario duration mode <<< "$case"
  seq=$out/seq/$name
  simulate_trust_case "$out" "$name" "$scenario" "$duration" "$mode"
  read -r -a rate_flags <<< "$(trust_rate_flags "$mode")"
  for preset in realtime paper; do
    run=$out/runs/$name/$preset
    [ -f "$run/summary.json" ] && continue
    mkdir -p "$out/runs/$name"
    /usr/bin/time -f "%U %S" -o "$out/runs/$name/$preset.cpu" \
      "$VIOSFM" run "$seq" --out "$run" --overwrite --preset "$preset" \
      --vio-trajectory "$seq/vio_emulated.tum" "${rate_flags[@]}" --no-progress \
      > "$out/runs/$name/$preset.log" 2>&1 ||
      echo "scripts/bench-presets.sh: $name with --preset $preset failed: see $out/runs/$name/$preset.log" >&2
  done
done

{
  echo "| sequence | input VIO Sim(3) | defaults: Sim(3) / SE(3) | registered | CPU s | \`--preset paper\`: Sim(3) / SE(3) | registered | CPU s | defaults / paper (Sim(3)) |"
  echo "|---|---|---|---|---|---|---|---|---|"
  for case in "${cases[@]}"; do
    IFS=: read -r name _ <<< "$case"
    runs=$out/runs/$name
    row="| $name | $(mm "$(metric "$runs/realtime" .eval.vio_metric.ate_sim3_rmse_m)")"
    for preset in realtime paper; do
      cpu=$(awk '{ printf "%.0f", $1 + $2 }' "$runs/$preset.cpu" 2>/dev/null || echo -)
      row+=" | $(mm "$(metric "$runs/$preset" .eval.metric.ate_sim3_rmse_m)") / $(mm "$(metric "$runs/$preset" .eval.metric.ate_se3_rmse_m)")"
      row+=" | $(metric "$runs/$preset" .frames.registered) of $(metric "$runs/$preset" .frames.selected) | $cpu"
    done
    ratio=$(awk -v a="$(metric "$runs/realtime" .eval.metric.ate_sim3_rmse_m)" \
                -v b="$(metric "$runs/paper" .eval.metric.ate_sim3_rmse_m)" \
                'BEGIN { if (a == "-" || b == "-" || b == 0) print "-"; else printf "%.2f", a / b }')
    echo "$row | $ratio |"
  done
} | tee "$out/table.md"
