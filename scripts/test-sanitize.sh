#!/usr/bin/env bash
# `make test-sanitize`: builds the whole test suite with AddressSanitizer and
# UndefinedBehaviorSanitizer (gcc, the project's compiler) in its own build
# folder and runs it. Any sanitizer finding aborts the test that hit it, so
# the run passes only if the suite passes with no finding. Suppressions for
# third-party libraries, each with its reason, are in scripts/sanitizer/.
#
#   scripts/test-sanitize.sh [BUILD_DIR]     default build-sanitize
# Environment: JOBS (default 2), CTEST_ARGS (e.g. "-R io/").
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build-sanitize}"
jobs="${JOBS:-2}"

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "${launcher[@]}" \
  -DVIOSFM_SANITIZE=address,undefined -DVIOSFM_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j "$jobs"

suppressions="$PWD/scripts/sanitizer"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$suppressions/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1:suppressions=$suppressions/ubsan.supp}"
start=$(date +%s)
# shellcheck disable=SC2086
ctest --test-dir "$build" -j "$jobs" --output-on-failure ${CTEST_ARGS:-}
echo "test-sanitize: passed in $(($(date +%s) - start)) s of wall clock (build in $build)"
