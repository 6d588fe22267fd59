#!/usr/bin/env bash
# `make test-tsan`: builds the tests that start threads of their own with
# ThreadSanitizer (gcc) in their own build folder and runs them: the
# parallel loops (util/parallel.h), the frame cache and the feature
# prefetch beside the VIO, descriptor matching and verification over pairs,
# the stream of frames and pairs to a mapper beside the verification, the
# whole pipeline, and the streamed and followed runs. Any report outside the third-party libraries
# listed, with their reasons, in scripts/sanitizer/tsan.supp fails the run.
#
#   scripts/test-tsan.sh [BUILD_DIR]     default build-tsan
# Environment: JOBS (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build-tsan}"
jobs="${JOBS:-2}"
tests=(util/parallel_test io/frame_cache_test pipeline/feature_prefetch_test
       matching/descriptor_matcher_test matching/verification_driver_test
       sfm/verified_pair_stream_test pipeline/pipeline_test pipeline/stream_pipeline_test)

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "${launcher[@]}" \
  -DVIOSFM_SANITIZE=thread -DVIOSFM_BUILD_BENCHMARKS=OFF >/dev/null
targets=()
for t in "${tests[@]}"; do targets+=("test_${t%%/*}_${t##*/}"); done
cmake --build "$build" -j "$jobs" --target "${targets[@]}"

# exitcode 66 on any unsuppressed report, after the test ran to its end.
export TSAN_OPTIONS="${TSAN_OPTIONS:-halt_on_error=0 exitcode=66 second_deadlock_stack=1 suppressions=$PWD/scripts/sanitizer/tsan.supp}"
start=$(date +%s)
regex="^($(IFS='|'; echo "${tests[*]}"))\$"
ctest --test-dir "$build" -j "$jobs" --output-on-failure -R "$regex"
echo "test-tsan: ${#tests[@]} tests passed with no report in $(($(date +%s) - start)) s of wall clock (build in $build)"
