// A recorded EuRoC folder written again as a recorder writes it while it
// records (the other side of euroc_follower.h; `viosfm replay`): for trying
// `viosfm run --follow` on a recording, and for measuring it.
//
// Into `target` (created; it must not hold a recording already): first the
// camera's and the IMU's sensor.yaml files, copied; then, in the order of
// their stamps and at their pace (divided by `speed`), each IMU row
// appended to imu0/data.csv and each image copied (under a temporary name,
// then renamed) before its row is appended to cam0/data.csv, the rows as
// the source has them; the ground truth, if any, at the end.
#pragma once

#include <filesystem>

namespace viosfm {

struct EurocReplayOptions {
  // Times real time; 0: as fast as the files can be written. Default 1.
  double speed = 1.0;
  // Seconds of the recording skipped at its start (rows before its first
  // stamp plus this are not written). Default 0.
  double skip_s = 0.0;
};

// Throws InputError naming the file for a source that is not a EuRoC
// folder with images and IMU, a target that holds a recording already, or
// options out of range.
void ReplayEurocRecording(const std::filesystem::path& source, const std::filesystem::path& target,
                          const EurocReplayOptions& options = {});

}  // namespace viosfm
