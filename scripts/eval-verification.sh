#!/usr/bin/env bash
# Ground-truth evaluation of the pair verification on simulated
# sequences with repeated structure, and its sensitivity to VIO drift.
#
# Per scenario (default two_floors and corridor, 60 s at 2 Hz = 121 frames,
# 752x480, seed 0; at most 2000 SIFT features a frame; N1 6 temporal + N2 10
# retrieval pairs):
#  1. viosfm simulate, viosfm features;
#  2. viosfm match four ways on the same candidate pairs and the same
#     tentative matches: RANSAC only (--no-vio-prior, the baseline; it
#     matches every pair), then on copies of its database with --reverify
#     (stored matches verified again): the paper's VIO-aided check
#     (--no-depth-check --fixed-band), the VIO-aided check with the depth
#     check and the fixed band (--fixed-band), the depth check with each
#     match judged alone against the band the VIO's drift allows
#     (--wide-band) and the default (the depth check, the VIO's relative pose
#     corrected by the matches within its drift, then the fixed band);
#  3. viosfm check-pairs against the simulator's ground truth;
#  4. drift sweep: the emulated VIO regenerated (--no-images, same seed, so
#     the same motion) with --vio-drift X, and the four VIO-aided variants
#     re-verified with it (the VIO model's rates at their defaults: the
#     verification is not told the drift); prints drift -> accepted wrong,
#     correct kept %. Earlier versions' default was the wide band. Then
#     guided matching (--guided-matching, part of --realtime), which matches
#     from the features again with the drifted VIO: in the fixed band of
#     20 px around its epipolar lines (--fixed-band; the band of every pair
#     before 2026-11-29) and in the band its drift allows (the default);
#     prints drift -> accepted correct, accepted wrong, correct kept % for
#     brute force (the default re-verified above) and both, and the wall
#     clock of each match.
# Prints Markdown tables; everything is kept in WORK_DIR.
#
# Usage: scripts/eval-verification.sh [WORK_DIR]
# Environment: VIOSFM (binary, default build/src/viosfm/cli/viosfm),
#   SCENARIOS ("two_floors corridor"), DURATION (s, 60), RATE (Hz, 2),
#   MAX_FEATURES (2000), N1 (6), N2 (10), SEED (0),
#   DRIFTS ("0 1 2 5 10 20", multiples of the default drift), THREADS (2),
#   VIO_PROFILE (gentle; or realistic: sim/vio_emulator.h).
set -euo pipefail

VIOSFM=$(realpath "${VIOSFM:-build/src/viosfm/cli/viosfm}")
WORK=$(realpath -m "${1:-/tmp/eval_verification}")
SCENARIOS=${SCENARIOS:-"two_floors corridor"}
DURATION=${DURATION:-60}
RATE=${RATE:-2}
MAX_FEATURES=${MAX_FEATURES:-2000}
N1=${N1:-6}
N2=${N2:-10}
SEED=${SEED:-0}
DRIFTS=${DRIFTS:-"0 1 2 5 10 20"}
THREADS=${THREADS:-2}
VIO_PROFILE=${VIO_PROFILE:-gentle}

mkdir -p "$WORK"
start=$(date +%s)

# match NAME SEQ DB VIO [ARGS...]: viosfm match with a report in $dir/NAME.
match() {
  local name=$1 seq=$2 db=$3 vio=$4
  shift 4
  "$VIOSFM" match "$seq" --database "$db" --vio-trajectory "$vio" --n1 "$N1" --n2 "$N2" \
    --threads "$THREADS" --seed "$SEED" --report "$dir/$name" "$@" > "$dir/$name.log" 2>&1
}

# row LABEL TABLE_LINE: prints "| LABEL | accepted wrong | correct kept |" from a
# check-pairs table line.
row() {
  local label=$1 line=$2
  local wrong kept
  wrong=$(echo "$line" | awk -F'|' '{gsub(/ /, "", $7); print $7}')
  kept=$(echo "$line" | awk -F'|' '{print $9}' | sed 's/^ *//; s/ *$//')
  echo "| $label | $wrong | $kept |"
}

for scenario in $SCENARIOS; do
  dir="$WORK/$scenario"
  mkdir -p "$dir"
  seq="$dir/sequence"
  echo "== $scenario: $DURATION s at $RATE Hz, seed $SEED"
  rm -rf "$seq"
  "$VIOSFM" simulate --scenario "$scenario" --duration "$DURATION" --rate "$RATE" \
    --seed "$SEED" --threads "$THREADS" --vio-profile "$VIO_PROFILE" --out "$seq" \
    > "$dir/simulate.log" 2>&1
  rm -f "$dir"/*.db "$dir"/*.db-*
  "$VIOSFM" features "$seq" --database "$dir/features.db" --max-features "$MAX_FEATURES" \
    --threads "$THREADS" > "$dir/features.log" 2>&1

  vio="$seq/vio_emulated.tum"
  cp "$dir/features.db" "$dir/ransac.db"
  match ransac_only "$seq" "$dir/ransac.db" "$vio" --no-vio-prior
  cp "$dir/ransac.db" "$dir/paper.db"
  match vio_paper "$seq" "$dir/paper.db" "$vio" --reverify --no-depth-check --fixed-band
  cp "$dir/ransac.db" "$dir/fixed.db"
  match vio_depth_fixed_band "$seq" "$dir/fixed.db" "$vio" --reverify --fixed-band
  cp "$dir/ransac.db" "$dir/depth.db"
  match vio_depth "$seq" "$dir/depth.db" "$vio" --reverify
  cp "$dir/ransac.db" "$dir/wide.db"
  match vio_depth_wide_band "$seq" "$dir/wide.db" "$vio" --reverify --wide-band
  "$VIOSFM" check-pairs "$seq" --report "$dir/ransac_only" --report "$dir/vio_paper" \
    --report "$dir/vio_depth_fixed_band" --report "$dir/vio_depth_wide_band" \
    --report "$dir/vio_depth" \
    --json "$dir/check_pairs.json" > "$dir/check_pairs.txt" \
    2> "$dir/check_pairs.log"
  echo
  echo "### $scenario ($(ls "$seq/mav0/cam0/data" | wc -l) frames)"
  echo
  grep '^|' "$dir/check_pairs.txt"

  # Drift sweep.
  echo
  echo "### $scenario: VIO drift sweep (multiple of the default emulated drift)"
  echo
  echo "| drift | VIO end error (m) | paper: accepted wrong | paper: correct kept | depth check, fixed band: accepted wrong | correct kept | depth check, wide band: accepted wrong | correct kept | depth check, corrected within the drift (default): accepted wrong | correct kept |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  for drift in $DRIFTS; do
    dseq="$dir/drift_$drift"
    rm -rf "$dseq"
    "$VIOSFM" simulate --scenario "$scenario" --duration "$DURATION" --rate "$RATE" \
      --seed "$SEED" --vio-drift "$drift" --vio-profile "$VIO_PROFILE" --no-images \
      --out "$dseq" > "$dseq.log" 2>&1
    end_error=$(grep -o 'end drift [0-9.e+-]*' "$dseq.log" | awk '{print $3}')
    for variant in paper fixed wide depth; do
      extra=(--reverify)
      [ "$variant" = paper ] && extra+=(--no-depth-check --fixed-band)
      [ "$variant" = fixed ] && extra+=(--fixed-band)
      [ "$variant" = wide ] && extra+=(--wide-band)
      cp "$dir/ransac.db" "$dir/drift_${drift}_$variant.db"
      match "drift_${drift}_$variant" "$seq" "$dir/drift_${drift}_$variant.db" \
        "$dseq/vio_emulated.tum" "${extra[@]}"
    done
    "$VIOSFM" check-pairs "$seq" --report "$dir/ransac_only" --report "$dir/drift_${drift}_paper" \
      --report "$dir/drift_${drift}_fixed" --report "$dir/drift_${drift}_wide" \
      --report "$dir/drift_${drift}_depth" \
      > "$dir/drift_${drift}_check.txt" 2> "$dir/drift_${drift}_check.log"
    paper_line=$(grep "^| drift_${drift}_paper " "$dir/drift_${drift}_check.txt")
    fixed_line=$(grep "^| drift_${drift}_fixed " "$dir/drift_${drift}_check.txt")
    wide_line=$(grep "^| drift_${drift}_wide " "$dir/drift_${drift}_check.txt")
    depth_line=$(grep "^| drift_${drift}_depth " "$dir/drift_${drift}_check.txt")
    p=$(row x "$paper_line" | awk -F'|' '{print $3 "|" $4}')
    f=$(row x "$fixed_line" | awk -F'|' '{print $3 "|" $4}')
    w=$(row x "$wide_line" | awk -F'|' '{print $3 "|" $4}')
    d=$(row x "$depth_line" | awk -F'|' '{print $3 "|" $4}')
    echo "| $drift | $end_error |$p|$f|$w|$d|"
    for variant in guided_fixed guided_drift; do
      extra=(--guided-matching)
      [ "$variant" = guided_fixed ] && extra+=(--fixed-band)
      cp "$dir/features.db" "$dir/drift_${drift}_$variant.db"
      /usr/bin/time -f "%e" -o "$dir/drift_${drift}_$variant.time" \
        "$VIOSFM" match "$seq" --database "$dir/drift_${drift}_$variant.db" \
        --vio-trajectory "$dseq/vio_emulated.tum" --n1 "$N1" --n2 "$N2" --threads "$THREADS" \
        --seed "$SEED" --report "$dir/drift_${drift}_$variant" "${extra[@]}" \
        > "$dir/drift_${drift}_$variant.log" 2>&1
    done
    "$VIOSFM" check-pairs "$seq" --report "$dir/drift_${drift}_depth" \
      --report "$dir/drift_${drift}_guided_fixed" --report "$dir/drift_${drift}_guided_drift" \
      > "$dir/drift_${drift}_guided_check.txt" 2> "$dir/drift_${drift}_guided_check.log"
  done

  echo
  echo "### $scenario: guided matching with the VIO drifted (correct kept: of brute force's)"
  echo
  echo "| drift | brute force (default): accepted correct | accepted wrong | guided, 20 px band: accepted correct | accepted wrong | correct kept | guided, the drift's band (default): accepted correct | accepted wrong | correct kept | match s: 20 px band, drift's band |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  for drift in $DRIFTS; do
    cells=""
    for variant in depth guided_fixed guided_drift; do
      line=$(grep "^| drift_${drift}_$variant " "$dir/drift_${drift}_guided_check.txt")
      correct=$(echo "$line" | awk -F'|' '{gsub(/ /, "", $6); print $6}')
      wrong=$(echo "$line" | awk -F'|' '{gsub(/ /, "", $7); print $7}')
      kept=$(echo "$line" | awk -F'|' '{print $9}' | sed 's/^ *//; s/ *$//')
      if [ "$variant" = depth ]; then
        cells+=" $correct | $wrong |"
      else
        cells+=" $correct | $wrong | $kept |"
      fi
    done
    echo "| $drift |$cells $(cat "$dir/drift_${drift}_guided_fixed.time"), $(cat "$dir/drift_${drift}_guided_drift.time") |"
  done
done
echo
echo "total $(($(date +%s) - start)) s"
