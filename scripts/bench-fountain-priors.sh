#!/usr/bin/env bash
# Real photos, a drifting VIO, metric ground truth: Strecha's fountain-P11
# (11 photos of 3072x2048 with ground-truth cameras), each photo given a
# stamp 1 s after the one before (keyframes of a walk along the facade), and
# a VIO emulated on the ground truth (`viosfm emulate-vio`: the uncertainty
# model's default drift and a 2 % scale error, at 20 Hz through the photos'
# stamps). Every variant of the relative-pose priors is mapped from the
# default run's stored matches, and COLMAP 3.8 reconstructs the same photos;
# each trajectory's Sim(3) and SE(3) ATE against the ground truth.
#
#   SEEDS="0 1 2" DRIFTS="1 3" scripts/bench-fountain-priors.sh OUT
#
# DRIFTS multiplies the emulated VIO's drift, noise and scale error
# (`--vio-drift`): 1 is the model the priors assume, 3 a VIO three times
# worse than they assume (as an external VIO of unknown quality may be).
#
# VIOSFM_DATA_DIR (default ../shared/data beside the project) holds
# strecha_fountain_p11. NO_COLMAP=1 skips COLMAP. The photos are read where
# they are (a timestamps file lists them); nothing is copied.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
# shellcheck source=lib/prior-variants.sh
. "$here/scripts/lib/prior-variants.sh"
data=${VIOSFM_DATA_DIR:-$here/../shared/data}/strecha_fountain_p11
out=${1:?usage: scripts/bench-fountain-priors.sh OUT}
seeds=${SEEDS:-0 1 2}
drifts=${DRIFTS:-1 3}
if [ ! -d "$data/images" ]; then
  echo "no $data/images (set VIOSFM_DATA_DIR to the folder holding strecha_fountain_p11)" >&2
  exit 2
fi
if ! /usr/bin/python3 -c 'import numpy' 2> /dev/null; then
  echo "bench-fountain-priors.sh: needs numpy for /usr/bin/python3 (apt-get install python3-numpy, or VIOSFM_WITH_COLMAP=1 scripts/install-deps.sh)" >&2
  exit 2
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)

# Timestamps (1 s apart), the camera (K of the photos, no distortion) and the
# ground truth as world_from_cam, its world turned so that z points up (the
# photos are upright: up is minus the mean of the cameras' y axes), as a
# gravity-aligned VIO's world would be.
/usr/bin/python3 "$here/scripts/lib/fountain_truth.py" "$data" "$out"

ate() {  # estimate reference -> "sim3_mm se3_mm scale_error_percent" (scale error: 1 / the Sim(3) fit's - 1)
  local j=$out/eval.tmp.json sim3 se3
  "$VIOSFM" eval --est "$1" --ref "$2" --align sim3 --json "$j" > /dev/null 2>&1 || { echo "- - -"; return; }
  sim3=$(jq -r '"\(.ate.translation_m.rmse) \(.alignment.scale)"' "$j")
  "$VIOSFM" eval --est "$1" --ref "$2" --align se3 --json "$j" > /dev/null 2>&1 || { echo "- - -"; return; }
  se3=$(jq -r '.ate.translation_m.rmse' "$j")
  echo "$sim3 $se3" | awk '{ printf "%.2f %.2f %+.2f\n", 1000 * $1, 1000 * $3, 100 * (1 / $2 - 1) }'
}

run_flags=(--timestamps "$out/timestamps.txt" --camera-yaml "$out/camera.yaml" --vio-frame cam
           --rate 0 --no-progress)
for drift in $drifts; do
for seed in $seeds; do
  vio=$out/vio_d${drift}_s$seed.tum
  [ -f "$vio" ] || "$VIOSFM" emulate-vio "$out/groundtruth_cam.tum" --seed "$seed" \
    --vio-drift "$drift" --out "$vio" > "$out/emulate_d${drift}_s$seed.log" 2>&1
  map_prior_variants "$out/d${drift}_s$seed" "$data/images" --vio-trajectory "$vio" \
    "${run_flags[@]}"
done
done

if [ "${NO_COLMAP:-0}" != 1 ] && [ ! -f "$out/colmap/sparse/0/images.bin" ]; then
  rm -rf "$out/colmap"
  mkdir -p "$out/colmap/sparse"
  export QT_QPA_PLATFORM=offscreen
  read -r fx fy cx cy < <(awk -F'[][, ]+' '/^intrinsics/ { print $2, $3, $4, $5 }' "$out/camera.yaml")
  start=$(date +%s.%N)
  colmap feature_extractor --database_path "$out/colmap/database.db" --image_path "$data/images" \
    --ImageReader.camera_model PINHOLE --ImageReader.single_camera 1 \
    --ImageReader.camera_params "$fx,$fy,$cx,$cy" --SiftExtraction.use_gpu 0 \
    --SiftExtraction.num_threads "${THREADS:-2}" > "$out/colmap/log.txt" 2>&1
  colmap exhaustive_matcher --database_path "$out/colmap/database.db" \
    --SiftMatching.use_gpu 0 --SiftMatching.num_threads "${THREADS:-2}" >> "$out/colmap/log.txt" 2>&1
  colmap mapper --database_path "$out/colmap/database.db" --image_path "$data/images" \
    --output_path "$out/colmap/sparse" --Mapper.num_threads "${THREADS:-2}" \
    --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_principal_point 0 \
    --Mapper.ba_refine_extra_params 0 >> "$out/colmap/log.txt" 2>&1
  echo "$(date +%s.%N) - $start" | bc > "$out/colmap/seconds.txt"
fi

{
  echo "Sim(3) ATE / SE(3) ATE mm, scale error % (1 / the Sim(3) fit's scale - 1), against the ground truth"
  echo
  echo "| VIO drift | seed | input VIO | **default** | \`--no-rpc\` | paper weighting | \`--no-bridging\` | registered (default) |"
  echo "|---|---|---|---|---|---|---|---|"
  for drift in $drifts; do
  for seed in $seeds; do
    runs=$out/d${drift}_s$seed
    read -r vs ve vsc <<< "$(ate "$out/vio_d${drift}_s$seed.tum" "$out/groundtruth_cam.tum")"
    row="| $drift | $seed | $vs / $ve, $vsc"
    for variant in default no_rpc paper no_bridging; do
      read -r s e sc <<< "$(ate "$runs/$variant/trajectory_cam.tum" "$out/groundtruth_cam.tum")"
      row="$row | $s / $e, $sc"
    done
    reg=$(jq -r '"\(.frames.registered) of \(.frames.selected)"' "$runs/default/summary.json" 2>/dev/null || echo -)
    echo "$row | $reg |"
  done
  done
  if [ -f "$out/colmap/sparse/0/images.bin" ]; then
    # COLMAP's model as world_from_cam at the photos' stamps.
    mkdir -p "$out/colmap/txt"
    colmap model_converter --input_path "$out/colmap/sparse/0" --output_path "$out/colmap/txt" \
      --output_type TXT > /dev/null 2>&1
    /usr/bin/python3 "$here/scripts/lib/colmap_to_tum.py" "$out/colmap/txt" "$out/timestamps.txt" \
      "$out/colmap/trajectory_cam.tum"
    read -r s e sc <<< "$(ate "$out/colmap/trajectory_cam.tum" "$out/groundtruth_cam.tum")"
    echo
    echo "COLMAP 3.8 (the same photos, exhaustive matching, K fixed): $(wc -l < "$out/colmap/trajectory_cam.tum") of 11 photos, Sim(3) ATE $s mm, $(awk '{ printf "%.0f", $1 }' "$out/colmap/seconds.txt") s"
  fi
} | tee "$out/table.md"
rm -f "$out/eval.tmp.json"
