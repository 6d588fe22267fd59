#!/usr/bin/env bash
# The main job on the built-in default: a simulated sequence, no download.
# Usage: scripts/demo.sh [--setup] [BUILD_DIR]
#   (output in $VIOSFM_DEMO_OUT, default out/demo)
#
# With --setup (what `make demo` runs) it first installs the Debian packages
# the program needs (scripts/install-deps.sh --demo), configures BUILD_DIR
# without the tests and benchmarks, and builds the `viosfm` program alone,
# each step timed. Then it simulates a 30 s handheld walk in a textured room
# (images at 10 Hz, IMU at 200 Hz, ground truth), reconstructs it with
# `viosfm run` from the images and the IMU alone (viosfm's own VIO, features,
# VIO-aided verification, batched mapping with relative-pose-constrained
# bundle adjustment, evaluation of the VIO and of the result against the
# ground truth), and writes the HTML report of the run.
set -euo pipefail
setup=0
if [[ "${1:-}" == "--setup" ]]; then
  setup=1
  shift
fi
build_dir=${1:-build}
out=${VIOSFM_DEMO_OUT:-out/demo}
viosfm="$build_dir/src/viosfm/cli/viosfm"
jobs=${JOBS:-$(nproc)}
start=$SECONDS

# "1 min 05 s" for a number of seconds.
minutes() { printf '%d min %02d s' $(($1 / 60)) $(($1 % 60)); }
step() {
  if ((setup)); then
    echo "== $1   [$(minutes $((SECONDS - start))) so far]"
  else
    echo "== $1"
  fi
  }

if ((setup)); then
  steps=6
  step "1/$steps packages: the Debian packages viosfm builds and runs with (scripts/install-deps.sh --demo)"
  ./scripts/install-deps.sh --demo
  step "2/$steps configure: $build_dir, the program only (no tests, no benchmarks)"
  cmake -S . -B "$build_dir" -G Ninja ${CMAKE_FLAGS:--DCMAKE_BUILD_TYPE=Release} \
    -DVIOSFM_BUILD_TESTS=OFF -DVIOSFM_BUILD_BENCHMARKS=OFF >"$build_dir.configure.log" 2>&1 ||
    { cat "$build_dir.configure.log" >&2; exit 1; }
  rm -f "$build_dir.configure.log"
  step "3/$steps build: the viosfm program, $jobs jobs ([files done/to do, elapsed])"
  NINJA_STATUS="[%f/%t, %es] " cmake --build "$build_dir" -j "$jobs" --target viosfm
  n=3
else
  steps=3
  n=0
fi
mkdir -p "$out"

step "$((n + 1))/$steps simulate: 'room', 30 s, images at 10 Hz, IMU at 200 Hz -> $out/sequence"
"$viosfm" simulate --scenario room --duration 30 --rate 10 --seed 0 --out "$out/sequence"

step "$((n + 2))/$steps run: own VIO, features, N1=10 temporal + N2=5 retrieval pairs, VIO-aided
   verification, batches of 50 frames, BA with relative-pose constraints -> $out/run"
# --overwrite: an earlier demo's run is replaced; viosfm removes only the
# files its manifest says it wrote.
"$viosfm" run "$out/sequence" --out "$out/run" --overwrite --n1 10 --n2 5 --max-features 1000 \
  --batch-size 50

step "$((n + 3))/$steps report -> $out/run/report.html"
"$viosfm" report "$out/run"
echo "== Done: $out/run (model/ for COLMAP, points.ply, trajectory_*.tum, vio/, summary.json, report.html)"
if ((setup)); then
  echo "== The report after $(minutes $((SECONDS - start))) (open $out/run/report.html in a browser)"
fi
