#!/usr/bin/env bash
# End-to-end integrity checks of `viosfm run` on a small simulated sequence
# (docs/robustness.md, "Run integrity"), one line of results each:
#   1. identical re-runs: two runs from scratch (--threads 1) give the same
#      bytes (models, trajectories, PLY, summary.json without its timings),
#      and so do two with --realtime;
#   2. a second dataset (another seed: the same image names and stamps) into
#      the first one's folder is refused and leaves it as it was; with
#      --overwrite it is recomputed, as a run of it from scratch;
#   3. SIGKILL at 5 points spread over the stages, then the same command
#      again: no killed folder looks complete, each re-run ends identical to
#      the uninterrupted run;
#   4. threads: runs with --threads 2 against --threads 1 (ATE, points, poses);
#   5. hostile inputs: the fuzz seed corpora (fuzz/corpus) and deterministic
#      mutations of them, read through the viosfm command; a crash is any
#      exit other than 0, 1 (usage) or 2 (input error), or a time-out.
#
# Usage: scripts/check-integrity.sh [BUILD_DIR [WORK_DIR]]
#   BUILD_DIR  default build (needs build/src/viosfm/cli/viosfm)
#   WORK_DIR   default BUILD_DIR/integrity (emptied first); logs in WORK_DIR/logs
# Takes about 8 minutes on 2 cores (measured 2026-11-29: 7 min 37 s). Exit status 1 if any check fails.
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

[[ -f "$WORK/failed" ]] && FAILED=1
say "time: ${SECONDS} s; logs in $LOGS"
exit $FAILED
