#include "viosfm/pipeline/stage_frames.h"

#include <algorithm>
#include <cmath>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
SelectedFrames SelectFramesStage(const Sequence& sequence, const VioPoses& vio,
                                 const PipelineOptions& options, const std::string& vio_name,
                                 FrameCache* frame_cache) {
  return SelectedFramesOf(
      sequence,
      SelectFrames(sequence, options.frame_selection, vio.absent ? nullptr : &vio.world_from_body),
      vio, options, vio_name, frame_cache);
}

SelectedFrames SelectedFramesOf(const Sequence& sequence, const FrameSelection& selection,
                                const VioPoses& vio, const PipelineOptions& options,
                                const std::string& vio_name, FrameCache* frame_cache) {
  SelectedFrames frames;
  frames.selection = selection;
  if (!frames.selection.ok()) {
    throw InputError(options.dataset.string(), 0,
                     "no frames to reconstruct: " + frames.selection.message);
  }
  frames.sequence = sequence;
  frames.sequence.images.clear();
  for (const size_t index : frames.selection.kept) {
    const SequenceImage& image = sequence.images[index];
    const std::optional<size_t> pose_index = NearestPoseIndex(
        vio.world_from_body, image.timestamp_ns, options.max_vio_time_difference_ns);
    frames.sequence.images.push_back(image);
    frames.vio_index.push_back(pose_index);
    if (pose_index) {
      frames.vio_at_frames.poses.push_back(
          {image.timestamp_ns, vio.world_from_body.poses[*pose_index].world_from_frame});
    } else {
      ++frames.num_without_vio_pose;
    }
  }
  if (!vio.absent && frames.vio_at_frames.size() < 2) {
    throw InputError(vio_name, 0,
                     "the VIO poses " +
                         FormatNsSpan(vio.world_from_body.poses.front().timestamp_ns,
                                      vio.world_from_body.poses.back().timestamp_ns) +
                         " do not overlap the selected images " +
                         FormatNsSpan(sequence.images.front().timestamp_ns,
                                      sequence.images.back().timestamp_ns) +
                         " in time: " + std::to_string(frames.vio_at_frames.size()) + " of " +
                         std::to_string(frames.selection.kept.size()) +
                         " images have a pose within " +
                         FormatNsAsSeconds(options.max_vio_time_difference_ns, 3) +
                         " s (at least 2 are needed)");
  }
  if (!vio.absent && frames.num_without_vio_pose > 0) {
    VIOSFM_LOG(WARNING) << "run: " << frames.num_without_vio_pose << " of "
                        << frames.sequence.images.size()
                        << " selected frames have no VIO pose within "
                        << FormatNsAsSeconds(options.max_vio_time_difference_ns, 3)
                        << " s (VIO not initialised, lost or re-initialising): they are "
                           "registered from the images where these allow";
  }
  if (vio.rolling_shutter_readout_s > 0.0) {
    const std::string readout = FormatNsAsSeconds(
        static_cast<timestamp_ns_t>(std::llround(vio.rolling_shutter_readout_s * 1e9)), 4);
    if (!options.compensate_rolling_shutter) {
      VIOSFM_LOG(WARNING) << "run: rolling shutter (readout " << readout << " s, "
                          << vio.rolling_shutter_source
                          << ") not compensated (rolling_shutter.compensate=false)";
    } else if (sequence.imu.empty()) {
      VIOSFM_LOG(WARNING) << "run: rolling shutter (readout " << readout << " s, "
                          << vio.rolling_shutter_source
                          << ") not compensated: the dataset has no IMU";
    } else {
      const SensorRig& rig = vio.own_vio_rig ? *vio.own_vio_rig : sequence.rig;
      frames.rolling_shutter.readout_s = vio.rolling_shutter_readout_s;
      double max_rate = 0.0;
      for (const SequenceImage& image : frames.sequence.images) {
        frames.rolling_shutter.cam_angular_rate.push_back(
            CamAngularRate(rig, sequence.imu, image.timestamp_ns));
        max_rate = std::max(max_rate, frames.rolling_shutter.cam_angular_rate.back().norm());
      }
      VIOSFM_LOG(INFO) << "run: rolling shutter: readout " << readout << " s ("
                       << vio.rolling_shutter_source
                       << "); the keypoints are turned back by the gyro's rotation over their "
                          "row's time (fastest turn "
                       << max_rate << " rad/s)";
    }
  }
  VIOSFM_LOG(INFO) << "run: " << frames.selection.message << "; "
                   << frames.sequence.images.size() - frames.num_without_vio_pose
                   << " frames with a VIO pose";
  std::vector<std::filesystem::path> selected_paths;
  for (const SequenceImage& image : frames.sequence.images) selected_paths.push_back(image.path);
  frame_cache->RetainOnly(selected_paths);
  return frames;
}

}  // namespace viosfm
