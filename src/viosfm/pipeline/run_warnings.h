// The decisions of a run a user should know, one short line each: the
// camera-IMU time offset changed, the IMU noise replaced, where the metric
// scale came from and how uncertain it is, frames without a pose, the VIO's
// segments and its stretches on the IMU alone, separate models. They are
// the console's last lines, summary.json's `warnings` and the top of the
// report; the details stay in summary.json and the log.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "viosfm/sensor/imu.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct PipelineSummary;

// What viosfm's own VIO decided (ran false for an external VIO or none).
struct OwnVioDecisions {
  bool ran = false;
  // The camera-IMU time offset (t_imu = t_cam + offset): whether the VIO's
  // estimate replaced the calibration's, and both.
  bool time_offset_estimated = false;
  timestamp_ns_t calibration_time_offset_ns = 0;
  timestamp_ns_t time_offset_ns = 0;
  // The IMU noise as the calibration states it and as the VIO used it.
  ImuNoise imu_noise_given;
  ImuNoise imu_noise_used;
  bool imu_noise_measured = false;  // measured at rest (else bounded by the quietest window)
  // Frames carried by the IMU alone (too few landmarks), in stretches of
  // consecutive frames, and the longest stretch (s).
  size_t num_imu_only_frames = 0;
  size_t num_imu_only_stretches = 0;
  double longest_imu_only_s = 0.0;
  int num_resets = 0;
};

// The lines, each at most kMaxConsoleLineLength - 4 characters (they are
// printed indented); the metric scale's line always, the others when the
// run decided so.
std::vector<std::string> RunWarnings(const PipelineSummary& summary);

}  // namespace viosfm
