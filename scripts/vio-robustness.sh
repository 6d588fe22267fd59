#!/usr/bin/env bash
# The VIO robustness set: `viosfm vio` on simulated `room` sequences with one
# imperfection each (docs/simulator.md, "Robustness options"), plus a clean
# baseline and all of them at once. Prints one markdown table row per case:
# frames tracking / initializing / IMU-only / lost, resets, first tracking
# (s after the first image), ATE RMSE after SE(3) and Sim(3) alignment (with
# the scale), and the VIO's CPU time; then what the VIO said about the time
# offset and the IMU noise figures.
#
# The VIO is given the rolling-shutter readout of the cases that have one
# (`--rolling-shutter-readout`, as a user gives their camera's), unless
# VIO_KNOWS_READOUT=0, which runs it as a global-shutter VIO.
#
# The ATE pairs every VIO pose with the ground truth at the frame's true
# exposure time: with a camera time offset the estimate's stamps (image
# stamps) are shifted back by the simulated offset (`viosfm eval --offset`).
#
# Usage: scripts/vio-robustness.sh [WORK_DIR]
# Environment: VIOSFM (binary running `vio`, default
#   build/src/viosfm/cli/viosfm), SIMULATOR (binary running `simulate` and
#   `eval`, default build/src/viosfm/cli/viosfm), TAG (name of this binary's
#   outputs in WORK_DIR, default "vio"), DURATION (s, 30), RATE (Hz, 20),
#   SEED (0), CASES (default: all, in the order below).
# Sequences are simulated once into WORK_DIR and reused (also by a second
# run with another VIOSFM and TAG, for a before/after comparison).
set -euo pipefail
VIOSFM=${VIOSFM:-build/src/viosfm/cli/viosfm}
SIMULATOR=${SIMULATOR:-build/src/viosfm/cli/viosfm}
TAG=${TAG:-vio}
WORK=${1:-/tmp/vio_robustness}
DURATION=${DURATION:-30}
RATE=${RATE:-20}
SEED=${SEED:-0}
VIO_KNOWS_READOUT=${VIO_KNOWS_READOUT:-1}
CASES=${CASES:-"baseline motion_blur auto_exposure rolling_shutter wrong_imu_noise time_offset white_walls all"}

# The simulate options of each case.
case_options() {
  case "$1" in
    baseline) echo "" ;;
    motion_blur) echo "--exposure-time 0.02" ;;
    auto_exposure) echo "--auto-exposure 1" ;;
    rolling_shutter) echo "--rolling-shutter-readout 0.03" ;;
    wrong_imu_noise) echo "--imu-noise-file-scale 0.077,30" ;;
    time_offset) echo "--camera-time-offset 0.047" ;;
    white_walls) echo "--white-walls" ;;
    all) echo "--exposure-time 0.02 --auto-exposure 1 --rolling-shutter-readout 0.03" \
      "--imu-noise-file-scale 0.077,30 --camera-time-offset 0.047 --white-walls" ;;
    *) echo "unknown case $1" >&2; exit 2 ;;
  esac
}

mkdir -p "$WORK"
echo "room, $DURATION s at $RATE Hz, seed $SEED, $(date -u +%F), $(nproc) cores; vio: $VIOSFM"
echo
echo "| case | simulate options | frames tracking / initializing / IMU-only / lost | resets | first tracking | ATE SE(3) | ATE Sim(3), scale | CPU time |"
echo "|---|---|---|---|---|---|---|---|"
NOTES=""
for name in $CASES; do
  options=$(case_options "$name")
  SEQ="$WORK/seq_${name}_${DURATION}s_${RATE}hz_seed${SEED}"
  if [ ! -f "$SEQ/simulation.yaml" ]; then
    # shellcheck disable=SC2086
    "$SIMULATOR" simulate --scenario room --duration "$DURATION" --rate "$RATE" --seed "$SEED" \
      $options --out "$SEQ" > "$WORK/simulate_${name}.log" 2>&1
  fi
  vio_options=""
  readout=$(echo "$options" | sed -n 's/.*--rolling-shutter-readout \([0-9.]*\).*/\1/p')
  if [ -n "$readout" ] && [ "$VIO_KNOWS_READOUT" = 1 ]; then
    vio_options="--rolling-shutter-readout $readout"
  fi
  OUT="$WORK/${TAG}_${name}"
  rm -rf "$OUT"
  status=0
  # shellcheck disable=SC2086
  /usr/bin/time -f "%U %S %e" -o "$WORK/${TAG}_${name}_time.txt" \
    "$VIOSFM" vio "$SEQ" --out "$OUT" $vio_options > "$WORK/${TAG}_${name}.log" 2>&1 || status=$?
  if [ "$status" -ne 0 ] || [ ! -f "$OUT/vio_summary.txt" ]; then
    echo "| $name | \`$options\` | vio failed (exit $status, see $WORK/${TAG}_${name}.log) | | | | | |"
    continue
  fi
  read -r user sys _ < "$WORK/${TAG}_${name}_time.txt"
  value() { awk -v key="$1:" '$1 == key { $1 = ""; sub(/^ /, ""); gsub(/"/, ""); print }' "$OUT/vio_summary.txt"; }
  frames="$(value frames_tracking) / $(value frames_initializing) / $(value frames_imu_only) / $(value frames_lost)"
  first_image=$(head -2 "$SEQ/mav0/cam0/data.csv" | tail -1 | cut -d, -f1)
  first_tracking=$(value first_tracking_ns)
  if [ "$first_tracking" -ge 0 ] 2>/dev/null; then
    first=$(awk -v a="$first_tracking" -v b="$first_image" 'BEGIN { printf "%.2f s", (a - b) * 1e-9 }')
  else
    first="never"
  fi
  offset=$(awk '$1 == "camera_time_offset_s:" { print -$2 }' "$SEQ/simulation.yaml")
  offset=${offset:-0}
  GT="$SEQ/mav0/state_groundtruth_estimate0/data.csv"
  ate() {
    "$SIMULATOR" eval --est "$OUT/trajectory_body.tum" --ref "$GT" --align "$1" --rpe-delta 0 \
      --offset "$offset" 2> /dev/null |
      awk -v mode="$1" '/^alignment:/ { for (i = 1; i < NF; ++i) if ($i == "scale") { scale = $(i + 1); gsub(",", "", scale) } }
           /ATE translation/ { rmse = $5 }
           END { if (rmse == "") { printf "-"; exit }
                 printf "%.4f m", rmse; if (mode == "sim3" && scale != "") printf ", %.4f", scale }' || echo "-"
  }
  cpu=$(echo "$user $sys" | awk '{ printf "%.1f s", $1 + $2 }')
  echo "| $name | \`${options:-(none)}\`${vio_options:+ (vio: \`$vio_options\`)} | $frames | $(value num_resets) | $first | $(ate se3) | $(ate sim3) | $cpu |"
  NOTES+="$name: time_offset_ns $(value time_offset_ns) ($(value time_offset_message)); imu noise: $(value imu_noise_message)"$'\n'
done
echo
printf "%s" "$NOTES"
