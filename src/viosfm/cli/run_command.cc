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
#include "viosfm/cli/commands.h"
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
  std::string vio_trajectory;
  std::string vio_format = "tum";
  std::string vio_frame = "body";
  double max_vio_time_difference_s = 0.005;
  double vio_max_gap_s = 1.0;
  std::string prior_weighting = "covariance";
  bool no_verify_registration = false;
  VerificationBandArguments band;
  bool no_imu_scale = false;
  bool no_imu = false;
  VioUncertaintyArguments vio_uncertainty;
  std::string timestamps;
  BagArguments bag;
  bool no_trim_static = false;
  bool no_vio_prior = false;
  bool no_rpc = false;
  bool no_bridging = false;
  bool no_progress = false;
  // --set KEY=VALUE, applied after every other flag.
  std::vector<std::string> set_options;
  PipelineOptions options;
};

// --list-options: every option key with its default, whether it shapes the
// stored data (a re-run with another value cannot reuse them) and its help.
void ListOptions() {
  for (const OptionDescription& option : OptionDescriptions<PipelineOptions>()) {
    std::cout << option.key << " = " << option.default_text << "  ["
              << (option.effect == kShapesStoredData ? "stored data" : "run only") << "]  "
              << option.help << "\n";
  }
}

void RunRun(RunArguments args) {
  PipelineOptions& options = args.options;
  options.dataset = args.dataset;
  options.output_folder = args.out;
  options.vio_trajectory = args.vio_trajectory;
  options.vio_format = ParseTrajectoryFormat(args.vio_format);
  options.vio_frame = ParseVioFrame(args.vio_frame);
  options.max_vio_time_difference_ns = SecondsToNs(args.max_vio_time_difference_s);
  options.vio_max_gap_ns = SecondsToNs(args.vio_max_gap_s);
  options.vio_uncertainty = args.vio_uncertainty.Model();
  options.mapper.ba.prior_weighting = ParsePriorWeighting(args.prior_weighting);
  options.mapper.registration.verify_with_images = !args.no_verify_registration;
  args.band.ApplyTo(&options.verification);
  options.use_imu_scale = !args.no_imu_scale;
  options.use_imu = !args.no_imu;
  options.image_folder.camera_yaml = args.bag.camera_yaml;
  options.rosbag = MakeRosbagOptions(args.bag, {});  // extract folder: OUT/bag
  options.image_folder.timestamps_file = args.timestamps;
  options.frame_selection.trim_static = !args.no_trim_static;
  options.verification.use_vio_prior = !args.no_vio_prior;
  options.mapper.ba.use_relative_pose_priors = !args.no_rpc;
  if (args.no_bridging) options.mapper.bridge_spans.clear();
  options.show_progress = !args.no_progress;
  for (const std::string& assignment : args.set_options) {
    const size_t equals = assignment.find('=');
    if (equals == std::string::npos) {
      throw InputError("--set " + assignment + ": expected KEY=VALUE");
    }
    const std::string key = assignment.substr(0, equals);
    SetOptionFromText(options, key, assignment.substr(equals + 1));
    if (SettledByTextureProbe(key)) options.texture_probe.enable = false;
  }
  options.num_threads = CapNumThreads(options.num_threads, "--threads");
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid run options: " + error);
  }
  VIOSFM_LOG(INFO) << "run: " << args.dataset << " -> " << args.out << " (N1 "
                   << options.verification.pairs.num_temporal_neighbors << ", N2 "
                   << options.verification.pairs.num_retrieval_neighbors << ", "
                   << options.frame_selection.target_rate_hz << " Hz, batch size "
                   << options.mapper.batch_size
                   << (options.mapper.ba_window_batches > 0
                           ? ", BA window " + std::to_string(options.mapper.ba_window_batches)
                           : std::string())
                   << ", max " << options.sift.max_num_features << " features, "
                   << (options.texture_probe.enable ? "rate and features by texture, " : "")
                   << (options.verification.guided_matching ? "guided matching, " : "")
                   << (options.follow   ? "followed as recorded, "
                       : options.stream ? "streamed, "
                                        : "")
                   << (options.verification.use_vio_prior ? "VIO prior" : "RANSAC only") << ", "
                   << (options.mapper.ba.use_relative_pose_priors
                           ? std::string("RPC, ") +
                                 PriorWeightingName(options.mapper.ba.prior_weighting) +
                                 " weighting"
                           : std::string("no RPC"))
                   << ")";
  const PipelineSummary summary = RunPipeline(options);
  std::cout << summary.ToString() << "\n";
}

// The flags that set one option each. Their help and default come from the
// option's own description (util/option_fields.h), written once there.
constexpr std::pair<const char*, const char*> kOptionFlags[] = {
    {"--rate", "frame_selection.target_rate_hz"},
    {"--max-features", "sift.max_num_features"},
    {"--n1", "verification.pairs.num_temporal_neighbors"},
    {"--n2", "verification.pairs.num_retrieval_neighbors"},
    {"--batch-size", "mapper.batch_size"},
    {"--ba-window", "mapper.ba_window_batches"},
    {"--batch-ba-iterations", "mapper.batch_ba_max_num_iterations"},
    {"--ba-sparse-max-images", "mapper.ba.max_images_for_sparse_schur"},
    {"--bridge-spans", "mapper.bridge_spans"},
    {"--bridge-max-matches", "mapper.bridge_max_matches"},
    {"--prior-loss-scale", "mapper.ba.prior_loss_scale"},
    {"--verification-batch", "verification.batch_size"},
    {"--max-correction-sigmas", "verification.max_correction_sigmas"},
    {"--threads", "num_threads"},
    {"--seed", "seed"},
};

// Adds kOptionFlags to `command`, each setting its option of `options`.
void AddOptionFlags(CLI::App* command, PipelineOptions* options) {
  const std::vector<OptionDescription> descriptions = OptionDescriptions<PipelineOptions>();
  for (const auto& [flag, key] : kOptionFlags) {
    const auto description =
        std::find_if(descriptions.begin(), descriptions.end(),
                     [key = key](const OptionDescription& d) { return d.key == key; });
    VIOSFM_CHECK(description != descriptions.end()) << "no option " << key << " for " << flag;
    std::string help = description->help;
    if (!help.empty())
      help[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(help[0])));
    command
        ->add_option(
            flag,
            [options, flag = std::string(flag),
             key = std::string(key)](const CLI::results_t& results) {
              try {
                SetOptionFromText(*options, key, results.front());
              } catch (const InputError& error) {
                throw InputError(flag + ": " + error.what());
              }
              // A rate or a feature count given by the user is kept: the texture
              // probe that --realtime turns on would change it.
              if (SettledByTextureProbe(key)) options->texture_probe.enable = false;
              return true;
            },
            help + " (option " + key + ")")
        ->default_str(description->default_text)
        ->expected(1);
  }
}

}  // namespace

void RegisterRun(CLI::App& app) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* command = app.add_subcommand(
      "run",
      "Reconstruct a dataset end to end: frame selection, features, VIO-aided verification, "
      "batched mapping with relative-pose constraints, evaluation against ground truth; writes "
      "model/, model_txt/, points.ply, trajectories, eval.json and summary.json (last) to --out; a "
      "re-run on the same folder reuses the stored features and matches when fingerprint.json "
      "says they were made from the same inputs and options");
  command
      ->add_option("dataset", args->dataset,
                   "EuRoC dataset (folder containing mav0/), a folder of images or a bag (ROS 1 "
                   ".bag; ROS 2 .db3, .mcap or bag folder)")
      ->required();
  command->add_option("--out", args->out, "Output folder (created if missing)")->required();
  AddCalibrationOptions(command, &args->options.calibration);
  AddDatasetCheckOptions(command, &args->options.dataset_checks);
  // Defined before the flags that set one option each: CLI11 runs the
  // callbacks in the order of definition, so those flags (and --set) override
  // the settings it applies.
  command->add_flag_callback(
      "--realtime", [args] { ApplyRealtimeSettings(&args->options); },
      "Settings that reconstruct a recording in about its own duration on 2 cores: N1 10, N2 "
      "5, 1000 features on images of at most 960 pixels, --guided-matching, --ba-window 4 with "
      "5 held views a point, and a textured recording (every frame rich in keypoints) taken at "
      "4 Hz with 2500 features a frame (the "
      "paper's settings are more accurate and far slower; flags given with it override it, "
      "--rate and --max-features the texture's choice too)");
  AddOptionFlags(command, &args->options);
  command->add_flag("--stream", args->options.stream,
                    "The run as one stream: the VIO, the features, the verification and the "
                    "mapper overlap, each frame's pairs with the frames before it verified as it "
                    "comes and each batch mapped once its frames are in (retrieval among earlier "
                    "frames only; a streamed run starts afresh, it does not resume)");
  command->add_flag(
      "--follow", args->options.follow,
      "The dataset is a EuRoC folder being recorded: follow it as it grows (its rows as they "
      "are appended, viosfm's own VIO), the model after every batch in OUT/live/, the final "
      "model once nothing was appended for --follow-idle seconds (implies --stream)");
  command
      ->add_option(
          "--follow-idle",
          [args](const CLI::results_t& results) {
            try {
              SetOptionFromText(args->options, "follow_idle_s", results.front());
            } catch (const InputError& error) {
              throw InputError(std::string("--follow-idle: ") + error.what());
            }
            return true;
          },
          "Seconds of silence after which a followed recording has ended (option follow_idle_s)")
      ->default_str("3")
      ->expected(1);
  // The camera's readout is one fact with two uses: viosfm's own VIO, and
  // the keypoints' compensation when the VIO is external.
  command
      ->add_option(
          "--rolling-shutter-readout",
          [args](const CLI::results_t& results) {
            for (const char* key :
                 {"own_vio.rolling_shutter_readout_s", "rolling_shutter.readout_s"}) {
              try {
                SetOptionFromText(args->options, key, results.front());
              } catch (const InputError& error) {
                throw InputError(std::string("--rolling-shutter-readout: ") + error.what());
              }
            }
            return true;
          },
          "The camera's rolling-shutter readout, first row to last (s; 0: not given): viosfm's "
          "own VIO uses it instead of its estimate, and the keypoints are compensated with it "
          "(options own_vio.rolling_shutter_readout_s and rolling_shutter.readout_s)")
      ->default_str("0")
      ->expected(1);
  command->add_option("--vio-trajectory", args->vio_trajectory,
                      "VIO trajectory (TUM by default), world_from_body unless --vio-frame cam; "
                      "without it viosfm's own VIO runs on the images and IMU");
  command->add_option("--vio-format", args->vio_format, "Its format: tum, euroc or kitti")
      ->capture_default_str();
  command->add_option("--vio-frame", args->vio_frame, "Frame of the VIO poses: body or cam")
      ->capture_default_str();
  command
      ->add_option("--max-vio-time-difference", args->max_vio_time_difference_s,
                   "Largest gap between an image stamp and its VIO pose (s)")
      ->capture_default_str();
  command->add_flag("--no-trim-static", args->no_trim_static,
                    "Keep the static frames at the start and the end");
  command->add_flag("--no-bridging", args->no_bridging,
                    "Relative-pose priors between consecutive frames only (the paper's)");
  command->add_flag("--no-vio-prior", args->no_vio_prior,
                    "RANSAC-only verification (COLMAP's; the baseline)");
  command->add_flag("--no-rpc", args->no_rpc,
                    "Bundle adjustment without the relative-pose constraints (ablation)");
  command
      ->add_option("--prior-weighting", args->prior_weighting,
                   "Relative-pose priors weighted by the VIO uncertainty model's covariance "
                   "under a robust loss (covariance) or by the paper's alpha exp(-beta c) with "
                   "fixed sigmas and rotation-only bridging priors (paper: the ablation; the "
                   "verification is the same, see --fixed-band)")
      ->capture_default_str();
  command->add_flag("--no-verify-registration", args->no_verify_registration,
                    "Place frames by the VIO alone (the paper's), without checking them "
                    "against their 2D-3D matches; frames without a VIO pose stay unposed");
  command->add_flag("--no-imu", args->no_imu,
                    "Leave the dataset's IMU out: the images alone (and a VIO trajectory file, "
                    "if given) make the model");
  command->add_flag("--no-imu-scale", args->no_imu_scale,
                    "Keep the VIO's metric scale instead of estimating it from the dataset's "
                    "IMU over the registered frames");
  AddVerificationBandOptions(command, &args->band);
  command
      ->add_option("--vio-max-gap", args->vio_max_gap_s,
                   "Time gaps in a VIO trajectory file longer than this (s) are judged by the "
                   "images: one segment where they confirm the VIO's relative pose across, a "
                   "break where they contradict it or see nothing (0: no gap is judged)")
      ->capture_default_str();
  AddVioUncertaintyOptions(command, &args->vio_uncertainty);
  command->add_flag("--guided-matching", args->options.verification.guided_matching,
                    "Match inside the VIO epipolar band instead of by brute force");
  command->add_option("--camera-yaml", args->bag.camera_yaml,
                      "Image folder or bag: Kalibr/EuRoC camera sensor.yaml");
  AddBagOptions(command, &args->bag, /*add_camera_yaml=*/false);
  command->add_option("--timestamps", args->timestamps,
                      "Image folder: file of 'filename timestamp' lines");
  command->add_flag("--overwrite", args->options.overwrite,
                    "Remove the stored database and outputs of an earlier run in --out and start "
                    "afresh (without it a re-run reuses them, and refuses a folder whose "
                    "fingerprint.json says they were made from other inputs or options)");
  command->add_flag("--no-progress", args->no_progress, "No progress bars");
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
      "features and matches, and its help; then exit");
  command->callback([args] { RunRun(*args); });
}

}  // namespace viosfm::cli
