// The options of a `viosfm run` (pipeline.h): the inputs, the output
// folder, the VIO source, and every stage's options with the paper's
// defaults. Each stage's own Options struct describes its fields; this file
// adds what the run as a whole decides (threads, seed, the VIO's trust) and
// hands it down to the stages (the Effective*Options()).
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/io/dataset_checks.h"
#include "viosfm/io/image_folder.h"
#include "viosfm/io/kalibr.h"
#include "viosfm/io/rosbag_dataset.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/pipeline/texture_probe.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/imu_scale.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {

// Which moving frame a VIO trajectory file gives.
enum class VioFrame { kBody, kCam };
// "body", "cam" (case-insensitive); InputError otherwise.
VioFrame ParseVioFrame(const std::string& name);
std::string VioFrameName(VioFrame frame);
// The option texts (util/option_fields.h).
inline std::string OptionText(VioFrame frame) {
  return VioFrameName(frame);
}
inline void ParseOptionText(const std::string& text, VioFrame* frame) {
  *frame = ParseVioFrame(text);
}

// A VIO run over a whole sequence, returning world_from_body poses with
// stamps (the hook for viosfm's own VIO).
using VioSource = std::function<Trajectory(const Sequence& sequence)>;

// The option texts (util/option_fields.h) of what only code can give:
// "function" or "file" for a VioSource, "given in code" or "" for a rig.
// Neither can be set from text (InputError).
std::string OptionText(const VioSource& source);
void ParseOptionText(const std::string& text, VioSource* source);
std::string OptionText(const std::optional<SensorRig>& rig);
void ParseOptionText(const std::string& text, std::optional<SensorRig>* rig);

struct PipelineOptions {
  // EuRoC dataset (the folder containing mav0/, or mav0 itself) or a folder
  // of images (then image_folder must give the camera). Required.
  std::filesystem::path dataset;
  // Used only when `dataset` is not a EuRoC folder.
  ImageFolderOptions image_folder;
  // Read the dataset's IMU; false: the images alone (and a VIO file, if
  // given). Default true.
  bool use_imu = true;
  // Used only when `dataset` is a ROS 1 bag (".bag"): topics and calibration.
  // Its images are extracted to rosbag.extract_folder, default OUT/bag (a
  // EuRoC folder of what was read, see io/rosbag_dataset.h).
  RosbagDatasetOptions rosbag;
  // Kalibr camchain.yaml (+ imu.yaml) replacing the dataset's calibration
  // (io/kalibr.h, ApplyCalibration). Default none.
  CalibrationFiles calibration;
  // What the dataset's sensors may say and where its files may lie
  // (io/dataset_checks.h: the IMU's bounds, links leaving the dataset).
  DatasetChecks dataset_checks;
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
  // s, the median interval between images beyond which viosfm's own VIO is
  // not run (it tracks corners from one frame to the next): the images and
  // the IMU make the model without a VIO (stage_vio.h). Default 0.25.
  double own_vio_max_frame_interval_s = 0.25;
  std::filesystem::path vio_trajectory;                  // trajectory file; default none
  TrajectoryFormat vio_format = TrajectoryFormat::kTum;  // default TUM
  // The frame of the file's poses; kCam poses are converted with the
  // sequence's body_from_cam. Default kBody.
  VioFrame vio_frame = VioFrame::kBody;
  // Largest gap between an image stamp and the VIO pose used for it (ns).
  // Default 5 ms.
  timestamp_ns_t max_vio_time_difference_ns = 5'000'000;
  // Gaps between a trajectory file's (or vio_source's) stamps longer than
  // this (ns) are candidate breaks the images judge (sfm/vio_gaps.h); 0:
  // none. Default 1 s.
  timestamp_ns_t vio_max_gap_ns = 1'000'000'000;
  // How far the VIO's relative poses are trusted (scene/vio_uncertainty.h):
  // the relative-pose priors' covariance (mapper.vio_uncertainty) and the
  // verification's epipolar band (verification.vio_uncertainty) are set from
  // it. Default: the model's defaults (an external VIO on EuRoC-class data).
  VioUncertaintyModel vio_uncertainty;

  // Rolling-shutter compensation of the keypoints the verification and the
  // mapper read (scene/rolling_shutter.h), with the dataset's IMU: each
  // keypoint turned back by the gyro's rotation over its row's readout time.
  // Default true.
  bool compensate_rolling_shutter = true;
  // s, the camera's readout (first row to last) when the VIO is external: a
  // trajectory file says nothing of it. 0 (default): a global shutter. With
  // viosfm's own VIO the readout it used is taken (own_vio.
  // rolling_shutter_readout_s, or its estimate).
  double rolling_shutter_readout_s = 0.0;
  // A readout the own VIO estimated (rather than was given) is used here
  // only when the images' evidence for it is at least this: the VIO's
  // residual as a global shutter over its residual with the readout. The VIO
  // keeps a readout that lowers its residual by 2 %; keypoints a fraction of
  // a pixel precise are moved by pixels by a wrong one, so these stages ask
  // for a quarter less. Default 1.25: between a simulated rolling shutter's
  // clear evidence and the real handheld recording's weak one. See
  // docs/benchmarks.md, section "Rolling shutter: the keypoints moved to the frame's stamp".
  double min_readout_evidence = 1.25;

  // Static trimming and downsampling (default: trimmed, 10 Hz, the paper).
  FrameSelectionOptions frame_selection;
  // The frame rate and the feature count decided from the images' texture
  // (texture_probe.h; off by default, on in the real-time preset).
  TextureProbeOptions texture_probe;
  // The real-time budget of features a second of recording (texture_probe.h;
  // off by default, on in `viosfm run`'s real-time preset).
  FeatureBudgetOptions feature_budget;
  // SIFT (default 8192 features, RootSIFT).
  SiftOptions sift;
  // Pairs (N1 40, N2 30), VIO prior (T_EE 20 px, ratio 0.5), RANSAC.
  VerificationOptions verification;
  // Batched mapper (k = 50, relative-pose priors on).
  BatchedMapperOptions mapper;
  // The run as one stream (stream_pipeline.h): the VIO, the features, the
  // verification and the mapper overlap, each frame taken on as soon as the
  // VIO has settled its pose, its pairs with the frames before it verified,
  // and each batch mapped once its frames are in. Default false.
  bool stream = false;
  // Streamed: the retrieval's vocabulary tree is trained on the first this
  // many selected frames' descriptors (a batch run trains it on the whole
  // recording), unless verification.retrieval.vocabulary_path gives one
  // (retrieval/incremental_retrieval.h); >= 1. Default 100.
  int stream_vocabulary_frames = 100;
  // The dataset is a EuRoC folder being recorded (io/euroc_follower.h): the
  // streamed run (stream is implied) takes its frames and IMU as they are
  // appended, with viosfm's own VIO, and writes the model as it grows to
  // OUT/live/ after every batch of the mapper; the recording has ended once
  // nothing was appended for follow_idle_s. Default false.
  bool follow = false;
  // s, the silence after which a followed recording has ended (> 0).
  // Default 3.
  double follow_idle_s = 3.0;
  // The metric scale from the IMU (metric_scale.h), when the dataset has
  // one. Default true.
  bool use_imu_scale = true;
  ImuScaleOptions imu_scale;

  // Worker threads of every stage (replaces the stages' own num_threads),
  // >= 1. Default 2.
  int num_threads = 2;
  // Seed of every random choice (RANSAC, vocabulary training). Default 0.
  uint64_t seed = 0;
  // Remove what viosfm wrote in the output folder (its manifest,
  // run_folder.h: an earlier run's database and outputs, report.html,
  // export/) before starting, instead of reusing them or refusing a folder
  // made from other inputs. Default false.
  bool overwrite = false;
  // Progress bars. Default true.
  bool show_progress = true;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
  // Every option as (name, value) text, in a fixed order (options.json). The
  // stage options carry the thread count, seed and progress set here.
  std::vector<std::pair<std::string, std::string>> ToKeyValues() const;
  // The options of ToKeyValues that shape the stored features and matches
  // (marked kShapesStoredData where they are described): the fingerprint's
  // options (run_fingerprint.h).
  std::vector<std::pair<std::string, std::string>> StoredDataKeyValues() const;
  // These options with the Effective*Options() applied.
  PipelineOptions WithEffectiveStageOptions() const;
  // The stage options with num_threads, seed, show_progress and the VIO
  // time difference applied.
  SiftOptions EffectiveSiftOptions() const;
  VerificationOptions EffectiveVerificationOptions() const;
  BatchedMapperOptions EffectiveMapperOptions() const;
  // rosbag with the default extract folder applied.
  RosbagDatasetOptions EffectiveRosbagOptions() const;
  // Whether viosfm's own VIO makes the poses: neither vio_source nor
  // vio_trajectory is given.
  bool UsesOwnVio() const { return !vio_source && vio_trajectory.empty(); }
  // The VIO as messages name it: the trajectory file, or "the VIO" (viosfm's
  // own, or vio_source).
  std::string VioName() const {
    return vio_source || vio_trajectory.empty() ? std::string("the VIO") : vio_trajectory.string();
  }

  // Every option of a run, in the order of options.json (see
  // util/option_fields.h). The stage options' own fields are described by
  // their structs.
  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    const bool is_bag = IsBagPath(self.dataset);
    const bool own_vio_runs = self.UsesOwnVio();
    // The uncertainty model widens the verification's epipolar band (and
    // weighs the mapper's priors, which stores nothing).
    const OptionEffect uncertainty_effect =
        self.verification.use_vio_prior && self.verification.band_follows_drift ? kShapesStoredData
                                                                                : kRunOnly;
    visit({"dataset", "EuRoC folder, image folder or bag, ROS 1 or 2 (content hashed)", kRunOnly},
          self.dataset);
    visit({"image_folder.timestamps_file", "image folder: 'filename timestamp' lines", kRunOnly},
          self.image_folder.timestamps_file);
    visit({"use_imu", "read the dataset's IMU; false: the images alone", kShapesStoredData},
          self.use_imu);
    visit({"image_folder.camera_yaml", "image folder: the camera's sensor.yaml", kRunOnly},
          self.image_folder.camera_yaml);
    visit({"calibration.camchain", "Kalibr camchain.yaml replacing the calibration", kRunOnly},
          self.calibration.camchain);
    visit({"calibration.imu", "Kalibr imu.yaml (needs camchain)", kRunOnly}, self.calibration.imu);
    VisitOptionGroup({"dataset_checks", "", kRunOnly}, self.dataset_checks, visit);
    visit({"output_folder", "the output folder", kRunOnly}, self.output_folder);
    visit({"vio.source", "function (given in code) or file", kRunOnly}, self.vio_source);
    visit({"vio.trajectory", "VIO trajectory file; empty: viosfm's own VIO", kRunOnly},
          self.vio_trajectory);
    visit({"own_vio_max_frame_interval_s",
           "s, median image interval beyond which the own VIO is not run", kShapesStoredData,
           own_vio_runs},
          self.own_vio_max_frame_interval_s);
    visit({"vio.format", "tum, euroc, kitti or colmap", kShapesStoredData}, self.vio_format);
    visit({"vio.frame", "body or cam: the moving frame of the file's poses", kShapesStoredData},
          self.vio_frame);
    visit({"vio.max_time_difference_ns", "ns, largest gap between an image and its VIO pose",
           kShapesStoredData},
          self.max_vio_time_difference_ns);
    visit({"vio.max_gap_ns", "ns, longer gaps in a VIO file are judged by the images; 0: none",
           kShapesStoredData},
          self.vio_max_gap_ns);
    visit({"rolling_shutter.compensate",
           "keypoints turned back by the gyro's rotation over their row's readout",
           kShapesStoredData},
          self.compensate_rolling_shutter);
    visit({"rolling_shutter.readout_s",
           "s, the camera's readout with an external VIO; 0: global shutter", kShapesStoredData,
           !own_vio_runs},
          self.rolling_shutter_readout_s);
    visit({"rolling_shutter.min_readout_evidence",
           "an estimated readout is used when the VIO's global-shutter residual is this many "
           "times its residual with it",
           kShapesStoredData, own_vio_runs},
          self.min_readout_evidence);
    VisitOptionGroup({"frame_selection", "", kShapesStoredData}, self.frame_selection, visit);
    VisitOptionGroup({"texture_probe", "", kShapesStoredData}, self.texture_probe, visit);
    VisitOptionGroup({"feature_budget", "", kShapesStoredData}, self.feature_budget, visit);
    visit(
        {"rosbag.image_topic", "bag: image topic; empty: found by type", kShapesStoredData, is_bag},
        self.rosbag.image_topic);
    visit({"rosbag.imu_topic", "bag: IMU topic; empty: found by type", kShapesStoredData, is_bag},
          self.rosbag.imu_topic);
    visit({"rosbag.groundtruth_topic", "bag: ground-truth topic", kShapesStoredData, is_bag},
          self.rosbag.groundtruth_topic);
    visit({"rosbag.camera_yaml", "bag: camera sensor.yaml (content hashed)", kRunOnly, is_bag},
          self.rosbag.camera_yaml);
    visit({"rosbag.imu_yaml", "bag: IMU sensor.yaml (content hashed)", kRunOnly, is_bag},
          self.rosbag.imu_yaml);
    visit({"rosbag.rig", "bag: calibration given in code", kRunOnly, is_bag}, self.rosbag.rig);
    visit({"rosbag.extract_folder", "bag: where its images are written; default OUT/bag", kRunOnly,
           is_bag},
          self.rosbag.extract_folder);
    VisitOptionGroup({"vio_uncertainty", "", uncertainty_effect}, self.vio_uncertainty, visit);
    VisitOptionGroup({"own_vio", "", kShapesStoredData, own_vio_runs}, self.own_vio, visit);
    VisitOptionGroup({"sift", "", kShapesStoredData}, self.sift, visit);
    VisitOptionGroup({"verification", "", kShapesStoredData}, self.verification, visit);
    VisitOptionGroup({"mapper", "", kRunOnly}, self.mapper, visit);
    visit({"stream", "the run as one stream: VIO, features, verification and mapper overlap",
           kRunOnly},
          self.stream);
    visit({"stream_vocabulary_frames",
           "streamed: the first frames the retrieval's vocabulary is trained on", kRunOnly},
          self.stream_vocabulary_frames);
    visit(
        {"follow", "the dataset is a EuRoC folder being recorded: follow it as it grows", kRunOnly},
        self.follow);
    visit({"follow_idle_s", "s of silence after which a followed recording has ended", kRunOnly},
          self.follow_idle_s);
    visit({"use_imu_scale", "the metric scale from the IMU", kRunOnly}, self.use_imu_scale);
    VisitOptionGroup({"imu_scale", "", kRunOnly}, self.imu_scale, visit);
    visit({"num_threads", "worker threads of every stage", kRunOnly}, self.num_threads);
    visit({"seed", "seed of every random choice", kRunOnly}, self.seed);
    visit({"show_progress", "progress bars", kRunOnly}, self.show_progress);
  }
};

// `viosfm run`'s presets. The fields' defaults above are the paper's
// settings (`--preset paper`). The real-time preset (`viosfm run`'s default,
// `--preset realtime`) reconstructs a recording in about its own duration on
// two cores: N1 10 and N2 5, a budget of 10000 features a second of
// recording (1000 a frame at 10 Hz, on images of at most 800 px; sparse
// frames and photos keep every feature), matching inside the VIO's epipolar
// band, the texture probe, per-batch adjustments over a window of 4 batches
// with 5 held views a point, looser bundle-adjustment tolerances and one
// refinement of the final adjustment at most. See docs/benchmarks.md,
// section "Real time: where a 100 s recording's time goes".
enum class RunPreset { kRealtime, kPaper };

// Sets the fields a preset decides; the others are left as they are.
void ApplyPreset(RunPreset preset, PipelineOptions* options);

// A recording whose frames come at `rate_hz` (> 0), slower than the feature
// budget limits (feature_budget.features_per_second / sift.max_num_features
// or fewer frames a second; budget on, paper_settings_when_sparse): its run
// has the time for the paper's retrieval neighbours (N2) and bundle
// adjustments (tolerance, conjugate-gradient steps, the final adjustment's
// refinements), which the real-time preset reduces for frame-rate
// recordings. Sets them and returns a line saying so; "" when it does not
// apply. Called before the budget is applied. See docs/benchmarks.md,
// section "Real time".
std::string ApplySparseRecordingSettings(double rate_hz, PipelineOptions* options);

// Whether the option `key` is one a user's choice of keeps from
// ApplySparseRecordingSettings.
bool SettledBySparseRecording(const std::string& key);

}  // namespace viosfm
