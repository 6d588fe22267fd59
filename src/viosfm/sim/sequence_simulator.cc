#include "viosfm/sim/sequence_simulator.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <iomanip>
#include <sstream>
#include <thread>

#include "viosfm/io/euroc_writer.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/scene_structure_io.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace fs = std::filesystem;

Camera SimulationOptions::DefaultCamera() {
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kOpenCV;
  camera.width = 752;
  camera.height = 480;
  camera.params = {458.654,     457.296,    367.215,    248.375,
                   -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  return camera;
}

Rigid3d SimulationOptions::DefaultBodyFromCam() {
  // Columns: the camera's x (right), y (down), z (forward) axes in the body
  // frame (x forward, y left, z up).
  Eigen::Matrix3d body_from_cam;
  body_from_cam << 0, 0, 1,  //
      -1, 0, 0,              //
      0, -1, 0;
  return Rigid3d(body_from_cam, Eigen::Vector3d(0.05, -0.02, 0.01));
}

std::string KeyframeSelectionOptions::Validate() const {
  if (!(min_gap_s > 0.0) || !(max_gap_s >= min_gap_s)) {
    return "keyframes: need 0 < min_gap_s <= max_gap_s";
  }
  return "";
}

std::string SimulationOptions::Validate() const {
  ScenarioOptions scenario_options;
  scenario_options.name = scenario;
  scenario_options.texels_per_metre = texels_per_metre;
  if (const std::string error = scenario_options.Validate(); !error.empty()) return error;
  if (photo_texture_size < 16 || photo_texture_size > 8192 ||
      (photo_texture_size & (photo_texture_size - 1)) != 0) {
    return "photo_texture_size must be a power of two in [16, 8192]";
  }
  if (!(route_speed_mps >= 0)) return "route_speed_mps must be >= 0";
  if (num_threads < 1) return "num_threads must be >= 1";
  if (!(duration_s > 0)) return "duration_s must be > 0";
  if (!(static_start_s >= 0 && static_start_s < duration_s)) {
    return "static_start_s must be in [0, duration_s)";
  }
  if (!(camera_rate_hz > 0)) return "camera_rate_hz must be > 0";
  if (!camera.HasValidParams()) return "camera has the wrong number of parameters";
  if (const std::string error = imu.Validate(); !error.empty()) return "imu: " + error;
  if (const std::string error = vio_drift.Validate(); !error.empty()) return "vio_drift: " + error;
  if (vio_profile != "gentle" && vio_profile != "realistic") {
    return "vio_profile must be 'gentle' or 'realistic'";
  }
  if (const std::string error = realistic_vio.Validate(); !error.empty()) {
    return "realistic_vio: " + error;
  }
  if (keyframes.enabled) {
    if (const std::string error = keyframes.Validate(); !error.empty()) return error;
  }
  if (const std::string error = auto_exposure.Validate(); !error.empty())
    return "auto_exposure: " + error;
  if (!(rolling_shutter_readout_s >= 0.0 && rolling_shutter_readout_s < 1.0))
    return "rolling_shutter_readout_s must be in [0, 1)";
  if (!(std::abs(camera_time_offset_s) < 1.0)) return "camera_time_offset_s must be in (-1, 1)";
  if (!(imu_noise_file_scale_gyro > 0.0)) return "imu_noise_file_scale_gyro must be > 0";
  if (!(imu_noise_file_scale_accel > 0.0)) return "imu_noise_file_scale_accel must be > 0";
  if (const std::string error = white_walls.Validate(); !error.empty())
    return "white_walls: " + error;
  return "";
}

bool SimulationOptions::HasImperfections() const {
  return auto_exposure.enabled() || rolling_shutter_readout_s > 0.0 ||
         camera_time_offset_s != 0.0 || imu_noise_file_scale_gyro != 1.0 ||
         imu_noise_file_scale_accel != 1.0 || white_walls.enabled;
}

SimulatedSequence SimulateSequence(const SimulationOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("simulation options: " + error);
  }
  ScenarioOptions scenario_options;
  scenario_options.name = options.scenario;
  // Without images the textures are never sampled: build the geometry only.
  scenario_options.texels_per_metre = options.render_images ? options.texels_per_metre : 8.0;
  scenario_options.seed = options.seed;
  if (options.render_images && !options.texture_folder.empty()) {
    scenario_options.photos = std::make_shared<const std::vector<Texture>>(
        LoadPhotoTextures(options.texture_folder, options.photo_texture_size));
  }
  ScenarioMotionOptions motion;
  motion.duration_s = options.duration_s;
  motion.static_start_s = options.static_start_s;
  motion.speed_mps = options.route_speed_mps;
  motion.walk = options.walk;
  motion.start_ns = options.walk.start_ns;
  motion.seed = options.seed * 3 + 0;
  ImuSynthesisOptions imu_options = options.imu;
  imu_options.seed = options.seed * 3 + 1;
  VioDriftOptions drift = options.vio_drift;
  drift.seed = options.seed * 3 + 2;

  SimulatedSequence out;
  auto scenario = std::make_shared<Scenario>(MakeScenario(scenario_options));
  if (options.scenario == "room") {
    // The room keeps WalkOptions' own box.
    scenario->walk_box_min = options.walk.box_min;
    scenario->walk_box_max = options.walk.box_max;
  }
  if (options.white_walls.enabled) {
    PaintWallsWhite(scenario.get(), options.white_walls, MixSeed(options.seed, 0x5768697465ULL));
  }
  if (imu_options.vibration.accel_rms_mps2 == 0.0 && scenario->vibration.accel_rms_mps2 > 0.0) {
    imu_options.vibration = scenario->vibration;
    imu_options.vibration.seed = MixSeed(options.seed, 0x5649425241ULL);
    imu_options.vibration.start_s = options.static_start_s;  // motors off before take-off
  }
  out.motion = GenerateScenarioMotion(*scenario, motion);
  out.scenario = scenario;
  const timestamp_ns_t start = out.motion.start_ns();
  const timestamp_ns_t end = start + SecondsToNs(options.duration_s);

  Sequence& sequence = out.sequence;
  sequence.rig.camera = options.camera;
  sequence.rig.body_from_cam = options.body_from_cam;
  sequence.rig.camera_rate_hz = options.camera_rate_hz;
  out.true_imu_noise = imu_options.noise;
  sequence.rig.imu_noise = ScaledImuNoise(imu_options.noise, options.imu_noise_file_scale_gyro,
                                          options.imu_noise_file_scale_accel);
  out.camera_time_offset_ns = SecondsToNs(options.camera_time_offset_s);
  const SynthesizedImu imu = SynthesizeImu(out.motion, start, end, imu_options);
  sequence.imu = imu.samples;

  const double period_ns = 1e9 / options.camera_rate_hz;
  std::vector<timestamp_ns_t> grid;  // every frame of the camera rate
  for (int64_t k = 0;; ++k) {
    const timestamp_ns_t t = start + static_cast<timestamp_ns_t>(std::llround(k * period_ns));
    if (t > end) break;
    grid.push_back(t);
  }
  // The frames: the whole grid, or keyframe-like irregular gaps on it.
  std::vector<size_t> frames;
  if (options.keyframes.enabled) {
    Random random(options.seed * 3 + 2 + 1000);
    const double log_min = std::log(options.keyframes.min_gap_s);
    const double log_max = std::log(options.keyframes.max_gap_s);
    for (size_t k = 0; k < grid.size();) {
      frames.push_back(k);
      const double gap_s = std::exp(random.Uniform(log_min, log_max));
      k += std::max<size_t>(1, static_cast<size_t>(std::llround(gap_s * 1e9 / period_ns)));
    }
  } else {
    for (size_t k = 0; k < grid.size(); ++k) frames.push_back(k);
  }
  for (size_t k = 0; k < grid.size(); ++k) {
    const timestamp_ns_t t = grid[k];
    GroundTruthState state;
    state.timestamp_ns = t;
    state.world_from_body = out.motion.WorldFromBody(t);
    state.velocity_in_world = out.motion.VelocityInWorld(t);
    state.gyro_bias = imu.GyroBiasAt(t);
    state.accel_bias = imu.AccelBiasAt(t);
    state.has_velocity_and_biases = true;
    sequence.ground_truth.push_back(state);
  }
  // The images, stamped camera_time_offset_ns after their true (IMU-clock)
  // exposure times.
  std::vector<timestamp_ns_t> image_true_times;
  for (const size_t k : frames) {
    const timestamp_ns_t t = grid[k];
    image_true_times.push_back(t);
    const timestamp_ns_t stamp = t + out.camera_time_offset_ns;
    std::ostringstream name;
    name << stamp << ".png";
    sequence.images.push_back({stamp, fs::path(name.str())});
    out.frame_regions.push_back(
        out.scenario->RegionIndex(ProjectionCenter(SimulatedCamFromWorld(out, t))));
  }
  const Trajectory truth = out.motion.Sample(grid);
  if (options.vio_profile == "realistic") {
    RealisticVioOptions realistic = options.realistic_vio;
    realistic.seed = options.seed * 3 + 2;
    EmulatedVio emulated = EmulateRealisticVio(truth, realistic);
    out.vio_body = std::move(emulated.world_from_frame);
    out.vio_segments = std::move(emulated.segments);
  } else {
    out.vio_body = EmulateVioDrift(truth, drift);
    out.vio_segments.assign(out.vio_body.size(), 0);
  }
  out.exposure_gains =
      AutoExposureGains(image_true_times, options.auto_exposure, MixSeed(options.seed, 0x4145ULL));
  return out;
}

Rigid3d SimulatedCamFromWorld(const SimulatedSequence& simulated, timestamp_ns_t t) {
  return (simulated.motion.WorldFromBody(t) * simulated.sequence.rig.body_from_cam).Inverse();
}

GreyImage RenderSimulatedFrame(const SimulatedSequence& simulated, const RayTable& rays,
                               size_t frame_index, const SimulationOptions& options,
                               int num_threads) {
  VIOSFM_CHECK(simulated.scenario != nullptr);
  VIOSFM_CHECK_LT(frame_index, simulated.sequence.images.size());
  RenderOptions render = simulated.scenario->render;
  render.seed = MixSeed(options.seed, frame_index);
  render.num_threads = num_threads;
  if (!simulated.exposure_gains.empty())
    render.exposure_gain *= simulated.exposure_gains[frame_index];
  const double exposure_s = options.exposure_time_s >= 0.0 ? options.exposure_time_s
                                                           : simulated.scenario->exposure_time_s;
  const timestamp_ns_t t = simulated.FrameTime(frame_index);
  const timestamp_ns_t half = SecondsToNs(0.5 * exposure_s);
  const auto pose_at = [&](timestamp_ns_t time) {
    return SimulatedCamFromWorld(
        simulated, std::clamp(time, simulated.motion.start_ns(), simulated.motion.end_ns()));
  };
  if (options.rolling_shutter_readout_s > 0.0) {
    const int height = rays.height();
    std::vector<Rigid3d> open(height);
    std::vector<Rigid3d> close;
    if (exposure_s > 0.0) close.resize(height);
    for (int y = 0; y < height; ++y) {
      const timestamp_ns_t row_t =
          RollingShutterRowTime(t, y, height, options.rolling_shutter_readout_s);
      if (exposure_s > 0.0) {
        open[y] = pose_at(row_t - half);
        close[y] = pose_at(row_t + half);
      } else {
        open[y] = pose_at(row_t);
      }
    }
    return RenderRowByRow(simulated.scenario->scene, rays, open, close, render);
  }
  if (exposure_s <= 0.0)
    return Render(simulated.scenario->scene, rays, SimulatedCamFromWorld(simulated, t), render);
  const timestamp_ns_t open = std::max(simulated.motion.start_ns(), t - half);
  const timestamp_ns_t close = std::min(simulated.motion.end_ns(), t + half);
  return RenderWithMotionBlur(simulated.scenario->scene, rays,
                              SimulatedCamFromWorld(simulated, open),
                              SimulatedCamFromWorld(simulated, close), render);
}

void RenderSimulatedImages(const fs::path& folder, const SimulatedSequence& simulated,
                           const SimulationOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  fs::create_directories(folder);
  const RayTable rays(simulated.sequence.rig.camera);
  const std::vector<SequenceImage>& images = simulated.sequence.images;
  ProgressBar progress("rendering " + simulated.scenario->name,
                       static_cast<int64_t>(images.size()));
  const auto render_and_write = [&](size_t k, int row_threads) {
    WriteGreyPng(folder / images[k].path.filename(),
                 RenderSimulatedFrame(simulated, rays, k, options, row_threads));
    progress.Update();
  };
  const int workers = options.threads_over_frames
                          ? std::min<int>(options.num_threads, static_cast<int>(images.size()))
                          : 1;
  if (workers <= 1) {
    for (size_t k = 0; k < images.size(); ++k) render_and_write(k, options.num_threads);
  } else {
    std::atomic<size_t> next{0};
    std::vector<std::exception_ptr> errors(workers);
    std::vector<std::thread> threads;
    for (int w = 0; w < workers; ++w) {
      threads.emplace_back([&, w]() {
        try {
          for (size_t k = next++; k < images.size(); k = next++) render_and_write(k, 1);
        } catch (...) {
          errors[w] = std::current_exception();
          next = images.size();  // the others stop early
        }
      });
    }
    for (std::thread& thread : threads) thread.join();
    for (const std::exception_ptr& error : errors) {
      if (error) std::rethrow_exception(error);
    }
  }
  progress.Finish();
}

namespace {

// frames.csv: each frame's region, floor and camera centre.
void WriteFrameRegions(const fs::path& path, const SimulatedSequence& simulated) {
  WriteFileAtomically(path, [&](std::ostream& stream) {
    stream << "#timestamp [ns],region,floor,p_cam_x [m],p_cam_y [m],p_cam_z [m]\n"
           << std::setprecision(17);
    const auto& regions = simulated.scenario->regions;
    for (size_t k = 0; k < simulated.sequence.images.size(); ++k) {
      const timestamp_ns_t t = simulated.sequence.images[k].timestamp_ns;
      const int region = simulated.frame_regions[k];
      const Eigen::Vector3d center =
          ProjectionCenter(SimulatedCamFromWorld(simulated, simulated.FrameTime(k)));
      stream << t << ',' << (region >= 0 ? regions[region].name : "none") << ','
             << (region >= 0 ? regions[region].floor : -1) << ',' << center.x() << ',' << center.y()
             << ',' << center.z() << '\n';
    }
  });
}

// simulation.yaml's robustness section: the imperfections the sequence
// was made with.
void WriteRobustnessYaml(std::ostream& stream, const SimulatedSequence& simulated,
                         const SimulationOptions& options) {
  const AutoExposureOptions& ae = options.auto_exposure;
  const ImuNoise& truth = simulated.true_imu_noise;
  stream << "robustness:\n"
         << "  auto_exposure:\n"
         << "    strength_stops: " << ae.strength_stops << "\n"
         << "    drift_stddev: " << ae.drift_stddev << "\n"
         << "    drift_time_constant_s: " << ae.drift_time_constant_s << "\n"
         << "    step_rate_hz: " << ae.step_rate_hz << "\n"
         << "    step_size: " << ae.step_size << "\n"
         << "    recovery_time_constant_s: " << ae.recovery_time_constant_s << "\n"
         << "  rolling_shutter_readout_s: " << options.rolling_shutter_readout_s << "\n"
         << "  camera_time_offset_s: " << options.camera_time_offset_s << "\n"
         << "  imu_noise_file_scale_gyro: " << options.imu_noise_file_scale_gyro << "\n"
         << "  imu_noise_file_scale_accel: " << options.imu_noise_file_scale_accel << "\n"
         << "  true_imu_noise: [" << truth.gyro_noise_density << ", " << truth.gyro_random_walk
         << ", " << truth.accel_noise_density << ", " << truth.accel_random_walk
         << "]  # gyro density, gyro walk, accel density, accel walk\n"
         << "  white_walls:\n"
         << "    enabled: " << (options.white_walls.enabled ? "true" : "false") << "\n"
         << "    mean: " << options.white_walls.mean << "\n"
         << "    contrast: " << options.white_walls.contrast << "\n"
         << "    texels_per_metre: " << options.white_walls.texels_per_metre << "\n";
}

// simulation.yaml: the options of the sequence.
void WriteSimulationYaml(const fs::path& path, const SimulatedSequence& simulated,
                         const SimulationOptions& options) {
  // The walk and the vibration the scenario used (mav replaces the walk's).
  const WalkOptions& walk =
      simulated.scenario->walk_style ? *simulated.scenario->walk_style : options.walk;
  const double vibration_rms = options.imu.vibration.accel_rms_mps2 > 0.0
                                   ? options.imu.vibration.accel_rms_mps2
                                   : simulated.scenario->vibration.accel_rms_mps2;
  WriteFileAtomically(path, [&](std::ostream& stream) {
    stream << std::setprecision(17) << "# viosfm simulate: the options of this sequence\n"
           << "scenario: " << options.scenario << "\n"
           << "duration_s: " << options.duration_s << "\n"
           << "static_start_s: " << options.static_start_s << "\n"
           << "camera_rate_hz: " << options.camera_rate_hz << "\n"
           << "seed: " << options.seed << "\n"
           << "route_speed_mps: " << options.route_speed_mps << "\n"
           << "texels_per_metre: " << options.texels_per_metre << "\n"
           << "texture_folder: \"" << options.texture_folder << "\"\n"
           << "photo_texture_size: " << options.photo_texture_size << "\n"
           << "render_images: " << (options.render_images ? "true" : "false") << "\n"
           << "exposure_time_s: "
           << (options.exposure_time_s >= 0.0 ? options.exposure_time_s
                                              : simulated.scenario->exposure_time_s)
           << "\n"
           << "walk:\n"
           << "  speed_mps: " << walk.speed_mps << "\n"
           << "  knot_spacing_s: " << walk.knot_spacing_s << "\n"
           << "  turn_stddev_rad: " << walk.turn_stddev_rad << "\n"
           << "  look_around_rad: " << walk.look_around_rad << "\n"
           << "imu:\n"
           << "  add_noise: " << (options.imu.add_noise ? "true" : "false") << "\n";
    if (vibration_rms > 0.0) stream << "  accel_vibration_rms_mps2: " << vibration_rms << "\n";
    stream << "vio_drift:\n"
           << "  position_walk_m_per_sqrt_m: " << options.vio_drift.position_walk_m_per_sqrt_m
           << "\n"
           << "  yaw_walk_rad_per_sqrt_m: " << options.vio_drift.yaw_walk_rad_per_sqrt_m << "\n"
           << "  scale_error: " << options.vio_drift.scale_error << "\n"
           << "  position_jitter_m: " << options.vio_drift.position_jitter_m << "\n"
           << "  rotation_jitter_rad: " << options.vio_drift.rotation_jitter_rad << "\n"
           << "vio_profile: " << options.vio_profile << "\n"
           << "realistic_vio:\n"
           << "  scale_error: " << options.realistic_vio.scale_error << "\n"
           << "  reinit_gap_s: " << options.realistic_vio.reinit_gap_s << "\n"
           << "  reinit_times_s: [";
    for (size_t i = 0; i < options.realistic_vio.reinit_times_s.size(); ++i) {
      stream << (i > 0 ? ", " : "") << options.realistic_vio.reinit_times_s[i];
    }
    stream << "]\n";
    for (const auto& [key, value] : options.realistic_vio.model.ToKeyValues()) {
      stream << "  " << key << ": " << value << "\n";
    }
    stream << "keyframes:\n"
           << "  enabled: " << (options.keyframes.enabled ? "true" : "false") << "\n"
           << "  min_gap_s: " << options.keyframes.min_gap_s << "\n"
           << "  max_gap_s: " << options.keyframes.max_gap_s << "\n";
    if (options.HasImperfections()) WriteRobustnessYaml(stream, simulated, options);
  });
}

// exposure.csv: each frame's auto-exposure gain.
void WriteExposureGains(const fs::path& path, const SimulatedSequence& simulated) {
  WriteFileAtomically(path, [&](std::ostream& stream) {
    stream << "#timestamp [ns],gain\n" << std::setprecision(17);
    for (size_t k = 0; k < simulated.sequence.images.size(); ++k) {
      stream << simulated.sequence.images[k].timestamp_ns << ',' << simulated.exposure_gains[k]
             << '\n';
    }
  });
}

}  // namespace

void WriteSimulatedSequence(const fs::path& out, const SimulatedSequence& simulated,
                            const SimulationOptions& options) {
  const fs::path cam0 = out / "mav0" / "cam0";
  if (options.render_images) {
    RenderSimulatedImages(cam0 / "data", simulated, options);
    WriteEurocDataset(out, simulated.sequence);  // lists the images in cam0/data.csv
  } else {
    Sequence without_images = simulated.sequence;
    without_images.images.clear();
    WriteEurocDataset(out, without_images);
  }
  fs::create_directories(cam0);
  WriteEurocCameraYaml(cam0 / "sensor.yaml", simulated.sequence.rig.camera,
                       simulated.sequence.rig.body_from_cam, simulated.sequence.rig.camera_rate_hz);
  WriteFrameRegions(out / "frames.csv", simulated);
  WriteFileAtomically(out / "camera_stamps.txt", [&](std::ostream& stream) {
    stream << "# camera timestamps [ns], one per line\n";
    for (const SequenceImage& image : simulated.sequence.images)
      stream << image.timestamp_ns << '\n';
  });
  WriteTumTrajectory(out / "vio_emulated.tum", simulated.vio_body);
  WriteSceneStructure(out / "scene.csv", ScenarioStructure(*simulated.scenario));
  WriteSimulationYaml(out / "simulation.yaml", simulated, options);
  if (options.auto_exposure.enabled()) WriteExposureGains(out / "exposure.csv", simulated);
}

}  // namespace viosfm
