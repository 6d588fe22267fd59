#!/usr/bin/env bash
# End to end through the command line: simulate a sequence, write it as a ROS 1
# bag with `viosfm convert`, run `viosfm run` on the folder and on the bag,
# and compare the outputs byte for byte. One thread and the simulator's
# emulated VIO file: viosfm's own VIO and multi-threaded stages can differ in
# the last digits between two runs of the same folder (heap layout, thread
# timing), which would test the process, not the bag (docs/file-formats.md).
#   scripts/check-bag-run.sh [BUILD_DIR] [DURATION_S]     (defaults: build, 20)
set -euo pipefail
build=${1:-build}
duration=${2:-20}
viosfm=$(realpath "$build/src/viosfm/cli/viosfm")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
"$viosfm" --log-level warning simulate --out sim --duration "$duration" --static-start 1 \
  --rate 10 --seed 1
"$viosfm" --log-level warning convert sim sim.bag
opts=(--vio-trajectory sim/vio_emulated.tum --n1 10 --n2 5 --max-features 1500 --threads 1
      --no-progress)
"$viosfm" --log-level warning run sim --out from_folder "${opts[@]}" > folder.txt
"$viosfm" --log-level warning run sim.bag --out from_bag "${opts[@]}" > bag.txt
status=0
for file in trajectory_body.tum trajectory_cam.tum vio_body.tum groundtruth_body.tum \
            model/cameras.bin model/images.bin model/points3D.bin points.ply \
            verification/pairs.csv; do
  if cmp -s "from_folder/$file" "from_bag/$file"; then
    echo "identical: $file ($(stat -c %s "from_folder/$file") bytes)"
  else
    echo "DIFFERENT: $file"
    status=1
  fi
done
grep -h "^ATE" folder.txt bag.txt || true
exit $status
