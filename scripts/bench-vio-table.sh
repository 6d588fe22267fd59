#!/usr/bin/env bash
# The simulated VIO table: `viosfm vio` on every scenario and seed, one
# markdown row each (frames tracking / initializing / IMU-only / lost,
# resets, ATE after SE(3) and Sim(3) alignment with the scale, CPU time),
# then the mean SE(3) ATE per scenario. `room` runs at 20 Hz, the others at
# 10 Hz, every one 30 s long.
#
# Usage: scripts/bench-vio-table.sh [WORK_DIR]
# Environment: VIOSFM (binary running `vio`, default
#   build/src/viosfm/cli/viosfm), SIMULATOR (binary running `simulate` and
#   `eval`, default VIOSFM), TAG (name of this binary's outputs in WORK_DIR,
#   default "vio"), SCENARIOS (default "room corridor two_floors dark mav"),
#   SEEDS (default "0 1 2"), DURATION (s, 30).
# Sequences are simulated once into WORK_DIR and reused (also by a second
# run with another VIOSFM and TAG, for a before/after comparison).
set -euo pipefail
VIOSFM=${VIOSFM:-build/src/viosfm/cli/viosfm}
SIMULATOR=${SIMULATOR:-$VIOSFM}
TAG=${TAG:-vio}
WORK=${1:-/tmp/bench_vio_table}
SCENARIOS=${SCENARIOS:-"room corridor two_floors dark mav"}
SEEDS=${SEEDS:-"0 1 2"}
DURATION=${DURATION:-30}
mkdir -p "$WORK"
echo "$DURATION s per sequence, $(date -u +%F), $(nproc) cores; vio: $VIOSFM"
echo
echo "| scenario | seed | tracking / initializing / IMU-only / lost | resets | ATE SE(3) | ATE Sim(3), scale | CPU time |"
echo "|---|---|---|---|---|---|---|"
declare -A sums counts
for scenario in $SCENARIOS; do
  rate=10
  [ "$scenario" = room ] || [ "$scenario" = mav ] && rate=20
  for seed in $SEEDS; do
    seq="$WORK/${scenario}_${DURATION}s_${rate}hz_s$seed"
    if [ ! -f "$seq/simulation.yaml" ]; then
      "$SIMULATOR" simulate --scenario "$scenario" --duration "$DURATION" --rate "$rate" \
        --seed "$seed" --out "$seq" > "$seq.simulate.log" 2>&1
    fi
    out="$WORK/$TAG/${scenario}_s$seed"
    rm -rf "$out"
    mkdir -p "$(dirname "$out")"
    /usr/bin/time -f "%U %S" -o "$out.time" "$VIOSFM" vio "$seq" --out "$out" > "$out.log" 2>&1
    read -r user sys < "$out.time"
    value() { awk -F': ' -v k="$1" '$1 == k { split($2, v, " "); print v[1] }' "$out/vio_summary.txt"; }
    gt="$seq/mav0/state_groundtruth_estimate0/data.csv"
    ate() {
      "$SIMULATOR" eval --est "$out/trajectory_body.tum" --ref "$gt" --align "$1" --rpe-delta 0 |
        awk '/^alignment:/ { for (i = 1; i < NF; ++i) if ($i == "scale") { s = $(i + 1); gsub(",", "", s) } }
             /ATE translation/ { rmse = $5 } END { printf "%.1f mm", rmse * 1e3; if (s != "" && s != 1) printf ", %.4f", s }'
    }
    se3=$(ate se3)
    echo "| $scenario | $seed | $(value frames_tracking) / $(value frames_initializing) / $(value frames_imu_only) / $(value frames_lost) | $(value num_resets) | $se3 | $(ate sim3) | $(echo "$user $sys" | awk '{ printf "%.1f s", $1 + $2 }') |"
    sums[$scenario]=$(echo "${sums[$scenario]:-0} ${se3% mm}" | awk '{ print $1 + $2 }')
    counts[$scenario]=$(( ${counts[$scenario]:-0} + 1 ))
  done
done
echo
for scenario in $SCENARIOS; do
  echo "$scenario: mean SE(3) ATE $(echo "${sums[$scenario]} ${counts[$scenario]}" | awk '{ printf "%.1f", $1 / $2 }') mm over ${counts[$scenario]} seeds"
done
