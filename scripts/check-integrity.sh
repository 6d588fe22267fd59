#!/usr/bin/env bash
# End-to-end integrity checks of `viosfm run` on a small simulated sequence
# (docs/robustness.md, "Run integrity"), one line of results each:
#   1. identical re-runs: two runs from scratch (--threads 1) give the same
#      bytes (models, trajectories, PLY, summary.json without its timings),
#      and so do two with --realtime;
#   2. a second dataset (another seed: the same image names and stamps) into
#      the first one's folder is refused and leaves it as it was; with
#      --overwrite it is recomputed, as a run of it from scratch, the earlier
#      report.html and export/ are gone and the user's files stay;
#   3. SIGKILL at 5 points spread over the stages, then the same command
#      again: no killed folder looks complete, each re-run ends identical to
#      the uninterrupted run;
#   4. threads: runs with --threads 2 against --threads 1 (ATE, points, poses);
#   5. hostile inputs: the fuzz seed corpora (fuzz/corpus) and deterministic
#      mutations of them, read through the viosfm command; a crash is any
#      exit other than 0, 1 (usage) or 2 (input error), or a time-out;
#   6. what a careless or hostile user tries (docs/robustness.md's table):
#      each command's exit code, the file its message names, every file of
#      the user's byte-identical afterwards, the peak memory where it is
#      bounded, and for the IMU rows an input error or a model whose scale is
#      within 1 % of the clean run's.
#
# Usage: scripts/check-integrity.sh [BUILD_DIR [WORK_DIR]]
#   BUILD_DIR  default build (needs build/src/viosfm/cli/viosfm)
#   WORK_DIR   default BUILD_DIR/integrity (emptied first); logs in WORK_DIR/logs
# Takes about 20 minutes on 2 cores. Exit status 1 if any check fails.
set -uo pipefail

BUILD_DIR=${1:-build}
WORK=${2:-$BUILD_DIR/integrity}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=$(realpath "$BUILD_DIR/src/viosfm/cli/viosfm" 2>/dev/null || true)
if [[ -z "$VIOSFM" || ! -x "$VIOSFM" ]]; then
  echo "check-integrity: no viosfm in $BUILD_DIR (build it: ninja -C $BUILD_DIR viosfm)" >&2
  exit 2
fi
rm -rf "$WORK" || { echo "check-integrity: cannot empty $WORK" >&2; exit 2; }
mkdir -p "$WORK/logs"
WORK=$(realpath "$WORK")
LOGS=$WORK/logs
FAILED=0
SECONDS=0

# Small settings: 80 moving frames, a few minutes for everything.
SIM_ARGS=(--scenario room --duration 10 --rate 10 --threads 1)
# Pairs stored every 40 (instead of 2000), so that a kill in the verification
# leaves a half-verified pair set behind.
RUN_ARGS=(--no-progress --max-features 1000 --n1 6 --n2 3 --batch-size 20 --verification-batch 40)

say() { echo "$*"; }
# (also from background jobs: the marker file carries the failure out)
fail() {
  FAILED=1
  touch "$WORK/failed"
  echo "FAILED: $*"
}

# run NAME DATASET OUT [extra args...]: viosfm run, log in LOGS/NAME.log; returns its exit code.
run() {
  local name=$1 dataset=$2 out=$3
  shift 3
  "$VIOSFM" run "$dataset" --out "$out" "${RUN_ARGS[@]}" "$@" >"$LOGS/$name.log" 2>&1
}

# compare DIR1 DIR2: "N of M identical" and the differing files (to stdout).
# Byte comparison, except: JSON files without timings, dates, resumed counts
# and the output folder's path; pairs.csv without its 'resumed' column.
compare() {
  python3 - "$1" "$2" <<'PY'
import csv, io, json, os, sys
a, b = sys.argv[1], sys.argv[2]
files = ["model/cameras.bin", "model/images.bin", "model/points3D.bin",
         "model_txt/cameras.txt", "model_txt/images.txt", "model_txt/points3D.txt",
         "points.ply", "trajectory_cam.tum", "trajectory_body.tum", "vio_body.tum",
         "groundtruth_body.tum", "eval.json", "eval_vio.json", "fingerprint.json",
         "vio/trajectory_body.tum", "vio/states.csv", "verification/pairs.csv",
         "verification/verification.json", "summary.json"]
DROP = ("seconds", "started_utc", "peak_memory_mb", "resumed", "database")
def clean(value, folder):
    if isinstance(value, dict):
        return {k: clean(v, folder) for k, v in value.items()
                if not any(d in k for d in DROP)}
    if isinstance(value, list):
        return [clean(v, folder) for v in value]
    if isinstance(value, str):
        return value.replace(folder, "OUT")
    return value
def content(folder, name):
    path = os.path.join(folder, name)
    if not os.path.exists(path):
        return None
    data = open(path, "rb").read()
    if name.endswith(".json"):
        return json.dumps(clean(json.loads(data), folder), sort_keys=True)
    if name.endswith("pairs.csv"):
        rows = list(csv.reader(io.StringIO(data.decode())))
        if rows and "resumed" in rows[0]:
            k = rows[0].index("resumed")
            rows = [r[:k] + r[k + 1:] for r in rows]
        return rows
    return data
same = [f for f in files if content(a, f) is not None and content(a, f) == content(b, f)]
differ = [f for f in files if f not in same]
print(f"{len(same)} of {len(files)} files identical" +
      (f"; different or missing: {' '.join(differ)}" if differ else ""))
sys.exit(0 if not differ else 1)
PY
}

# ------------------------------------------------------------------ datasets
"$VIOSFM" simulate --out "$WORK/simA" --seed 1 "${SIM_ARGS[@]}" >"$LOGS/simA.log" 2>&1 &
"$VIOSFM" simulate --out "$WORK/simB" --seed 2 "${SIM_ARGS[@]}" >"$LOGS/simB.log" 2>&1 &
wait
if ! cmp -s "$WORK/simA/mav0/cam0/data.csv" "$WORK/simB/mav0/cam0/data.csv"; then
  fail "the two simulated datasets should share their image names and stamps"
fi

# ------------------------------------------------------- 1. identical re-runs
run ref "$WORK/simA" "$WORK/ref" --threads 1 &
pid_ref=$!
run again "$WORK/simA" "$WORK/again" --threads 1 &
pid_again=$!
wait $pid_ref || fail "reference run (log: $LOGS/ref.log)"
wait $pid_again || fail "second run (log: $LOGS/again.log)"
if result=$(compare "$WORK/ref" "$WORK/again"); then
  say "identical re-runs (--threads 1, two runs from scratch): $result"
else
  fail "identical re-runs: $result"
fi
# The same with --realtime (guided matching, the windowed adjustments), its
# two runs one after the other.
run rt1 "$WORK/simA" "$WORK/rt1" --threads 1 --realtime || fail "--realtime run (log: $LOGS/rt1.log)"
run rt2 "$WORK/simA" "$WORK/rt2" --threads 1 --realtime || fail "--realtime run (log: $LOGS/rt2.log)"
if result=$(compare "$WORK/rt1" "$WORK/rt2"); then
  say "identical re-runs (--realtime --threads 1, two runs from scratch): $result"
else
  fail "identical re-runs with --realtime: $result"
fi

# Stage durations of the reference run (s), for the kill points.
stage_seconds() {
  python3 -c "import json,sys; s=json.load(open('$WORK/ref/summary.json'))
print([x['seconds'] for x in s['stages'] if x['name']=='$1'][0])"
}

# ----------------------------------------------- 2. a second dataset, same folder
# Every file of a folder with its checksum.
checksums() { (cd "$1" && find . -type f -print0 | sort -z | xargs -0 sha256sum); }
cp -r "$WORK/ref" "$WORK/second"
# The earlier model's report and export, and files of the user's beside and
# inside viosfm's folders: --overwrite removes the first two, never the rest.
"$VIOSFM" --log-level error report "$WORK/second" >/dev/null 2>&1 || fail "report of $WORK/second"
"$VIOSFM" --log-level error export "$WORK/second" >/dev/null 2>&1 || fail "export of $WORK/second"
echo "the user's notes" >"$WORK/second/notes.txt"
echo "the user's plot" >"$WORK/second/vio/my_plot.svg"
mkdir -p "$WORK/second/export/colmap_sparse/0"
echo "COLMAP's model, the user's" >"$WORK/second/export/colmap_sparse/0/images.bin"
user_files=(notes.txt vio/my_plot.svg export/colmap_sparse/0/images.bin)
user_before=$(cd "$WORK/second" && sha256sum "${user_files[@]}")
before=$(checksums "$WORK/second")
run second_refused "$WORK/simB" "$WORK/second" --threads 1
code=$?
changed=$(grep -o "[a-z_./0-9]* was '" "$LOGS/second_refused.log" | sed "s/ was '//" | tr '\n' ' ')
if [[ $code -eq 2 && "$(checksums "$WORK/second")" == "$before" ]]; then
  refused="refused (exit 2; changed: ${changed% }); every file of the folder unchanged"
else
  fail "second dataset: exit $code, expected 2 and an unchanged folder (log: $LOGS/second_refused.log)"
  refused="NOT refused (exit $code)"
fi
run second_overwrite "$WORK/simB" "$WORK/second" --threads 1 --overwrite &
pid_over=$!
run freshB "$WORK/simB" "$WORK/freshB" --threads 1 &
pid_fresh=$!
wait $pid_over || fail "second dataset with --overwrite (log: $LOGS/second_overwrite.log)"
wait $pid_fresh || fail "run of the second dataset (log: $LOGS/freshB.log)"
extracted=$(grep -o "features [0-9]* images ([0-9]* extracted, [0-9]* already stored)" \
  "$LOGS/second_overwrite.log" | head -1)
if result=$(compare "$WORK/freshB" "$WORK/second"); then
  say "second dataset into the same folder: $refused; with --overwrite recomputed ($extracted), as a run of it from scratch: $result"
else
  fail "second dataset with --overwrite: $result"
fi
stale=""
for file in report.html export/transforms.json export/database.db export/sparse/0/images.bin; do
  [[ -e "$WORK/second/$file" ]] && stale="$stale $file"
done
if [[ -z $stale && "$(cd "$WORK/second" && sha256sum "${user_files[@]}")" == "$user_before" ]]; then
  overwrite_row="--overwrite removed the earlier report.html and export/ (viosfm's), kept the user's ${#user_files[@]} files byte for byte"
  say "  $overwrite_row"
else
  fail "--overwrite: stale files left:${stale:- none}; the user's files $( [[ "$(cd "$WORK/second" && sha256sum "${user_files[@]}" 2>&1)" == "$user_before" ]] && echo unchanged || echo CHANGED)"
fi

# ----------------------------------------------------------- 3. SIGKILL points
# kill_point NAME STAGE FRACTION [COPY_OF]: starts the reference command into
# WORK/kill_NAME (a copy of COPY_OF if given), kills it with SIGKILL when
# FRACTION of the reference's STAGE time has passed in STAGE, checks that the
# folder does not look complete, runs the same command again and compares.
kill_point() {
  local name=$1 stage=$2 fraction=$3 copy_of=${4:-}
  local out=$WORK/kill_$name log=$LOGS/kill_$name.log
  [[ -n "$copy_of" ]] && cp -r "$copy_of" "$out"
  local delay
  delay=$(python3 -c "print(f'{$(stage_seconds "$stage") * $fraction:.2f}')")
  "$VIOSFM" run "$WORK/simA" --out "$out" "${RUN_ARGS[@]}" --threads 1 >"$log" 2>&1 &
  local pid=$! waited=0
  until grep -q "run \[[0-9]*/10\] $stage\$" "$log" 2>/dev/null; do
    if ! kill -0 $pid 2>/dev/null || ((waited > 6000)); then break; fi
    sleep 0.05
    waited=$((waited + 1))
  done
  sleep "$delay"
  local at
  at=$(grep -o "run \[[0-9]*/10\] [a-z_]*$" "$log" | tail -1 | sed 's/.*\] //')
  kill -9 $pid 2>/dev/null
  wait $pid 2>/dev/null
  local code=$?
  local line="kill in $stage (+$delay s, during '$at', exit $code)"
  if [[ $code -ne 137 ]]; then
    line="$line: finished before the kill"
  elif [[ -f "$out/summary.json" ]]; then
    fail "killed run $name left a summary.json: the folder looks complete"
    line="$line: LOOKS COMPLETE"
  else
    # What reads a finished run refuses the killed one.
    "$VIOSFM" --log-level error export "$out" --out "$WORK/export_$name" >/dev/null 2>&1
    local export_code=$?
    [[ $export_code -eq 2 ]] || fail "viosfm export of killed run $name: exit $export_code, expected 2"
    line="$line: incomplete (no summary.json; export exit $export_code)"
  fi
  if ! run "kill_${name}_rerun" "$WORK/simA" "$out" --threads 1; then
    fail "re-run after the kill $name (log: $LOGS/kill_${name}_rerun.log)"
    echo "$line; re-run FAILED" >"$WORK/kill_$name.result"
    return
  fi
  # What the re-run found stored.
  local stored_features stored_pairs
  stored_features=$(grep -o "features [0-9]* images ([0-9]* extracted, [0-9]* already stored)" \
    "$LOGS/kill_${name}_rerun.log" | head -1 | sed 's/features \([0-9]*\) images ([0-9]* extracted, \([0-9]*\) .*/\2 of \1/')
  stored_pairs=$(grep -o "verification: [0-9]* pairs .*; [0-9]* already stored" \
    "$LOGS/kill_${name}_rerun.log" | head -1 | sed 's/verification: \([0-9]*\) pairs .*; \([0-9]*\) already stored/\2 of \1/')
  line="$line; the re-run found ${stored_features:-no} images' features and ${stored_pairs:-no} pairs stored"
  local result
  if result=$(compare "$WORK/ref" "$out"); then
    echo "$line; re-run: $result" >"$WORK/kill_$name.result"
  else
    fail "re-run after the kill $name: $result"
    echo "$line; re-run: $result" >"$WORK/kill_$name.result"
  fi
}
kill_point vio vio 0.5 &
kill_point features features 0.5 &
wait
kill_point verification verification 0.4 &
kill_point mapper_of_a_rerun mapper 0.5 "$WORK/again" &
wait
kill_point write_outputs write_outputs 0.2
num_identical=0
for name in vio features verification mapper_of_a_rerun write_outputs; do
  grep -q "re-run: 19 of 19 files identical" "$WORK/kill_$name.result" &&
    num_identical=$((num_identical + 1))
done
say "SIGKILL at 5 points, then the same command: $num_identical of 5 re-runs identical to the uninterrupted run"
for name in vio features verification mapper_of_a_rerun write_outputs; do
  say "  $name: $(cat "$WORK/kill_$name.result")"
done

# ----------------------------------------------------------------- 4. threads
run threads2a "$WORK/simA" "$WORK/threads2a" --threads 2 || fail "run with --threads 2"
run threads2b "$WORK/simA" "$WORK/threads2b" --threads 2 || fail "second run with --threads 2"
threads=$(python3 - "$WORK/ref" "$WORK/threads2a" "$WORK/threads2b" <<'PY'
import json, sys, math
def load(folder):
    s = json.load(open(f"{folder}/summary.json"))
    poses = {}
    for line in open(f"{folder}/trajectory_body.tum"):
        if line.startswith("#") or not line.strip():
            continue
        v = line.split()
        poses[v[0]] = [float(x) for x in v[1:4]]
    return s, poses
ref, ref_poses = load(sys.argv[1])
parts = []
bounded = True
for folder in sys.argv[2:]:
    s, poses = load(folder)
    common = [k for k in poses if k in ref_poses]
    d = max(math.dist(poses[k], ref_poses[k]) for k in common)
    ate, ref_ate = s['eval']['ate_rmse_m'], ref['eval']['ate_rmse_m']
    parts.append(f"points {s['points']} vs {ref['points']}, observations {s['observations']} vs "
                 f"{ref['observations']}, registered {s['frames']['registered']} vs "
                 f"{ref['frames']['registered']}, ATE {1000 * ate:.4f} vs {1000 * ref_ate:.4f} mm "
                 f"(difference {abs(ate - ref_ate):.1e} m), largest camera position difference "
                 f"{d:.1e} m over {len(common)} frames")
    # The bound: floating-point summation order, nothing more.
    bounded = bounded and d < 1e-6 and abs(ate - ref_ate) < 1e-6 and len(common) == len(ref_poses)
print("; ".join(parts))
sys.exit(0 if bounded else 1)
PY
)
threads_code=$?
t2same=$(compare "$WORK/threads2a" "$WORK/threads2b" | cut -d';' -f1)
t12same=$(compare "$WORK/ref" "$WORK/threads2a" | cut -d';' -f1)
say "threads: two runs with --threads 2 against one with --threads 1: $threads; byte comparison: the two --threads 2 runs $t2same, --threads 2 against 1 $t12same"
[[ $threads_code -eq 0 ]] || fail "threads: differences beyond 1e-6 m"

# ---------------------------------------------------------- 5. hostile inputs
# A minimal EuRoC folder whose files the inputs replace; its images are not
# PNGs, so every command stops at the latest when it decodes one.
hostile_dataset() {
  local mav0=$1/mav0
  mkdir -p "$mav0/cam0/data" "$mav0/imu0"
  printf '#timestamp [ns],filename\n1000,a.png\n2000,b.png\n' >"$mav0/cam0/data.csv"
  echo x >"$mav0/cam0/data/a.png"
  echo x >"$mav0/cam0/data/b.png"
  printf 'T_BS: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\nresolution: [640, 480]\nintrinsics: [500, 500, 320, 240]\n' >"$mav0/cam0/sensor.yaml"
  printf 'gyroscope_noise_density: 1e-4\ngyroscope_random_walk: 1e-5\naccelerometer_noise_density: 1e-3\naccelerometer_random_walk: 1e-3\n' >"$mav0/imu0/sensor.yaml"
  printf '500,0,0,0,0,0,9.81\n2500,0,0,0,0,0,9.81\n' >"$mav0/imu0/data.csv"
}
HOSTILE=$WORK/hostile
mkdir -p "$HOSTILE/inputs"
# The corpus files and deterministic mutations of each: truncations, byte
# flips, deleted and repeated chunks, and hostile values in place of numbers.
python3 - "$ROOT/fuzz/corpus" "$HOSTILE/inputs" <<'PY'
import os, random, sys
corpus, out = sys.argv[1], sys.argv[2]
rng = random.Random(17)
specials = [b"nan", b"inf", b"-1", b"1e999", b"18446744073709551617", b"\x00", b"",
            b"9" * 400, b"-0", b"0x10"]
for parser in sorted(os.listdir(corpus)):
    os.makedirs(os.path.join(out, parser), exist_ok=True)
    for name in sorted(os.listdir(os.path.join(corpus, parser))):
        data = open(os.path.join(corpus, parser, name), "rb").read()
        variants = [data]
        for k in range(1, 9):
            variants.append(data[: len(data) * k // 9])
        for _ in range(10):
            mutated = bytearray(data)
            for _ in range(rng.randint(1, 4)):
                if mutated:
                    mutated[rng.randrange(len(mutated))] = rng.randrange(256)
            variants.append(bytes(mutated))
        for _ in range(4):
            i, j = sorted(rng.randrange(len(data) + 1) for _ in range(2))
            variants.append(data[:i] + data[j:])
            variants.append(data[:j] + data[i:j] * rng.randint(2, 50) + data[j:])
        digits = [i for i, c in enumerate(data) if chr(c).isdigit()]
        for special in specials:
            if digits:
                i = rng.choice(digits)
                j = i
                while j < len(data) and (chr(data[j]).isdigit() or data[j] in b".e-+"):
                    j += 1
                variants.append(data[:i] + special + data[j:])
        for k, variant in enumerate(variants):
            open(os.path.join(out, parser, f"{name}.{k:03d}"), "wb").write(variant)
PY
# Splits a multi-file input at the fuzzers' separator (fuzz/fuzz_util.h).
split_input() {
  python3 - "$@" <<'PY'
import sys
data = open(sys.argv[1], "rb").read()
outputs = sys.argv[2:]
parts = data.split(b"\n#--viosfm-fuzz-next-file--\n", len(outputs) - 1)
parts += [b""] * (len(outputs) - len(parts))
for path, part in zip(outputs, parts):
    open(path, "wb").write(part)
PY
}
num_inputs=0
num_runs=0
num_crashes=0
crashes=""
try() {
  local input=$1
  shift
  num_runs=$((num_runs + 1))
  timeout 60 "$VIOSFM" --log-level error "$@" >/dev/null 2>"$HOSTILE/stderr"
  local code=$?
  if [[ $code -ne 0 && $code -ne 1 && $code -ne 2 ]]; then
    num_crashes=$((num_crashes + 1))
    crashes="$crashes $(basename "$input")(exit $code: $*)"
    cp "$input" "$HOSTILE/crash_$(basename "$input")"
  fi
}
for input in "$HOSTILE"/inputs/*/*; do
  parser=$(basename "$(dirname "$input")")
  dir=$HOSTILE/case
  rm -rf "$dir"
  mkdir -p "$dir"
  hostile_dataset "$dir/dataset"
  mav0=$dir/dataset/mav0
  num_inputs=$((num_inputs + 1))
  case $parser in
    tum | kitti | euroc_trajectory)
      format=${parser%_trajectory}
      try "$input" eval --est "$input" --ref "$input" --est-format "$format" --ref-format "$format"
      ;;
    euroc_csv)
      mkdir -p "$mav0/state_groundtruth_estimate0"
      split_input "$input" "$mav0/cam0/data.csv" "$mav0/imu0/data.csv" \
        "$mav0/state_groundtruth_estimate0/data.csv"
      try "$input" vio "$dir/dataset" --out "$dir/out"
      try "$input" eval --est "$mav0/state_groundtruth_estimate0/data.csv" \
        --ref "$mav0/state_groundtruth_estimate0/data.csv" --est-format euroc --ref-format euroc
      ;;
    euroc_yaml)
      cp "$input" "$mav0/cam0/sensor.yaml"
      try "$input" vio "$dir/dataset" --out "$dir/out"
      hostile_dataset "$dir/dataset"
      cp "$input" "$mav0/imu0/sensor.yaml"
      try "$input" vio "$dir/dataset" --out "$dir/out"
      ;;
    kalibr)
      split_input "$input" "$dir/camchain.yaml" "$dir/imu.yaml"
      try "$input" vio "$dir/dataset" --out "$dir/out" --calibration "$dir/camchain.yaml" \
        --imu-calibration "$dir/imu.yaml"
      ;;
    colmap_text | colmap_binary)
      mkdir -p "$dir/model"
      ext=txt
      [[ $parser == colmap_binary ]] && ext=bin
      split_input "$input" "$dir/model/cameras.$ext" "$dir/model/images.$ext" \
        "$dir/model/points3D.$ext"
      try "$input" eval --est "$dir/model" --ref "$dir/model" --est-format colmap \
        --ref-format colmap
      ;;
    colmap_database)
      cp "$input" "$dir/database.db"
      try "$input" features "$dir/dataset" --database "$dir/database.db"
      cp "$input" "$dir/database.db"
      try "$input" match "$dir/dataset" --database "$dir/database.db"
      ;;
    *)
      # io_other (PLY, vocabulary, pair lists, scene.csv): no viosfm command
      # reads these from a user's file alone; `make fuzz` covers them.
      num_inputs=$((num_inputs - 1))
      ;;
  esac
done
if [[ $num_crashes -eq 0 ]]; then
  say "hostile inputs: $num_inputs inputs (the fuzz corpora of 9 parsers and mutations of them), $num_runs viosfm commands, 0 crashes"
else
  fail "hostile inputs: $num_crashes crashes of $num_runs commands:$crashes"
fi

# ------------------------------------------- 6. what a careless or hostile user tries
# The rows of docs/robustness.md's table "What a careless or hostile user
# tried": each command must give its exit code, its message must name the
# file (or the flag) at fault, and every file below the folders it lists
# (none of them written by viosfm) must be byte-identical afterwards; an IMU
# row passes with an input error or with a model whose metric scale (Sim(3)
# against the ground truth) is within 1 % of the clean run's.
A=$WORK/attacks
mkdir -p "$A"
SEQ=$WORK/simA
num_rows=0
num_rows_ok=0
# Every file and link below the given paths with its checksum.
tree_sums() {
  local path
  for path in "$@"; do
    if [[ ! -e $path ]]; then
      echo "absent $path"
      continue
    fi
    (cd "$path" && find . \( -type f -o -type l \) -print0 | sort -z | xargs -0 -r sha256sum --)
  done
}
# The line a user reads: the error, else the first warning.
message_of() { grep -m1 "^error:" "$1" || grep -m1 "^W " "$1" || true; }
row_result() {  # NAME ok|bad DETAIL
  num_rows=$((num_rows + 1))
  if [[ $2 == ok ]]; then
    num_rows_ok=$((num_rows_ok + 1))
    say "  $1: $3"
  else
    fail "attack $1: $3"
  fi
}
# measured LOG ARGS...: viosfm ARGS with its output in LOG; prints its exit
# code and its peak resident memory (MB).
measured() {
  local log=$1
  shift
  python3 - "$log" "$VIOSFM" "$@" <<'PY'
import resource, subprocess, sys
log, command = sys.argv[1], sys.argv[2:]
with open(log, "w") as out:
    code = subprocess.call(command, stdout=out, stderr=subprocess.STDOUT)
print(code, int(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024))
PY
}
# attack NAME CODE NAMED KEEP... -- ARGS...: viosfm ARGS must exit with
# CODE, name NAMED in its output, leave every file below each KEEP path as it
# was, and (with LIMIT_MB set) stay below LIMIT_MB of resident memory.
attack() {
  local name=$1 code=$2 named=$3
  shift 3
  local keep=()
  while [[ $1 != -- ]]; do
    keep+=("$1")
    shift
  done
  shift
  local log=$LOGS/attack_$name.log before after got peak problems=""
  before=$(tree_sums "${keep[@]}")
  read -r got peak < <(measured "$log" "$@")
  after=$(tree_sums "${keep[@]}")
  [[ $got -eq $code ]] || problems+="exit $got (expected $code); "
  grep -qF -- "$named" "$log" || problems+="the message does not name '$named'; "
  [[ "$before" == "$after" ]] || problems+="files viosfm did not write changed; "
  [[ -z ${LIMIT_MB:-} || $peak -le ${LIMIT_MB:-0} ]] || problems+="peak memory $peak MB > $LIMIT_MB MB; "
  if [[ -z $problems ]]; then
    row_result "$name" ok "exit $got, peak $peak MB, ${#keep[@]} folder(s) unchanged: $(message_of "$log" | cut -c1-240)"
  else
    row_result "$name" bad "${problems}log $log"
  fi
}
# A copy of the clean dataset (images hard-linked: no command writes into a
# dataset, and a file replaced below is a new file).
dataset_copy() {
  rm -rf "$A/$1"
  cp -al "$SEQ" "$A/$1"
}
# replace_file FILE: FILE's content from stdin, as a new file (a hard link
# to the clean dataset is not written through).
replace_file() {
  local tmp
  tmp=$(mktemp "$1.XXXX")
  cat >"$tmp"
  rm -f "$1"
  mv "$tmp" "$1"
}
RUN_ONE=("${RUN_ARGS[@]}" --threads 1)

# The output folder of an export: never a folder of the user's, the run, or
# a folder holding it; an earlier export is replaced, the user's files in it
# kept.
mkdir -p "$A/users_folder/model"
echo "the user's notes" >"$A/users_folder/notes.txt"
echo "the user's model" >"$A/users_folder/model/cameras.bin"
attack export_into_a_users_folder 2 "$A/users_folder: --out" "$A/users_folder" "$WORK/ref" -- \
  export "$WORK/ref" --out "$A/users_folder"
attack export_into_the_run 2 "$WORK/ref: --out is the run folder itself" "$WORK/ref" -- \
  export "$WORK/ref" --out "$WORK/ref"
mkdir -p "$A/parent"
cp -r "$WORK/ref" "$A/parent/run"
echo "the user's notes" >"$A/parent/notes.txt"
attack export_into_the_runs_parent 2 "$A/parent: --out holds the run folder" "$A/parent" -- \
  export "$A/parent/run" --out "$A/parent"
"$VIOSFM" --log-level error export "$WORK/ref" --out "$A/exported" >/dev/null 2>&1 ||
  fail "export into a new folder"
mkdir -p "$A/exported/colmap_sparse/0"
echo "COLMAP's model, the user's" >"$A/exported/colmap_sparse/0/images.bin"
attack export_again_into_an_earlier_export 0 "-> $A/exported" "$A/exported/colmap_sparse" "$WORK/ref" -- \
  export "$WORK/ref" --out "$A/exported"

# run --out into a folder of the user's that holds a model/, with and
# without --overwrite.
mkdir -p "$A/unrelated/model"
echo "the user's model" >"$A/unrelated/model/cameras.bin"
echo '{"mine": 1}' >"$A/unrelated/summary.json"
attack run_into_a_users_folder 2 "$A/unrelated: --out: the folder holds files and viosfm did not make it" \
  "$A/unrelated" "$SEQ" -- run "$SEQ" --out "$A/unrelated" "${RUN_ONE[@]}"
attack overwrite_a_users_folder 2 "$A/unrelated: --out: the folder holds files and viosfm did not make it" \
  "$A/unrelated" "$SEQ" -- run "$SEQ" --out "$A/unrelated" "${RUN_ONE[@]}" --overwrite
if [[ -n ${overwrite_row:-} ]]; then
  row_result overwrite_with_another_dataset ok "$overwrite_row (check 2)"
else
  row_result overwrite_with_another_dataset bad "check 2 failed"
fi

# IMU values no IMU measures: an input error naming the file and line.
imu_value() {  # NAME LINE COLUMN VALUE
  dataset_copy "$1"
  python3 - "$SEQ/mav0/imu0/data.csv" "$2" "$3" "$4" <<'PY' | replace_file "$A/$1/mav0/imu0/data.csv"
import sys
path, line, column, value = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
lines = open(path).read().split("\n")
fields = lines[line - 1].split(",")
fields[column] = value
lines[line - 1] = ",".join(fields)
sys.stdout.write("\n".join(lines))
PY
  attack "$1" 2 "$A/$1/mav0/imu0/data.csv:$2: " "$A/$1" -- run "$A/$1" --out "$A/out_$1" "${RUN_ONE[@]}"
}
imu_value imu_accel_1e6 201 6 1e6
imu_value imu_gyro_1e308 301 2 1e308
imu_value imu_accel_1e30 401 4 -1e30
imu_value imu_gyro_1e12 501 1 1e12

# Calibrations no camera has: an input error naming sensor.yaml and the line.
calibration() {  # NAME PYTHON-REPLACEMENT
  dataset_copy "$1"
  python3 -c "import re,sys; t=open(sys.argv[1]).read(); sys.stdout.write($2)" \
    "$SEQ/mav0/cam0/sensor.yaml" | replace_file "$A/$1/mav0/cam0/sensor.yaml"
  attack "$1" 2 "$A/$1/mav0/cam0/sensor.yaml:" "$A/$1" -- run "$A/$1" --out "$A/out_$1" "${RUN_ONE[@]}"
}
calibration calibration_principal_point \
  're.sub(r"intrinsics: \[([^,]*), ([^,]*), [^,]*, [^\]]*\]", r"intrinsics: [\1, \2, -5000, 1e9]", t)'
calibration calibration_distortion_1e200 \
  're.sub(r"distortion_coefficients: \[[^,]*,", "distortion_coefficients: [1e200,", t)'
calibration calibration_translation_1e300 \
  're.sub(r"data: \[([^,]*), ([^,]*), ([^,]*), [^,]*,", r"data: [\1, \2, \3, 1e300,", t, count=1)'
# A key twice in a yaml; an image under two stamps.
calibration duplicate_yaml_key 't + "\nrate_hz: 20\n"'
dataset_copy image_under_two_stamps
python3 - "$SEQ/mav0/cam0/data.csv" <<'PY' | replace_file "$A/image_under_two_stamps/mav0/cam0/data.csv"
import sys
lines = open(sys.argv[1]).read().split("\n")
stamp = lines[5].split(",")[0]
lines[5] = stamp + "," + lines[4].split(",")[1]  # line 6 names line 5's image
sys.stdout.write("\n".join(lines))
PY
attack image_under_two_stamps 2 "$A/image_under_two_stamps/mav0/cam0/data.csv:6: image" \
  "$A/image_under_two_stamps" -- run "$A/image_under_two_stamps" --out "$A/out_two_stamps" "${RUN_ONE[@]}"

# An image replaced by another of the same byte size (one pixel changed, the
# PNG padded to its old size), then the same command again: refused, naming it.
dataset_copy replaced
image=$(sed -n 4p "$SEQ/mav0/cam0/data.csv" | cut -d, -f2 | tr -d '\r ')
python3 - "$SEQ/mav0/cam0/data/$image" <<'PY' | replace_file "$A/replaced/mav0/cam0/data/$image"
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
chunks, pos = [], 8
while pos < len(data):
    length = struct.unpack(">I", data[pos:pos + 4])[0]
    chunks.append((data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]))
    pos += 12 + length
width, height = struct.unpack(">II", chunks[0][1][:8])
raw = bytearray(zlib.decompress(b"".join(body for kind, body in chunks if kind == b"IDAT")))
row = height // 2 * (width + 1)  # 8-bit grey: a filter byte, then the row
raw[row:row + width + 1] = bytes(width + 1)  # the middle row black, unfiltered
def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
head = data[:8] + b"".join(chunk(k, b) for k, b in chunks if k not in (b"IDAT", b"IEND"))
def deflate(level, strategy):
    stream = zlib.compressobj(level, zlib.DEFLATED, 15, 9, strategy)
    return stream.compress(bytes(raw)) + stream.flush()
idat = min((deflate(level, strategy) for level in range(1, 10)
            for strategy in (zlib.Z_DEFAULT_STRATEGY, zlib.Z_FILTERED)), key=len)
out = head + chunk(b"IDAT", idat)
pad = len(data) - len(out) - 12 - 12
assert pad >= 0, "recompressed image larger than the original"
out += chunk(b"vsFm", b"\0" * pad) + chunk(b"IEND", b"")
assert len(out) == len(data)
sys.stdout.buffer.write(out)
PY
cp -r "$WORK/ref" "$A/replaced_run"
attack image_replaced_same_size 2 "changed: $image" "$A/replaced" "$A/replaced_run" -- \
  run "$A/replaced" --out "$A/replaced_run" "${RUN_ONE[@]}"

# viosfm features and match into a run's database: other options or another
# VIO refused before anything changes; the run then finds its own rows.
cp -r "$WORK/ref" "$A/featured"
attack features_into_a_runs_database 2 "$A/featured/fingerprint.json: " "$A/featured" "$SEQ" -- \
  features "$SEQ" --database "$A/featured/database.db" --max-features 100
attack match_into_a_runs_database 2 "$A/featured/fingerprint.json: " "$A/featured" "$SEQ" -- \
  match "$SEQ" --database "$A/featured/database.db" --vio-trajectory "$WORK/ref/vio_body.tum"
if run featured_rerun "$SEQ" "$A/featured" --threads 1 && result=$(compare "$WORK/ref" "$A/featured"); then
  row_result run_after_the_refused_commands ok "$result to the uninterrupted run"
else
  row_result run_after_the_refused_commands bad "${result:-exit code}; log $LOGS/featured_rerun.log"
fi

# Paths that leave the dataset: --timestamps names, a symbolic link.
mkdir -p "$A/image_folder"
for k in 2 3; do
  name=$(sed -n ${k}p "$SEQ/mav0/cam0/data.csv" | cut -d, -f2 | tr -d '\r ')
  cp "$SEQ/mav0/cam0/data/$name" "$A/image_folder/$((k - 1)).png"
done
cp "$SEQ/mav0/cam0/data/$name" "$WORK/outside.png"
printf '1.png 1.0\n2.png 1.1\n../../outside.png 1.2\n' >"$A/timestamps_up.txt"
printf '1.png 1.0\n2.png 1.1\n/etc/passwd 1.2\n' >"$A/timestamps_absolute.txt"
for kind in up absolute; do
  attack "timestamps_$kind" 2 "$A/timestamps_$kind.txt:3: image name" "$A/image_folder" "$SEQ" -- \
    run "$A/image_folder" --out "$A/out_timestamps_$kind" --timestamps "$A/timestamps_$kind.txt" \
    --camera-yaml "$SEQ/mav0/cam0/sensor.yaml" --vio-trajectory "$WORK/ref/vio_body.tum" "${RUN_ONE[@]}"
done
dataset_copy link_outside
rm "$A/link_outside/mav0/cam0/data/$image"
ln -s "$WORK/outside.png" "$A/link_outside/mav0/cam0/data/$image"
attack link_outside_the_dataset 2 "$A/link_outside/mav0/cam0/data/$image: " "$A/link_outside" -- \
  run "$A/link_outside" --out "$A/out_link" "${RUN_ONE[@]}"

# Bounded resources: 10 million rows naming one image; a PNG that declares
# 32000 x 32000 pixels; 20000 threads.
dataset_copy ten_million_rows
python3 - "$SEQ/mav0/cam0/data.csv" "$image" <<'PY' | replace_file "$A/ten_million_rows/mav0/cam0/data.csv"
import sys
first = int(open(sys.argv[1]).read().split("\n")[1].split(",")[0])
out = sys.stdout
out.write("#timestamp [ns],filename\n")
row = "," + sys.argv[2] + "\n"
for i in range(10_000_000):
    out.write(str(first + 1000 * i) + row)
PY
LIMIT_MB=256 attack ten_million_rows_one_image 2 "$A/ten_million_rows/mav0/cam0/data.csv:3: image" \
  "$A/ten_million_rows" -- run "$A/ten_million_rows" --out "$A/out_rows" "${RUN_ONE[@]}"
dataset_copy huge_png
python3 - <<'PY' | replace_file "$A/huge_png/mav0/cam0/data/$image"
import struct, sys, zlib
def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
ihdr = struct.pack(">IIBBBBB", 32000, 32000, 8, 0, 0, 0, 0)
data = zlib.compress(b"\0" * (8 << 20), 9)[:1 << 20]  # 1 MB of a stream that would go on
sys.stdout.buffer.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", data) +
                        chunk(b"IEND", b""))
PY
LIMIT_MB=256 attack png_declaring_32000x32000 2 "$A/huge_png/mav0/cam0/data/$image: " "$A/huge_png" -- \
  run "$A/huge_png" --out "$A/out_png" "${RUN_ONE[@]}"
LIMIT_MB=1024 attack threads_20000 0 "--threads 20000: capped at" "$SEQ" -- \
  run "$SEQ" --out "$A/out_threads" "${RUN_ARGS[@]}" --threads 20000

# Command lines that cannot be parsed: exit 2, the flag named.
attack parse_missing_out 2 "--out is required" "$SEQ" -- run "$SEQ"
attack parse_unknown_flag 2 "--no-such-flag" "$SEQ" -- run "$SEQ" --out "$A/out_parse" --no-such-flag
attack parse_bad_value 2 "--first-octave" "$SEQ" -- features "$SEQ" --database "$A/parse.db" --first-octave 5

# IMU gaps, and a gap over the static start: an input error, or a model
# whose scale is within 1 % of the clean run's (clean and gapped runs of a
# 12 s sequence and of one with a 2 s static start).
"$VIOSFM" simulate --out "$A/sim12" --seed 1 --scenario room --duration 12 --rate 10 --threads 1 \
  >"$LOGS/sim12.log" 2>&1 &
"$VIOSFM" simulate --out "$A/simS" --seed 1 --scenario room --duration 10 --static-start 2 --rate 10 \
  --threads 1 >"$LOGS/simS.log" 2>&1 &
wait
imu_gap() {  # NAME SOURCE FROM_S TO_S: the IMU's samples from FROM_S to TO_S (after its first) removed
  rm -rf "$A/$1"
  cp -al "$2" "$A/$1"
  python3 - "$2/mav0/imu0/data.csv" "$3" "$4" <<'PY' | replace_file "$A/$1/mav0/imu0/data.csv"
import sys
lines = open(sys.argv[1]).read().split("\n")
rows = [l for l in lines if l and not l.startswith("#")]
first = int(rows[0].split(",")[0])
start, end = first + int(float(sys.argv[2]) * 1e9), first + int(float(sys.argv[3]) * 1e9)
kept = [l for l in lines if not l or l.startswith("#") or not start < int(l.split(",")[0]) < end]
sys.stdout.write("\n".join(kept))
PY
}
imu_gap gap_5s "$A/sim12" 4 9
imu_gap gap_1s "$A/sim12" 5 6
imu_gap gap_over_static_start "$A/simS" 0.3 1.7
run clean12 "$A/sim12" "$A/clean12" --threads 1 &
run cleanS "$A/simS" "$A/cleanS" --threads 1 &
wait
for name in gap_5s gap_1s gap_over_static_start; do
  run "$name" "$A/$name" "$A/out_$name" --threads 1 &
  [[ $name == gap_1s ]] && wait
done
wait
scale_of() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['eval']['metric']['scale'])" "$1/summary.json" 2>/dev/null; }
for name in gap_5s gap_1s gap_over_static_start; do
  clean=$A/clean12
  [[ $name == gap_over_static_start ]] && clean=$A/cleanS
  log=$LOGS/$name.log
  named="$A/$name/mav0/imu0/data.csv"
  if grep -q "^error: $named" "$log"; then
    row_result "$name" ok "input error: $(message_of "$log" | cut -c1-240)"
  elif [[ -f $A/out_$name/summary.json ]]; then
    verdict=$(python3 -c "
s, c = float('$(scale_of "$A/out_$name")'), float('$(scale_of "$clean")')
print(('ok' if abs(s / c - 1) <= 0.01 else 'bad') + f' scale {s:.4f} against the clean run\'s {c:.4f} ({100 * (s / c - 1):+.2f} %)')")
    grep -qF "$named: " "$log" || verdict="bad ${verdict#* }; no warning naming $named"
    row_result "$name" "${verdict%% *}" "exit 0, ${verdict#* }; $(grep -m1 -F "W " "$log" | cut -c1-200)"
  else
    row_result "$name" bad "neither an input error nor a model (log $log)"
  fi
done
say "a careless or hostile user: $num_rows_ok of $num_rows rows as they must be"

[[ -f "$WORK/failed" ]] && FAILED=1
say "time: ${SECONDS} s; logs in $LOGS"
exit $FAILED
