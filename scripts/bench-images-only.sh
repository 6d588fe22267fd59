#!/usr/bin/env bash
# Images alone on real photos with metric ground truth (Strecha's
# fountain-P11: 11 photos of 3072x2048, ground-truth cameras), viosfm beside
# COLMAP 3.8 in the same run:
#   viosfm      `viosfm run IMAGES --out OUT` (no calibration: the camera
#               guessed from the image size and refined, as COLMAP does
#               without EXIF data; the photos an unordered collection)
#   viosfm_k    the same with the ground truth's K (--camera-yaml)
#   colmap      feature_extractor (single camera, SIMPLE_RADIAL guessed),
#               exhaustive_matcher, mapper: COLMAP's defaults
#   colmap_pp   COLMAP's defaults with its principal point refined as well
#               (Mapper.ba_refine_principal_point), as viosfm refines a
#               guessed camera's
#   colmap_k    the same with K given and kept
# Each: photos registered, camera-centre ATE against the ground truth after
# Sim(3) alignment (mm), seconds.
#
#   scripts/bench-images-only.sh OUT
#
# VIOSFM_DATA_DIR (default ../shared/data beside the project) holds
# strecha_fountain_p11; NO_COLMAP=1 skips COLMAP. Needs jq, python3-numpy.
# PRESET (environment): viosfm run's --preset, default paper (the settings of the
# documented figures); PRESET=realtime runs viosfm's default.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
data=${VIOSFM_DATA_DIR:-$here/../shared/data}/strecha_fountain_p11
out=${1:?usage: scripts/bench-images-only.sh OUT}
threads=${THREADS:-2}
if [ ! -d "$data/images" ]; then
  echo "no $data/images (set VIOSFM_DATA_DIR to the folder holding strecha_fountain_p11)" >&2
  exit 2
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
/usr/bin/python3 "$here/scripts/lib/fountain_truth.py" "$data" "$out"

ate() {  # ESTIMATE.tum -> "sim3_mm poses"
  local j=$out/eval.tmp.json
  "$VIOSFM" eval --est "$1" --ref "$out/groundtruth_cam.tum" --align sim3 --json "$j" \
    > /dev/null 2>&1 || { echo "- 0"; return; }
  jq -r '"\(1000 * .ate.translation_m.rmse) \(.ate.translation_m.count // .num_pairs // "-")"' "$j" |
    awk '{ printf "%.2f %s\n", $1, $2 }'
}

timed() {  # SECONDS_FILE COMMAND...
  local file=$1 start
  shift
  start=$(date +%s.%N)
  "$@"
  echo "$(date +%s.%N) - $start" | bc > "$file"
}

for variant in viosfm viosfm_k; do
  [ -f "$out/$variant/summary.json" ] && continue
  flags=(--no-progress --threads "$threads" --preset "${PRESET:-paper}")
  [ "$variant" = viosfm_k ] && flags+=(--camera-yaml "$out/camera.yaml")
  timed "$out/$variant.seconds" "$VIOSFM" run "$data/images" --out "$out/$variant" "${flags[@]}" \
    > "$out/$variant.log" 2>&1 || true
done

colmap_run() {  # NAME EXTRA_FEATURE_FLAGS... -- EXTRA_MAPPER_FLAGS...
  local name=$1 dir=$out/$1
  shift
  local feature_flags=() mapper_flags=() in_mapper=0
  for flag in "$@"; do
    if [ "$flag" = -- ]; then in_mapper=1; continue; fi
    if [ $in_mapper = 1 ]; then mapper_flags+=("$flag"); else feature_flags+=("$flag"); fi
  done
  [ -f "$dir/trajectory_cam.tum" ] && return
  rm -rf "$dir"
  mkdir -p "$dir/sparse"
  export QT_QPA_PLATFORM=offscreen
  timed "$out/$name.seconds" bash -c "
    colmap feature_extractor --database_path '$dir/database.db' --image_path '$data/images' \
      --ImageReader.single_camera 1 --SiftExtraction.use_gpu 0 \
      --SiftExtraction.num_threads $threads ${feature_flags[*]} &&
    colmap exhaustive_matcher --database_path '$dir/database.db' --SiftMatching.use_gpu 0 \
      --SiftMatching.num_threads $threads &&
    colmap mapper --database_path '$dir/database.db' --image_path '$data/images' \
      --output_path '$dir/sparse' --Mapper.num_threads $threads ${mapper_flags[*]}" \
    > "$dir/log.txt" 2>&1 || true
  [ -f "$dir/sparse/0/images.bin" ] || return
  mkdir -p "$dir/txt"
  colmap model_converter --input_path "$dir/sparse/0" --output_path "$dir/txt" --output_type TXT \
    > /dev/null 2>&1
  /usr/bin/python3 "$here/scripts/lib/colmap_to_tum.py" "$dir/txt" "$out/timestamps.txt" \
    "$dir/trajectory_cam.tum"
}

if [ "${NO_COLMAP:-0}" != 1 ]; then
  colmap_run colmap
  colmap_run colmap_pp -- --Mapper.ba_refine_principal_point 1
  read -r fx fy cx cy < <(awk -F'[][, ]+' '/^intrinsics/ { print $2, $3, $4, $5 }' "$out/camera.yaml")
  colmap_run colmap_k --ImageReader.camera_model PINHOLE \
    --ImageReader.camera_params "$fx,$fy,$cx,$cy" -- --Mapper.ba_refine_focal_length 0 \
    --Mapper.ba_refine_principal_point 0 --Mapper.ba_refine_extra_params 0
fi

{
  echo "Strecha fountain-P11, 11 photos: camera-centre ATE after Sim(3) alignment against the ground truth."
  echo
  echo "| run | calibration | photos posed | ATE Sim(3) mm | seconds |"
  echo "|---|---|---|---|---|"
  for variant in viosfm viosfm_k colmap colmap_pp colmap_k; do
    case $variant in
      viosfm) traj=$out/viosfm/trajectory_cam.tum; calib="guessed, refined" ;;
      viosfm_k) traj=$out/viosfm_k/trajectory_cam.tum; calib="ground-truth K" ;;
      colmap) traj=$out/colmap/trajectory_cam.tum; calib="guessed, refined (not the principal point)" ;;
      colmap_pp) traj=$out/colmap_pp/trajectory_cam.tum; calib="guessed, refined" ;;
      colmap_k) traj=$out/colmap_k/trajectory_cam.tum; calib="ground-truth K, fixed" ;;
    esac
    [ -f "$traj" ] || { echo "| $variant | $calib | 0 | - | - |"; continue; }
    read -r mm _ <<< "$(ate "$traj")"
    posed=$(grep -vc '^#' "$traj")
    seconds=$(awk '{ printf "%.0f", $1 }' "$out/$variant.seconds" 2>/dev/null || echo -)
    echo "| $variant | $calib | $posed of 11 | $mm | $seconds |"
  done
} | tee "$out/table.md"
rm -f "$out/eval.tmp.json"
