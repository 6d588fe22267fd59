// `viosfm run`: the whole VIO-aided reconstruction of a dataset into an
// output folder (see pipeline/pipeline.h).
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/cli/bag_options.h"
#include "viosfm/cli/command_help.h"
#include "viosfm/cli/commands.h"
#include "viosfm/cli/option_flags.h"
#include "viosfm/cli/vio_uncertainty_options.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/pipeline/pipeline.h"
#include "viosfm/pipeline/texture_probe.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"

namespace viosfm::cli {
namespace {

struct RunArguments {
  std::string dataset;
  std::string out;
  VerificationBandArguments band;
  VioUncertaintyArguments vio_uncertainty;
  BagArguments bag;
  // --set KEY=VALUE, applied after every other flag.
  std::vector<std::string> set_options;
  PipelineOptions options;
};

// A rate, a feature count, an image size, N2 or an adjustment setting the
// user gives is kept: the texture probe, the feature budget and a sparse
// recording's settings would change it.
void KeepUsersChoice(const std::string& key, PipelineOptions* options) {
  if (SettledByTextureProbe(key)) options->texture_probe.enable = false;
  if (SettledByFeatureBudget(key)) options->feature_budget.features_per_second = 0;
  if (SettledBySparseRecording(key)) options->feature_budget.paper_settings_when_sparse = false;
}

// --list-options: every option key with its default, whether it shapes the
// stored data (a re-run with another value cannot reuse them), the flag
// that sets it, if any, and its help.
void ListOptions() {
  PipelineOptions defaults;
  ApplyPreset(RunPreset::kRealtime, &defaults);
  std::cout << "# defaults of --preset realtime; --preset paper sets the paper's\n";
  for (const OptionDescription& option : OptionDescriptions(defaults)) {
    const OptionFlag* flag = FlagOfKey(option.key);
    std::cout << option.key << " = " << option.default_text << "  ["
              << (option.effect == kShapesStoredData ? "stored data" : "run only") << "]  "
              << (flag != nullptr ? flag->name + ": " : std::string()) << option.help << "\n";
  }
}

void RunRun(RunArguments args) {
  PipelineOptions& options = args.options;
  options.dataset = args.dataset;
  options.output_folder = args.out;
  options.vio_uncertainty = args.vio_uncertainty.Model();
  args.band.ApplyTo(&options.verification);
  options.image_folder.camera_yaml = args.bag.camera_yaml;
  options.rosbag = MakeRosbagOptions(args.bag, {});  // extract folder: OUT/bag
  for (const std::string& assignment : args.set_options) {
    const size_t equals = assignment.find('=');
    if (equals == std::string::npos) {
      throw InputError("--set " + assignment + ": expected KEY=VALUE");
    }
    const std::string key = assignment.substr(0, equals);
    SetOptionFromText(options, key, assignment.substr(equals + 1));
    KeepUsersChoice(key, &options);
  }
  options.num_threads = CapNumThreads(options.num_threads, "--threads");
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid run options: " + error);
  }
  VIOSFM_LOG(INFO) << "run: " << args.dataset << " -> " << args.out << ": N1 "
                   << options.verification.pairs.num_temporal_neighbors << ", N2 "
                   << options.verification.pairs.num_retrieval_neighbors << ", "
                   << options.frame_selection.target_rate_hz << " Hz, "
                   << (options.feature_budget.features_per_second > 0
                           ? std::to_string(options.feature_budget.features_per_second) +
                                 " features a second (at most " +
                                 std::to_string(options.sift.max_num_features) + " a frame)"
                           : "max " + std::to_string(options.sift.max_num_features) + " features")
                   << LogDetails() << ", batch size " << options.mapper.batch_size
                   << (options.mapper.ba_window_batches > 0
                           ? ", BA window " + std::to_string(options.mapper.ba_window_batches)
                           : std::string())
                   << ", " << (options.texture_probe.enable ? "rate and features by texture, " : "")
                   << (options.verification.guided_matching ? "guided matching, " : "")
                   << (options.follow   ? "followed as recorded, "
                       : options.stream ? "streamed, "
                                        : "")
                   << (options.verification.use_vio_prior ? "VIO prior" : "RANSAC only") << ", "
                   << (options.mapper.ba.use_relative_pose_priors
                           ? std::string("RPC, ") +
                                 PriorWeightingName(options.mapper.ba.prior_weighting) +
                                 " weighting"
                           : std::string("no RPC"));
  const PipelineSummary summary = RunPipeline(options);
  std::cout << summary.ToString() << "\n";
}

constexpr const char* kRunExamples =
    "Examples:\n"
    "  # A EuRoC folder (mav0/cam0 and mav0/imu0 with their sensor.yaml):\n"
    "  viosfm run /data/V1_01_easy --out out/v101\n"
    "  # A bag (ROS 1 .bag; ROS 2 .db3, .mcap or a rosbag2 folder), with the topics and the\n"
    "  # EuRoC/Kalibr sensor.yaml files where the bag does not tell them:\n"
    "  viosfm run rec.mcap --out out/rec --image-topic /cam/image_raw --imu-topic /cam/imu \\\n"
    "      --camera-yaml cam0_sensor.yaml --imu-yaml imu0_sensor.yaml\n"
    "  # Images only: a folder of photos, no IMU (the camera is guessed from the image size,\n"
    "  # or given with --camera-yaml; --timestamps gives the stamps of a sequence):\n"
    "  viosfm run photos/ --out out/photos\n"
    "\n"
    "Then `viosfm report OUT` (an HTML page) and `viosfm export OUT` (COLMAP, nerfstudio, gsplat). "
    "`viosfm run --help-all` lists every flag; `viosfm run --list-options` every option key "
    "for --set.";

// The preset options, defined before the flags that set one option each.
void AddPresetOptions(CLI::App* command, const std::shared_ptr<RunArguments>& args) {
  // `viosfm run` starts from the real-time preset; --preset is defined
  // before the flags that set one option each: CLI11 runs the callbacks in
  // the order of definition, so those flags (and --set) override it.
  ApplyPreset(RunPreset::kRealtime, &args->options);
  command
      ->add_option_function<std::string>(
          "--preset",
          [args](const std::string& name) {
            ApplyPreset(name == "paper" ? RunPreset::kPaper : RunPreset::kRealtime, &args->options);
          },
          "realtime (default): a recording reconstructed in about its own duration on 2 cores "
          "(N1 10, N2 5, 10000 features a second of recording, guided matching, a bundle-"
          "adjustment window); paper: the paper's settings (N1 40, N2 30, 8192 features a frame), "
          "slower")
      ->check(CLI::IsMember({"realtime", "paper"}))
      ->default_str("realtime");
  command->add_flag_callback(
      "--realtime", [args] { ApplyPreset(RunPreset::kRealtime, &args->options); },
      "The same as --preset realtime");
}

// The flags bound to one option each (cli/option_flags.h).
void AddRunOptionFlags(CLI::App* command, const std::shared_ptr<RunArguments>& args) {
  // A rate or a feature count given by the user is kept: the texture probe
  // and the feature budget would change it.
  const OptionTarget target = MakeOptionTarget(
      &args->options, "", [args](const std::string& key) { KeepUsersChoice(key, &args->options); });
  AddOptionFlags(command, target,
                 {"--timestamps",
                  "--no-imu",
                  "--vio-trajectory",
                  "--vio-format",
                  "--vio-frame",
                  "--max-vio-time-difference",
                  "--vio-max-gap",
                  "--no-imu-scale",
                  "--rolling-shutter-readout",
                  "--rate",
                  "--max-features",
                  "--no-trim-static",
                  "--n1",
                  "--n2",
                  "--guided-matching",
                  "--no-vio-prior",
                  "--max-correction-sigmas",
                  "--verification-batch",
                  "--batch-size",
                  "--ba-window",
                  "--batch-ba-iterations",
                  "--ba-sparse-max-images",
                  "--bridge-spans",
                  "--bridge-max-matches",
                  "--no-bridging",
                  "--prior-loss-scale",
                  "--prior-weighting",
                  "--no-rpc",
                  "--no-verify-registration",
                  "--stream",
                  "--follow",
                  "--follow-idle",
                  "--threads",
                  "--seed",
                  "--no-progress"});
}

// The flags of the run as a whole: --overwrite, --set, --list-options.
void AddRunControlOptions(CLI::App* command, const std::shared_ptr<RunArguments>& args) {
  command->add_flag("--overwrite", args->options.overwrite,
                    "Remove the stored database and outputs of an earlier run in --out and start "
                    "afresh (without it a re-run reuses them, and refuses a folder whose "
                    "fingerprint.json says they were made from other inputs or options)");
  command->add_option("--set", args->set_options,
                      "KEY=VALUE: set any option by its options.json key (repeatable; applied "
                      "after the other flags; --list-options lists the keys)");
  // Runs while the arguments are parsed, before the required ones are checked.
  command->add_flag_callback(
      "--list-options",
      [] {
        ListOptions();
        throw CLI::Success();
      },
      "List every option key (for --set) with its default, whether it shapes the stored "
      "features and matches, the flag that sets it, and its help; then exit");
}

// The help's sections: the shown ones first, the others under --help-all.
void SetRunSections(CLI::App* command) {
  SetOptionSections(
      command,
      {{"Run",
        true,
        {"--out", "--vio-trajectory", "--no-imu", "--preset", "--realtime", "--threads",
         "--overwrite", "--set", "--list-options"}},
       {"Dataset",
        true,
        {"--calibration", "--timestamps", "--image-topic", "--imu-topic", "--camera-yaml",
         "--imu-yaml"}},
       {"Dataset: more",
        false,
        {"--imu-calibration", "--groundtruth-topic", "--allow-external-links", "--imu-max-accel",
         "--imu-max-gyro"}},
       {"VIO",
        false,
        {"--vio-format", "--vio-frame", "--max-vio-time-difference", "--vio-max-gap",
         "--no-imu-scale", "--rolling-shutter-readout"}},
       {"Frames and features", false, {"--rate", "--max-features", "--no-trim-static"}},
       {"Pairs and verification",
        false,
        {"--n1", "--n2", "--guided-matching", "--no-vio-prior", "--fixed-band", "--wide-band",
         "--max-correction-sigmas", "--verification-batch"}},
       {"Mapping",
        false,
        {"--batch-size", "--ba-window", "--batch-ba-iterations", "--ba-sparse-max-images",
         "--bridge-spans", "--bridge-max-matches", "--no-bridging", "--prior-loss-scale",
         "--prior-weighting", "--no-rpc", "--no-verify-registration"}},
       {kVioUncertaintyGroup, false, VioUncertaintyFlagNames()},
       {"A stream, a recording followed", false, {"--stream", "--follow", "--follow-idle"}},
       {"Run: more", false, {"--seed", "--no-progress"}}});
}

}  // namespace

void RegisterRun(CLI::App& app) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* command = app.add_subcommand(
      "run",
      "Reconstruct a dataset (EuRoC folder, bag or images) into a model. "
      "The steps: VIO poses, features, VIO-aided verification, batched mapping with "
      "relative-pose constraints and bundle adjustment, evaluation against ground truth. Writes "
      "the COLMAP model (model/, model_txt/), points.ply, trajectories, eval.json "
      "and, last, summary.json to --out; a re-run into the same folder reuses the stored "
      "features and matches when fingerprint.json says they were made from the same inputs and "
      "options.");
  command->footer(kRunExamples);
  command
      ->add_option("dataset", args->dataset,
                   "A EuRoC folder (containing mav0/), a folder of images, or a bag (ROS 1 .bag; "
                   "ROS 2 .db3, .mcap or bag folder)")
      ->required();
  command->add_option("--out", args->out, "Output folder (created if missing)")->required();
  AddCalibrationOptions(command, &args->options.calibration);
  AddDatasetCheckOptions(command, &args->options.dataset_checks);
  AddBagOptions(command, &args->bag);
  AddPresetOptions(command, args);
  AddRunOptionFlags(command, args);
  AddVerificationBandOptions(command, &args->band);
  AddVioUncertaintyOptions(command, &args->vio_uncertainty);
  AddRunControlOptions(command, args);
  SetRunSections(command);
  command->callback([args] { RunRun(*args); });
}

}  // namespace viosfm::cli
