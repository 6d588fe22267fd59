#include "viosfm/pipeline/stage_vio.h"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <sstream>
#include <vector>

#include "viosfm/io/trajectory_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

void CompleteVioPoses(VioPoses* poses);

// Why viosfm's own VIO cannot run on the sequence, if it cannot.
std::optional<std::string> WhyNoOwnVio(const Sequence& sequence, const PipelineOptions& options) {
  if (!sequence.has_imu()) {
    return std::string(
        "no IMU and no VIO trajectory (--vio-trajectory): the images alone make the model, "
        "in the scale and frame of its first two views");
  }
  std::vector<timestamp_ns_t> intervals;
  for (size_t i = 1; i < sequence.images.size(); ++i) {
    intervals.push_back(sequence.images[i].timestamp_ns - sequence.images[i - 1].timestamp_ns);
  }
  if (intervals.empty()) return std::nullopt;
  std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
  const double median_s = NsToSeconds(intervals[intervals.size() / 2]);
  if (median_s <= options.own_vio_max_frame_interval_s) return std::nullopt;
  std::ostringstream reason;
  reason << std::fixed << std::setprecision(2) << "the images are " << median_s
         << " s apart (median), too far for viosfm's own VIO to track corners from one to the "
            "next (own_vio_max_frame_interval_s "
         << options.own_vio_max_frame_interval_s
         << "): the images make the model and the IMU gives it its metric scale and gravity";
  return reason.str();
}

// viosfm's own VIO on the sequence: every posed frame, a new segment after
// every stretch without a pose.
VioPoses RunOwnVio(const Sequence& sequence, const PipelineOptions& options, FrameCache* frames,
                   const VioProgressCallback& on_progress) {
  if (!sequence.has_imu()) {
    throw InputError(sequence.root.string(), 0,
                     "no VIO poses: the dataset has no IMU for viosfm's own VIO; pass "
                     "--vio-trajectory FILE (the TUM trajectory of any VIO)");
  }
  VIOSFM_LOG(INFO) << "run: no VIO trajectory given: running viosfm's own VIO";
  return PosesOfOwnVio(sequence, options,
                       RunVio(sequence, OwnVioOptions(options), frames, on_progress));
}

// The segments' odometers, and the log lines of the poses.
void CompleteVioPoses(VioPoses* poses) {
  poses->odometers = ComputeVioOdometers(poses->world_from_body, poses->segments);
  if (poses->num_segments() > 1) {
    VIOSFM_LOG(WARNING) << "run: the VIO poses form " << poses->num_segments()
                        << " segments (split at " << poses->segment_rule
                        << "); no relative pose joins two segments, the images do";
  }
  const Trajectory& vio = poses->world_from_body;
  VIOSFM_LOG(INFO) << "run: " << vio.size() << " VIO poses over "
                   << FormatNsSpan(vio.poses.front().timestamp_ns, vio.poses.back().timestamp_ns)
                   << " in " << poses->num_segments() << " segment(s)";
}

// The own VIO's decisions for the run's warnings (run_warnings.h).
OwnVioDecisions OwnVioDecisionsOf(const VioResult& result) {
  OwnVioDecisions decisions;
  decisions.ran = true;
  const TimeOffsetEstimate& offset = result.summary.time_offset;
  decisions.time_offset_estimated = offset.estimated;
  decisions.calibration_time_offset_ns = offset.calibration_offset_ns;
  decisions.time_offset_ns = offset.offset_ns;
  decisions.imu_noise_given = result.summary.imu_noise.given;
  decisions.imu_noise_used = result.summary.imu_noise.used;
  decisions.imu_noise_measured = result.summary.imu_noise.measured;
  decisions.num_resets = result.summary.num_resets;
  // Stretches of consecutive frames carried by the IMU alone.
  bool in_stretch = false;
  timestamp_ns_t start_ns = 0;
  timestamp_ns_t last_ns = 0;
  const auto end_stretch = [&] {
    if (!in_stretch) return;
    decisions.longest_imu_only_s =
        std::max(decisions.longest_imu_only_s, static_cast<double>(last_ns - start_ns) * 1e-9);
    in_stretch = false;
  };
  for (const VioFrameResult& frame : result.frames) {
    if (frame.status == VioStatus::kImuOnly) {
      ++decisions.num_imu_only_frames;
      if (!in_stretch) {
        ++decisions.num_imu_only_stretches;
        in_stretch = true;
        start_ns = frame.timestamp_ns;
      }
      last_ns = frame.timestamp_ns;
    } else {
      end_stretch();
    }
  }
  end_stretch();
  return decisions;
}

}  // namespace

VioOptions OwnVioOptions(const PipelineOptions& options) {
  VioOptions vio_options = options.own_vio;
  vio_options.show_progress = vio_options.show_progress && options.show_progress;
  return vio_options;
}

VioPoses PosesOfOwnVio(const Sequence& sequence, const PipelineOptions& options,
                       const VioResult& result) {
  WriteVioResult(options.output_folder / "vio", result);
  // Every frame the VIO gives a pose (tracking, IMU-only, or held at a
  // static start), in the VIO's own segments: a reset it re-localised stays
  // in its segment, one it did not starts a new one.
  VioPoses poses;
  std::vector<int> segment_ids;
  for (const VioFrameResult& frame : result.frames) {
    if (!frame.has_pose) continue;
    poses.world_from_body.poses.push_back({frame.timestamp_ns, frame.state.world_from_body});
    segment_ids.push_back(frame.segment);
  }
  // Renumbered 0, 1, ... in order (a segment whose frames all lack a pose
  // leaves no gap).
  int segment = -1;
  int previous_id = -1;
  for (const int id : segment_ids) {
    if (segment < 0 || id != previous_id) ++segment;
    previous_id = id;
    poses.segments.push_back(segment);
  }
  const size_t num_unposed = result.frames.size() - poses.world_from_body.size();
  if (num_unposed > 0 || result.summary.num_frames_beyond_imu > 0) {
    VIOSFM_LOG(WARNING) << "run: own VIO: " << num_unposed
                        << " frame(s) without a pose (before its initialisation or while "
                           "re-initialising), "
                        << result.summary.num_frames_beyond_imu
                        << " after the IMU's last sample; the images place them if they can";
  }
  if (poses.world_from_body.empty()) {
    throw InputError(sequence.root.string(), 0,
                     "viosfm's own VIO never initialised: " + result.summary.message);
  }
  SensorRig rig = sequence.rig;
  rig.cam_time_offset_ns = result.summary.time_offset.offset_ns;
  rig.imu_noise = result.summary.imu_noise.used;
  poses.own_vio_rig = rig;
  poses.own_vio = OwnVioDecisionsOf(result);
  poses.own_vio_summary = result.summary;
  const OwnVioReadout readout = OwnVioRollingShutter(options, result.summary.time_offset, true);
  poses.rolling_shutter_readout_s = readout.readout_s;
  poses.rolling_shutter_source = readout.source;
  poses.segment_rule =
      "the own VIO's segments (a new one after every reset it did not re-localise)";
  VIOSFM_LOG(INFO) << "run: own VIO: " << poses.world_from_body.size() << " of "
                   << result.frames.size() << " frames posed in " << segment + 1 << " segment(s) ("
                   << result.summary.num_resets << " reset(s)), " << result.summary.cpu_seconds
                   << " CPU s" << LogDetails() << " (output in "
                   << (options.output_folder / "vio").string() << ")";
  CompleteVioPoses(&poses);
  return poses;
}

OwnVioReadout OwnVioRollingShutter(const PipelineOptions& options,
                                   const TimeOffsetEstimate& time_offset, bool log) {
  OwnVioReadout readout;
  if (options.own_vio.rolling_shutter_readout_s > 0.0) {
    readout.readout_s = options.own_vio.rolling_shutter_readout_s;
    readout.source = "given to the own VIO";
  } else if (time_offset.readout_estimated && time_offset.rolling_shutter_cost_px > 0.0) {
    const double evidence =
        time_offset.global_shutter_cost_px / time_offset.rolling_shutter_cost_px;
    std::ostringstream source;
    source << std::fixed << std::setprecision(2)
           << "the own VIO's estimate; its residual as a global shutter " << evidence
           << " times the one with the readout";
    if (evidence >= options.min_readout_evidence) {
      readout.readout_s = time_offset.readout_s;
      readout.source = source.str();
    } else {
      readout.source = source.str() + ", under rolling_shutter.min_readout_evidence: not used";
      if (log) {
        VIOSFM_LOG(INFO) << "run: rolling-shutter readout of the own VIO (" << std::setprecision(1)
                         << std::fixed << time_offset.readout_s * 1e3
                         << " ms) not used: the images' evidence is weak" << LogDetails() << " ("
                         << source.str() << ", under rolling_shutter.min_readout_evidence "
                         << std::setprecision(2) << options.min_readout_evidence
                         << "): the keypoints are taken as from a global shutter";
      }
    }
  } else {
    readout.source = "the own VIO: a global shutter explains the images";
  }
  return readout;
}

Trajectory ReadVioTrajectoryFile(const fs::path& path, TrajectoryFormat format, VioFrame frame,
                                 const Rigid3d& body_from_cam) {
  if (!fs::is_regular_file(path))
    throw InputError(path.string(), 0, "VIO trajectory file not found");
  Trajectory vio = ReadTrajectory(path, format);
  if (!vio.has_timestamps)
    throw InputError(path.string(), 0, "the VIO trajectory needs timestamps");
  if (vio.empty()) throw InputError(path.string(), 0, "the VIO trajectory has no poses");
  if (frame == VioFrame::kCam) vio = CameraToBodyTrajectory(vio, body_from_cam);
  return vio;
}

Trajectory LoadVioTrajectory(const Sequence& sequence, const PipelineOptions& options) {
  if (options.vio_source) {
    Trajectory vio = options.vio_source(sequence);
    if (vio.empty()) throw InputError("the VIO gave no poses for " + sequence.root.string());
    return vio;
  }
  if (options.vio_trajectory.empty()) {
    throw InputError("no VIO trajectory given (and viosfm's own VIO is run by LoadVioPoses)");
  }
  return ReadVioTrajectoryFile(options.vio_trajectory, options.vio_format, options.vio_frame,
                               sequence.rig.body_from_cam);
}

VioPoses LoadVioPoses(const Sequence& sequence, const PipelineOptions& options, FrameCache* frames,
                      const VioProgressCallback& on_progress) {
  if (options.UsesOwnVio()) {
    if (const std::optional<std::string> reason = WhyNoOwnVio(sequence, options)) {
      VioPoses poses;
      poses.absent = true;
      poses.segment_rule = *reason;
      VIOSFM_LOG(WARNING) << "run: " << *reason;
      return poses;
    }
    return RunOwnVio(sequence, options, frames, on_progress);
  }
  VioPoses poses;
  {
    poses.world_from_body = LoadVioTrajectory(sequence, options);
    poses.rolling_shutter_readout_s = options.rolling_shutter_readout_s;
    poses.rolling_shutter_source = "rolling_shutter.readout_s";
    // One segment: a time gap alone is no re-initialisation. The gaps
    // longer than vio_max_gap_ns are candidate breaks, which the images
    // confirm or refute before mapping (sfm/vio_gaps.h).
    poses.segments.assign(poses.world_from_body.size(), 0);
    poses.segment_rule = options.vio_max_gap_ns > 0
                             ? "one segment; its time gaps longer than " +
                                   FormatNsAsSeconds(options.vio_max_gap_ns, 3) +
                                   " s judged by the images"
                             : "one segment (--vio-max-gap 0)";
  }
  CompleteVioPoses(&poses);
  const std::vector<int> gaps = SegmentsFromTimeGaps(poses.world_from_body, options.vio_max_gap_ns);
  for (size_t k = 0; k < gaps.size(); ++k) poses.odometers[k].gap = gaps[k];
  if (!gaps.empty() && gaps.back() > 0) {
    VIOSFM_LOG(INFO) << "run: the VIO trajectory has " << gaps.back() << " time gap(s) longer than "
                     << FormatNsAsSeconds(options.vio_max_gap_ns, 3)
                     << " s: each is one segment where the images confirm the VIO's relative pose "
                        "across it, a break where they contradict it or show nothing";
  }
  return poses;
}

}  // namespace viosfm
