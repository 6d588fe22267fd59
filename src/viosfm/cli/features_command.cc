// `viosfm features`: SIFT/RootSIFT features of every image of a dataset into
// a COLMAP-compatible database (see features/feature_extraction.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "viosfm/cli/bag_options.h"
#include "viosfm/cli/commands.h"
#include "viosfm/cli/option_flags.h"
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

// `viosfm features` runs the feature stage of a run: its flags set a run's
// options (option_flags.h), of which it uses the dataset's and the SIFT's.
struct FeaturesArguments {
  std::string dataset;
  std::string database;
  std::string camera;
  BagArguments bag;
  PipelineOptions options;
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

// The run's options of the features: the dataset's, with a bag's images
// beside the database (OUT/bag), and the SIFT's.
PipelineOptions FeaturesRunOptions(const FeaturesArguments& args) {
  PipelineOptions options = args.options;
  options.dataset = args.dataset;
  options.rosbag = MakeRosbagOptions(args.bag, BagFolder(args));
  options.image_folder.camera_yaml = args.bag.camera_yaml;
  options.num_threads = CapNumThreads(options.num_threads, "--threads");
  return options;
}

Sequence ReadFeaturesDataset(const FeaturesArguments& args, const PipelineOptions& run_options) {
  DatasetReadOptions options;
  options.rosbag = MakeRosbagOptions(args.bag, fs::absolute(args.database).parent_path() / "bag");
  options.image_folder = run_options.image_folder;
  if (!args.camera.empty()) options.image_folder.camera = ParseCameraOption(args.camera);
  options.calibration = run_options.calibration;
  options.checks = run_options.dataset_checks;
  return ReadDataset(args.dataset, options);
}

// What the features stored in the database are made from, under the keys a
// run's fingerprint gives them (pipeline/run_fingerprint.h).
RunFingerprint FeaturesFingerprint(const PipelineOptions& options, const Sequence& sequence) {
  RunFingerprint fingerprint = FingerprintOfInputs(options);
  AddSequenceToFingerprint(sequence, &fingerprint);
  return FingerprintPart(fingerprint, FeaturesFingerprintPrefixes());
}

void RunFeatures(const FeaturesArguments& args) {
  const PipelineOptions run_options = FeaturesRunOptions(args);
  const SiftOptions options = run_options.EffectiveSiftOptions();
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
  const Sequence sequence = ReadFeaturesDataset(args, run_options);
  folder.CheckAndRecord(FeaturesFingerprint(run_options, sequence));
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
      "Extract SIFT features into a COLMAP database (the feature stage of `viosfm run`). RootSIFT "
      "features of every image into a COLMAP 3.8 database, with the flags of `viosfm run`; a "
      "re-run skips the images already stored, "
      "and a database whose features other inputs or options made is refused (fingerprint.json "
      "beside it, as a run's)");
  command
      ->add_option("dataset", args->dataset,
                   "EuRoC dataset (folder containing mav0/), a folder of images or a bag (ROS 1 "
                   ".bag; ROS 2 .db3, .mcap or bag folder)")
      ->required();
  command->add_option("--database", args->database, "COLMAP database (created if missing)")
      ->required();
  AddCalibrationOptions(command, &args->options.calibration);
  AddDatasetCheckOptions(command, &args->options.dataset_checks);
  AddOptionFlags(command, MakeOptionTarget(&args->options, ""),
                 {"--max-features", "--no-root-sift", "--threads", "--peak-threshold",
                  "--first-octave", "--timestamps"});
  command->get_option("--first-octave")->check(CLI::IsMember({-1, 0}));
  AddBagOptions(command, &args->bag);
  command->add_option("--camera", args->camera,
                      "Image folder: MODEL,WIDTH,HEIGHT,PARAMS... (COLMAP model and order)");
  command->callback([args] { RunFeatures(*args); });
}

}  // namespace viosfm::cli
