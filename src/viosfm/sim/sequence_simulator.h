// A simulated visual-inertial sequence with exact ground truth: body motion,
// IMU at 200 Hz with noise and bias random walks, ground-truth state at the
// camera stamps, and an emulated (drifting) VIO trajectory, written in the
// EuRoC ASL layout so every reader and stage can consume it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "viosfm/io/sequence.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/sim/vio_emulator.h"

namespace viosfm {

struct SimulationOptions {
  std::string scenario = "room";  // scene and motion preset (see AvailableScenarios())
  double duration_s = 60.0;       // s, sequence length including the static start
  double static_start_s = 2.0;    // s, motionless start (as every EuRoC sequence has)
  double camera_rate_hz = 20.0;   // Hz
  uint64_t seed = 0;              // every random stream is derived from it
  WalkOptions walk;               // motion; duration/static start/seed are set from above
  ImuSynthesisOptions imu;        // IMU noise; seed set from above
  VioDriftOptions vio_drift;      // emulated VIO; seed set from above
  Camera camera = DefaultCamera();
  Rigid3d body_from_cam = DefaultBodyFromCam();

  // EuRoC cam0-like: OPENCV 752x480, fx 458.654, fy 457.296, cx 367.215, cy 248.375.
  static Camera DefaultCamera();
  // Camera looking along the body's x axis (forward), 5 cm ahead of the IMU.
  static Rigid3d DefaultBodyFromCam();

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

std::vector<std::string> AvailableScenarios();

struct SimulatedSequence {
  Sequence sequence;        // no image files yet: `images` lists the camera stamps
  BodyTrajectory motion;    // continuous-time truth
  Trajectory vio_body;      // emulated VIO, world_from_body at the camera stamps
};

SimulatedSequence SimulateSequence(const SimulationOptions& options);

// Writes <out>/mav0/{imu0, state_groundtruth_estimate0, cam0/sensor.yaml},
// <out>/vio_emulated.tum (world_from_body at the camera stamps),
// <out>/camera_stamps.txt and <out>/simulation.yaml (the options used).
void WriteSimulatedSequence(const std::filesystem::path& out, const SimulatedSequence& simulated,
                            const SimulationOptions& options);

}  // namespace viosfm
