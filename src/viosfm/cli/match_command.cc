// `viosfm match`: pairs, descriptor matching and the paper's two-step
// VIO-aided geometric verification into a COLMAP database whose features
// `viosfm features` extracted (see matching/verification_driver.h).
#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>

#include "viosfm/cli/bag_options.h"
#include "viosfm/cli/commands.h"
#include "viosfm/cli/vio_uncertainty_options.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/dataset.h"
#include "viosfm/io/rosbag.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/io/verification_report.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/timestamp.h"

namespace viosfm::cli {
namespace {

namespace fs = std::filesystem;

struct MatchArguments {
  std::string dataset;
  std::string database;
  CalibrationFiles calibration;
  std::string vio_trajectory;
  std::string vio_frame = "body";
  bool no_vio_prior = false;
  bool no_depth_check = false;
  std::string pairs_mode = "temporal_retrieval";
  double max_pose_time_difference_s = 0.005;
  double vio_max_gap_s = 1.0;
  VerificationBandArguments band;
  VioUncertaintyArguments vio_uncertainty;
  std::string report;
  VerificationOptions options;
  BagArguments bag;
  DatasetChecks checks;
};

// What the matches stored in the database are made from, under the keys a
// run's fingerprint gives them (pipeline/run_fingerprint.h).
RunFingerprint MatchFingerprint(const MatchArguments& args, VioFrame vio_frame,
                                const Sequence& sequence) {
  PipelineOptions options;
  options.dataset = args.dataset;
  options.rosbag = MakeRosbagOptions(args.bag, fs::absolute(args.database).parent_path() / "bag");
  options.calibration = args.calibration;
  options.verification = args.options;
  if (args.options.use_vio_prior) {
    options.vio_trajectory = args.vio_trajectory;
    options.vio_format = GuessTrajectoryFormat(args.vio_trajectory);
  }
  options.vio_frame = vio_frame;
  options.max_vio_time_difference_ns = args.options.max_pose_time_difference_ns;
  options.vio_max_gap_ns = SecondsToNs(args.vio_max_gap_s);
  options.vio_uncertainty = args.options.vio_uncertainty;
  RunFingerprint fingerprint = FingerprintOfInputs(options);
  AddSequenceToFingerprint(sequence, &fingerprint);
  std::vector<std::string> prefixes = MatchesFingerprintPrefixes();
  if (!args.options.use_vio_prior) {
    prefixes.erase(
        std::remove_if(prefixes.begin(), prefixes.end(),
                       [](const std::string& prefix) { return prefix.rfind("vio", 0) == 0; }),
        prefixes.end());
  }
  return FingerprintPart(fingerprint, prefixes);
}

void RunMatch(MatchArguments args) {
  VerificationOptions& options = args.options;
  options.pairs.mode = ParsePairMode(args.pairs_mode);
  options.use_vio_prior = !args.no_vio_prior;
  options.prior.check_depth = !args.no_depth_check;
  options.max_pose_time_difference_ns = SecondsToNs(args.max_pose_time_difference_s);
  options.num_threads = CapNumThreads(options.num_threads, "--threads");
  options.retrieval.num_threads = options.num_threads;
  options.vio_uncertainty = args.vio_uncertainty.Model();
  args.band.ApplyTo(&options);
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid match options: " + error);
  }
  const VioFrame vio_frame = ParseVioFrame(args.vio_frame);
  if (options.use_vio_prior && args.vio_trajectory.empty()) {
    throw InputError("--vio-trajectory is required unless --no-vio-prior is given");
  }

  const fs::path database_path = args.database;
  if (!fs::exists(database_path)) {
    throw InputError(args.database, 0, "database not found (run `viosfm features` first)");
  }
  CheckDatasetExists(args.dataset);
  // The database's folder locked as a run's; its record checked and written
  // before its rows change (as `viosfm features` does).
  const fs::path bag_folder = HasRosbagExtension(args.dataset)
                                  ? fs::absolute(args.database).parent_path() / "bag"
                                  : fs::path();
  DatabaseFolder folder(database_path, bag_folder);
  if (!bag_folder.empty()) folder.MarkWriting();

  DatasetReadOptions read;
  // As `viosfm features` does: a bag's images go beside the database (OUT/bag).
  read.rosbag = MakeRosbagOptions(args.bag, fs::absolute(args.database).parent_path() / "bag");
  read.calibration = args.calibration;
  read.checks = args.checks;
  const Sequence sequence = ReadDataset(args.dataset, read);

  Trajectory vio;
  if (options.use_vio_prior) {
    vio = ReadVioTrajectoryFile(args.vio_trajectory, GuessTrajectoryFormat(args.vio_trajectory),
                                vio_frame, sequence.rig.body_from_cam);
  }

  folder.CheckAndRecord(MatchFingerprint(args, vio_frame, sequence));
  ColmapDatabase database = ColmapDatabase::Open(database_path);
  VIOSFM_LOG(INFO) << "match: " << sequence.images.size() << " images of " << args.dataset
                   << ", pairs " << PairModeName(options.pairs.mode) << " (N1 "
                   << options.pairs.num_temporal_neighbors << ", N2 "
                   << options.pairs.num_retrieval_neighbors << "), "
                   << (options.use_vio_prior
                           ? "VIO prior (T_EE " +
                                 std::to_string(options.prior.max_epipolar_error_px) +
                                 " px, outlier ratio " +
                                 std::to_string(options.prior.max_outlier_ratio) +
                                 (options.prior.check_depth
                                      ? ", depth check to " +
                                            std::to_string(options.prior.max_scene_depth_m) + " m"
                                      : std::string(", no depth check")) +
                                 ") + RANSAC"
                           : std::string("RANSAC only"));
  const std::vector<int> segments = SegmentsFromTimeGaps(vio, SecondsToNs(args.vio_max_gap_s));
  if (!segments.empty() && segments.back() > 0) {
    VIOSFM_LOG(WARNING) << "match: the VIO trajectory has " << segments.back() + 1
                        << " segments (gaps longer than " << args.vio_max_gap_s
                        << " s); pairs across them are verified by RANSAC only";
  }
  const VerificationResult result = RunVerification(sequence, vio, &database, options, segments);
  VIOSFM_LOG(INFO) << "match: " << FormatVerificationSummary(result.summary) << "; database holds "
                   << database.NumMatchedImagePairs() << " matched and "
                   << database.NumVerifiedImagePairs() << " verified pairs";

  if (!args.report.empty()) {
    const fs::path report = args.report;
    fs::create_directories(report);
    WritePairDecisionsCsv(report / "pairs.csv", result.decisions);
    WriteVerificationJson(report / "verification.json", result.summary, result.decisions);
    VIOSFM_LOG(INFO) << "match: report in " << report.string() << " (pairs.csv, verification.json)";
  }
  folder.Finish();
}

}  // namespace

void RegisterMatch(CLI::App& app) {
  auto args = std::make_shared<MatchArguments>();
  CLI::App* command =
      app.add_subcommand("match",
                         "Generate image pairs, match descriptors and verify each pair: "
                         "the VIO-prior epipolar "
                         "check (step 1), then RANSAC (step 2); writes matches and "
                         "verified geometries to the "
                         "database; a re-run skips the pairs already stored");
  command
      ->add_option("dataset", args->dataset,
                   "EuRoC dataset (folder containing mav0/) or a bag (ROS 1 .bag; ROS 2 .db3, "
                   ".mcap or bag folder)")
      ->required();
  command->add_option("--database", args->database, "COLMAP database with features")->required();
  AddBagOptions(command, &args->bag, /*add_camera_yaml=*/true);
  AddCalibrationOptions(command, &args->calibration);
  AddDatasetCheckOptions(command, &args->checks);
  command->add_option("--vio-trajectory", args->vio_trajectory,
                      "VIO trajectory (TUM, EuRoC or KITTI-with-stamps file), world_from_body "
                      "unless --vio-frame cam");
  command->add_option("--vio-frame", args->vio_frame, "Frame of the VIO poses: body or cam")
      ->capture_default_str();
  AddVerificationBandOptions(command, &args->band);
  command
      ->add_option("--max-correction-sigmas", args->options.max_correction_sigmas,
                   "Largest correction of the VIO's relative pose taken as its drift, "
                   "Mahalanobis distance")
      ->capture_default_str();
  command
      ->add_option("--vio-max-gap", args->vio_max_gap_s,
                   "The VIO trajectory is split into segments (no VIO prior across) at time "
                   "gaps longer than this, s (0: never)")
      ->capture_default_str();
  AddVioUncertaintyOptions(command, &args->vio_uncertainty);
  command->add_flag("--no-vio-prior", args->no_vio_prior,
                    "RANSAC-only verification (COLMAP's; the baseline)");
  command
      ->add_option("--n1", args->options.pairs.num_temporal_neighbors,
                   "Temporal neighbours per image (sequential mode: next images)")
      ->capture_default_str();
  command
      ->add_option("--n2", args->options.pairs.num_retrieval_neighbors,
                   "Retrieval neighbours per image")
      ->capture_default_str();
  command
      ->add_option("--pairs-mode", args->pairs_mode, "temporal_retrieval, sequential or exhaustive")
      ->capture_default_str();
  command
      ->add_option("--max-epipolar-error", args->options.prior.max_epipolar_error_px,
                   "T_EE: a match farther from its VIO epipolar line is an outlier (px)")
      ->capture_default_str();
  command
      ->add_option("--max-outlier-ratio", args->options.prior.max_outlier_ratio,
                   "Reject a pair when its VIO outlier ratio exceeds this")
      ->capture_default_str();
  command->add_flag("--no-depth-check", args->no_depth_check,
                    "VIO step: the paper's epipolar test only, without the depth-consistency "
                    "check (matches must show the parallax the metric VIO baseline implies)");
  command
      ->add_option("--max-scene-depth", args->options.prior.max_scene_depth_m,
                   "Depth check: farthest scene point expected (m)")
      ->capture_default_str();
  command
      ->add_option("--depth-tolerance", args->options.prior.depth_tolerance_px,
                   "Depth check: parallax tolerance (px)")
      ->capture_default_str();
  command
      ->add_option("--min-depth-parallax", args->options.prior.min_depth_parallax_px,
                   "Depth check: a match is scored when a point at the max scene depth would "
                   "show at least this parallax (px)")
      ->capture_default_str();
  command
      ->add_option("--min-inliers", args->options.geometry.min_num_inliers,
                   "RANSAC inliers needed to keep a pair")
      ->capture_default_str();
  command
      ->add_option("--max-error", args->options.geometry.max_error_px,
                   "RANSAC inlier threshold (Sampson error, px)")
      ->capture_default_str();
  command
      ->add_option("--max-pose-time-difference", args->max_pose_time_difference_s,
                   "Largest gap between an image stamp and its VIO pose (s)")
      ->capture_default_str();
  command->add_flag("--reverify", args->options.reverify_stored_matches,
                    "Verify again the pairs whose matches are stored (instead of skipping them), "
                    "replacing their stored geometry");
  command->add_flag("--guided-matching", args->options.guided_matching,
                    "Match inside the VIO epipolar band instead of by brute force");
  command->add_option("--vocabulary", args->options.retrieval.vocabulary_path,
                      "Vocabulary tree file for retrieval (default: trained on the images)");
  command->add_option("--threads", args->options.num_threads, "Worker threads")
      ->capture_default_str();
  command->add_option("--seed", args->options.seed, "Seed of RANSAC and of the vocabulary training")
      ->capture_default_str();
  command->add_option("--report", args->report,
                      "Folder for pairs.csv and verification.json (one record per pair)");
  command->callback([args] { RunMatch(*args); });
}

}  // namespace viosfm::cli
