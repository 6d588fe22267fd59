#!/usr/bin/env bash
# Real time: how long `viosfm run` takes to reconstruct a recording, stage
# by stage, against the recording's own duration.
#
# Usage:
#   bench/realtime.sh [--out DIR] [--scenarios "room two_floors corridor"]
#                     [--duration S] [--rate HZ] [--threads "2 1"]
#                     [--repeat N] [--build DIR] [-- EXTRA RUN ARGS...]
#
# For every scenario it simulates DURATION seconds at RATE Hz (752x480, IMU
# at 200 Hz, ground truth; default 100 s at 10 Hz, 1000 images), then runs
# `viosfm run` on it from the images and the IMU alone (viosfm's own VIO)
# with its defaults (or with EXTRA RUN ARGS, e.g. `-- --realtime`, the
# settings meant for it), once per thread count, each into a fresh folder,
# under /usr/bin/time. It writes DIR/realtime.md: per run the wall clock of
# every stage (summary.json "stages"; in brackets the CPU seconds the
# process used meanwhile, every thread) and in total, the CPU of the whole
# run and how many cores it kept busy on average, the ratio of the total
# to the recording's duration (1.0 is real time), the registered frames,
# the Sim(3) and SE(3) ATE, the image decodes and the peak memory.
#
# With --repeat N every scenario and thread count runs N times in a row
# (folders run_tT_rK), each run a row of its own, and a second table gives
# the median, smallest and largest total of each.
#
# The figures are measured, never asserted: a shared machine is noisy, so
# repeat a row before trusting a small difference.
set -euo pipefail

out=out/realtime
scenarios="room two_floors corridor"
duration=100
rate=10
threads="2 1"
repeat=1
build=build
extra=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) out=$2; shift 2 ;;
    --scenarios) scenarios=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --repeat) repeat=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "bench/realtime.sh: unknown argument '$1' (see the top of the script)" >&2; exit 2 ;;
  esac
done
viosfm="$build/src/viosfm/cli/viosfm"
if [[ ! -x "$viosfm" ]]; then
  echo "bench/realtime.sh: $viosfm not found: build first (make build)" >&2
  exit 2
fi
mkdir -p "$out"
table="$out/realtime.md"
{
  echo "# viosfm run against the recording's duration"
  echo
  echo "$(date -u +%Y-%m-%d), $(nproc) cores; ${duration} s at ${rate} Hz per scenario;" \
       "run arguments: ${extra[*]:-(defaults)}"
  echo
  echo "| scenario | threads | rate Hz, features | vio s (CPU) | features s (CPU) |" \
       "verification s (CPU) | mapper s (CPU) | other s | total s | CPU s | cores busy |" \
       "x real time | registered | ATE Sim(3) mm | ATE SE(3) mm | decodes | peak MiB |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
} > "$table"

for scenario in $scenarios; do
  sequence="$out/$scenario/sequence"
  mkdir -p "$out/$scenario"
  if [[ ! -f "$sequence/simulation.yaml" ]]; then
    "$viosfm" simulate --scenario "$scenario" --duration "$duration" --rate "$rate" --seed 0 \
      --out "$sequence" > "$out/$scenario/simulate.log" 2>&1
  fi
  for t in $threads; do
  for r in $(seq 1 "$repeat"); do
    name=run_t$t
    label=$scenario
    if [[ $repeat -gt 1 ]]; then
      name=run_t${t}_r$r
      label="$scenario, run $r"
    fi
    run="$out/$scenario/$name"
    rm -rf "$run"
    /usr/bin/time -v -o "$out/$scenario/time_${name#run_}.txt" \
      "$viosfm" run "$sequence" --out "$run" --threads "$t" --no-progress "${extra[@]}" \
      > "$out/$scenario/$name.log" 2>&1 || {
        echo "bench/realtime.sh: $scenario with $t thread(s) failed: see $out/$scenario/$name.log" >&2
        continue
      }
    python3 - "$run/summary.json" "$out/$scenario/time_${name#run_}.txt" "$label" "$t" "$duration" \
      >> "$table" <<'EOF'
import json, re, sys
summary = json.load(open(sys.argv[1]))
time_text = open(sys.argv[2]).read()
scenario, threads, duration = sys.argv[3], sys.argv[4], float(sys.argv[5])
stages = {s["name"]: s["seconds"] for s in summary["stages"]}
cpu = {s["name"]: s.get("cpu_seconds", float("nan")) for s in summary["stages"]}
main = ["vio", "features", "verification", "mapper"]
other = sum(v for k, v in stages.items() if k not in main)
total = summary["total_seconds"]
total_cpu = sum(cpu.values())
def stage(name):
    return "%.1f (%.1f)" % (stages.get(name, 0), cpu.get(name, 0))
peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", time_text).group(1)) / 1024
ev = summary.get("eval", {}).get("metric", {})
def mm(key):
    return "%.2f" % (1000 * ev[key]) if key in ev else "n/a"
# The frame rate and feature count the run used (the texture probe may
# have settled them, summary.json "texture_probe").
probe = summary.get("texture_probe", {})
used = "%g, %d" % (probe["frame_rate_hz"], probe["max_num_features"]) if probe else "n/a"
print("| %s | %s | %s | %s | %s | %s | %s | %.1f | %.1f | %.1f | %.2f | %.2f | %d of %d | %s | %s | %d | %.0f |" % (
    scenario, threads, used, stage("vio"), stage("features"), stage("verification"), stage("mapper"),
    other, total, total_cpu, total_cpu / total, total / duration,
    summary["frames"]["registered"], summary["frames"]["selected"],
    mm("ate_sim3_rmse_m"), mm("ate_se3_rmse_m"), summary.get("images", {}).get("decoded", 0), peak))
EOF
  done
  done
done
if [[ $repeat -gt 1 ]]; then
  python3 - "$out" "$duration" "$repeat" "$threads" $scenarios >> "$table" <<'EOF'
import json, os, statistics, sys
out, duration, repeat, threads = sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
print()
print("| scenario | threads | runs | median total s | x real time | smallest s | largest s |")
print("|---|---|---|---|---|---|---|")
for scenario in sys.argv[5:]:
    for t in threads.split():
        totals = []
        for r in range(1, repeat + 1):
            path = os.path.join(out, scenario, "run_t%s_r%d" % (t, r), "summary.json")
            if os.path.exists(path):
                totals.append(json.load(open(path))["total_seconds"])
        if totals:
            median = statistics.median(totals)
            print("| %s | %s | %d | %.1f | %.2f | %.1f | %.1f |" % (
                scenario, t, len(totals), median, median / duration, min(totals), max(totals)))
EOF
fi
echo "bench/realtime.sh: $table"
cat "$table"
