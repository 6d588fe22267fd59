#!/usr/bin/env bash
# CPU time and accuracy of `viosfm vio` on a simulated sequence: is it faster
# than real time on one core? Prints the sequence length, the CPU time
# (user + system, all threads) and wall time of the VIO, the frames per
# status, and the ATE (SE(3) and Sim(3)) against the ground truth.
#
# Usage: scripts/bench-vio.sh [WORK_DIR]
# Environment: VIOSFM (binary, default build/src/viosfm/cli/viosfm),
#   SCENARIO (room), DURATION (s, 60), RATE (Hz, 20), SEED (0).
set -euo pipefail
VIOSFM=${VIOSFM:-build/src/viosfm/cli/viosfm}
WORK=${1:-/tmp/bench_vio}
SCENARIO=${SCENARIO:-room}
DURATION=${DURATION:-60}
RATE=${RATE:-20}
SEED=${SEED:-0}
mkdir -p "$WORK"
SEQ="$WORK/sequence_${SCENARIO}_${DURATION}s_${RATE}hz"
if [ ! -f "$SEQ/simulation.yaml" ]; then
  "$VIOSFM" simulate --scenario "$SCENARIO" --duration "$DURATION" --rate "$RATE" --seed "$SEED" \
    --out "$SEQ" > "$WORK/simulate.log" 2>&1
fi
OUT="$WORK/vio_${SCENARIO}"
rm -rf "$OUT"
/usr/bin/time -f "%U %S %e %M" -o "$WORK/time.txt" \
  "$VIOSFM" vio "$SEQ" --out "$OUT" > "$WORK/vio.log" 2>&1
read -r user sys wall kib < "$WORK/time.txt"
GT="$SEQ/mav0/state_groundtruth_estimate0/data.csv"
# ate MODE: "rmse median [scale]" of the ATE translation after MODE alignment.
ate() {
  "$VIOSFM" eval --est "$OUT/trajectory_body.tum" --ref "$GT" --align "$1" --rpe-delta 0 |
    awk '/^alignment:/ { for (i = 1; i < NF; ++i) if ($i == "scale") { scale = $(i + 1); gsub(",", "", scale) } }
         /ATE translation/ { printf "ATE RMSE %s m, median %s m", $5, $7 }
         END { if (scale != "") printf ", scale %s", scale; print "" }'
}
echo "$SCENARIO, $DURATION s at $RATE Hz, seed $SEED, $(date -u +%F), $(nproc) cores"
echo "CPU time $(echo "$user $sys" | awk '{ printf "%.1f", $1 + $2 }') s (user $user, system $sys)," \
  "wall $wall s, peak memory $((kib / 1024)) MiB, for $DURATION s of data"
grep -E "^frames_|^first_tracking|^message" "$OUT/vio_summary.txt"
echo "SE(3): $(ate se3)"
echo "Sim(3): $(ate sim3)"
