#!/usr/bin/env bash
# `make fuzz`: builds the libFuzzer targets of fuzz/ with clang, AddressSanitizer
# and UndefinedBehaviorSanitizer in their own build folder, then runs each for
# a bounded time, one after the other, starting from the committed seed
# corpus fuzz/corpus/<parser>/. Prints one line per fuzzer (executions, rate,
# corpus size, crashes) and exits non-zero if any fuzzer crashed; crash
# inputs are kept in <build>/fuzz-artifacts/ (turn each into a regression test).
#
#   scripts/fuzz.sh [BUILD_DIR]          default build-fuzz
# Environment:
#   FUZZ_SECONDS=60     seconds per fuzzer
#   FUZZERS="tum kitti" only these (default: all of fuzz/CMakeLists.txt)
#   FUZZ_JOBS=2         build jobs
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build-fuzz}"
seconds="${FUZZ_SECONDS:-60}"
jobs="${FUZZ_JOBS:-2}"

# Debian's clang and its libFuzzer/sanitizer runtimes (only this target needs them).
need=()
command -v clang++ >/dev/null 2>&1 || need+=(clang)
clang_major=$( (clang++ --version 2>/dev/null || true) | sed -n 's/.*clang version \([0-9]*\).*/\1/p' | head -1)
if [[ -n "$clang_major" ]] && ! dpkg-query -W -f='${Status}' "libclang-rt-${clang_major}-dev" 2>/dev/null |
  grep -q "install ok installed"; then
  need+=("libclang-rt-${clang_major}-dev")
fi
if [[ ${#need[@]} -gt 0 ]]; then
  echo "fuzz: installing ${need[*]}"
  SUDO=()
  [[ $(id -u) -eq 0 ]] || SUDO=(sudo)
  "${SUDO[@]}" apt-get update -qq
  "${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${need[@]}"
  [[ -n "$clang_major" ]] || exec "$0" "$@"  # clang was missing: start again to name its runtime
fi

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" \
  -DVIOSFM_BUILD_FUZZERS=ON -DVIOSFM_SANITIZE=address,undefined \
  -DVIOSFM_BUILD_TESTS=OFF -DVIOSFM_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j "$jobs" --target viosfm_fuzzers

fuzzers="${FUZZERS:-$(sed -n '/^set(VIOSFM_FUZZERS/,/)/p' fuzz/CMakeLists.txt |
  tr -d '()' | sed 's/set//; s/VIOSFM_FUZZERS//' | tr -s ' \n' ' ')}"
artifacts="$build/fuzz-artifacts"
mkdir -p "$artifacts"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

printf '%-18s %12s %10s %8s %8s %s\n' parser executions "exec/s" corpus crashes "seconds"
failed=0
for name in $fuzzers; do
  seeds="fuzz/corpus/$name"
  work="$build/fuzz-corpus/$name"  # grows run after run; not committed
  mkdir -p "$work"
  log="$build/fuzz-$name.log"
  start=$(date +%s)
  status=0
  "$build/fuzz/fuzz_$name" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 \
    -malloc_limit_mb=256 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$artifacts/$name-" "$work" "$seeds" >"$log" 2>&1 || status=$?
  elapsed=$(($(date +%s) - start))
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  corpus=$(find "$work" -type f | wc -l)
  crashes=0
  if [[ $status -ne 0 ]]; then
    crashes=1
    failed=1
  fi
  printf '%-18s %12s %10s %8s %8s %s\n' "$name" "${executions:-?}" "${rate:-?}" "$corpus" \
    "$crashes" "$elapsed"
  if [[ $status -ne 0 ]]; then
    echo "  crash: see $log; input in $artifacts/" >&2
    grep -m3 -E "ERROR: |runtime error|property violated|terminate called" "$log" | sed 's/^/  /' >&2 || true
  fi
done
exit $failed
