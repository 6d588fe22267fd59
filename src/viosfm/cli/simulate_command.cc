#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include "viosfm/cli/commands.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/timer.h"

namespace viosfm::cli {
namespace {

struct SimulateArgs {
  SimulationOptions options;
  std::string out;
  double drift_factor = 1.0;
  double scale_error = std::numeric_limits<double>::quiet_NaN();  // NaN: the profile's
  bool no_imu_noise = false;
  bool no_images = false;
  bool row_parallel = false;
  std::vector<double> imu_noise_file_scale;  // gyro, accel factors
};

void RunSimulate(const SimulateArgs& args) {
  SimulationOptions options = args.options;
  options.vio_drift = options.vio_drift.Scaled(args.drift_factor);
  options.realistic_vio = options.realistic_vio.Scaled(args.drift_factor);
  if (!std::isnan(args.scale_error)) {
    options.vio_drift.scale_error = args.scale_error;
    options.realistic_vio.scale_error = args.scale_error;
  }
  options.imu.add_noise = !args.no_imu_noise;
  options.render_images = !args.no_images;
  options.threads_over_frames = !args.row_parallel;
  options.num_threads = CapNumThreads(options.num_threads, "--threads");
  if (!args.imu_noise_file_scale.empty()) {
    options.imu_noise_file_scale_gyro = args.imu_noise_file_scale[0];
    options.imu_noise_file_scale_accel = args.imu_noise_file_scale[1];
  }
  Timer timer;
  const SimulatedSequence simulated = SimulateSequence(options);
  const double setup_seconds = timer.ElapsedSeconds();
  WriteFolderAtomically(args.out, [&](const std::filesystem::path& folder) {
    WriteSimulatedSequence(folder, simulated, options);
  });
  const Sequence& sequence = simulated.sequence;
  if (options.render_images) {
    const double write_seconds = timer.ElapsedSeconds() - setup_seconds;
    VIOSFM_LOG(INFO) << "scene and motion in " << setup_seconds << " s; rendered and wrote "
                     << sequence.images.size() << " images in " << write_seconds << " s ("
                     << sequence.images.size() / std::max(write_seconds, 1e-9) << " frames/s, "
                     << options.num_threads << " thread(s))";
  }
  const double length = simulated.motion.PathLength(sequence.images.front().timestamp_ns,
                                                    sequence.images.back().timestamp_ns);
  const double vio_end_error = (simulated.vio_body.poses.back().world_from_frame.translation -
                                sequence.ground_truth.back().world_from_body.translation)
                                   .norm();
  const int num_segments = simulated.vio_segments.empty() ? 0 : simulated.vio_segments.back() + 1;
  VIOSFM_LOG(INFO) << "simulated '" << options.scenario << "': " << sequence.images.size()
                   << (options.keyframes.enabled ? " keyframes" : " camera stamps") << ", "
                   << sequence.imu.size() << " IMU samples, path " << length << " m -> " << args.out
                   << LogDetails() << "; " << options.vio_profile << " emulated VIO ("
                   << simulated.vio_body.size() << " poses, " << num_segments
                   << " segment(s)), end drift " << vio_end_error << " m, in "
                   << timer.ElapsedSeconds() << " s";
}

}  // namespace

void RegisterSimulate(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* command = app.add_subcommand(
      "simulate",
      "Simulate a visual-inertial sequence with exact ground truth. A EuRoC folder: rendered "
      "images, motion, IMU, ground-truth state, per-frame scene regions and an emulated "
      "drifting VIO trajectory");
  command->add_option("--out", args->out, "Output folder (replaced atomically)")->required();
  command
      ->add_option("--scenario", args->options.scenario,
                   "Scene and motion preset: room, two_floors, corridor, dark or mav")
      ->capture_default_str();
  command->add_option("--duration", args->options.duration_s, "Length in seconds")
      ->capture_default_str();
  command
      ->add_option("--static-start", args->options.static_start_s,
                   "Motionless seconds at the start")
      ->capture_default_str();
  command->add_option("--rate", args->options.camera_rate_hz, "Camera rate in Hz")
      ->capture_default_str();
  command->add_option("--seed", args->options.seed, "Seed of every random stream")
      ->capture_default_str();
  command
      ->add_option("--vio-drift", args->drift_factor,
                   "Multiplier of the emulated VIO's drift and noise (0: perfect VIO)")
      ->capture_default_str();
  command->add_option("--vio-scale-error", args->scale_error,
                      "Metric scale error of the emulated VIO (0.02: its displacements 2 % too "
                      "long); default: the profile's (gentle 0, realistic 0.02)");
  command
      ->add_option("--vio-profile", args->options.vio_profile,
                   "Emulated VIO: gentle (distance random walks and white jitter) or realistic "
                   "(drift in time, distance and rotation, scale error, correlated noise, "
                   "optional re-initialisations; the VIO uncertainty model's defaults)")
      ->capture_default_str();
  command
      ->add_option("--vio-reinit-at", args->options.realistic_vio.reinit_times_s,
                   "Realistic VIO: seconds after the start at which it loses track and "
                   "re-initialises in a new world frame (comma-separated)")
      ->delimiter(',');
  command
      ->add_option("--vio-reinit-gap", args->options.realistic_vio.reinit_gap_s,
                   "Realistic VIO: seconds without a pose at each re-initialisation (0: a jump "
                   "with no gap in the stamps)")
      ->capture_default_str();
  command->add_flag("--keyframes", args->options.keyframes.enabled,
                    "Keyframe-like frames: irregular gaps (log-uniform in [--keyframe-min-gap, "
                    "--keyframe-max-gap]) on the camera-rate grid; ground truth and VIO stay on "
                    "the grid");
  command
      ->add_option("--keyframe-min-gap", args->options.keyframes.min_gap_s,
                   "Shortest keyframe gap in seconds")
      ->capture_default_str();
  command
      ->add_option("--keyframe-max-gap", args->options.keyframes.max_gap_s,
                   "Longest keyframe gap in seconds")
      ->capture_default_str();
  command->add_flag("--no-imu-noise", args->no_imu_noise, "Exact IMU measurements");
  command
      ->add_option("--speed", args->options.route_speed_mps,
                   "Walking speed in m/s on route scenarios (two_floors, corridor, dark); 0 "
                   "fits the whole route into the duration")
      ->capture_default_str();
  command
      ->add_option("--texels-per-metre", args->options.texels_per_metre,
                   "Texture resolution of the textured surfaces")
      ->capture_default_str();
  command
      ->add_option("--exposure-time", args->options.exposure_time_s,
                   "Shutter time in s for motion blur (negative: the scenario's own, dark "
                   "0.02 s, others 0 = sharp)")
      ->capture_default_str();
  command
      ->add_option("--texture-folder", args->options.texture_folder,
                   "Folder of photos (.png/.jpg/...) textured onto the scene instead of the "
                   "procedural textures, in file-name order (default: procedural)")
      ->check(CLI::ExistingDirectory);
  command
      ->add_option("--photo-texture-size", args->options.photo_texture_size,
                   "Side in texels (a power of two) each photo is resampled to")
      ->capture_default_str();
  command->add_flag("--no-images", args->no_images,
                    "Write motion, IMU and ground truth only (no rendering)");
  command->add_option("--threads", args->options.num_threads, "Rendering threads")
      ->capture_default_str();
  command->add_flag("--row-parallel", args->row_parallel,
                    "Render one frame at a time with its rows split over the threads (default: "
                    "frames in parallel)");
  // Robustness cases (sim/robustness.h, docs/simulator.md).
  command
      ->add_option("--auto-exposure", args->options.auto_exposure.strength_stops,
                   "Auto-exposure changes: per-frame gain 2^(STOPS * (drift + steps)), a smooth "
                   "drift of about +-0.5 STOPS and sudden steps of 0.5-1 STOPS every 5 s on "
                   "average that recover in about 1 s (0: off)")
      ->capture_default_str();
  command
      ->add_option("--rolling-shutter-readout", args->options.rolling_shutter_readout_s,
                   "Rolling shutter: rows exposed top to bottom over this many seconds, the "
                   "middle row at the stamp (0: global shutter)")
      ->capture_default_str();
  command
      ->add_option("--camera-time-offset", args->options.camera_time_offset_s,
                   "Image stamps minus true exposure times in s (0.047: images stamped 47 ms "
                   "late); the calibration does not state it")
      ->capture_default_str();
  command
      ->add_option("--imu-noise-file-scale", args->imu_noise_file_scale,
                   "GYRO,ACCEL: factors on the IMU noise figures written to imu0/sensor.yaml "
                   "against the simulated noise (a wrong calibration; default 1,1)")
      ->delimiter(',')
      ->expected(2);
  command->add_flag("--white-walls", args->options.white_walls.enabled,
                    "Repaint the outer walls and ceiling nearly uniform white");
  command
      ->add_option("--white-wall-contrast", args->options.white_walls.contrast,
                   "Peak-to-peak texture contrast of the white walls (1 = 255 grey levels)")
      ->capture_default_str();
  command->callback([args] { RunSimulate(*args); });
}

}  // namespace viosfm::cli
