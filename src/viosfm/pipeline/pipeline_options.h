// The options of a `viosfm run` (pipeline.h): the inputs, the output
// folder, the VIO source, and every stage's options with the paper's
// defaults. Each stage's own Options struct describes its fields; this file
// adds what the run as a whole decides (threads, seed, the VIO's trust) and
// hands it down to the stages (the Effective*Options()).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/io/image_folder.h"
#include "viosfm/io/kalibr.h"
#include "viosfm/io/rosbag_dataset.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/imu_scale.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {

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
  // re-initialisations a segment of its own (stage_vio.h).
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
  // (stage_vio.h).
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

}  // namespace viosfm
