// `viosfm match`: pairs, descriptor matching and the paper's two-step
// VIO-aided geometric verification into a COLMAP database whose features
// `viosfm features` extracted (see matching/verification_driver.h).
#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>

#include "viosfm/cli/bag_options.h"
#include "viosfm/cli/commands.h"
#include "viosfm/cli/option_flags.h"
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

// `viosfm match` runs the verification stage of a run: its flags set a
// run's options (option_flags.h), of which it uses the verification's and
// the VIO file's.
struct MatchArguments {
  std::string dataset;
  std::string database;
  VerificationBandArguments band;
  VioUncertaintyArguments vio_uncertainty;
  std::string report;
  BagArguments bag;
  PipelineOptions options;
};

// What the matches stored in the database are made from, under the keys a
// run's fingerprint gives them (pipeline/run_fingerprint.h).
RunFingerprint MatchFingerprint(const PipelineOptions& options, const Sequence& sequence) {
  RunFingerprint fingerprint = FingerprintOfInputs(options);
  AddSequenceToFingerprint(sequence, &fingerprint);
  std::vector<std::string> prefixes = MatchesFingerprintPrefixes();
  if (!options.verification.use_vio_prior) {
    prefixes.erase(
        std::remove_if(prefixes.begin(), prefixes.end(),
                       [](const std::string& prefix) { return prefix.rfind("vio", 0) == 0; }),
        prefixes.end());
  }
  return FingerprintPart(fingerprint, prefixes);
}

void RunMatch(MatchArguments args) {
  PipelineOptions& run_options = args.options;
  run_options.dataset = args.dataset;
  run_options.num_threads = CapNumThreads(run_options.num_threads, "--threads");
  run_options.vio_uncertainty = args.vio_uncertainty.Model();
  args.band.ApplyTo(&run_options.verification);
  // As `viosfm features` does: a bag's images go beside the database (OUT/bag).
  run_options.rosbag =
      MakeRosbagOptions(args.bag, fs::absolute(args.database).parent_path() / "bag");
  run_options.image_folder.camera_yaml = args.bag.camera_yaml;
  if (!run_options.verification.use_vio_prior) {
    run_options.vio_trajectory.clear();
  } else if (!run_options.vio_trajectory.empty()) {
    run_options.vio_format = GuessTrajectoryFormat(run_options.vio_trajectory);
  }
  const VerificationOptions options = run_options.EffectiveVerificationOptions();
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid match options: " + error);
  }
  if (options.use_vio_prior && run_options.vio_trajectory.empty()) {
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
  read.rosbag = run_options.rosbag;
  read.image_folder = run_options.image_folder;
  read.calibration = run_options.calibration;
  read.checks = run_options.dataset_checks;
  const Sequence sequence = ReadDataset(args.dataset, read);

  Trajectory vio;
  if (options.use_vio_prior) {
    vio = ReadVioTrajectoryFile(run_options.vio_trajectory, run_options.vio_format,
                                run_options.vio_frame, sequence.rig.body_from_cam);
  }

  folder.CheckAndRecord(MatchFingerprint(run_options, sequence));
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
  const std::vector<int> segments = SegmentsFromTimeGaps(vio, run_options.vio_max_gap_ns);
  if (!segments.empty() && segments.back() > 0) {
    VIOSFM_LOG(WARNING) << "match: the VIO trajectory has " << segments.back() + 1
                        << " segments (gaps longer than "
                        << FormatNsAsSeconds(run_options.vio_max_gap_ns, 3)
                        << " s); pairs across them are verified by RANSAC only";
  }
  const VerificationResult result = RunVerification(sequence, vio, &database, options, segments);
  VIOSFM_LOG(INFO) << "match: " << FormatVerificationHeadline(result.summary) << LogDetails()
                   << " (" << FormatVerificationSummary(result.summary) << "); database holds "
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
  CLI::App* command = app.add_subcommand(
      "match",
      "Match and verify image pairs (the verification stage of `viosfm run`). It generates "
      "image pairs, matches descriptors and verifies each pair: the VIO-prior epipolar "
      "check (step 1), then RANSAC (step 2); writes matches and verified geometries to the "
      "database, with the flags of `viosfm run`; a re-run skips the pairs already stored");
  command
      ->add_option("dataset", args->dataset,
                   "EuRoC dataset (folder containing mav0/) or a bag (ROS 1 .bag; ROS 2 .db3, "
                   ".mcap or bag folder)")
      ->required();
  command->add_option("--database", args->database, "COLMAP database with features")->required();
  AddBagOptions(command, &args->bag);
  AddCalibrationOptions(command, &args->options.calibration);
  AddDatasetCheckOptions(command, &args->options.dataset_checks);
  AddOptionFlags(command, MakeOptionTarget(&args->options, ""),
                 {"--vio-trajectory",
                  "--vio-frame",
                  "--max-vio-time-difference",
                  "--vio-max-gap",
                  "--no-vio-prior",
                  "--n1",
                  "--n2",
                  "--pairs-mode",
                  "--vocabulary",
                  "--max-epipolar-error",
                  "--max-outlier-ratio",
                  "--no-depth-check",
                  "--max-scene-depth",
                  "--depth-tolerance",
                  "--min-depth-parallax",
                  "--max-correction-sigmas",
                  "--min-inliers",
                  "--max-error",
                  "--reverify",
                  "--guided-matching",
                  "--threads",
                  "--seed"});
  AddVerificationBandOptions(command, &args->band);
  AddVioUncertaintyOptions(command, &args->vio_uncertainty);
  command->add_option("--report", args->report,
                      "Folder for pairs.csv and verification.json (one record per pair)");
  command->callback([args] { RunMatch(*args); });
}

}  // namespace viosfm::cli
