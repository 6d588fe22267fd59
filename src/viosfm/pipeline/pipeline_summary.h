// What a `viosfm run` did (pipeline.h): frame counts (selected, registered,
// placed by the VIO only, unposed and why), the stages' summaries, the
// model's size, the accuracy against the ground truth when there is one,
// the time of each stage and the peak memory; summary.json's document.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/eval/metric_accuracy.h"
#include "viosfm/features/feature_extraction.h"
#include "viosfm/io/frame_cache.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/all_frame_poses.h"
#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/pipeline/metric_scale.h"
#include "viosfm/pipeline/run_warnings.h"
#include "viosfm/pipeline/texture_probe.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/vio_gaps.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {

// The version written to summary.json.
std::string ViosfmVersion();

struct PipelineStageTime {
  std::string name;
  double seconds = 0.0;  // wall clock
  // CPU time of the whole process during the stage (user + system, every
  // thread): seconds of CPU over seconds of wall clock is how many cores
  // it kept busy.
  double cpu_seconds = 0.0;
};

// Accuracy against the ground truth (metres): the Sim(3)-aligned ATE
// statistics, and the metric figures (eval/metric_accuracy.h) of the
// estimate and of the input VIO on the same frames.
struct PipelineEvaluation {
  double ate_rmse_m = 0.0;
  double ate_median_m = 0.0;
  double ate_mean_m = 0.0;
  double ate_max_m = 0.0;
  // The input VIO's figures below are there (a run without a VIO has none).
  bool has_vio = true;
  double vio_ate_rmse_m = 0.0;  // the input VIO on the same frames
  double vio_ate_median_m = 0.0;
  size_t num_poses = 0;       // associated poses
  MetricAccuracy metric;      // the estimate
  MetricAccuracy vio_metric;  // the input VIO on the same frames (one alignment over all segments)
  // Every image of the recording posed (all_frame_poses.h), against the
  // ground truth at the images' stamps.
  std::optional<MetricAccuracy> all_frames_metric;
};

// The model's rotations against the dataset's gyro (eval/gyro_check.h):
// relative rotations over 1 s intervals, at the camera-IMU time offset the
// run used. The model is made with the gyro (its priors,
// sfm/gyro_priors.h), so this is its consistency with the gyro, not an
// independent accuracy; with an IMU only.
struct PipelineGyroCheck {
  size_t num_intervals = 0;
  double rmse_deg = 0.0;
  double median_deg = 0.0;
  double max_deg = 0.0;
  // The worst interval, in seconds since the first compared frame.
  double worst_from_s = 0.0;
  double worst_to_s = 0.0;
  timestamp_ns_t time_offset_ns = 0;  // t_imu = t_cam + offset
};

// A streamed run (stream_pipeline.h): its stages overlapped, so each
// one's busy time instead of one after the other, and how long the model
// took once the last frame had come.
struct PipelineStreamSummary {
  bool streamed = false;
  // Wall clock from the stream's start until the VIO had processed every
  // frame (own VIO), until the verification had decided every pair, and
  // until the mapper ended.
  double vio_seconds = 0.0;
  double verification_seconds = 0.0;
  double mapper_seconds = 0.0;
  // Of the verification's, the seconds it spent matching and verifying
  // pairs (the rest it waited for the VIO and the features).
  double verification_busy_seconds = 0.0;
  // Frames whose features were extracted beside the VIO (the rest by the
  // verification's thread itself).
  size_t num_features_beside = 0;
  // From the last frame's features to the mapper's end: what a run that
  // follows a recording takes once the recording ends.
  double seconds_after_last_frame = 0.0;
  // The retrieval's vocabulary: trained on the first frames (how many), or
  // loaded from a file.
  size_t num_vocabulary_frames = 0;
  // A followed recording (--follow): when its last row came (seconds since
  // the stream's start), and from then to the model, the wait for the
  // silence that ends it (follow_idle_s) included.
  bool followed = false;
  double recording_end_seconds = 0.0;
  double seconds_after_recording_end = 0.0;
};

struct PipelineSummary {
  std::string dataset;
  // The hash of the run's fingerprint (run_fingerprint.h, RunFingerprint::Hash):
  // runs with equal ones were made from the same inputs and data-shaping options.
  std::string fingerprint;
  std::filesystem::path output_folder;
  std::string started_utc;  // ISO 8601 in UTC, "YYYY-MM-DDTHH:MM:SSZ"
  size_t num_frames_in = 0;
  size_t num_frames_selected = 0;          // selected (with or without a VIO pose)
  size_t num_frames_without_vio_pose = 0;  // selected frames without a VIO pose
  // Posed frames whose pose the images support (registered), placed by the
  // VIO only, and frames without any pose (mapper.frames says why).
  size_t num_frames_registered = 0;
  size_t num_frames_vio_only = 0;
  size_t num_frames_unposed = 0;
  int num_vio_segments = 0;  // in the VIO input (after the gaps' decisions)
  // What viosfm's own VIO decided (time offset, IMU noise, IMU-only stretches).
  OwnVioDecisions own_vio;
  std::string vio_segment_rule;
  // viosfm's own VIO's summary (its frames by status, resets, stretches on
  // the IMU alone); empty for an external VIO or none.
  std::optional<VioSummary> own_vio_summary;
  // The gaps of a VIO trajectory file judged by the images (sfm/vio_gaps.h).
  VioGapSummary vio_gaps;
  // A camera guessed from the image size, as the adjustment refined it
  // ("MODEL params"); empty for a calibrated one.
  std::string camera_refined;
  FrameSelection frame_selection;
  // The texture probe (texture_probe.h), and the frame rate (Hz) and
  // feature count the run used after it.
  TextureProbeResult texture_probe;
  std::string texture_probe_message;
  double frame_rate_hz = 0.0;
  int max_num_features = 0;
  // The rolling-shutter readout the keypoints were compensated for (s; 0:
  // none), and where it came from or why it was not used.
  double rolling_shutter_readout_s = 0.0;
  std::string rolling_shutter_source;
  // Every image of the recording: how it was posed (all_frame_poses.h;
  // trajectory_body_all_frames.tum).
  AllFramePoseCounts all_frames;
  FeatureExtractionSummary features;
  MetricScaleSummary metric_scale;
  VerificationSummary verification;
  BatchedMapperSummary mapper;
  size_t num_points = 0;
  size_t num_observations = 0;
  double mean_track_length = 0.0;
  double mean_reprojection_error_px = 0.0;
  std::optional<PipelineEvaluation> evaluation;  // with ground truth only
  // With an IMU and at least one 1 s interval within it; else the message
  // says why there is none.
  std::optional<PipelineGyroCheck> gyro_check;
  std::string gyro_check_message;
  // Image decodes of the run (io/frame_cache.h): each image the run reads
  // is decoded once unless the cache had no room for it (not_kept) or an
  // earlier run stored its features (decoded once more for the colours).
  FrameCache::Counts images;
  size_t frame_cache_max_bytes = 0;
  std::vector<PipelineStageTime> stages;
  PipelineStreamSummary stream;  // a streamed run only
  double total_seconds = 0.0;
  double peak_memory_mb = 0.0;  // getrusage ru_maxrss

  // A few lines for the terminal, none wider than kMaxConsoleLineLength,
  // the decisions (RunWarnings) last.
  std::string ToString() const;
};

// summary.json's document (see the top of this file for the keys).
std::string PipelineSummaryToJson(const PipelineSummary& summary);

}  // namespace viosfm
