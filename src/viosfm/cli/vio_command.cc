// `viosfm vio DATASET --out DIR`: monocular visual-inertial odometry over a
// EuRoC-layout dataset (see vio/odometry.h); writes the body and camera
// trajectories (TUM), the per-frame states with their status, and a summary.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "viosfm/cli/bag_options.h"
#include "viosfm/cli/commands.h"
#include "viosfm/io/dataset.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/vio/odometry.h"

namespace viosfm::cli {
namespace {

namespace fs = std::filesystem;

struct VioArguments {
  std::string dataset;
  std::string out;
  CalibrationFiles calibration;
  DatasetChecks checks;
  VioOptions options;
  BagArguments bag;
  std::vector<std::string> set_options;
};

void RunVioCommand(VioArguments args) {
  const fs::path root = args.dataset;
  for (const std::string& assignment : args.set_options) {
    const size_t equals = assignment.find('=');
    if (equals == std::string::npos) {
      throw InputError("--set " + assignment + ": expected KEY=VALUE");
    }
    SetOptionFromText(args.options, assignment.substr(0, equals), assignment.substr(equals + 1));
  }
  args.options.window.num_threads = CapNumThreads(args.options.window.num_threads, "--threads");
  if (const std::string error = args.options.Validate(); !error.empty()) {
    throw InputError("invalid vio options: " + error);
  }
  DatasetReadOptions read;
  read.rosbag = MakeRosbagOptions(args.bag, fs::path(args.out) / "bag");
  read.calibration = args.calibration;
  read.require_imu = true;
  read.checks = args.checks;
  const Sequence sequence = ReadDataset(root, read);
  VIOSFM_LOG(INFO) << "vio: " << sequence.images.size() << " images, " << sequence.imu.size()
                   << " IMU samples from " << args.dataset;
  const VioResult result = RunVio(sequence, args.options);
  WriteVioResult(args.out, result);
  const VioSummary& summary = result.summary;
  VIOSFM_LOG(INFO) << "vio: wrote " << (fs::path(args.out) / "trajectory_body.tum").string()
                   << ", trajectory_cam.tum, states.csv, vio_summary.txt; " << summary.num_frames
                   << " frames: tracking " << summary.status_counts[1] << ", initializing "
                   << summary.status_counts[0] << ", imu_only " << summary.status_counts[2]
                   << ", lost " << summary.status_counts[3] << "; "
                   << summary.num_frames_without_pose
                   << " without a pose (before the moving start was initialised, left out of "
                      "the trajectories); CPU "
                   << summary.cpu_seconds << " s";
}

}  // namespace

void RegisterVio(CLI::App& app) {
  auto args = std::make_shared<VioArguments>();
  CLI::App* command = app.add_subcommand(
      "vio",
      "Monocular visual-inertial odometry (KLT front end, sliding-window back end with IMU "
      "preintegration and marginalisation): a pose, velocity, biases and status for every frame");
  command
      ->add_option("dataset", args->dataset,
                   "EuRoC dataset (folder containing mav0/) or a bag (ROS 1 .bag; ROS 2 .db3, "
                   ".mcap or bag folder)")
      ->required();
  command->add_option("--out", args->out, "Output folder")->required();
  AddCalibrationOptions(command, &args->calibration);
  AddDatasetCheckOptions(command, &args->checks);
  command
      ->add_option("--max-frames", args->options.max_frames,
                   "Process only the first N images (0: all)")
      ->capture_default_str();
  command->add_option("--threads", args->options.window.num_threads, "Threads of the window solver")
      ->capture_default_str();
  command->add_option("--window-size", args->options.window.window_size, "Keyframes in the window")
      ->capture_default_str();
  command
      ->add_option("--max-features", args->options.tracker.max_num_features,
                   "Corners tracked per image")
      ->capture_default_str();
  command
      ->add_option("--iterations", args->options.window.max_num_iterations,
                   "Solver iterations per frame")
      ->capture_default_str();
  command
      ->add_option("--rolling-shutter-readout", args->options.rolling_shutter_readout_s,
                   "s, the camera's rolling-shutter readout time, first row to last; "
                   "observations are moved to the frame's stamp (0: not given, estimated with the "
                   "time offset; a global shutter when the images show none)")
      ->capture_default_str();
  AddBagOptions(command, &args->bag, /*add_camera_yaml=*/true);
  command->add_option("--set", args->set_options,
                      "KEY=VALUE: set any VIO option by its key, as `viosfm run --list-options` "
                      "lists it without the leading 'own_vio.' (repeatable; applied after the "
                      "other flags)");
  command->callback([args] { RunVioCommand(*args); });
}

}  // namespace viosfm::cli
