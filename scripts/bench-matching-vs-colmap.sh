#!/usr/bin/env bash
# Features + matching + verification time of viosfm against COLMAP 3.8 (CPU)
# on the same images and the same candidate pairs, measured in one run.
#
#  1. simulate a sequence (default: `room`, 60 s at 5 Hz = 300 frames, 752x480);
#  2. viosfm features + viosfm match (N1 temporal + N2 retrieval pairs, the
#     VIO-aided check, RANSAC), twice: brute-force matching, and matching
#     guided by the VIO epipolar geometry (--guided-matching);
#  3. COLMAP feature_extractor (same camera model and intrinsics, same
#     feature cap) + matches_importer on viosfm's candidate pair list.
# Every step runs with 2 threads; wall-clock and peak memory come from
# /usr/bin/time. Prints a Markdown table.
#
# Usage: scripts/bench-matching-vs-colmap.sh [WORK_DIR]
# Environment: VIOSFM (binary, default build/src/viosfm/cli/viosfm),
#   SCENARIO (room), DURATION (s, 60), RATE (Hz, 5), MAX_FEATURES (2000),
#   N1 (10), N2 (5), SEED (0).
set -euo pipefail

VIOSFM=${VIOSFM:-build/src/viosfm/cli/viosfm}
WORK=${1:-/tmp/bench_matching}
SCENARIO=${SCENARIO:-room}
DURATION=${DURATION:-60}
RATE=${RATE:-5}
MAX_FEATURES=${MAX_FEATURES:-2000}
N1=${N1:-10}
N2=${N2:-5}
SEED=${SEED:-0}
export QT_QPA_PLATFORM=offscreen
command -v colmap > /dev/null || { echo "error: colmap not found (apt-get install colmap)" >&2; exit 2; }

# The simulator's default camera, OPENCV: fx fy cx cy k1 k2 p1 p2 (COLMAP's
# principal point convention: +0.5 px against viosfm's).
CAMERA_PARAMS="458.654,457.296,367.715,248.875,-0.28340811,0.07395907,0.00019359,1.76187114e-05"

rm -rf "$WORK"
mkdir -p "$WORK"
SEQ="$WORK/sequence"
IMAGES="$SEQ/mav0/cam0/data"
"$VIOSFM" simulate --scenario "$SCENARIO" --duration "$DURATION" --rate "$RATE" --seed "$SEED" \
  --out "$SEQ" > "$WORK/simulate.log" 2>&1
num_images=$(ls "$IMAGES" | wc -l)

# timed NAME COMMAND...: runs COMMAND, appends "NAME seconds peak_MiB" to times.txt.
timed() {
  local name=$1
  shift
  /usr/bin/time -f "%e %M" -o "$WORK/time_$name.txt" "$@" > "$WORK/$name.log" 2>&1
  read -r seconds kib < "$WORK/time_$name.txt"
  echo "$name $seconds $((kib / 1024))" >> "$WORK/times.txt"
}

# viosfm, brute force and guided.
for mode in brute guided; do
  db="$WORK/viosfm_$mode.db"
  extra=()
  [ "$mode" = guided ] && extra=(--guided-matching)
  timed "viosfm_features_$mode" "$VIOSFM" features "$SEQ" --database "$db" \
    --max-features "$MAX_FEATURES" --threads 2
  timed "viosfm_match_$mode" "$VIOSFM" match "$SEQ" --database "$db" \
    --vio-trajectory "$SEQ/vio_emulated.tum" --n1 "$N1" --n2 "$N2" --threads 2 \
    --seed "$SEED" --report "$WORK/report_$mode" "${extra[@]}"
done

# The candidate pairs viosfm generated (name1, name2: columns 3 and 4).
tail -n +2 "$WORK/report_brute/pairs.csv" | cut -d, -f3,4 | tr , ' ' > "$WORK/pairs.txt"
num_pairs=$(wc -l < "$WORK/pairs.txt")

timed colmap_features colmap feature_extractor --database_path "$WORK/colmap.db" \
  --image_path "$IMAGES" --ImageReader.camera_model OPENCV --ImageReader.single_camera 1 \
  --ImageReader.camera_params "$CAMERA_PARAMS" --SiftExtraction.use_gpu 0 \
  --SiftExtraction.num_threads 2 --SiftExtraction.max_num_features "$MAX_FEATURES"
timed colmap_match colmap matches_importer --database_path "$WORK/colmap.db" \
  --match_list_path "$WORK/pairs.txt" --match_type pairs --SiftMatching.use_gpu 0 \
  --SiftMatching.num_threads 2

field() { awk -v n="$1" -v c="$2" '$1 == n { print $c }' "$WORK/times.txt"; }
sum() { echo "$1 $2" | awk '{ printf "%.1f", $1 + $2 }'; }
verified() { sqlite3 "$1" "SELECT COUNT(*) FROM two_view_geometries WHERE rows > 0"; }

echo
echo "$SCENARIO, $num_images images (752x480), $num_pairs candidate pairs (N1 $N1, N2 $N2)," \
  "at most $MAX_FEATURES features an image, 2 threads, $(date -u +%F)"
echo
echo "| | features (s) | matching + verification (s) | total (s) | peak memory (MiB) | verified pairs |"
echo "|---|---|---|---|---|---|"
for mode in brute guided; do
  f=$(field "viosfm_features_$mode" 2)
  m=$(field "viosfm_match_$mode" 2)
  mem=$(field "viosfm_match_$mode" 3)
  echo "| viosfm ($mode matching) | $f | $m | $(sum "$f" "$m") | $mem | $(verified "$WORK/viosfm_$mode.db") |"
done
f=$(field colmap_features 2)
m=$(field colmap_match 2)
mem=$(field colmap_match 3)
echo "| COLMAP 3.8 (matches_importer) | $f | $m | $(sum "$f" "$m") | $mem | $(verified "$WORK/colmap.db") |"
