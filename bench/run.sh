#!/usr/bin/env bash
# The benchmark suite: viosfm against COLMAP 3.8 (CPU) and the input VIO on
# the simulated scenarios (or on datasets a user has), one command.
#
# Usage:
#   bench/run.sh [--quick] [--out DIR] [--scenarios "room two_floors corridor"]
#                [--dataset EUROC_DIR --vio-trajectory TUM]... [--no-colmap]
#                [--no-sweeps] [--sweeps-only] [--colmap-modes "pairs sequential"]
#                [--jobs 1|2] [--lane viosfm|colmap] [--force] [--docs FILE]
#                [--lengths "300 600 1200 2400"] [--length-window N]
#                [--vio-profile gentle|realistic]
#                [--colmap-scenarios "room two_floors corridor"]
#
# For every scenario (simulated: images, IMU, ground truth and the emulated
# drifting VIO that stands in for a VIO's output) or dataset, it runs
#   viosfm                 `viosfm run` (full method)
#   viosfm_no_vio_check    the same without the VIO-aided verification
#   viosfm_no_rpc          the same without the relative-pose term in BA
#   viosfm_paper_weighting the same with the paper's weighting of the
#                          relative-pose priors (--prior-weighting paper)
#   viosfm_no_bridging     the same with the paper's consecutive-frame
#                          relative-pose terms only (no bridging priors)
#   colmap_same_pairs      COLMAP feature_extractor (same camera model and
#                          intrinsics, same feature cap) + matches_importer
#                          on viosfm's candidate pairs + mapper
#   colmap_sequential      COLMAP's own sequential matcher + mapper
#   vio                    the input VIO trajectory itself
#   viosfm_own_vio         `viosfm run` with viosfm's own VIO (images + IMU
#                          only)
#   own_vio                viosfm's own VIO trajectory itself
# evaluates each with `viosfm eval` (Sim(3)-aligned ATE of the body
# trajectory against the ground truth, and the SE(3)-aligned one: the
# metric accuracy), records wall-clock time and peak
# memory of each run (/usr/bin/time), and then, on the first scenario, the
# batch-size sweep (the paper's Fig. 6) and, in full mode, the sequence-length
# sweep. `viosfm bench-report` turns the folder into tables and plots
# (docs/benchmarks-suite.md and docs/images/bench_*.svg by default after a
# full run with COLMAP; OUT/report/ after --quick, --no-colmap, --sweeps-only
# or --lane; --docs FILE chooses).
#
# Full mode: 63 s at 10 Hz (631 images, 610 after the static start is
# trimmed) a scenario, N1 10, N2 5, at most 1000 features, batch 50; the
# batch-size sweep on a 30 s room sequence (the paper's Fig. 6, with COLMAP on
# the same images as reference); the length sweep on room with 300, 600, 1200
# and 2400 images, each per-batch BA over the last 4 batches (--ba-window 4;
# the final global BA over all images). --lengths "" skips the length sweep,
# --length-window 0 frees every image in every BA. --quick: room and
# two_floors, 8 s at 10 Hz, COLMAP with viosfm's pairs on room only (8 s of
# two_floors never leave the first floor), batch sizes 10 and 25 on room: a
# few minutes. --vio-profile realistic simulates the realistic emulated VIO
# (sim/vio_emulator.h: drift in time, distance and rotation, a 2 % scale
# error, correlated noise) instead of the gentle one the suite's published
# rows used. --colmap-scenarios limits COLMAP to some scenarios (datasets
# always get COLMAP).
#
# Two jobs run at a time (--jobs 2, the default, on 2 cores): the viosfm runs
# in one lane and the COLMAP runs in the other, each job single-threaded, so
# every figure is the time of a one-core run and viosfm and COLMAP are timed
# under the same conditions. --jobs 1 runs one job at a time with 2 threads.
# --lane viosfm or --lane colmap runs one lane only (two invocations into the
# same folder make the two lanes). The viosfm lane runs the full method on
# every sequence first (COLMAP's pairs come from it), then the ablations, the
# sweeps, and viosfm with its own VIO.
# The viosfm w/o relative-pose term run reuses the features and verified
# matches of the full run (its time covers the mapping only); COLMAP's two
# matchers share one feature extraction (both times include it).
# A finished run (time.txt without failed) is kept when the suite is run again
# into the same folder; --force reruns everything.
# Needs: viosfm built (make build), colmap, /usr/bin/time, sqlite3
# (VIOSFM_WITH_COLMAP=1 scripts/install-deps.sh installs them).
# PRESET (environment): viosfm run's --preset, default paper (the settings of the
# documented figures); PRESET=realtime runs viosfm's default.
set -euo pipefail

here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
out=out/bench-suite
quick=0
scenarios=""
datasets=()
dataset_vio=()
with_colmap=1
with_sweeps=1
with_runs=1
colmap_modes=""
colmap_scenarios=""
jobs=2
lane_only=""
force=0
lengths_arg=unset
length_window_arg=unset
vio_profile=gentle
docs=""
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
    --colmap-scenarios) colmap_scenarios=$2; shift ;;
    --jobs) jobs=$2; shift ;;
    --lane) lane_only=$2; shift ;;
    --force) force=1 ;;
    --docs) docs=$2; shift ;;
    --lengths) lengths_arg=$2; shift ;;
    --vio-profile) vio_profile=$2; shift ;;
    --length-window) length_window_arg=$2; shift ;;
    -h|--help) sed -n 2,50p "$0"; exit 0 ;;
    *) echo "bench/run.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done
if [ ${#datasets[@]} -ne ${#dataset_vio[@]} ]; then
  echo "bench/run.sh: every --dataset needs its --vio-trajectory (a TUM file of a VIO run on it)" >&2
  exit 2
fi
for i in "${!datasets[@]}"; do
  [ -d "${datasets[$i]}/mav0/cam0" ] ||
    { echo "bench/run.sh: ${datasets[$i]}: no mav0/cam0 (not a EuRoC-layout dataset)" >&2; exit 2; }
  [ -f "${dataset_vio[$i]}" ] ||
    { echo "bench/run.sh: ${dataset_vio[$i]}: file does not exist (--vio-trajectory)" >&2; exit 2; }
done
case "$jobs" in 1|2) ;; *) echo "bench/run.sh: --jobs must be 1 or 2" >&2; exit 2 ;; esac
case "$lane_only" in ""|viosfm|colmap) ;; *) echo "bench/run.sh: --lane must be viosfm or colmap" >&2; exit 2 ;; esac
[ -x "$VIOSFM" ] || { echo "bench/run.sh: $VIOSFM not built (make build)" >&2; exit 2; }
if [ $with_colmap = 1 ] && ! command -v colmap > /dev/null; then
  echo "bench/run.sh: colmap not found: install it (VIOSFM_WITH_COLMAP=1 scripts/install-deps.sh) or pass --no-colmap" >&2
  exit 2
fi
export QT_QPA_PLATFORM=offscreen

if [ $quick = 1 ]; then
  duration=8; rate=10; n1=6; n2=4; max_features=1000; batch=25
  default_scenarios="room two_floors"; default_modes="pairs"; default_colmap_scenarios="room"
  sweep_duration=8; batch_sizes="10 25"; lengths=""; length_window=0
else
  duration=63; rate=10; n1=10; n2=5; max_features=1000; batch=50
  default_scenarios="room two_floors corridor"; default_modes="pairs sequential"
  default_colmap_scenarios="room two_floors corridor"
  sweep_duration=30; batch_sizes="5 10 25 50 100 200"; lengths="300 600 1200 2400"
  length_window=4
fi
[ "$lengths_arg" != unset ] && lengths=$lengths_arg
[ "$length_window_arg" != unset ] && length_window=$length_window_arg
[ -z "$scenarios" ] && [ ${#datasets[@]} = 0 ] && scenarios=$default_scenarios
[ -z "$colmap_modes" ] && colmap_modes=$default_modes
[ -z "$colmap_scenarios" ] && colmap_scenarios=$default_colmap_scenarios
threads=$((jobs == 2 ? 1 : 2))
mkdir -p "$out"
out=$(cd "$out" && pwd)
# The published page (docs/benchmarks-suite.md) is rewritten only by a full
# run with COLMAP; any other run writes its page into the results folder, so
# that a partial run cannot replace the published COLMAP rows.
if [ -z "$docs" ]; then
  if [ "$with_colmap" = 1 ] && [ "$quick" = 0 ] && [ "$with_runs" = 1 ] && [ -z "$lane_only" ]; then
    docs=$here/docs/benchmarks-suite.md
  else
    docs=$out/report/benchmarks-suite.md
  fi
fi
# The viosfm version of the runs (meta.txt and each viosfm run's version.txt,
# so that a folder filled by several invocations says which made what).
version=${BENCH_VERSION:-$(git -C "$here" describe --always --dirty 2>/dev/null || echo unknown)}
{
  echo "date: $(date -u +%FT%TZ)"
  echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
  echo "memory_gib: $(awk '/MemTotal/ { printf "%.0f", $2 / 1048576 }' /proc/meminfo)"
  echo "mode: $([ $quick = 1 ] && echo quick || echo full)"
  echo "viosfm: $version"
  colmap_help=$(colmap -h 2> /dev/null || true)
  if [[ $colmap_help =~ COLMAP\ [0-9.]+ ]]; then
    echo "colmap: ${BASH_REMATCH[0]}"
  else
    echo "colmap: none"
  fi
  echo "settings: $duration s at $rate Hz, N1 $n1, N2 $n2, at most $max_features features, batch $batch"
  echo "jobs: $jobs at a time, $threads thread(s) each"
} > "$out/meta.txt"
echo "== bench: results in $out"

# done_run DIR: whether DIR holds a finished run to keep.
done_run() {
  [ $force = 0 ] && [ -s "$1/time.txt" ] && [ ! -f "$1/failed" ]
}

# timed DIR COMMAND...: runs COMMAND with its log in DIR/log.txt and writes
# "seconds peak_kib user_s system_s" to DIR/time.txt. A failed command leaves
# DIR/failed.
timed() {
  local dir=$1
  shift
  mkdir -p "$dir"
  rm -f "$dir/failed"
  if ! /usr/bin/time -f "%e %M %U %S" -o "$dir/time.txt" "$@" > "$dir/log.txt" 2>&1; then
    touch "$dir/failed"
    echo "   (failed, see $dir/log.txt)"
  fi
}

# evaluate DIR EST FORMAT SEQ [camera]: Sim(3) ATE of EST against SEQ's ground
# truth into DIR/eval.json (its alignment's scale: the metric scale), SE(3)
# ATE into DIR/eval_se3.json.
evaluate() {
  local dir=$1 est=$2 format=$3 seq=$4 cam=${5:-}
  local extra=()
  [ -n "$cam" ] && extra=(--extrinsics-yaml "$seq/mav0/cam0/sensor.yaml" --cam-frame est)
  mkdir -p "$dir"
  "$VIOSFM" eval --est "$est" --est-format "$format" \
    --ref "$seq/mav0/state_groundtruth_estimate0/data.csv" --ref-format euroc \
    --align sim3 --rpe-delta 0 "${extra[@]}" --json "$dir/eval.json" > "$dir/eval.txt" 2>&1 ||
    echo "   (evaluation failed, see $dir/eval.txt)"
  "$VIOSFM" eval --est "$est" --est-format "$format" \
    --ref "$seq/mav0/state_groundtruth_estimate0/data.csv" --ref-format euroc \
    --align se3 --rpe-delta 0 "${extra[@]}" --json "$dir/eval_se3.json" > "$dir/eval_se3.txt" 2>&1 ||
    rm -f "$dir/eval_se3.json"
}

# viosfm_run DIR SEQ VIO [args...]   (VIO "own": viosfm's own VIO). With
# REUSE=FOLDER set, starts from the database of the run in FOLDER.
viosfm_run() {
  local dir=$1 seq=$2 vio=$3
  shift 3
  if done_run "$dir"; then
    echo "-- viosfm run -> $dir (kept)"
  else
    echo "-- viosfm run -> $dir"
    rm -rf "$dir/run" "$dir/reused.txt"
    if [ -n "${REUSE:-}" ] && [ -f "$REUSE/run/database.db" ]; then
      mkdir -p "$dir"
      # The reused run's folder with its manifest: viosfm takes the copy as
      # its own (it refuses a folder it did not make) and re-maps it.
      cp -a "$REUSE/run" "$dir/run"
      echo "features and verified matches of $(basename "$REUSE")" > "$dir/reused.txt"
    fi
    local source=(--vio-trajectory "$vio")
    [ "$vio" = own ] && source=()
    mkdir -p "$dir"
    echo "$version" > "$dir/version.txt"
    timed "$dir" "$VIOSFM" run "$seq" --out "$dir/run" --preset "${PRESET:-paper}" "${source[@]}" --rate "$rate" \
      --n1 "$n1" --n2 "$n2" --max-features "$max_features" --threads "$threads" "$@"
  fi
  [ -f "$dir/run/trajectory_body.tum" ] && evaluate "$dir" "$dir/run/trajectory_body.tum" tum "$seq"
  return 0
}

# colmap_features DIR SEQ: COLMAP's feature extraction (same camera model,
# intrinsics and feature cap as viosfm) into DIR/database.db, once.
colmap_features() {
  local dir=$1 seq=$2
  done_run "$dir" && return 0
  echo "-- colmap feature_extractor -> $dir"
  rm -rf "$dir"
  mkdir -p "$dir"
  # The camera of the sequence (OPENCV, COLMAP's principal point convention).
  local params
  params=$(awk '
    /intrinsics:/ { gsub(/[\[\],]/, " "); fx = $2; fy = $3; cx = $4 + 0.5; cy = $5 + 0.5 }
    /distortion_coefficients:/ { gsub(/[\[\],]/, " "); k1 = $2; k2 = $3; p1 = $4; p2 = $5 }
    END { printf "%s,%s,%s,%s,%s,%s,%s,%s", fx, fy, cx, cy, k1, k2, p1, p2 }' "$seq/mav0/cam0/sensor.yaml")
  timed "$dir" colmap feature_extractor --database_path "$dir/database.db" \
    --image_path "$seq/mav0/cam0/data" \
    --ImageReader.camera_model OPENCV --ImageReader.single_camera 1 \
    --ImageReader.camera_params "$params" --SiftExtraction.use_gpu 0 \
    --SiftExtraction.num_threads "$threads" --SiftExtraction.max_num_features "$max_features"
}

# colmap_run DIR SEQ FEATURES MATCHER [PAIRS]: COLMAP matching + mapping on the
# features in FEATURES/database.db; DIR/time.txt includes the extraction.
colmap_run() {
  local dir=$1 seq=$2 features=$3 matcher=$4 pairs=${5:-}
  if done_run "$dir"; then
    echo "-- colmap ($matcher) -> $dir (kept)"
  elif [ -f "$features/failed" ] || [ ! -f "$features/database.db" ]; then
    echo "-- colmap ($matcher) -> $dir: no features (see $features/log.txt)"
    mkdir -p "$dir"
    touch "$dir/failed"
    return 0
  else
    echo "-- colmap ($matcher) -> $dir"
    rm -rf "$dir"
    mkdir -p "$dir/sparse"
    cp "$features/database.db" "$dir/database.db"
    {
      echo "set -e"
      if [ "$matcher" = pairs ]; then
        echo "colmap matches_importer --database_path '$dir/database.db'" \
          "--match_list_path '$pairs' --match_type pairs --SiftMatching.use_gpu 0" \
          "--SiftMatching.num_threads $threads"
      else
        echo "colmap sequential_matcher --database_path '$dir/database.db'" \
          "--SiftMatching.use_gpu 0 --SiftMatching.num_threads $threads" \
          "--SequentialMatching.overlap $n1 --SequentialMatching.loop_detection 0"
      fi
      echo "colmap mapper --database_path '$dir/database.db' --image_path '$seq/mav0/cam0/data'" \
        "--output_path '$dir/sparse' --Mapper.num_threads $threads"
    } > "$dir/run.sh"
    timed "$dir" bash "$dir/run.sh"
    # Extraction + matching + mapping.
    local e_s e_kib e_u e_sys m_s m_kib m_u m_sys
    read -r e_s e_kib e_u e_sys < "$features/time.txt"
    read -r m_s m_kib m_u m_sys < "$dir/time.txt"
    awk -v a="$e_s" -v b="$m_s" -v ka="$e_kib" -v kb="$m_kib" -v ua="$e_u" -v ub="$m_u" \
      -v sa="$e_sys" -v sb="$m_sys" \
      'BEGIN { printf "%.2f %d %.2f %.2f\n", a + b, (ka > kb ? ka : kb), ua + ub, sa + sb }' \
      > "$dir/time.txt"
    echo "matching and mapping $m_s s, feature extraction $e_s s ($features)" > "$dir/stages.txt"
  fi
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

# viosfm_full NAME SEQ VIO: the input VIO and the full method on one sequence.
viosfm_full() {
  local name=$1 seq=$2 vio=$3
  local root="$out/$name/runs"
  echo "== $name: viosfm"
  evaluate "$root/vio" "$vio" tum "$seq"
  viosfm_run "$root/viosfm" "$seq" "$vio" --batch-size "$batch"
}

# viosfm_ablations NAME SEQ VIO: the ablations on one sequence.
viosfm_ablations() {
  local name=$1 seq=$2 vio=$3
  local root="$out/$name/runs"
  echo "== $name: viosfm ablations"
  REUSE="$root/viosfm" viosfm_run "$root/viosfm_no_rpc" "$seq" "$vio" --batch-size "$batch" --no-rpc
  REUSE="$root/viosfm" viosfm_run "$root/viosfm_paper_weighting" "$seq" "$vio" \
    --batch-size "$batch" --prior-weighting paper
  REUSE="$root/viosfm" viosfm_run "$root/viosfm_no_bridging" "$seq" "$vio" --batch-size "$batch" \
    --no-bridging
  viosfm_run "$root/viosfm_no_vio_check" "$seq" "$vio" --batch-size "$batch" --no-vio-prior
}

# viosfm_own NAME SEQ: viosfm with its own VIO (images + IMU only) on one
# sequence, and that VIO's trajectory.
viosfm_own() {
  local name=$1 seq=$2
  local root="$out/$name/runs"
  viosfm_run "$root/viosfm_own_vio" "$seq" own --batch-size "$batch"
  [ -f "$root/viosfm_own_vio/run/vio/trajectory_body.tum" ] &&
    evaluate "$root/own_vio" "$root/viosfm_own_vio/run/vio/trajectory_body.tum" tum "$seq"
  return 0
}

# colmap_all NAME SEQ MODES: COLMAP on one sequence; the "pairs" mode waits for
# viosfm's candidate pairs of the sequence.
colmap_all() {
  local name=$1 seq=$2 modes=$3
  local root="$out/$name/runs"
  echo "== $name: COLMAP"
  colmap_features "$out/$name/colmap_features" "$seq"
  if [[ " $modes " == *" pairs "* ]]; then
    local pairs="$root/viosfm/run/verification/pairs.csv"
    # (GNU time creates its output file at the start and fills it at the end.)
    while [ ! -s "$root/viosfm/time.txt" ]; do sleep 10; done
    if [ -f "$pairs" ]; then
      tail -n +2 "$pairs" | cut -d, -f3,4 | tr , ' ' > "$out/$name/pairs.txt"
      colmap_run "$root/colmap_same_pairs" "$seq" "$out/$name/colmap_features" pairs \
        "$out/$name/pairs.txt"
    else
      echo "   (no viosfm pairs for $name: $root/viosfm failed)"
    fi
  fi
  if [[ " $modes " == *" sequential "* ]]; then
    colmap_run "$root/colmap_sequential" "$seq" "$out/$name/colmap_features" sequential
  fi
  return 0
}

simulate() {
  local scenario=$1 seconds=$2 dest=$3
  if [ ! -f "$dest/simulation.yaml" ]; then
    echo "-- simulate $scenario, $seconds s at $rate Hz -> $dest"
    mkdir -p "$(dirname "$dest")"
    "$VIOSFM" simulate --scenario "$scenario" --duration "$seconds" --rate "$rate" --seed 0 \
      --vio-profile "$vio_profile" --out "$dest" > "$dest.log" 2>&1
  fi
}

# The sequences: simulated scenarios, then the user's datasets.
names=()
seqs=()
vios=()
for scenario in $scenarios; do
  simulate "$scenario" "$duration" "$out/$scenario/sequence"
  names+=("$scenario")
  seqs+=("$out/$scenario/sequence")
  vios+=("$out/$scenario/sequence/vio_emulated.tum")
done
num_simulated=${#names[@]}
for i in "${!datasets[@]}"; do
  name=$(basename "${datasets[$i]}")
  # The report finds every sequence at RESULTS/NAME/sequence: a link to the dataset.
  mkdir -p "$out/$name"
  ln -sfn "$(cd "${datasets[$i]}" && pwd)" "$out/$name/sequence"
  names+=("$name")
  seqs+=("${datasets[$i]}")
  vios+=("${dataset_vio[$i]}")
done
# The batch-size sweep's sequence: room of sweep_duration seconds (the room
# scenario itself when it has that length).
sweep_name=room_${sweep_duration}s
[ "$sweep_duration" = "$duration" ] && [[ " $scenarios " == *" room "* ]] && sweep_name=room
[ $with_sweeps = 1 ] && simulate room "$sweep_duration" "$out/$sweep_name/sequence"

# Lane 2: COLMAP (in the background with --jobs 2).
colmap_lane() {
  [ $with_colmap = 1 ] || return 0
  if [ $with_runs = 1 ]; then
    for i in "${!names[@]}"; do
      # Simulated scenarios outside --colmap-scenarios go without COLMAP.
      if [ "$i" -lt "$num_simulated" ] &&
        [[ " $colmap_scenarios " != *" ${names[$i]} "* ]]; then
        continue
      fi
      colmap_all "${names[$i]}" "${seqs[$i]}" "$colmap_modes"
    done
  fi
  [ $with_sweeps = 1 ] && colmap_all "$sweep_name" "$out/$sweep_name/sequence" pairs
  return 0
}

# Lane 1: viosfm. The full method on every sequence first (COLMAP's pairs
# come from it), then the ablations, the sweeps and the own-VIO runs.
viosfm_lane() {
  if [ $with_runs = 1 ]; then
    for i in "${!names[@]}"; do viosfm_full "${names[$i]}" "${seqs[$i]}" "${vios[$i]}"; done
    for i in "${!names[@]}"; do viosfm_ablations "${names[$i]}" "${seqs[$i]}" "${vios[$i]}"; done
  fi
  if [ $with_sweeps = 1 ]; then
    local seq="$out/$sweep_name/sequence"
    # The sweep sequence's reference rows: its VIO and viosfm at the default
    # batch size (whose pairs COLMAP gets); every batch size reuses its
    # features and verified matches, so the sweep times the mapping.
    evaluate "$out/$sweep_name/runs/vio" "$seq/vio_emulated.tum" tum "$seq"
    viosfm_run "$out/$sweep_name/runs/viosfm" "$seq" "$seq/vio_emulated.tum" --batch-size "$batch"
    echo "$sweep_name" > "$out/batch_size_sequence.txt"
    for k in $batch_sizes; do
      REUSE="$out/$sweep_name/runs/viosfm" viosfm_run "$out/batch_size/$k" "$seq" \
        "$seq/vio_emulated.tum" --batch-size "$k"
    done
    for frames in $lengths; do
      local lseq="$out/length/$frames/sequence"
      simulate room "$((frames / rate))" "$lseq"
      viosfm_run "$out/length/$frames" "$lseq" "$lseq/vio_emulated.tum" --batch-size "$batch" \
        --ba-window "$length_window"
    done
  fi
  if [ $with_runs = 1 ]; then
    for i in "${!names[@]}"; do viosfm_own "${names[$i]}" "${seqs[$i]}"; done
  fi
  return 0
}

if [ "$lane_only" = viosfm ]; then
  viosfm_lane
elif [ "$lane_only" = colmap ]; then
  colmap_lane
elif [ "$jobs" = 2 ]; then
  colmap_lane > "$out/colmap_lane.log" 2>&1 &
  lane=$!
  viosfm_lane
  echo "== waiting for the COLMAP runs ($out/colmap_lane.log)"
  wait "$lane"
  cat "$out/colmap_lane.log"
else
  viosfm_lane
  colmap_lane
fi

"$VIOSFM" bench-report "$out" --markdown "$docs" --figures "$(dirname "$docs")/images"
echo "== bench: tables in $docs"
