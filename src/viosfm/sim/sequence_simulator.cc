#include "viosfm/sim/sequence_simulator.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "viosfm/io/euroc_writer.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace fs = std::filesystem;

Camera SimulationOptions::DefaultCamera() {
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kOpenCV;
  camera.width = 752;
  camera.height = 480;
  camera.params = {458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359,
                   1.76187114e-05};
  return camera;
}

Rigid3d SimulationOptions::DefaultBodyFromCam() {
  // Columns: the camera's x (right), y (down), z (forward) axes in the body
  // frame (x forward, y left, z up).
  Eigen::Matrix3d body_from_cam;
  body_from_cam << 0, 0, 1,   //
      -1, 0, 0,               //
      0, -1, 0;
  return Rigid3d(body_from_cam, Eigen::Vector3d(0.05, -0.02, 0.01));
}

std::vector<std::string> AvailableScenarios() { return {"room"}; }

std::string SimulationOptions::Validate() const {
  const auto scenarios = AvailableScenarios();
  if (std::find(scenarios.begin(), scenarios.end(), scenario) == scenarios.end()) {
    std::string list;
    for (const auto& name : scenarios) list += (list.empty() ? "" : ", ") + name;
    return "scenario '" + scenario + "' is unknown (available: " + list + ")";
  }
  if (!(duration_s > 0)) return "duration_s must be > 0";
  if (!(static_start_s >= 0 && static_start_s < duration_s)) {
    return "static_start_s must be in [0, duration_s)";
  }
  if (!(camera_rate_hz > 0)) return "camera_rate_hz must be > 0";
  if (!camera.HasValidParams()) return "camera has the wrong number of parameters";
  if (const std::string error = imu.Validate(); !error.empty()) return "imu: " + error;
  if (const std::string error = vio_drift.Validate(); !error.empty()) return "vio_drift: " + error;
  return "";
}

SimulatedSequence SimulateSequence(const SimulationOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("simulation options: " + error);
  }
  WalkOptions walk = options.walk;
  walk.duration_s = options.duration_s;
  walk.static_start_s = options.static_start_s;
  walk.seed = options.seed * 3 + 0;
  ImuSynthesisOptions imu_options = options.imu;
  imu_options.seed = options.seed * 3 + 1;
  VioDriftOptions drift = options.vio_drift;
  drift.seed = options.seed * 3 + 2;

  SimulatedSequence out;
  out.motion = GenerateWalk(walk);
  const timestamp_ns_t start = out.motion.start_ns();
  const timestamp_ns_t end = start + SecondsToNs(options.duration_s);

  Sequence& sequence = out.sequence;
  sequence.rig.camera = options.camera;
  sequence.rig.body_from_cam = options.body_from_cam;
  sequence.rig.camera_rate_hz = options.camera_rate_hz;
  sequence.rig.imu_noise = imu_options.noise;
  const SynthesizedImu imu = SynthesizeImu(out.motion, start, end, imu_options);
  sequence.imu = imu.samples;

  const double period_ns = 1e9 / options.camera_rate_hz;
  std::vector<timestamp_ns_t> stamps;
  for (int64_t k = 0;; ++k) {
    const timestamp_ns_t t = start + static_cast<timestamp_ns_t>(std::llround(k * period_ns));
    if (t > end) break;
    stamps.push_back(t);
    std::ostringstream name;
    name << t << ".png";
    sequence.images.push_back({t, fs::path(name.str())});
    GroundTruthState state;
    state.timestamp_ns = t;
    state.world_from_body = out.motion.WorldFromBody(t);
    state.velocity_in_world = out.motion.VelocityInWorld(t);
    state.gyro_bias = imu.GyroBiasAt(t);
    state.accel_bias = imu.AccelBiasAt(t);
    state.has_velocity_and_biases = true;
    sequence.ground_truth.push_back(state);
  }
  out.vio_body = EmulateVioDrift(out.motion.Sample(stamps), drift);
  return out;
}

void WriteSimulatedSequence(const fs::path& out, const SimulatedSequence& simulated,
                            const SimulationOptions& options) {
  Sequence without_images = simulated.sequence;
  without_images.images.clear();  // no rendered image files yet
  WriteEurocDataset(out, without_images);
  const fs::path cam0 = out / "mav0" / "cam0";
  fs::create_directories(cam0);
  WriteEurocCameraYaml(cam0 / "sensor.yaml", simulated.sequence.rig.camera,
                       simulated.sequence.rig.body_from_cam, simulated.sequence.rig.camera_rate_hz);
  WriteFileAtomically(out / "camera_stamps.txt", [&](std::ostream& stream) {
    stream << "# camera timestamps [ns], one per line\n";
    for (const SequenceImage& image : simulated.sequence.images) stream << image.timestamp_ns << '\n';
  });
  WriteTumTrajectory(out / "vio_emulated.tum", simulated.vio_body);
  WriteFileAtomically(out / "simulation.yaml", [&](std::ostream& stream) {
    stream << std::setprecision(17) << "# viosfm simulate: the options of this sequence\n"
           << "scenario: " << options.scenario << "\n"
           << "duration_s: " << options.duration_s << "\n"
           << "static_start_s: " << options.static_start_s << "\n"
           << "camera_rate_hz: " << options.camera_rate_hz << "\n"
           << "seed: " << options.seed << "\n"
           << "walk:\n"
           << "  speed_mps: " << options.walk.speed_mps << "\n"
           << "  knot_spacing_s: " << options.walk.knot_spacing_s << "\n"
           << "  turn_stddev_rad: " << options.walk.turn_stddev_rad << "\n"
           << "  look_around_rad: " << options.walk.look_around_rad << "\n"
           << "imu:\n"
           << "  add_noise: " << (options.imu.add_noise ? "true" : "false") << "\n"
           << "vio_drift:\n"
           << "  position_walk_m_per_sqrt_m: " << options.vio_drift.position_walk_m_per_sqrt_m << "\n"
           << "  yaw_walk_rad_per_sqrt_m: " << options.vio_drift.yaw_walk_rad_per_sqrt_m << "\n"
           << "  scale_error: " << options.vio_drift.scale_error << "\n"
           << "  position_jitter_m: " << options.vio_drift.position_jitter_m << "\n"
           << "  rotation_jitter_rad: " << options.vio_drift.rotation_jitter_rad << "\n";
  });
}

}  // namespace viosfm
