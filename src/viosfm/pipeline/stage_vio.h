// Stage 2 of a `viosfm run` (pipeline.h): the VIO poses of the whole
// sequence, from viosfm's own VIO, a trajectory file or a VioSource.
//
// Segments. A VIO that loses track and re-initialises gives no pose for a
// while, then poses in a new world frame; a relative pose between the two
// stretches means nothing, so every pose carries the index of its segment
// and nothing joins two segments but the images (sfm/relative_pose_priors.h,
// sfm/frame_registration.h). viosfm's own VIO says so itself: every posed
// frame (tracking or IMU-only) after a frame without a pose (initialising
// again, or lost) starts a new segment, and all its posed frames are used.
// A trajectory file, or a VIO source, is split at every gap between
// consecutive stamps longer than PipelineOptions::vio_max_gap_ns (default
// 1 s: a VIO gives poses at its frame rate, 10-30 Hz; a trajectory of
// keyframes only, tens of seconds apart, needs a larger value or 0, never
// split).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/io/frame_cache.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/run_warnings.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {

struct VioPoses {
  // No VIO: the images alone (no IMU, no trajectory file), or the images and
  // the IMU (frames too far apart for viosfm's own VIO); `segment_rule` says
  // why. The mapper then starts, carries and joins its models from the images.
  bool absent = false;
  Trajectory world_from_body;          // time ordered
  std::vector<int> segments;           // per pose
  std::vector<VioOdometer> odometers;  // per pose (ComputeVioOdometers)
  // How the segments were found, for the log.
  std::string segment_rule;
  // The sensor rig as viosfm's own VIO found it (its camera-IMU time offset
  // estimate and the IMU noise figures it used), for what else reads the
  // IMU (the metric scale); empty for an external VIO.
  std::optional<SensorRig> own_vio_rig;
  // What viosfm's own VIO decided (ran false for an external VIO).
  OwnVioDecisions own_vio;
  // s, the camera's rolling-shutter readout for the structure-from-motion
  // stages: the one viosfm's own VIO was given, or its estimate when the
  // images' evidence for it reaches PipelineOptions::min_readout_evidence;
  // PipelineOptions::rolling_shutter_readout_s for an external VIO; 0: a
  // global shutter.
  double rolling_shutter_readout_s = 0.0;
  std::string rolling_shutter_source;  // for the log: where the readout came from
  // What viosfm's own VIO said of its run (frame counts by status, resets,
  // stretches on the IMU alone); empty for an external VIO.
  std::optional<VioSummary> own_vio_summary;
  int num_segments() const { return segments.empty() ? 0 : segments.back() + 1; }
};

// A VIO trajectory file: world_from_body poses with stamps (`frame` kCam
// poses are converted with body_from_cam). Throws InputError naming the
// file when it is missing, unreadable, without stamps or without poses.
Trajectory ReadVioTrajectoryFile(const std::filesystem::path& path, TrajectoryFormat format,
                                 VioFrame frame, const Rigid3d& body_from_cam);

// The VIO trajectory (world_from_body, stamped) of the sequence, as the
// options say: vio_source, else the file vio_trajectory. Throws InputError
// naming the file when none is given, it cannot be read, has no stamps or no
// poses.
Trajectory LoadVioTrajectory(const Sequence& sequence, const PipelineOptions& options);

// The VIO poses as the options say (viosfm's own VIO without a source or
// file, else LoadVioTrajectory) with their segments and odometers. Without a
// source or file, no VIO runs where the dataset has no IMU, or where its
// images are further apart (median) than own_vio_max_frame_interval_s: the
// own VIO tracks corners from frame to frame (VioPoses::absent).
// viosfm's own VIO reads the images through `frames` (kept there for the
// features stage) when given, and reports its progress to `on_progress`
// (vio/odometry.h RunVio) when given.
VioPoses LoadVioPoses(const Sequence& sequence, const PipelineOptions& options,
                      FrameCache* frames = nullptr, const VioProgressCallback& on_progress = {});

// The own VIO's options in a run (its progress bar only when the run shows
// progress).
VioOptions OwnVioOptions(const PipelineOptions& options);
// The VIO poses of viosfm's own VIO's result on `sequence` (as LoadVioPoses
// gives them): every frame the VIO posed, in its segments (a new one after
// every reset it did not re-localise), their odometers, the rig it found;
// writes OUT/vio/. Throws InputError naming the dataset if it posed none.
VioPoses PosesOfOwnVio(const Sequence& sequence, const PipelineOptions& options,
                       const VioResult& result);

// The rolling-shutter readout the structure-from-motion stages take from
// viosfm's own VIO (VioPoses::rolling_shutter_readout_s): the one it was
// given, or its estimate (with the time offset) when the images' evidence
// reaches PipelineOptions::min_readout_evidence; 0 otherwise. `log`: say
// so when an estimate is too weak to use.
struct OwnVioReadout {
  double readout_s = 0.0;
  std::string source;  // for the log
};
OwnVioReadout OwnVioRollingShutter(const PipelineOptions& options,
                                   const TimeOffsetEstimate& time_offset, bool log);

}  // namespace viosfm
