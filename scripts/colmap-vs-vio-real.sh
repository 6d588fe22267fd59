#!/usr/bin/env bash
# An independent check of viosfm's own VIO on the real handheld recording
# (no ground truth there): COLMAP 3.8 reconstructs every STEP-th frame from
# the images alone (CPU SIFT with the calibration's pinhole intrinsics, one
# camera, sequential matching, the mapper without intrinsics refinement);
# its largest model is Sim(3)-aligned to the VIO's camera trajectory and to
# viosfm run's model, and the RMSE, the scale factor and the frames in
# common are printed (`viosfm eval`, camera positions, nearest stamp). Each
# model's relative rotations over 1 s are then checked against the
# recording's gyro (`viosfm eval --gyro`, eval/gyro_check.h), the one
# independent judge of all three: at the camera-IMU time offset the VIO
# estimated (time_offset_ns of vio_summary.txt beside the VIO trajectory,
# else the calibration's).
#
# Usage: scripts/colmap-vs-vio-real.sh WORK_DIR VIO_TRAJECTORY_CAM_TUM [RUN_MODEL_DIR]
#   VIO_TRAJECTORY_CAM_TUM: `viosfm vio`'s trajectory_cam.tum (or a run's
#   vio/trajectory_cam.tum); RUN_MODEL_DIR: a `viosfm run` output's model_txt
#   (or model) folder.
# Environment: DATA (default ../shared/data/realsense_room_30s beside the
#   checkout), STEP (3), OVERLAP (sequential matching overlap, 10), THREADS
#   (COLMAP's threads, 1), VIOSFM (binary, default build/src/viosfm/cli/viosfm).
# Needs colmap (Debian's package; VIOSFM_WITH_COLMAP=1 scripts/install-deps.sh).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
DATA=${DATA:-$here/../shared/data/realsense_room_30s}
STEP=${STEP:-3}
OVERLAP=${OVERLAP:-10}
THREADS=${THREADS:-1}
work=${1:?usage: scripts/colmap-vs-vio-real.sh WORK_DIR VIO_TRAJECTORY_CAM_TUM [RUN_MODEL_DIR]}
vio_cam=${2:?usage: scripts/colmap-vs-vio-real.sh WORK_DIR VIO_TRAJECTORY_CAM_TUM [RUN_MODEL_DIR]}
run_model=${3:-}
if [ ! -d "$DATA/mav0" ]; then
  echo "skipped: $DATA not found (the shared real recordings are not on this machine)"
  exit 0
fi
command -v colmap > /dev/null || { echo "colmap not found: apt-get install colmap" >&2; exit 1; }
# The references are checked before COLMAP's minutes of work.
[ -f "$vio_cam" ] || { echo "$vio_cam: file does not exist (VIO_TRAJECTORY_CAM_TUM)" >&2; exit 2; }
if [ -n "$run_model" ] && [ ! -d "$run_model" ]; then
  echo "$run_model: folder does not exist (RUN_MODEL_DIR)" >&2
  exit 2
fi
export QT_QPA_PLATFORM=offscreen

# The frames: every STEP-th image of cam0, linked under its stamp's name.
images=$work/images
rm -rf "$images" "$work/database.db" "$work/sparse" "$work/model_txt"
mkdir -p "$images" "$work/sparse" "$work/model_txt"
awk -F, -v step="$STEP" 'NR > 1 && $1 !~ /^#/ { if ((n++ % step) == 0) print $2 }' \
  "$DATA/mav0/cam0/data.csv" | tr -d '\r' | while read -r name; do
  ln -s "$(cd "$DATA/mav0/cam0/data" && pwd)/$name" "$images/$name"
done
echo "frames: $(ls "$images" | wc -l) (one in $STEP of $DATA)"

# Pinhole intrinsics of the calibration (camera.txt: fx fy cx cy k1).
read -r fx fy cx cy _ < "$DATA/calibration/camera.txt"
start=$(date +%s)
colmap feature_extractor --database_path "$work/database.db" --image_path "$images" \
  --ImageReader.camera_model PINHOLE --ImageReader.single_camera 1 \
  --ImageReader.camera_params "$fx,$fy,$cx,$cy" \
  --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads "$THREADS" > "$work/colmap.log" 2>&1
colmap sequential_matcher --database_path "$work/database.db" --SiftMatching.use_gpu 0 \
  --SiftMatching.num_threads "$THREADS" --SequentialMatching.overlap "$OVERLAP" \
  >> "$work/colmap.log" 2>&1
colmap mapper --database_path "$work/database.db" --image_path "$images" \
  --output_path "$work/sparse" --Mapper.num_threads "$THREADS" \
  --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_principal_point 0 \
  --Mapper.ba_refine_extra_params 0 >> "$work/colmap.log" 2>&1
echo "COLMAP: $(( $(date +%s) - start )) s"

# The largest model (COLMAP may split the sequence into several).
best=""
best_count=0
for model in "$work"/sparse/*/; do
  [ -f "$model/images.bin" ] || continue
  rm -rf "$work/model_tmp" && mkdir -p "$work/model_tmp"
  colmap model_converter --input_path "$model" --output_path "$work/model_tmp" \
    --output_type TXT > /dev/null 2>&1
  # Two lines an image, the second empty for an image without points.
  count=$(awk '!/^#/ { n++ } END { print int((n + 1) / 2) }' "$work/model_tmp/images.txt")
  echo "model $(basename "$model"): $count images"
  if [ "$count" -gt "$best_count" ]; then
    best_count=$count
    best=$model
    rm -rf "$work/model_txt" && mv "$work/model_tmp" "$work/model_txt"
  fi
done
rm -rf "$work/model_tmp"
[ -n "$best" ] || { echo "COLMAP produced no model (see $work/colmap.log)" >&2; exit 1; }
echo "largest model: $best_count images"

compare() {  # label reference
  "$VIOSFM" eval --est "$work/model_txt" --ref "$2" --align sim3 --rpe-delta 0 \
    --json "$work/eval_$1.json" > "$work/eval_$1.txt"
  echo "COLMAP against $1: $(jq -r '"\(.alignment.num_pairs) frames in common, RMSE \(.ate.translation_m.rmse) m (max \(.ate.translation_m.max)), scale \(.alignment.scale)"' \
    "$work/eval_$1.json")"
}
compare vio "$vio_cam"
if [ -n "$run_model" ]; then compare run "$run_model"; fi

offset=()
summary=$(dirname "$vio_cam")/vio_summary.txt
if [ -f "$summary" ]; then
  ns=$(awk -F': ' '$1 == "time_offset_ns" { print $2 }' "$summary")
  [ -n "$ns" ] && offset=("--gyro-time-offset=$(awk -v ns="$ns" 'BEGIN { printf "%.6f", ns * 1e-9 }')")
fi
gyro() {  # label trajectory
  "$VIOSFM" --log-level warning eval --est "$2" --gyro "$DATA" \
    --calibration "$DATA/calibration/camchain.yaml" "${offset[@]}" \
    --json "$work/gyro_$1.json" > "$work/gyro_$1.txt"
  echo "$1 against the gyro: $(jq -r '.gyro | "\(.num_intervals) intervals, error RMSE \(.error_deg.rmse * 1000 | round / 1000) deg (max \(.error_deg.max * 1000 | round / 1000))"' \
    "$work/gyro_$1.json")"
}
echo "rotations over 1 s against the gyro (time offset: ${offset[*]:-as calibrated}):"
gyro colmap "$work/model_txt"
gyro vio "$vio_cam"
if [ -n "$run_model" ]; then gyro run "$run_model"; fi
