#!/usr/bin/env bash
# The images-only core under the VIO, on simulated sequences with exact
# ground truth (docs/benchmarks.md "Without a VIO, or with a sparse one"):
#
#   kf_vio      keyframe-like frames (0.05-7 s apart, as EuRoC V1_01's 100
#               keyframes in 144 s) and a VIO file with poses at the
#               keyframes only (a keyframe-based VIO's trajectory), against
#               the same frames with the VIO's dense trajectory (uncut)
#   kf_reinit   the same with a re-initialisation at 60 s (a new world frame
#               after a 1 s gap): one break found, the rest one segment
#   cut_vio     10 Hz frames, the VIO's poses dropped for about 20 % of the
#               frames in 3-5 s stretches, against the uncut VIO
#   no_imu      10 Hz frames, the images alone (--no-imu, no VIO), beside
#               COLMAP 3.8 on the same images with the same calibration
#               (sequential matching; NO_COLMAP=1 skips it)
#   sparse_imu  keyframe-like frames 0.5-2 s apart with the IMU and no VIO:
#               metric scale and gravity from the IMU; beside the images
#               alone, and COLMAP 3.8 (exhaustive matching)
#
# Usage: scripts/bench-sfm-core.sh OUT [CASE...]   (default: every case)
# SCENARIO (default room), SEED (default 0). Needs jq and python3-numpy.
# Writes OUT/table.md.
# PRESET (environment): viosfm run's --preset, default paper (the settings of the
# documented figures); PRESET=realtime runs viosfm's default.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
out=${1:?usage: scripts/bench-sfm-core.sh OUT [CASE...]}
shift
cases=("$@")
[ ${#cases[@]} = 0 ] && cases=(kf_vio kf_reinit cut_vio no_imu sparse_imu)
scenario=${SCENARIO:-room}
seed=${SEED:-0}
mkdir -p "$out"
out=$(cd "$out" && pwd)
max_features=1500  # viosfm's and COLMAP's SIFT features per image
run_flags=(--n1 10 --n2 5 --max-features "$max_features" --no-progress --threads 2)

simulate() {  # NAME FLAGS...: the sequence OUT/seq/NAME, made once
  local name=$1
  shift
  if [ ! -d "$out/seq/$name" ]; then
    "$VIOSFM" simulate --scenario "$scenario" --seed "$seed" --vio-profile realistic "$@" \
      --out "$out/seq/$name" > "$out/seq_$name.log" 2>&1
  fi
  echo "$out/seq/$name"
}

run() {  # NAME DATASET FLAGS...: OUT/runs/NAME, run once
  local name=$1 dataset=$2
  shift 2
  mkdir -p "$out/runs"
  if [ ! -f "$out/runs/$name/summary.json" ]; then
    "$VIOSFM" run "$dataset" --out "$out/runs/$name" --preset "${PRESET:-paper}" "${run_flags[@]}" "$@" \
      > "$out/runs/$name.log" 2>&1 || echo "run $name failed: $out/runs/$name.log" >&2
  fi
}

# The VIO's poses at the image stamps only (a keyframe trajectory file).
at_image_stamps() {  # SEQ VIO_IN VIO_OUT
  /usr/bin/python3 - "$1/mav0/cam0/data.csv" "$2" "$3" <<'PY'
import sys
def ns(text):  # decimal seconds or integer nanoseconds, exactly
    whole, _, frac = text.partition(".")
    return int(whole) * 10**9 + int((frac + "000000000")[:9]) if "." in text else int(text)
stamps = {int(l.split(",")[0]) for l in open(sys.argv[1]) if not l.startswith("#")}
with open(sys.argv[3], "w") as out:
    for l in open(sys.argv[2]):
        if l.startswith("#") or ns(l.split()[0]) in stamps:
            out.write(l)
PY
}

# The VIO's poses dropped in stretches of 3-5 s covering about 20 % of the time.
cut_stretches() {  # VIO_IN VIO_OUT
  /usr/bin/python3 - "$1" "$2" "$seed" <<'PY'
import sys, random
rows = [l for l in open(sys.argv[1]) if not l.startswith("#")]
random.seed(int(sys.argv[3]))
t0, t1 = float(rows[0].split()[0]), float(rows[-1].split()[0])
cuts, t = [], t0 + 3.0
while t < t1 - 5.0:
    length = random.uniform(3.0, 5.0)
    cuts.append((t, t + length))
    t += length / 0.2
with open(sys.argv[2], "w") as f:
    for l in rows:
        s = float(l.split()[0])
        if not any(a <= s < b for a, b in cuts):
            f.write(l)
PY
}

# COLMAP 3.8 on a simulated sequence's images with its calibration and as many
# SIFT features per image as viosfm extracts:
# OUT/colmap_NAME/trajectory_body.tum.
colmap_on() {  # NAME SEQ MATCHER
  local dir=$out/colmap_$1 seq=$2 matcher=$3
  [ "${NO_COLMAP:-0}" = 1 ] && return
  [ -f "$dir/trajectory_body.tum" ] && return
  rm -rf "$dir"
  mkdir -p "$dir/sparse"
  export QT_QPA_PLATFORM=offscreen
  local params
  params=$(/usr/bin/python3 - "$seq/mav0/cam0/sensor.yaml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
def numbers(key):
    return [float(v) for v in re.search(key + r":\s*\[([^\]]*)\]", text).group(1).split(",")]
fx, fy, cx, cy = numbers("intrinsics")
k1, k2, p1, p2 = numbers("distortion_coefficients")
print(",".join(str(v) for v in [fx, fy, cx + 0.5, cy + 0.5, k1, k2, p1, p2]))
PY
)
  local start
  start=$(date +%s.%N)
  {
    colmap feature_extractor --database_path "$dir/database.db" \
      --image_path "$seq/mav0/cam0/data" --ImageReader.camera_model OPENCV \
      --ImageReader.single_camera 1 --ImageReader.camera_params "$params" \
      --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads 2 \
      --SiftExtraction.max_num_features "$max_features" &&
      colmap "$matcher" --database_path "$dir/database.db" --SiftMatching.use_gpu 0 \
        --SiftMatching.num_threads 2 &&
      colmap mapper --database_path "$dir/database.db" --image_path "$seq/mav0/cam0/data" \
        --output_path "$dir/sparse" --Mapper.num_threads 2 --Mapper.ba_refine_focal_length 0 \
        --Mapper.ba_refine_principal_point 0 --Mapper.ba_refine_extra_params 0
  } > "$dir/log.txt" 2>&1 || true
  echo "$(date +%s.%N) - $start" | bc > "$dir/seconds.txt"
  [ -f "$dir/sparse/0/images.bin" ] || return
  mkdir -p "$dir/txt"
  colmap model_converter --input_path "$dir/sparse/0" --output_path "$dir/txt" --output_type TXT \
    > /dev/null 2>&1
  /usr/bin/python3 "$here/scripts/lib/colmap_to_tum.py" "$dir/txt" - "$dir/trajectory_body.tum" \
    "$seq/mav0/cam0/sensor.yaml"
}

# Sim(3) ATE (mm), SE(3) ATE (mm), scale, gravity error (deg: the tilt
# between the model's vertical and the truth's after the SE(3) fit) of a
# body trajectory against the truth (default: a run's trajectory_body.tum
# against its groundtruth_body.tum).
accuracy() {  # RUN [ESTIMATE.tum]
  /usr/bin/python3 - "$1" "${2:-$1/trajectory_body.tum}" <<'PY'
import sys, numpy as np
run, estimate = sys.argv[1], sys.argv[2]
def load(p):
    d = {}
    for l in open(p):
        if l.startswith("#"): continue
        v = l.split()
        d[round(float(v[0]), 6)] = np.array(list(map(float, v[1:8])))
    return d
try:
    est, gt = load(estimate), load(f"{run}/groundtruth_body.tum")
except OSError:
    print("- - - -"); sys.exit()
keys = sorted(set(est) & set(gt))
if len(keys) < 3:
    print("- - - -"); sys.exit()
P = np.array([est[k][:3] for k in keys]); Q = np.array([gt[k][:3] for k in keys])
def umeyama(P, Q, scale):
    mp, mq = P.mean(0), Q.mean(0)
    C = (Q - mq).T @ (P - mp) / len(P)
    U, D, Vt = np.linalg.svd(C)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0: S[2, 2] = -1
    R = U @ S @ Vt
    s = np.trace(np.diag(D) @ S) / ((P - mp) ** 2).sum(1).mean() if scale else 1.0
    return s, R, mq - s * R @ mp
def ate(scale):
    s, R, t = umeyama(P, Q, scale)
    return np.sqrt(((s * (R @ P.T).T + t - Q) ** 2).sum(1).mean()), s, R
sim3, s, _ = ate(True)
se3, _, R = ate(False)
tilt = np.degrees(np.arccos(np.clip((R @ np.array([0, 0, 1.0]))[2], -1, 1)))
print(f"{1000 * sim3:.2f} {1000 * se3:.2f} {1 / s:.4f} {tilt:.2f}")
PY
}

row() {  # CASE RUN NOTE
  local summary=$out/runs/$2/summary.json
  local frames="-"
  [ -f "$summary" ] && frames=$(jq -r '"\(.frames.registered + .frames.vio_only) of \(.frames.selected) posed (\(.frames.unposed) unposed), \(.models.frames | length) model(s), VIO segments \(.vio.segments)"' "$summary")
  read -r sim3 se3 scale tilt <<< "$(accuracy "$out/runs/$2")"
  echo "| $1 | $2 | $frames | $sim3 | $se3 | $scale | $tilt | $3 |"
}

colmap_row() {  # CASE NAME RUN (whose ground truth it is judged against)
  local traj=$out/colmap_$2/trajectory_body.tum
  [ -f "$traj" ] || return 0
  local posed
  posed=$(grep -vc '^#' "$traj")
  read -r sim3 se3 scale tilt <<< "$(accuracy "$out/runs/$3" "$traj")"
  echo "| $1 | COLMAP 3.8 | $posed posed | $sim3 | $se3 | $scale | $tilt | the same images and calibration, $(awk '{ printf "%.0f", $1 }' "$out/colmap_$2/seconds.txt") s |"
}

table=()
for case in "${cases[@]}"; do
  case $case in
    kf_vio)
      seq=$(simulate kf --duration 144 --rate 20 --keyframes)
      at_image_stamps "$seq" "$seq/vio_emulated.tum" "$out/kf_vio.tum"
      run kf_dense "$seq" --rate 0 --vio-trajectory "$seq/vio_emulated.tum"
      run kf_vio "$seq" --rate 0 --vio-trajectory "$out/kf_vio.tum"
      table+=("$(row kf_vio kf_dense "the VIO's dense trajectory (uncut)")")
      table+=("$(row kf_vio kf_vio "the VIO at the keyframes only")")
      ;;
    kf_reinit)
      seq=$(simulate kf_reinit --duration 144 --rate 20 --keyframes --vio-reinit-at 60)
      at_image_stamps "$seq" "$seq/vio_emulated.tum" "$out/kf_reinit.tum"
      run kf_reinit "$seq" --rate 0 --vio-trajectory "$out/kf_reinit.tum"
      table+=("$(row kf_reinit kf_reinit "re-initialised at 60 s: $(jq -r '"\(.vio.gaps.contradicted) contradicted, \(.vio.gaps.without_pairs) unseen, \(.vio.gaps.confirmed) confirmed of \(.vio.gaps.candidates) gaps"' "$out/runs/kf_reinit/summary.json" 2>/dev/null)")")
      ;;
    cut_vio)
      seq=$(simulate walk10 --duration 60 --rate 10)
      cut_stretches "$seq/vio_emulated.tum" "$out/cut_vio.tum"
      run walk_vio "$seq" --vio-trajectory "$seq/vio_emulated.tum"
      run walk_cut "$seq" --vio-trajectory "$out/cut_vio.tum"
      table+=("$(row cut_vio walk_vio "the VIO uncut")")
      table+=("$(row cut_vio walk_cut "the VIO cut for $(awk 'END { print NR }' "$out/cut_vio.tum") of $(awk 'END { print NR }' "$seq/vio_emulated.tum") poses")")
      ;;
    no_imu)
      seq=$(simulate walk10 --duration 60 --rate 10)
      run walk_no_imu "$seq" --no-imu
      colmap_on walk10 "$seq" sequential_matcher
      table+=("$(row no_imu walk_no_imu "images only")")
      table+=("$(colmap_row no_imu walk10 walk_no_imu)")
      ;;
    sparse_imu)
      seq=$(simulate sparse --duration 60 --rate 20 --keyframes --keyframe-min-gap 0.5 --keyframe-max-gap 2)
      run sparse_imu "$seq" --rate 0
      run sparse_no_imu "$seq" --rate 0 --no-imu
      colmap_on sparse "$seq" exhaustive_matcher
      table+=("$(row sparse_imu sparse_imu "the images and the IMU, no VIO")")
      table+=("$(row sparse_imu sparse_no_imu "the images alone")")
      table+=("$(colmap_row sparse_imu sparse sparse_no_imu)")
      ;;
  esac
done

{
  echo "Scenario $scenario, seed $seed. ATE against the ground truth after Sim(3) and SE(3) alignment (mm), the trajectory's scale (1 / the Sim(3) fit's), and the tilt of its vertical against the truth's after the SE(3) fit (deg)."
  echo
  echo "| case | run | frames | ATE Sim(3) mm | ATE SE(3) mm | scale | gravity error deg | |"
  echo "|---|---|---|---|---|---|---|---|"
  printf '%s\n' "${table[@]}"
} | tee "$out/table.md"
