#!/usr/bin/env bash
# COLMAP 3.8 (CPU, sequential matching) on a simulated `two_floors` sequence,
# evaluated against the simulator's ground truth: frames registered, ATE of
# every model, and whether the two identical floors were merged.
#
# Usage: scripts/colmap_two_floors.sh [WORK_DIR]
# Environment: VIOSFM (the viosfm binary, default build/src/viosfm/cli/viosfm),
#   DURATION (s, default 60), RATE (Hz, default 5), SEED (default 0),
#   OVERLAP (sequential matcher overlap, default 10),
#   MATCHER (sequential or exhaustive, default sequential),
#   MAX_FEATURES (SIFT features per image, default 8192 as COLMAP's).
set -euo pipefail

VIOSFM=${VIOSFM:-build/src/viosfm/cli/viosfm}
WORK=${1:-/tmp/colmap_two_floors}
DURATION=${DURATION:-60}
RATE=${RATE:-5}
SEED=${SEED:-0}
OVERLAP=${OVERLAP:-10}
MATCHER=${MATCHER:-sequential}
MAX_FEATURES=${MAX_FEATURES:-8192}
export QT_QPA_PLATFORM=offscreen

# The simulator's default camera (EuRoC cam0-like), OPENCV: fx fy cx cy k1 k2 p1 p2.
CAMERA_PARAMS="458.654,457.296,367.215,248.375,-0.28340811,0.07395907,0.00019359,1.76187114e-05"

rm -rf "$WORK"
mkdir -p "$WORK/sparse"
SEQ="$WORK/sequence"
IMAGES="$SEQ/mav0/cam0/data"
DB="$WORK/database.db"

"$VIOSFM" simulate --scenario two_floors --duration "$DURATION" --rate "$RATE" --seed "$SEED" \
  --out "$SEQ"

start=$(date +%s)
colmap feature_extractor --database_path "$DB" --image_path "$IMAGES" \
  --ImageReader.camera_model OPENCV --ImageReader.single_camera 1 \
  --ImageReader.camera_params "$CAMERA_PARAMS" \
  --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads 2 \
  --SiftExtraction.max_num_features "$MAX_FEATURES" > "$WORK/feature_extractor.log" 2>&1
if [ "$MATCHER" = exhaustive ]; then
  colmap exhaustive_matcher --database_path "$DB" --SiftMatching.use_gpu 0 \
    --SiftMatching.num_threads 2 > "$WORK/matcher.log" 2>&1
else
  colmap sequential_matcher --database_path "$DB" --SiftMatching.use_gpu 0 \
    --SiftMatching.num_threads 2 --SequentialMatching.overlap "$OVERLAP" \
    --SequentialMatching.loop_detection 0 > "$WORK/matcher.log" 2>&1
fi
colmap mapper --database_path "$DB" --image_path "$IMAGES" --output_path "$WORK/sparse" \
  --Mapper.num_threads 2 > "$WORK/mapper.log" 2>&1
end=$(date +%s)
echo "COLMAP ($MATCHER matching) took $((end - start)) s"

total=$(ls "$IMAGES" | wc -l)
for model in "$WORK"/sparse/*/; do
  model=${model%/}
  colmap model_converter --input_path "$model" --output_path "$model" --output_type TXT \
    > /dev/null 2>&1
  registered=$(grep -v '^#' "$model/images.txt" | awk 'NF && NR % 2 == 1' | wc -l)
  echo "== model $(basename "$model"): $registered of $total frames registered"
  "$VIOSFM" eval --est "$model" --est-format colmap \
    --ref "$SEQ/mav0/state_groundtruth_estimate0/data.csv" --ref-format euroc \
    --extrinsics-yaml "$SEQ/mav0/cam0/sensor.yaml" --cam-frame est --align sim3 \
    --json "$model/eval.json" 2>&1 || true
  # Floors merged? The distance between the mean camera centres of the
  # floor-1 and floor-2 frames, over the spread of the floor-1 centres
  # (scale-free); the same from the ground truth.
  python3 - "$model/images.txt" "$SEQ/frames.csv" <<'PY'
import math, sys
images, frames = sys.argv[1], sys.argv[2]
floor = {}
truth = {}
for line in open(frames):
    if line.startswith('#'):
        continue
    stamp, region, _, x, y, z = line.strip().split(',')
    floor[stamp] = region
    truth[stamp] = (float(x), float(y), float(z))
est = {}
rows = [l for l in open(images) if not l.startswith('#')]
for header in rows[0::2]:
    f = header.split()
    if len(f) < 10:
        continue
    qw, qx, qy, qz, tx, ty, tz = map(float, f[1:8])
    # centre = -R^T t
    R = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
         [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
         [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    t = (tx, ty, tz)
    est[f[9].split('/')[-1].rsplit('.', 1)[0]] = tuple(-sum(R[r][c] * t[r] for r in range(3)) for c in range(3))
def separation(centres):
    a = [centres[s] for s in centres if floor.get(s) == 'floor1']
    b = [centres[s] for s in centres if floor.get(s) == 'floor2']
    if len(a) < 3 or len(b) < 3:
        return None, len(a), len(b)
    mean = lambda p: tuple(sum(v[i] for v in p) / len(p) for i in range(3))
    ma, mb = mean(a), mean(b)
    spread = math.sqrt(sum(sum((v[i] - ma[i]) ** 2 for i in range(3)) for v in a) / len(a))
    return math.dist(ma, mb) / spread, len(a), len(b)
s_est, n1, n2 = separation(est)
s_true, _, _ = separation({k: truth[k] for k in est if k in truth})
print(f"floor1 frames {n1}, floor2 frames {n2}, stairwell frames "
      f"{sum(1 for s in est if floor.get(s) == 'stairwell')}; floor separation / floor-1 spread: "
      f"estimate {s_est if s_est is None else round(s_est, 3)}, truth {s_true if s_true is None else round(s_true, 3)}")
PY
done
