#!/usr/bin/env bash
# Ground-truth evaluation of guided matching (`--guided-matching`, part of
# `--realtime`) against brute-force matching, with the VIO drifted.
#
# Per scenario (default two_floors and corridor, 60 s at 2 Hz = 121 frames,
# 752x480, seed 0; at most 2000 SIFT features a frame; N1 6 temporal + N2 10
# retrieval pairs, the settings of scripts/eval-verification.sh):
#  1. viosfm simulate, viosfm features;
#  2. per drift factor, the emulated VIO regenerated (--no-images, same seed,
#     so the same motion) with --vio-drift X, then viosfm match three ways,
#     each from the features alone (the matches differ): brute force (the
#     default), guided matching in the fixed band of 20 px around the VIO's
#     epipolar lines (--guided-matching --fixed-band: the band of every pair
#     before 2026-11-29) and guided matching in the band the VIO's drift
#     allows (--guided-matching);
#  3. viosfm check-pairs against the simulator's ground truth.
# Prints per drift the Markdown table of check-pairs ("correct kept" is
# against the brute-force run) and the wall clock of each match; everything
# is kept in WORK_DIR.
#
# Usage: scripts/eval-guided-matching.sh [WORK_DIR]
# Environment: VIOSFM (binary, default build/src/viosfm/cli/viosfm),
#   SCENARIOS ("two_floors corridor"), DURATION (s, 60), RATE (Hz, 2),
#   MAX_FEATURES (2000), N1 (6), N2 (10), SEED (0), DRIFTS ("1 5 10",
#   multiples of the default drift), THREADS (2), VIO_PROFILE (gentle).
set -euo pipefail

VIOSFM=$(realpath "${VIOSFM:-build/src/viosfm/cli/viosfm}")
WORK=$(realpath -m "${1:-/tmp/eval_guided_matching}")
SCENARIOS=${SCENARIOS:-"two_floors corridor"}
DURATION=${DURATION:-60}
RATE=${RATE:-2}
MAX_FEATURES=${MAX_FEATURES:-2000}
N1=${N1:-6}
N2=${N2:-10}
SEED=${SEED:-0}
DRIFTS=${DRIFTS:-"1 5 10"}
THREADS=${THREADS:-2}
VIO_PROFILE=${VIO_PROFILE:-gentle}

mkdir -p "$WORK"
start=$(date +%s)
for scenario in $SCENARIOS; do
  dir="$WORK/$scenario"
  mkdir -p "$dir"
  seq="$dir/sequence"
  rm -rf "$seq"
  "$VIOSFM" simulate --scenario "$scenario" --duration "$DURATION" --rate "$RATE" \
    --seed "$SEED" --threads "$THREADS" --vio-profile "$VIO_PROFILE" --out "$seq" \
    > "$dir/simulate.log" 2>&1
  rm -f "$dir"/*.db "$dir"/*.db-*
  "$VIOSFM" features "$seq" --database "$dir/features.db" --max-features "$MAX_FEATURES" \
    --threads "$THREADS" > "$dir/features.log" 2>&1
  for drift in $DRIFTS; do
    dseq="$dir/drift_$drift"
    rm -rf "$dseq"
    "$VIOSFM" simulate --scenario "$scenario" --duration "$DURATION" --rate "$RATE" \
      --seed "$SEED" --vio-drift "$drift" --vio-profile "$VIO_PROFILE" --no-images \
      --out "$dseq" > "$dseq.log" 2>&1
    echo
    echo "### $scenario, drift x$drift ($(grep -o 'end drift [0-9.e+-]*' "$dseq.log" | awk '{print $3}') m at the end)"
    echo
    for variant in brute guided_fixed_band guided_drift_band; do
      extra=()
      [ "$variant" = guided_fixed_band ] && extra=(--guided-matching --fixed-band)
      [ "$variant" = guided_drift_band ] && extra=(--guided-matching)
      name="drift_${drift}_$variant"
      cp "$dir/features.db" "$dir/$name.db"
      /usr/bin/time -f "%e" -o "$dir/$name.time" "$VIOSFM" match "$seq" \
        --database "$dir/$name.db" --vio-trajectory "$dseq/vio_emulated.tum" --n1 "$N1" \
        --n2 "$N2" --threads "$THREADS" --seed "$SEED" --report "$dir/$name" \
        "${extra[@]}" > "$dir/$name.log" 2>&1
    done
    "$VIOSFM" check-pairs "$seq" --report "$dir/drift_${drift}_brute" \
      --report "$dir/drift_${drift}_guided_fixed_band" \
      --report "$dir/drift_${drift}_guided_drift_band" \
      > "$dir/drift_${drift}_check.txt" 2> "$dir/drift_${drift}_check.log"
    grep '^|' "$dir/drift_${drift}_check.txt"
    echo
    echo "match wall clock s: brute $(cat "$dir/drift_${drift}_brute.time"), guided fixed band" \
      "$(cat "$dir/drift_${drift}_guided_fixed_band.time"), guided drift band" \
      "$(cat "$dir/drift_${drift}_guided_drift_band.time")"
  done
done
echo
echo "total $(($(date +%s) - start)) s"
