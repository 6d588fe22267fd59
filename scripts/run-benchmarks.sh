#!/usr/bin/env bash
# Runs every benchmark binary (bench_*) of a build; results (JSON, one file a
# binary) go to $VIOSFM_BENCH_OUT (default out/bench). Figures and their
# baselines are summarised in docs/benchmarks.md.
set -euo pipefail
build_dir=${1:-build}
out=${VIOSFM_BENCH_OUT:-out/bench}
mkdir -p "$out"
echo "== machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%F)"
find "$build_dir/src" -type f -name 'bench_*' -perm -u+x | sort | while read -r bench; do
  name=$(basename "$bench")
  echo "== $name"
  "$bench" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$out/$name.json" --benchmark_out_format=json
done
