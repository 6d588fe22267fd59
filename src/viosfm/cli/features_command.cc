// `viosfm features`: SIFT/RootSIFT features of every image of a dataset into
// a COLMAP-compatible database (see features/feature_extraction.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "viosfm/cli/bag_options.h"
#include "viosfm/cli/commands.h"
#include "viosfm/features/feature_extraction.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/dataset.h"
#include "viosfm/io/image_folder.h"
#include "viosfm/io/rosbag.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm::cli {
namespace {

namespace fs = std::filesystem;

struct FeaturesArguments {
  std::string dataset;
  std::string database;
  SiftOptions sift;
  bool no_root_sift = false;
  std::string camera;
  BagArguments bag;
  std::string timestamps;
  CalibrationFiles calibration;
  DatasetChecks checks;
};

// "MODEL,WIDTH,HEIGHT,p1,p2,..." e.g. "PINHOLE,752,480,458.6,457.3,367.2,248.4".
Camera ParseCameraOption(const std::string& text) {
  const std::vector<std::string_view> fields = Split(text, ",", /*skip_empty=*/false);
  const auto fail = [&text](const std::string& what) -> Camera {
    throw InputError("--camera '" + text + "': " + what);
  };
  if (fields.size() < 4) return fail("expected MODEL,WIDTH,HEIGHT,PARAMS...");
  const CameraModelId model_id = CameraModelIdFromName(std::string(Trim(fields[0])));
  if (model_id == CameraModelId::kInvalid) {
    return fail("unknown camera model '" + std::string(fields[0]) + "'");
  }
  const std::optional<int64_t> width = ParseInt(Trim(fields[1]));
  const std::optional<int64_t> height = ParseInt(Trim(fields[2]));
  if (!width || !height || *width <= 0 || *height <= 0) {
    return fail("expected a positive integer width and height");
  }
  std::vector<double> params;
  for (size_t i = 3; i < fields.size(); ++i) {
    const std::optional<double> value = ParseDouble(Trim(fields[i]));
    if (!value) return fail("parameter '" + std::string(fields[i]) + "' is not a number");
    params.push_back(*value);
  }
  return MakeCamera(model_id, static_cast<uint64_t>(*width), static_cast<uint64_t>(*height),
                    std::move(params));
}

// Where a bag's images go: beside the database, as a EuRoC folder (bag/).
fs::path BagFolder(const FeaturesArguments& args) {
  return HasRosbagExtension(args.dataset) ? fs::absolute(args.database).parent_path() / "bag"
                                          : fs::path();
}

Sequence ReadFeaturesDataset(const FeaturesArguments& args) {
  DatasetReadOptions options;
  options.rosbag = MakeRosbagOptions(args.bag, fs::absolute(args.database).parent_path() / "bag");
  options.image_folder.timestamps_file = args.timestamps;
  options.image_folder.camera_yaml = args.bag.camera_yaml;
  if (!args.camera.empty()) options.image_folder.camera = ParseCameraOption(args.camera);
  options.calibration = args.calibration;
  options.checks = args.checks;
  return ReadDataset(args.dataset, options);
}

// What the features stored in the database are made from, under the keys a
// run's fingerprint gives them (pipeline/run_fingerprint.h).
RunFingerprint FeaturesFingerprint(const FeaturesArguments& args, const SiftOptions& sift,
                                   const Sequence& sequence) {
  PipelineOptions options;
  options.dataset = args.dataset;
  options.image_folder.timestamps_file = args.timestamps;
  options.image_folder.camera_yaml = args.bag.camera_yaml;
  options.rosbag = MakeRosbagOptions(args.bag, BagFolder(args));
  options.calibration = args.calibration;
  options.sift = sift;
  RunFingerprint fingerprint = FingerprintOfInputs(options);
  AddSequenceToFingerprint(sequence, &fingerprint);
  return FingerprintPart(fingerprint, FeaturesFingerprintPrefixes());
}

void RunFeatures(const FeaturesArguments& args) {
  SiftOptions options = args.sift;
  options.root_sift = !args.no_root_sift;
  options.num_threads = CapNumThreads(options.num_threads, "--threads");
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid feature options: " + error);
  }
  CheckDatasetExists(args.dataset);
  const fs::path database_path = args.database;
  // The database's folder locked as a run's, its files that viosfm did not
  // write never written over; the database's record checked and written
  // before its rows change.
  DatabaseFolder folder(database_path, BagFolder(args));
  if (!BagFolder(args).empty()) folder.MarkWriting();
  const Sequence sequence = ReadFeaturesDataset(args);
  folder.CheckAndRecord(FeaturesFingerprint(args, options, sequence));
  ColmapDatabase database = ColmapDatabase::Open(database_path);
  VIOSFM_LOG(INFO) << "features: " << sequence.images.size() << " images of " << args.dataset
                   << " -> " << database_path.string() << " (max " << options.max_num_features
                   << " per image, " << (options.root_sift ? "RootSIFT" : "SIFT") << ", "
                   << options.num_threads << " threads)";
  const FeatureExtractionSummary summary = ExtractFeatures(sequence, options, &database);
  VIOSFM_LOG(INFO) << "features: " << summary.ToString() << "; database holds "
                   << database.NumImages() << " images, " << database.NumKeypoints()
                   << " keypoints";
  folder.Finish();
}

}  // namespace

void RegisterFeatures(CLI::App& app) {
  auto args = std::make_shared<FeaturesArguments>();
  CLI::App* command = app.add_subcommand(
      "features",
      "Extract SIFT (RootSIFT) features of every image into a COLMAP 3.8 database; a re-run "
      "skips the images already stored, and a database whose features other inputs or options "
      "made is refused (fingerprint.json beside it, as a run's)");
  command
      ->add_option("dataset", args->dataset,
                   "EuRoC dataset (folder containing mav0/), a folder of images or a bag (ROS 1 "
                   ".bag; ROS 2 .db3, .mcap or bag folder)")
      ->required();
  command->add_option("--database", args->database, "COLMAP database (created if missing)")
      ->required();
  AddCalibrationOptions(command, &args->calibration);
  AddDatasetCheckOptions(command, &args->checks);
  command->add_option("--max-features", args->sift.max_num_features, "Features kept per image")
      ->capture_default_str();
  command->add_flag("--no-root-sift", args->no_root_sift,
                    "L2-normalised SIFT descriptors instead of RootSIFT");
  command->add_option("--threads", args->sift.num_threads, "Images extracted in parallel")
      ->capture_default_str();
  command
      ->add_option("--peak-threshold", args->sift.peak_threshold,
                   "Minimum DoG response (intensities in [0, 1])")
      ->capture_default_str();
  command
      ->add_option("--first-octave", args->sift.first_octave,
                   "First octave of the scale space: -1 (image doubled, COLMAP's) or 0 (the image "
                   "itself: about half the time, coarser keypoints)")
      ->check(CLI::IsMember({-1, 0}))
      ->capture_default_str();
  command->add_option("--camera-yaml", args->bag.camera_yaml,
                      "Image folder or bag: Kalibr/EuRoC camera sensor.yaml");
  AddBagOptions(command, &args->bag, /*add_camera_yaml=*/false);
  command->add_option("--camera", args->camera,
                      "Image folder: MODEL,WIDTH,HEIGHT,PARAMS... (COLMAP model and order)");
  command->add_option("--timestamps", args->timestamps,
                      "Image folder: file of 'filename timestamp' lines");
  command->callback([args] { RunFeatures(*args); });
}

}  // namespace viosfm::cli
