// A simulated visual-inertial sequence with exact ground truth: a scenario's
// scene and body motion, rendered camera images, IMU at 200 Hz with noise and
// bias random walks, ground-truth state at the camera stamps, the region of
// the floor plan of every frame, and an emulated (drifting) VIO trajectory,
// written in the EuRoC ASL layout so every reader and stage can consume it.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "viosfm/scene/sequence.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/robustness.h"
#include "viosfm/sim/scenarios.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/sim/vio_emulator.h"

namespace viosfm {

// Keyframe-like frame selection: instead of every frame of the camera-rate
// grid, frames with irregular gaps, as a keyframe-based VIO or a user's
// selection leaves them (as 100 keyframes of EuRoC V1_01's 144 s with gaps
// of 0.05-7 s). The gaps are drawn
// log-uniformly in [min_gap_s, max_gap_s] (mean (max - min) / ln(max / min),
// 1.4 s for the defaults, as 100 keyframes in 144 s) and rounded to the
// grid; ground truth and the emulated VIO stay on the dense grid (a VIO
// outputs a pose per camera frame).
struct KeyframeSelectionOptions {
  bool enabled = false;
  double min_gap_s = 0.05;       // s. Default 0.05
  double max_gap_s = 7.0;        // s. Default 7
  std::string Validate() const;  // empty if valid, else names the bad field
};

struct SimulationOptions {
  std::string scenario = "room";  // scene and motion preset (see AvailableScenarios())
  double duration_s = 60.0;       // s, sequence length including the static start
  double static_start_s = 2.0;    // s, motionless start (as every EuRoC sequence has)
  double camera_rate_hz = 20.0;   // Hz
  uint64_t seed = 0;              // every random stream (and the textures) derive from it
  // m/s, walking speed of route scenarios (two_floors, corridor, dark); 0
  // (default) fits the scenario's whole route into the duration.
  double route_speed_mps = 0.0;
  double texels_per_metre = 128.0;  // texture resolution of the textured surfaces
  // Folder of photos (any of .png/.jpg/.jpeg/.bmp/.tif/.tiff/.pgm/.ppm, used
  // in file-name order) textured onto the richly textured surfaces instead of
  // procedural textures (see ScenarioOptions::photos); empty (default):
  // procedural textures.
  std::string texture_folder;
  int photo_texture_size = 1024;  // texels, side of each photo's square texture (power of two)
  bool render_images = true;      // false: motion, IMU and ground truth only (fast)
  // s, shutter time for motion blur; < 0 (default): the scenario's own (dark:
  // 0.02 s, others 0 = sharp).
  double exposure_time_s = -1.0;
  int num_threads = 2;  // rendering threads (>= 1)
  // true (default): frames are rendered in parallel, one thread each; false:
  // one frame at a time with its rows split over the threads.
  bool threads_over_frames = true;
  WalkOptions walk;         // random walk of `room`; duration/static start/seed are set from above
  ImuSynthesisOptions imu;  // IMU noise; seed set from above
  // The emulated VIO: "gentle" (EmulateVioDrift with vio_drift, the
  // default: distance random walks, no
  // scale error, white jitter) or "realistic" (EmulateRealisticVio with
  // realistic_vio: the VIO uncertainty model's defaults, a 2 % scale error,
  // optional re-initialisations; sim/vio_emulator.h).
  std::string vio_profile = "gentle";
  VioDriftOptions vio_drift;           // gentle VIO; seed set from above
  RealisticVioOptions realistic_vio;   // realistic VIO; seed set from above
  KeyframeSelectionOptions keyframes;  // default off: every frame of the grid
  Camera camera = DefaultCamera();
  Rigid3d body_from_cam = DefaultBodyFromCam();

  // Imperfections for robustness tests (sim/robustness.h); every default
  // leaves the sequence as it is without them.
  // Per-frame exposure gain (auto exposure); default off.
  AutoExposureOptions auto_exposure;
  // s, rolling-shutter readout time: row y of a frame stamped t is exposed
  // at RollingShutterRowTime(t, y, height, readout) (rows top to bottom, the
  // middle row at t). 0 (default): global shutter.
  double rolling_shutter_readout_s = 0.0;
  // s, camera clock against the IMU clock: the image exposed at true (IMU)
  // time t is stamped t + camera_time_offset_s in cam0/data.csv and its file
  // name; the IMU, the ground truth (at t) and the calibration (which states
  // no offset) are unchanged. 0 (default): one clock. E.g. 0.047: images
  // stamped 47 ms late.
  double camera_time_offset_s = 0.0;
  // Factors on the noise figures written to imu0/sensor.yaml (densities and
  // random walks of the gyro, resp. the accelerometer) against the noise
  // actually simulated (`imu`): a wrong calibration. Default 1 (true figures).
  double imu_noise_file_scale_gyro = 1.0;
  double imu_noise_file_scale_accel = 1.0;
  WhiteWallOptions white_walls;  // nearly textureless outer walls and ceiling; default off

  // Whether any of the imperfections above is set.
  bool HasImperfections() const;

  // EuRoC cam0-like: OPENCV 752x480, fx 458.654, fy 457.296, cx 367.215, cy 248.375.
  static Camera DefaultCamera();
  // Camera looking along the body's x axis (forward), 5 cm ahead of the IMU.
  static Rigid3d DefaultBodyFromCam();

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct SimulatedSequence {
  // `images` lists the camera stamps with paths <stamp>.png relative to
  // mav0/cam0/data/ (the files exist once written).
  Sequence sequence;
  // Scene, regions, exposure. Without options.render_images its textures
  // are coarse (8 texels/m): only the geometry is meant to be used.
  std::shared_ptr<const Scenario> scenario;
  BodyTrajectory motion;  // continuous-time truth
  // Emulated VIO, world_from_body at the stamps of the camera-rate grid
  // (the image stamps unless keyframes are selected), none while it
  // re-initialises; and the segment of each pose.
  Trajectory vio_body;
  std::vector<int> vio_segments;
  std::vector<int> frame_regions;  // per image: index into scenario->regions (-1: none)
  // ns, image stamp minus true exposure time (options.camera_time_offset_s).
  timestamp_ns_t camera_time_offset_ns = 0;
  // Per image: the auto-exposure gain (all 1 without auto exposure).
  std::vector<double> exposure_gains;
  // The IMU noise simulated; sequence.rig.imu_noise is what the written
  // calibration states (different with imu_noise_file_scale_*).
  ImuNoise true_imu_noise;

  // True (IMU-clock) time of image k's exposure (of its middle row).
  timestamp_ns_t FrameTime(size_t k) const {
    return sequence.images[k].timestamp_ns - camera_time_offset_ns;
  }
};

SimulatedSequence SimulateSequence(const SimulationOptions& options);

// Camera pose at stamp t: (world_from_body(t) * body_from_cam)^-1.
Rigid3d SimulatedCamFromWorld(const SimulatedSequence& simulated, timestamp_ns_t t);

// Renders image `frame_index` with the scenario's exposure times the
// frame's auto-exposure gain, noise seed MixSeed(options.seed, frame_index),
// at the frame's true time FrameTime(frame_index), with motion blur over the
// shutter time centred on it when the exposure time is > 0, and with every
// row at its own time (RollingShutterRowTime; each row blurred over its own
// shutter interval) when options.rolling_shutter_readout_s > 0. `rays` is
// the sequence camera's RayTable; num_threads splits the rows.
GreyImage RenderSimulatedFrame(const SimulatedSequence& simulated, const RayTable& rays,
                               size_t frame_index, const SimulationOptions& options,
                               int num_threads = 1);

// Renders every image to <folder>/<stamp>.png (8-bit grey), in parallel as
// options.num_threads/threads_over_frames say, with a progress bar.
void RenderSimulatedImages(const std::filesystem::path& folder, const SimulatedSequence& simulated,
                           const SimulationOptions& options);

// Writes <out>/mav0/{cam0/{data.csv, data/*.png, sensor.yaml}, imu0,
// state_groundtruth_estimate0}, <out>/frames.csv (per frame: stamp, region,
// floor, camera centre), <out>/vio_emulated.tum (world_from_body at the
// stamps of the camera-rate grid, none while it re-initialises), <out>/scene.csv (every textured
// quad with its region, floor, texture id and world geometry: io/scene_structure_io.h),
// <out>/camera_stamps.txt and <out>/simulation.yaml (the options used); with
// auto exposure also <out>/exposure.csv (per frame: stamp, gain). Without
// options.render_images, cam0 has sensor.yaml only.
void WriteSimulatedSequence(const std::filesystem::path& out, const SimulatedSequence& simulated,
                            const SimulationOptions& options);

}  // namespace viosfm
