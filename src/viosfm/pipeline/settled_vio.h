// The VIO's poses as a stream's frames need them, while the VIO runs: its
// rig and readout once known, and each frame's pose once settled.
#pragma once

#include <condition_variable>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/util/errors.h"

namespace viosfm {

// What the structure-from-motion side takes from the VIO before its first
// frame: the rig it ran with (its camera-IMU time offset and IMU noise) and
// the rolling-shutter readout.
struct VioSetup {
  SensorRig rig;
  double readout_s = 0.0;
  std::string readout_source;
};

// The VIO's poses as they settle, for the frames the stream reaches: from
// the own VIO's thread (Report), or all at once (SetAll). The poses, their
// segments and odometers are those LoadVioPoses gives at the end, pose for
// pose (the segments numbered as RunOwnVio numbers them).
class SettledVio {
 public:
  SettledVio(const SensorRig& rig, const std::filesystem::path& root,
             const PipelineOptions& options)
      : rig_(rig), root_(root), options_(options) {}

  // The own VIO's progress (called on its thread).
  void Report(const VioProgress& progress) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!setup_) {
        VioSetup setup;
        setup.rig = rig_;
        setup.rig.cam_time_offset_ns = progress.time_offset->offset_ns;
        setup.rig.imu_noise = progress.imu_noise->used;
        const OwnVioReadout readout =
            OwnVioRollingShutter(options_, *progress.time_offset, /*log=*/false);
        setup.readout_s = readout.readout_s;
        setup.readout_source = readout.source;
        setup_ = setup;
      }
      const std::vector<VioFrameResult>& frames = *progress.frames;
      for (; consumed_ < progress.num_settled; ++consumed_) {
        const VioFrameResult& frame = frames[consumed_];
        settled_until_ns_ = frame.timestamp_ns;
        if (!frame.has_pose) continue;
        if (segments_.empty() || frame.segment != last_raw_segment_) ++segment_;
        last_raw_segment_ = frame.segment;
        AddPose(frame.timestamp_ns, frame.state.world_from_body, segment_);
      }
      finished_ = progress.finished;
    }
    changed_.notify_all();
  }

  // An external VIO's poses, all of them.
  void SetAll(const VioPoses& poses) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      VioSetup setup;
      setup.rig = poses.own_vio_rig.value_or(rig_);
      setup.readout_s = poses.rolling_shutter_readout_s;
      setup.readout_source = poses.rolling_shutter_source;
      setup_ = setup;
      posed_ = poses.world_from_body;
      segments_ = poses.segments;
      odometers_ = poses.odometers;
      // A VIO file's gaps are judged by the pairs across them before a run
      // in turn maps (sfm/vio_gaps.h); a stream maps before those pairs are
      // all known, so each gap is a break here.
      for (size_t k = 0; k < odometers_.size(); ++k) {
        segments_[k] += odometers_[k].gap;
        odometers_[k].segment = segments_[k];
        odometers_[k].gap = 0;
      }
      finished_ = true;
    }
    changed_.notify_all();
  }

  void Fail(const std::string& message) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      failure_ = message;
    }
    changed_.notify_all();
  }

  // Blocks until the rig and the readout are known.
  VioSetup WaitForSetup() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return setup_.has_value() || finished_ || !failure_.empty(); });
    if (!failure_.empty()) throw std::runtime_error(failure_);
    if (!setup_) throw InputError(root_.string(), 0, "the VIO processed no frame");
    return *setup_;
  }

  // The VIO pose nearest to `stamp_ns` within max_gap_ns, as
  // SelectFramesStage associates it: blocks until the VIO has settled a
  // frame after stamp_ns + max_gap_ns (or finished).
  std::optional<FrameVioPose> PoseAt(timestamp_ns_t stamp_ns, timestamp_ns_t max_gap_ns) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] {
      return finished_ || !failure_.empty() || settled_until_ns_ > stamp_ns + max_gap_ns;
    });
    if (!failure_.empty()) throw std::runtime_error(failure_);
    const std::optional<size_t> index = NearestPoseIndex(posed_, stamp_ns, max_gap_ns);
    if (!index) return std::nullopt;
    return FrameVioPose{posed_.poses[*index].world_from_frame, odometers_[*index]};
  }

  size_t num_poses() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return posed_.size();
  }

 private:
  void AddPose(timestamp_ns_t stamp_ns, const Rigid3d& world_from_body, int segment) {
    VioOdometer odometer;
    odometer.segment = segment;
    if (!posed_.empty() && segments_.back() == segment) {
      const Rigid3d& before = posed_.poses.back().world_from_frame;
      odometer.distance_m =
          odometers_.back().distance_m + (world_from_body.translation - before.translation).norm();
      odometer.rotation_rad = odometers_.back().rotation_rad +
                              before.rotation.angularDistance(world_from_body.rotation);
    }
    posed_.poses.push_back({stamp_ns, world_from_body});
    segments_.push_back(segment);
    odometers_.push_back(odometer);
  }

  const SensorRig rig_;
  const std::filesystem::path root_;
  const PipelineOptions& options_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::optional<VioSetup> setup_;
  Trajectory posed_;
  std::vector<int> segments_;
  std::vector<VioOdometer> odometers_;
  int segment_ = -1;
  int last_raw_segment_ = -1;
  size_t consumed_ = 0;
  timestamp_ns_t settled_until_ns_ = std::numeric_limits<timestamp_ns_t>::min();
  bool finished_ = false;
  std::string failure_;
};

}  // namespace viosfm
