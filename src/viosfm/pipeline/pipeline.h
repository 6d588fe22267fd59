// The end-to-end VIO-aided reconstruction of one sequence (`viosfm run`),
// the paper's pipeline (its Fig. "overview"): VIO poses, frame selection,
// features, two-step VIO-aided verification, batched incremental mapping with
// relative-pose-constrained bundle adjustment, then evaluation and outputs.
//
// Stages (each timed, reported in summary.json "stages"):
//  1. read_dataset   EuRoC ASL folder (mav0/), an image folder or a ROS 1 bag;
//  2. vio            the VIO trajectory (world_from_body) of the sequence,
//                    from PipelineOptions::vio_source if set, else from the
//                    file vio_trajectory, else from viosfm's own VIO
//                    (vio/odometry.h) on the images and IMU, split into
//                    segments at re-initialisations (vio_input.h);
//  3. select_frames  static start/end trimming and downsampling to
//                    target_rate_hz (matching/frame_selection.h); a frame
//                    without a VIO pose within max_vio_time_difference_ns
//                    is kept without one (counted and logged) and
//                    registered from the images where they allow;
//  4. features       SIFT into OUT/database.db (resumable);
//  5. verification   pairs, matching, VIO check and RANSAC (resumable);
//  6. load_matches   the inlier matches of the accepted pairs;
//  7. mapper         sfm/batched_mapper.h, then the IMU's metric scale
//                    (metric_scale.h) when the dataset has an IMU;
//  8. colors         each point's colour: the mean over its observations of
//                    the image value at the keypoint (grey images give grey);
//  9. evaluation     with ground truth only: Sim(3) ATE of the estimated body
//                    trajectory and of the input VIO on the same frames;
// 10. write_outputs  the files below.
//
// Output folder (every file written atomically; summary.json last, so a
// folder holding summary.json is complete):
//   OUT/options.json                 every option, name -> value text
//   OUT/database.db                  COLMAP database (features, matches, geometries)
//   OUT/verification/pairs.csv, verification.json
//   OUT/model/                       COLMAP binary model (cameras, images, points3D .bin)
//   OUT/model_txt/                   the same as COLMAP text
//   OUT/points.ply                   coloured points
//   OUT/trajectory_cam.tum           estimated world_from_cam of the registered frames
//   OUT/trajectory_body.tum          estimated world_from_body of the registered frames
//   OUT/vio_body.tum                 the input VIO world_from_body of the selected frames
//   OUT/groundtruth_body.tum         ground truth at the selected frames (if present)
//   OUT/eval.json, OUT/eval_vio.json eval/report.h JSON (if ground truth)
//   OUT/summary.json                 see PipelineSummaryToJson
//
//   OUT/fingerprint.json             what the stored features and matches were
//                                    made from (run_fingerprint.h)
//
// Resume: a re-run on the same folder reuses the stored features and pair
// verifications when its fingerprint (run_fingerprint.h: the dataset's
// files, images and calibration, the VIO's input and poses, every option
// that shapes the stored data) equals the stored one; otherwise it is an
// InputError naming each changed key with its old and new value, before
// anything in the folder changes. `overwrite` removes the run's stored
// outputs first (RemoveRunOutputs) and starts afresh. Mapper options do not
// count: a re-run with other ones reuses the features and matches.
//
// Crash safety: a run killed at any point (SIGKILL included) and run again
// with the same options ends as an uninterrupted run would, byte for byte
// (with the same thread count): the database keeps every committed image's
// features and every verified pair (SQLite, WAL; one transaction per image
// and per pair), a pair stored as rejected is decided again from its stored
// matches, and every other output is recomputed. summary.json is removed
// when the folder starts to change and written last, atomically: a folder
// without it is incomplete (`viosfm report` and `viosfm export` refuse it).
// Leftovers of interrupted atomic writes are removed at the start, and the
// folder is locked (util/file_util.h FolderLock) while a run writes into it.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/eval/metric_accuracy.h"
#include "viosfm/features/feature_extraction.h"
#include "viosfm/features/sift.h"
#include "viosfm/io/image_folder.h"
#include "viosfm/io/kalibr.h"
#include "viosfm/io/rosbag_dataset.h"
#include "viosfm/io/sequence.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/matching/frame_selection.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/metric_scale.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {

// The version written to summary.json.
std::string ViosfmVersion();

// Which moving frame a VIO trajectory file gives.
enum class VioFrame { kBody, kCam };
// "body", "cam" (case-insensitive); InputError otherwise.
VioFrame ParseVioFrame(const std::string& name);
std::string VioFrameName(VioFrame frame);

// A VIO run over a whole sequence, returning world_from_body poses with
// stamps (the hook for viosfm's own VIO).
using VioSource = std::function<Trajectory(const Sequence& sequence)>;

struct PipelineOptions {
  // EuRoC dataset (the folder containing mav0/, or mav0 itself) or a folder
  // of images (then image_folder must give the camera). Required.
  std::filesystem::path dataset;
  // Used only when `dataset` is not a EuRoC folder.
  ImageFolderOptions image_folder;
  // Used only when `dataset` is a ROS 1 bag (".bag"): topics and calibration.
  // Its images are extracted to rosbag.extract_folder, default OUT/bag (a
  // EuRoC folder of what was read, see io/rosbag_dataset.h).
  RosbagDatasetOptions rosbag;
  // Kalibr camchain.yaml (+ imu.yaml) replacing the dataset's calibration
  // (io/kalibr.h, ApplyCalibration). Default none.
  CalibrationFiles calibration;
  // The output folder (created if missing). Required.
  std::filesystem::path output_folder;

  // VIO poses. When vio_source is set it is called on the sequence and the
  // file options are ignored; otherwise the file vio_trajectory is read.
  VioSource vio_source;
  // Without vio_source and vio_trajectory, viosfm's own VIO (vio/odometry.h)
  // runs on the images and IMU with these options; its output goes to
  // OUT/vio/ and every posed frame is used, each stretch between
  // re-initialisations a segment of its own (vio_input.h).
  VioOptions own_vio;
  std::filesystem::path vio_trajectory;                  // trajectory file; default none
  TrajectoryFormat vio_format = TrajectoryFormat::kTum;  // default TUM
  // The frame of the file's poses; kCam poses are converted with the
  // sequence's body_from_cam. Default kBody.
  VioFrame vio_frame = VioFrame::kBody;
  // Largest gap between an image stamp and the VIO pose used for it (ns).
  // Default 5 ms.
  timestamp_ns_t max_vio_time_difference_ns = 5'000'000;
  // A trajectory file (or vio_source) is split into segments at gaps between
  // its stamps longer than this (ns); 0: one segment. Default 1 s
  // (vio_input.h).
  timestamp_ns_t vio_max_gap_ns = 1'000'000'000;
  // How far the VIO's relative poses are trusted (scene/vio_uncertainty.h):
  // the relative-pose priors' covariance (mapper.vio_uncertainty) and the
  // verification's epipolar band (verification.vio_uncertainty) are set from
  // it. Default: the model's defaults (an external VIO on EuRoC-class data).
  VioUncertaintyModel vio_uncertainty;

  // Static trimming and downsampling (default: trimmed, 10 Hz, the paper).
  FrameSelectionOptions frame_selection;
  // SIFT (default 8192 features, RootSIFT).
  SiftOptions sift;
  // Pairs (N1 40, N2 30), VIO prior (T_EE 20 px, ratio 0.5), RANSAC.
  VerificationOptions verification;
  // Batched mapper (k = 50, relative-pose priors on).
  BatchedMapperOptions mapper;
  // The metric scale from the IMU (metric_scale.h), when the dataset has
  // one. Default true.
  bool use_imu_scale = true;
  ImuScaleOptions imu_scale;

  // Worker threads of every stage (replaces the stages' own num_threads),
  // >= 1. Default 2.
  int num_threads = 2;
  // Seed of every random choice (RANSAC, vocabulary training). Default 0.
  uint64_t seed = 0;
  // Remove the output folder's stored database and outputs of an earlier
  // run (RunOutputNames, run_fingerprint.h) before starting, instead of
  // reusing them or refusing a folder made from other inputs. Default false.
  bool overwrite = false;
  // Progress bars. Default true.
  bool show_progress = true;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
  // Every option as (name, value) text, in a fixed order (options.json). The
  // stage options carry the thread count, seed and progress set here.
  std::vector<std::pair<std::string, std::string>> ToKeyValues() const;
  // The stage options with num_threads, seed, show_progress and the VIO
  // time difference applied.
  SiftOptions EffectiveSiftOptions() const;
  VerificationOptions EffectiveVerificationOptions() const;
  BatchedMapperOptions EffectiveMapperOptions() const;
  // rosbag with the default extract folder applied.
  RosbagDatasetOptions EffectiveRosbagOptions() const;
};

struct PipelineStageTime {
  std::string name;
  double seconds = 0.0;
};

// Accuracy against the ground truth (metres): the Sim(3)-aligned ATE
// statistics, and the metric figures (eval/metric_accuracy.h) of the
// estimate and of the input VIO on the same frames.
struct PipelineEvaluation {
  double ate_rmse_m = 0.0;
  double ate_median_m = 0.0;
  double ate_mean_m = 0.0;
  double ate_max_m = 0.0;
  double vio_ate_rmse_m = 0.0;  // the input VIO on the same frames
  double vio_ate_median_m = 0.0;
  size_t num_poses = 0;       // associated poses
  MetricAccuracy metric;      // the estimate
  MetricAccuracy vio_metric;  // the input VIO on the same frames (one alignment over all segments)
};

struct PipelineSummary {
  std::string dataset;
  // The hash of the run's fingerprint (run_fingerprint.h, RunFingerprint::Hash):
  // runs with equal ones were made from the same inputs and data-shaping options.
  std::string fingerprint;
  std::filesystem::path output_folder;
  std::string started_utc;  // "2026-11-21T07:38:16Z"
  size_t num_frames_in = 0;
  size_t num_frames_selected = 0;          // selected (with or without a VIO pose)
  size_t num_frames_without_vio_pose = 0;  // selected frames without a VIO pose
  // Posed frames whose pose the images support (registered), placed by the
  // VIO only, and frames without any pose (mapper.frames says why).
  size_t num_frames_registered = 0;
  size_t num_frames_vio_only = 0;
  size_t num_frames_unposed = 0;
  int num_vio_segments = 0;  // in the VIO input
  std::string vio_segment_rule;
  FrameSelection frame_selection;
  FeatureExtractionSummary features;
  MetricScaleSummary metric_scale;
  VerificationSummary verification;
  BatchedMapperSummary mapper;
  size_t num_points = 0;
  size_t num_observations = 0;
  double mean_track_length = 0.0;
  double mean_reprojection_error_px = 0.0;
  std::optional<PipelineEvaluation> evaluation;  // with ground truth only
  std::vector<PipelineStageTime> stages;
  double total_seconds = 0.0;
  double peak_memory_mb = 0.0;  // getrusage ru_maxrss

  // A few lines for the terminal.
  std::string ToString() const;
};

// summary.json's document (see the top of this file for the keys).
std::string PipelineSummaryToJson(const PipelineSummary& summary);

// The VIO trajectory (world_from_body, stamped) of the sequence, as the
// options say: vio_source, else the file (viosfm's own VIO: LoadVioPoses,
// vio_input.h). Throws InputError naming the file when none is given, it
// cannot be read, has no stamps or no poses.
Trajectory LoadVioTrajectory(const Sequence& sequence, const PipelineOptions& options);

// Whether `folder` is a EuRoC dataset: it holds mav0/, or is mav0/ with cam0/.
bool IsEurocDatasetFolder(const std::filesystem::path& folder);

// Reads a dataset folder: EuRoC if it holds mav0/ (or is mav0), else an
// image folder read with `image_folder`; then applies `calibration` (if any).
// Throws InputError naming the folder.
Sequence ReadPipelineDataset(const std::filesystem::path& dataset,
                             const ImageFolderOptions& image_folder,
                             const CalibrationFiles& calibration = {});

// Runs the pipeline (see the top of this file). Throws InputError for invalid
// options, unreadable or empty input, a VIO trajectory that does not overlap
// the images in time, a sequence without moving frames, a stored database
// made from other inputs or options (see Resume above), or an output folder
// another run is writing into.
PipelineSummary RunPipeline(const PipelineOptions& options);

}  // namespace viosfm
