#!/usr/bin/env bash
# The benchmark suite: viosfm against COLMAP 3.8 (CPU) and the input VIO on
# the simulated scenarios (or on datasets a user has), one command.
#
# Usage:
#   bench/run.sh [--quick] [--out DIR] [--scenarios "room two_floors corridor"]
#                [--dataset EUROC_DIR --vio-trajectory TUM]... [--no-colmap]
#                [--no-sweeps] [--sweeps-only] [--colmap-modes "pairs sequential"]
#                [--docs FILE]
#
# For every scenario (simulated: images, IMU, ground truth and the emulated
# drifting VIO that stands in for a VIO's output) or dataset, it runs
#   viosfm                 `viosfm run` (full method)
#   viosfm_no_vio_check    the same without the VIO-aided verification
#   viosfm_no_rpc          the same without the relative-pose term in BA
#   colmap_same_pairs      COLMAP feature_extractor (same camera model and
#                          intrinsics, same feature cap) + matches_importer
#                          on viosfm's candidate pairs + mapper
#   colmap_sequential      COLMAP's own sequential matcher + mapper
#   vio                    the input VIO trajectory itself
#   viosfm_own_vio         `viosfm run` with viosfm's own VIO (images + IMU
#                          only; simulated scenarios)
#   own_vio                viosfm's own VIO trajectory itself
# evaluates each with `viosfm eval` (Sim(3)-aligned ATE of the body
# trajectory against the ground truth), records wall-clock time and peak
# memory of each run (/usr/bin/time), and then, on the first scenario, the
# batch-size sweep (the paper's Fig. 6) and, in full mode, the sequence-length
# sweep. `viosfm bench-report` turns the folder into tables and plots
# (docs/benchmarks-suite.md and docs/images/bench_*.svg by default).
#
# Full mode: 60 s at 10 Hz (600 frames) a scenario; --quick: 15 s at 10 Hz.
# Needs: viosfm built (make build), colmap, /usr/bin/time, sqlite3
# (VIOSFM_WITH_COLMAP=1 scripts/install-deps.sh installs them).
set -euo pipefail

here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
out=out/bench-suite
quick=0
scenarios="room two_floors corridor"
datasets=()
dataset_vio=()
with_colmap=1
with_sweeps=1
with_runs=1
colmap_modes="pairs sequential"
docs=$here/docs/benchmarks-suite.md
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --out) out=$2; shift ;;
    --scenarios) scenarios=$2; shift ;;
    --dataset) datasets+=("$2"); shift ;;
    --vio-trajectory) dataset_vio+=("$2"); shift ;;
    --no-colmap) with_colmap=0 ;;
    --no-sweeps) with_sweeps=0 ;;
    --sweeps-only) with_runs=0 ;;
    --colmap-modes) colmap_modes=$2; shift ;;
    --docs) docs=$2; shift ;;
    -h|--help) sed -n 2,30p "$0"; exit 0 ;;
    *) echo "bench/run.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done
if [ ${#datasets[@]} -ne ${#dataset_vio[@]} ]; then
  echo "bench/run.sh: every --dataset needs its --vio-trajectory (a TUM file of a VIO run on it)" >&2
  exit 2
fi
[ -x "$VIOSFM" ] || { echo "bench/run.sh: $VIOSFM not built (make build)" >&2; exit 2; }
if [ $with_colmap = 1 ] && ! command -v colmap > /dev/null; then
  echo "bench/run.sh: colmap not found: install it (VIOSFM_WITH_COLMAP=1 scripts/install-deps.sh) or pass --no-colmap" >&2
  exit 2
fi
export QT_QPA_PLATFORM=offscreen

if [ $quick = 1 ]; then
  duration=15; rate=10; n1=6; n2=4; max_features=1500; batch=25
  batch_sizes="5 10 25 50"; lengths=""
else
  duration=60; rate=10; n1=10; n2=5; max_features=1500; batch=50
  batch_sizes="5 10 25 50 100 200"; lengths="300 600 1200 2400"
fi
threads=2
mkdir -p "$out"
out=$(cd "$out" && pwd)
{
  echo "date: $(date -u +%FT%TZ)"
  echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
  echo "memory_gib: $(awk '/MemTotal/ { printf "%.0f", $2 / 1048576 }' /proc/meminfo)"
  echo "mode: $([ $quick = 1 ] && echo quick || echo full)"
  echo "viosfm: $(git -C "$here" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "colmap: $(command -v colmap > /dev/null && colmap -h 2>/dev/null | grep -m1 -o 'COLMAP [0-9.]*' || echo none)"
  echo "settings: $duration s at $rate Hz, N1 $n1, N2 $n2, at most $max_features features, batch $batch, $threads threads"
} > "$out/meta.txt"
echo "== bench: results in $out"

# timed DIR COMMAND...: runs COMMAND with its log in DIR/log.txt and writes
# "seconds peak_kib" to DIR/time.txt. A failed command leaves DIR/failed.
timed() {
  local dir=$1
  shift
  mkdir -p "$dir"
  rm -f "$dir/failed"
  if ! /usr/bin/time -f "%e %M" -o "$dir/time.txt" "$@" > "$dir/log.txt" 2>&1; then
    touch "$dir/failed"
    echo "   (failed, see $dir/log.txt)"
  fi
}

# evaluate DIR EST FORMAT SEQ [camera]: Sim(3) ATE of EST against SEQ's ground
# truth into DIR/eval.json.
evaluate() {
  local dir=$1 est=$2 format=$3 seq=$4 cam=${5:-}
  local extra=()
  [ -n "$cam" ] && extra=(--extrinsics-yaml "$seq/mav0/cam0/sensor.yaml" --cam-frame est)
  "$VIOSFM" eval --est "$est" --est-format "$format" \
    --ref "$seq/mav0/state_groundtruth_estimate0/data.csv" --ref-format euroc \
    --align sim3 --rpe-delta 0 "${extra[@]}" --json "$dir/eval.json" > "$dir/eval.txt" 2>&1 ||
    echo "   (evaluation failed, see $dir/eval.txt)"
}

# viosfm_run DIR SEQ VIO [args...]   (VIO "own": viosfm's own VIO)
viosfm_run() {
  local dir=$1 seq=$2 vio=$3
  shift 3
  echo "-- viosfm run -> $dir"
  rm -rf "$dir/run"
  local source=(--vio-trajectory "$vio")
  [ "$vio" = own ] && source=()
  timed "$dir" "$VIOSFM" run "$seq" --out "$dir/run" "${source[@]}" --rate "$rate" \
    --n1 "$n1" --n2 "$n2" --max-features "$max_features" --threads "$threads" "$@"
  [ -f "$dir/run/trajectory_body.tum" ] && evaluate "$dir" "$dir/run/trajectory_body.tum" tum "$seq"
  return 0
}

# colmap_run DIR SEQ MATCHER [PAIRS]: COLMAP on the sequence's images.
colmap_run() {
  local dir=$1 seq=$2 matcher=$3 pairs=${4:-}
  echo "-- colmap ($matcher) -> $dir"
  rm -rf "$dir"
  mkdir -p "$dir/sparse"
  local images="$seq/mav0/cam0/data"
  # The camera of the sequence (OPENCV, COLMAP's principal point convention).
  local params
  params=$(awk '
    /intrinsics:/ { gsub(/[\[\],]/, " "); fx = $2; fy = $3; cx = $4 + 0.5; cy = $5 + 0.5 }
    /distortion_coefficients:/ { gsub(/[\[\],]/, " "); k1 = $2; k2 = $3; p1 = $4; p2 = $5 }
    END { printf "%s,%s,%s,%s,%s,%s,%s,%s", fx, fy, cx, cy, k1, k2, p1, p2 }' "$seq/mav0/cam0/sensor.yaml")
  cat > "$dir/run.sh" << EOF
set -e
colmap feature_extractor --database_path "$dir/database.db" --image_path "$images" \
  --ImageReader.camera_model OPENCV --ImageReader.single_camera 1 \
  --ImageReader.camera_params "$params" --SiftExtraction.use_gpu 0 \
  --SiftExtraction.num_threads $threads --SiftExtraction.max_num_features $max_features
if [ "$matcher" = pairs ]; then
  colmap matches_importer --database_path "$dir/database.db" --match_list_path "$pairs" \
    --match_type pairs --SiftMatching.use_gpu 0 --SiftMatching.num_threads $threads
else
  colmap sequential_matcher --database_path "$dir/database.db" --SiftMatching.use_gpu 0 \
    --SiftMatching.num_threads $threads --SequentialMatching.overlap $n1 \
    --SequentialMatching.loop_detection 0
fi
colmap mapper --database_path "$dir/database.db" --image_path "$images" \
  --output_path "$dir/sparse" --Mapper.num_threads $threads
EOF
  timed "$dir" bash "$dir/run.sh"
  # The model with the most images.
  local best="" best_n=0 n
  for model in "$dir"/sparse/*/; do
    [ -f "$model/images.bin" ] || continue
    n=$(stat -c %s "$model/images.bin")
    if [ "$n" -gt "$best_n" ]; then best=$model; best_n=$n; fi
  done
  ls -d "$dir"/sparse/*/ 2> /dev/null | wc -l > "$dir/num_models.txt"
  if [ -n "$best" ]; then
    evaluate "$dir" "${best%/}" colmap "$seq" camera
  else
    echo "   (no model)"
  fi
}

# run_all NAME SEQ VIO OWN: every method on one sequence (OWN=1: also with
# viosfm's own VIO).
run_all() {
  local name=$1 seq=$2 vio=$3 own=$4
  local root="$out/$name/runs"
  mkdir -p "$root/vio"
  echo "== $name"
  evaluate "$root/vio" "$vio" tum "$seq"
  viosfm_run "$root/viosfm" "$seq" "$vio" --batch-size "$batch"
  viosfm_run "$root/viosfm_no_vio_check" "$seq" "$vio" --batch-size "$batch" --no-vio-prior
  viosfm_run "$root/viosfm_no_rpc" "$seq" "$vio" --batch-size "$batch" --no-rpc
  if [ "$own" = 1 ]; then
    viosfm_run "$root/viosfm_own_vio" "$seq" own --batch-size "$batch"
    mkdir -p "$root/own_vio"
    [ -f "$root/viosfm_own_vio/run/vio/trajectory_body.tum" ] &&
      evaluate "$root/own_vio" "$root/viosfm_own_vio/run/vio/trajectory_body.tum" tum "$seq"
  fi
  if [ $with_colmap = 1 ]; then
    local pairs="$root/viosfm/run/verification/pairs.csv"
    if [ -f "$pairs" ] && [[ " $colmap_modes " == *" pairs "* ]]; then
      tail -n +2 "$pairs" | cut -d, -f3,4 | tr , ' ' > "$out/$name/pairs.txt"
      colmap_run "$root/colmap_same_pairs" "$seq" pairs "$out/$name/pairs.txt"
    fi
    if [[ " $colmap_modes " == *" sequential "* ]]; then
      colmap_run "$root/colmap_sequential" "$seq" sequential
    fi
  fi
}

simulate() {
  local scenario=$1 seconds=$2 dest=$3
  if [ ! -f "$dest/simulation.yaml" ]; then
    echo "-- simulate $scenario, $seconds s at $rate Hz -> $dest"
    "$VIOSFM" simulate --scenario "$scenario" --duration "$seconds" --rate "$rate" --seed 0 \
      --out "$dest" > "$dest.log" 2>&1
  fi
}

for scenario in $scenarios; do
  seq="$out/$scenario/sequence"
  mkdir -p "$out/$scenario"
  simulate "$scenario" "$duration" "$seq"
  [ $with_runs = 1 ] && run_all "$scenario" "$seq" "$seq/vio_emulated.tum" 1
done
if [ $with_runs = 1 ]; then
  for i in "${!datasets[@]}"; do
    name=$(basename "${datasets[$i]}")
    run_all "$name" "${datasets[$i]}" "${dataset_vio[$i]}" 1
  done
fi

if [ $with_sweeps = 1 ]; then
  first=${scenarios%% *}
  if [ -n "$first" ]; then
    seq="$out/$first/sequence"
    for k in $batch_sizes; do
      viosfm_run "$out/batch_size/$k" "$seq" "$seq/vio_emulated.tum" --batch-size "$k"
    done
    for frames in $lengths; do
      seconds=$((frames / rate))
      lseq="$out/length/$frames/sequence"
      mkdir -p "$out/length/$frames"
      simulate room "$seconds" "$lseq"
      viosfm_run "$out/length/$frames" "$lseq" "$lseq/vio_emulated.tum" --batch-size "$batch"
    done
  fi
fi

"$VIOSFM" bench-report "$out" --markdown "$docs" --figures "$(dirname "$docs")/images"
echo "== bench: tables in $docs"
