#!/usr/bin/env bash
# viosfm's own VIO on the real handheld RealSense recording of ../shared/data
# (1280x720 at about 18 Hz, IMU at about 220 Hz, Kalibr calibration): frames
# per status, resets, segments, when tracking starts, the camera-IMU time
# offset and IMU noise figures it settled on, and its CPU time per frame
# against the camera's frame interval (real time).
#
# Usage: scripts/bench-vio-real.sh [WORK_DIR]
# Environment: VIOSFM (binary, default build/src/viosfm/cli/viosfm), DATA
#   (default ../shared/data/realsense_room_30s next to the checkout).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
VIOSFM=${VIOSFM:-$here/build/src/viosfm/cli/viosfm}
DATA=${DATA:-$here/../shared/data/realsense_room_30s}
WORK=${1:-/tmp/bench_vio_real}
if [ ! -d "$DATA/mav0" ]; then
  echo "skipped: $DATA not found (the shared real recordings are not on this machine)"
  exit 0
fi
mkdir -p "$WORK"
OUT="$WORK/vio"
rm -rf "$OUT"
/usr/bin/time -f "%U %S %e %M" -o "$WORK/time.txt" \
  "$VIOSFM" vio "$DATA" --calibration "$DATA/calibration/camchain.yaml" --out "$OUT" \
  > "$WORK/vio.log" 2>&1
read -r user sys wall kib < "$WORK/time.txt"
S="$OUT/vio_summary.txt"
value() { awk -F': ' -v k="$1" '$1 == k { print $2 }' "$S"; }
frames=$(value num_frames)
first_image_ns=$(awk -F, 'NR > 1 && $1 !~ /^#/ { print $1; exit }' "$DATA/mav0/cam0/data.csv")
last_image_ns=$(awk -F, '$1 !~ /^#/ { t = $1 } END { print t }' "$DATA/mav0/cam0/data.csv")
first_tracking_ns=$(value first_tracking_ns)
posed=$(awk -F, 'NR > 1 && $NF == 1 { n++ } END { print n + 0 }' "$OUT/states.csv")
awk -v frames="$frames" -v posed="$posed" -v user="$user" -v sys="$sys" -v wall="$wall" \
  -v kib="$kib" -v t0="$first_image_ns" -v t1="$last_image_ns" -v tt="$first_tracking_ns" \
  -v tracking="$(value frames_tracking)" -v init="$(value frames_initializing)" \
  -v imu_only="$(value frames_imu_only)" -v lost="$(value frames_lost)" \
  -v resets="$(value num_resets)" -v segments="$(value num_segments)" \
  -v beyond="$(value num_frames_beyond_imu)" -v offset="$(value time_offset_ns)" 'BEGIN {
  duration = (t1 - t0) / 1e9
  printf "frames %d over %.1f s: tracking %d, initializing %d, imu_only %d, lost %d; %d after the IMU\n",
    frames, duration, tracking, init, imu_only, lost, beyond
  printf "with a pose: %d of %d (%.1f %%); resets %d; segments %d\n",
    posed, frames, 100 * posed / frames, resets, segments
  if (tt >= 0) printf "tracking from %.2f s after the first image\n", (tt - t0) / 1e9
  else print "never tracking"
  printf "camera-IMU time offset: %.1f ms\n", offset / 1e6
  cpu = user + sys
  printf "CPU %.1f s (user %.1f, system %.1f), wall %.1f s, peak memory %.0f MiB\n",
    cpu, user, sys, wall, kib / 1024
  printf "CPU per frame %.1f ms against a frame interval of %.1f ms: %.2f of real time\n",
    1000 * cpu / frames, 1000 * duration / (frames - 1), cpu / duration
}'
grep -E "vio: (camera-IMU time offset|IMU noise)" "$WORK/vio.log" | sed 's/^[IW] [0-9:]* //' || true
