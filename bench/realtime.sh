#!/usr/bin/env bash
# Real time: how long `viosfm run` takes to reconstruct a recording, stage
# by stage, against the recording's own duration.
#
# Usage:
#   bench/realtime.sh [--out DIR] [--scenarios "room two_floors corridor"]
#                     [--duration S] [--rate HZ] [--threads "2 1"]
#                     [--repeat N] [--follow] [--build DIR] [-- EXTRA RUN ARGS...]
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
# With --follow every run follows its recording as it is made: `viosfm
# replay` writes the simulated sequence into DIR/SCENARIO/recording_tT at
# the pace of its stamps while `viosfm run --follow` reconstructs it (the
# EXTRA RUN ARGS apply to it); the table then gives, beside the totals, when
# the recording ended and how long after its end the model was ready. With
# --stream among the EXTRA RUN ARGS the same stream table is written for a
# recorded sequence.
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
follow=0
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
    --follow) follow=1; shift ;;
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
streamed=$follow
for arg in "${extra[@]}"; do [[ "$arg" == "--stream" ]] && streamed=1; done
{
  echo "# viosfm run against the recording's duration"
  echo
  echo "$(date -u +%Y-%m-%d), $(nproc) cores; ${duration} s at ${rate} Hz per scenario;" \
       "run arguments: ${extra[*]:-(defaults)}$([[ $follow == 1 ]] && echo ", followed as recorded")"
  echo
  if [[ $streamed == 1 ]]; then
    echo "| scenario | threads | rate Hz, features | VIO done s | verification done s |" \
         "total s | CPU s | cores busy | x real time | recording ends s | model after the" \
         "recording's end s | model after the last frame s | registered | ATE Sim(3) mm |" \
         "ATE SE(3) mm | decodes | peak MiB |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  else
    echo "| scenario | threads | rate Hz, features | vio s (CPU) | features s (CPU) |" \
         "verification s (CPU) | mapper s (CPU) | other s | total s | CPU s | cores busy |" \
         "x real time | registered | ATE Sim(3) mm | ATE SE(3) mm | decodes | peak MiB |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  fi
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
    input="$sequence"
    follow_args=()
    replay_pid=
    if [[ $follow == 1 ]]; then
      # The recording made again, at its pace, while the run follows it.
      input="$out/$scenario/recording_${name#run_}"
      rm -rf "$input"
      "$viosfm" replay "$sequence" --out "$input" > "$out/$scenario/replay_${name#run_}.log" 2>&1 &
      replay_pid=$!
      while [[ ! -f "$input/mav0/imu0/sensor.yaml" ]]; do sleep 0.05; done
      follow_args=(--follow)
    fi
    /usr/bin/time -v -o "$out/$scenario/time_${name#run_}.txt" \
      "$viosfm" run "$input" --out "$run" --threads "$t" --no-progress "${follow_args[@]}" \
      "${extra[@]}" > "$out/$scenario/$name.log" 2>&1 || {
        echo "bench/realtime.sh: $scenario with $t thread(s) failed: see $out/$scenario/$name.log" >&2
        [[ -n "$replay_pid" ]] && wait "$replay_pid"
        continue
      }
    [[ -n "$replay_pid" ]] && wait "$replay_pid"
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
if "stream" in summary:
    st = summary["stream"]
    end = "%.1f" % st["recording_end_seconds"] if "recording_end_seconds" in st else "n/a"
    after_end = ("%.1f" % st["seconds_after_recording_end"]
                 if "seconds_after_recording_end" in st else "n/a")
    print("| %s | %s | %s | %.1f | %.1f | %.1f | %.1f | %.2f | %.2f | %s | %s | %.1f | %d of %d | %s | %s | %d | %.0f |" % (
        scenario, threads, used, st["vio_seconds"], st["verification_seconds"], total, total_cpu,
        total_cpu / total, total / duration, end, after_end, st["seconds_after_last_frame"],
        summary["frames"]["registered"], summary["frames"]["selected"],
        mm("ate_sim3_rmse_m"), mm("ate_se3_rmse_m"), summary.get("images", {}).get("decoded", 0),
        peak))
    sys.exit(0)
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
