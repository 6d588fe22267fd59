#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "viosfm/cli/commands.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/sim/vio_emulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm::cli {
namespace {

struct EmulateVioArgs {
  std::string ground_truth;
  std::string format;  // empty: guess
  std::string out;
  double rate_hz = 20.0;
  uint64_t seed = 0;
  double drift_factor = 1.0;
  double scale_error = std::numeric_limits<double>::quiet_NaN();  // NaN: the model's 0.02
  std::vector<double> reinit_times_s;
  double reinit_gap_s = 1.0;
};

void RunEmulateVio(const EmulateVioArgs& args) {
  const TrajectoryFormat format = args.format.empty() ? GuessTrajectoryFormat(args.ground_truth)
                                                      : ParseTrajectoryFormat(args.format);
  if (format == TrajectoryFormat::kColmap) {
    throw InputError(args.ground_truth, 0, "a COLMAP model is not a trajectory with stamps");
  }
  const Trajectory truth = ReadTrajectory(args.ground_truth, format);
  if (!truth.has_timestamps) {
    throw InputError(args.ground_truth, 0,
                     "has no timestamps (KITTI); the VIO's drift grows with time");
  }
  if (truth.size() < 2) {
    throw InputError(args.ground_truth, 0,
                     "needs at least 2 poses, has " + std::to_string(truth.size()));
  }
  for (size_t k = 1; k < truth.size(); ++k) {
    if (truth.poses[k].timestamp_ns <= truth.poses[k - 1].timestamp_ns) {
      throw InputError(args.ground_truth, 0,
                       "pose " + std::to_string(k + 1) +
                           ": stamps must increase (two poses at the same time or out of order)");
    }
  }
  if (!(args.rate_hz > 0.0) || !std::isfinite(args.rate_hz)) {
    throw InputError("--rate must be > 0");
  }
  RealisticVioOptions options = RealisticVioOptions().Scaled(args.drift_factor);
  if (!std::isnan(args.scale_error)) options.scale_error = args.scale_error;
  options.reinit_times_s = args.reinit_times_s;
  options.reinit_gap_s = args.reinit_gap_s;
  options.seed = args.seed;
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("emulated VIO: " + error);
  }
  const EmulatedVio vio = EmulateRealisticVioOnGrid(truth, options, args.rate_hz);
  WriteTumTrajectory(args.out, vio.world_from_frame);
  const Eigen::Vector3d end_error = vio.world_from_frame.poses.back().world_from_frame.translation -
                                    truth.poses.back().world_from_frame.translation;
  VIOSFM_LOG(INFO) << "emulated VIO of " << truth.size() << " poses over "
                   << 1e-9 * static_cast<double>(truth.poses.back().timestamp_ns -
                                                 truth.poses.front().timestamp_ns)
                   << " s: " << vio.world_from_frame.size() << " poses at " << args.rate_hz
                   << " Hz or more, " << (vio.segments.empty() ? 0 : vio.segments.back() + 1)
                   << " segment(s), end drift " << end_error.norm() << " m (scale error "
                   << options.scale_error << ", seed " << args.seed << ") -> " << args.out;
}

}  // namespace

void RegisterEmulateVio(CLI::App& app) {
  auto args = std::make_shared<EmulateVioArgs>();
  CLI::App* command = app.add_subcommand(
      "emulate-vio",
      "Emulate a drifting VIO on a ground-truth trajectory. Of any spacing (the photos of a "
      "survey, keyframes): the simulator's realistic VIO (drift in time, distance and "
      "rotation, scale error, correlated noise, optional re-initialisations; the VIO "
      "uncertainty model's defaults) on a grid through every ground-truth stamp, written as "
      "a TUM trajectory for `viosfm run --vio-trajectory`");
  command->add_option("ground_truth", args->ground_truth, "Ground-truth trajectory with stamps")
      ->required();
  command->add_option("--format", args->format, "Its format: tum, euroc or kitti (default: guess)")
      ->check(CLI::IsMember({"tum", "euroc", "kitti"}, CLI::ignore_case));
  command->add_option("--out", args->out, "TUM trajectory to write (replaced atomically)")
      ->required();
  command
      ->add_option("--rate", args->rate_hz,
                   "Hz, the VIO's output rate (at least; the grid passes through every "
                   "ground-truth stamp)")
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Seed of the drift")->capture_default_str();
  command
      ->add_option("--vio-drift", args->drift_factor,
                   "Multiplier of the drift and noise (0: perfect VIO)")
      ->capture_default_str();
  command->add_option("--vio-scale-error", args->scale_error,
                      "Metric scale error (0.02: displacements 2 % too long); default 0.02 "
                      "times --vio-drift");
  command
      ->add_option("--vio-reinit-at", args->reinit_times_s,
                   "Seconds after the start at which it loses track and re-initialises in a "
                   "new world frame (comma-separated)")
      ->delimiter(',');
  command
      ->add_option("--vio-reinit-gap", args->reinit_gap_s,
                   "Seconds without a pose at each re-initialisation")
      ->capture_default_str();
  command->callback([args] { RunEmulateVio(*args); });
}

}  // namespace viosfm::cli
