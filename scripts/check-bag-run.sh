#!/usr/bin/env bash
# End to end through the command line: write a EuRoC folder as bags with
# `viosfm convert` (ROS 1 .bag, ROS 2 .db3 and .mcap), run `viosfm run` on the
# folder and on each bag, and compare the outputs byte for byte.
#
# Simulated (default): a sequence of DURATION_S seconds, run with one thread
# and the simulator's emulated VIO file: viosfm's own VIO and multi-threaded
# stages can differ in the last digits between two runs of the same folder
# (heap layout, thread timing), which would test the process, not the bag
# (docs/file-formats.md).
# Real (DATASET=folder): the EuRoC folder as it is, viosfm's own VIO, one
# thread, the run's defaults (EXTRA_OPTS adds options). CONVERT_OPTS adds
# options to `viosfm convert` (--compressed-images keeps a folder's JPEG
# files, and so their names, in the bag).
#
#   scripts/check-bag-run.sh [BUILD_DIR] [DURATION_S] [CONTAINERS]
#       defaults: build, 20, "bag db3 mcap"
#   DATASET=../shared/data/realsense_room_30s scripts/check-bag-run.sh build - "db3 mcap"
# Prints the time of each conversion and run, the bag sizes, and
# "identical"/"DIFFERENT" per output file; exits 1 if any differs.
set -euo pipefail
build=${1:-build}
duration=${2:-20}
containers=${3:-bag db3 mcap}
viosfm=$(realpath "$build/src/viosfm/cli/viosfm")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
dataset=${DATASET:+$(realpath "$DATASET")}
cd "$work"
if [[ -z "$dataset" ]]; then
  "$viosfm" --log-level warning simulate --out sim --duration "$duration" --static-start 1 \
    --rate 10 --seed 1
  dataset=$work/sim
  opts=(--vio-trajectory sim/vio_emulated.tum --n1 10 --n2 5 --max-features 1500 --threads 1
        --no-progress)
else
  opts=(--threads 1 --no-progress)
fi
read -r -a extra <<< "${EXTRA_OPTS:-}"
opts+=("${extra[@]}")

seconds() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(seconds)" 'BEGIN { printf "%.1f", b - a }'; }

start=$(seconds)
"$viosfm" --log-level warning run "$dataset" --out from_folder "${opts[@]}" > folder.txt
echo "run folder: $(elapsed "$start") s"
status=0
for container in $containers; do
  bag="dataset.$container"
  start=$(seconds)
  read -r -a convert_opts <<< "${CONVERT_OPTS:-}"
  "$viosfm" --log-level warning convert "$dataset" "$bag" "${convert_opts[@]}"
  echo "convert to .$container: $(elapsed "$start") s, $(du -m "$bag" | cut -f1) MB"
  start=$(seconds)
  "$viosfm" --log-level warning run "$bag" --out "from_$container" "${opts[@]}" > "$container.txt"
  echo "run .$container: $(elapsed "$start") s"
  for file in trajectory_body.tum trajectory_cam.tum vio_body.tum groundtruth_body.tum \
              model/cameras.bin model/images.bin model/points3D.bin points.ply \
              verification/pairs.csv; do
    [[ -f "from_folder/$file" ]] || continue
    if cmp -s "from_folder/$file" "from_$container/$file"; then
      echo "  identical: $file ($(stat -c %s "from_folder/$file") bytes)"
    elif python3 -c 'import sys; a, b = (open(f, "rb").read() for f in sys.argv[1:]);
sys.exit(a != b.replace(b".png", b".jpg"))' "from_folder/$file" "from_$container/$file"; then
      # A folder of JPEG files written as mono8 images is extracted as PNG.
      echo "  identical but for the image names' .png: $file"
      status=1
    else
      echo "  DIFFERENT: $file"
      status=1
    fi
  done
  rm -rf "$bag" "from_$container/bag"
done
grep -h "^ATE" folder.txt ./*.txt 2>/dev/null | sort -u || true
exit $status
