// Named simulation scenarios: a scene, the route or box a handheld camera
// walks, how the camera exposes (light, noise, motion blur), and named
// regions of the floor plan for per-frame scene ground truth.
//
//   room        an 8 x 8 x 3 m textured room with furniture-like boxes (like
//               EuRoC's Vicon room); random walk inside it.
//   two_floors  two identical rooms (same layout, same textures) stacked at
//               z = 0 and z = 3.5 m, joined by a weakly textured stairwell;
//               the walk loops floor 1, climbs, and loops floor 2 over the
//               same plan: the repeated-structure trap.
//   corridor    a rectangular ring corridor (outer 24 x 16 m, 2 m wide) with
//               28 identical doors; the walk goes once round and closes
//               the loop.
//   dark        a 24 m tunnel in low light (dim, noisy, motion-blurred) with a
//               6 m stretch of almost no texture; the walk goes to the far
//               end and back.
//   mav         the room flown by a small drone, as EuRoC's Vicon-room
//               flights: 0.5 m/s, fast yaw (swings of +-50 degrees about
//               the heading, up to about 60 deg/s) and pitch (+-9 degrees
//               a knot of 0.4 s), and propeller vibration in the
//               accelerometer (1.2 m/s^2 RMS a axis, 60-190 Hz, aliased by
//               the 200 Hz sampling, as EuRoC's IMU shows in flight).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/scene/scene_structure.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/scene_model.h"
#include "viosfm/sim/trajectory.h"

namespace viosfm {

// A named part of a floor plan (a floor, a stairwell, a corridor segment).
struct SceneRegion {
  std::string name;
  int floor = 0;            // storey index (0 = ground floor; -1: between floors, a stairwell)
  Eigen::AlignedBox3d box;  // where the camera centre is while in the region
};

struct Scenario {
  std::string name;
  Scene scene;
  // Regions of the plan, tested in order (the first containing box wins).
  std::vector<SceneRegion> regions;
  // How the camera exposes in this scenario (seed and num_threads are set
  // per frame by the simulator).
  RenderOptions render;
  double exposure_time_s = 0.0;  // s, shutter time for motion blur (0: sharp)
  // Body waypoints of the walk (GenerateRouteWalk); empty: a random walk
  // (GenerateWalk) inside walk_box_min/max.
  std::vector<Eigen::Vector3d> route;
  Eigen::Vector3d walk_box_min{-3.0, -3.0, 0.8};  // m, random-walk box (room)
  Eigen::Vector3d walk_box_max{3.0, 3.0, 2.0};
  double storey_height_m = 0.0;  // m, vertical offset between floors (two_floors)
  // Route-less scenarios that do not walk (mav): the random walk's pace and
  // rotation, replacing the walk options given; unset: those are used.
  std::optional<WalkOptions> walk_style;
  // Vibration in the accelerometer's readings (mav); its accel_rms_mps2 0:
  // none (the simulator sets its seed and start).
  ImuVibrationOptions vibration;

  // Index into `regions` of the region containing `point`; -1 if none.
  int RegionIndex(const Eigen::Vector3d& point) const;
};

struct ScenarioOptions {
  std::string name = "room";        // one of AvailableScenarios()
  double texels_per_metre = 128.0;  // texture resolution of the richly textured surfaces
  uint64_t seed = 0;                // texture seeds derive from it
  // Non-empty: the richly textured surfaces (and corridor walls) show these
  // photos instead of procedural textures, surface k photo k mod count;
  // weakly textured ones (stairwell, dark's blank stretch) and the corridor
  // doors stay procedural. Textures shared by design stay shared (both
  // floors of two_floors, every corridor door). Default: none.
  PhotoTextures photos;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

std::vector<std::string> AvailableScenarios();

// Throws InputError for an unknown name.
Scenario MakeScenario(const ScenarioOptions& options);

// The scenario's quads in scene order, each with the region containing its
// centre ("none", floor -1 if no region does).
SceneStructure ScenarioStructure(const Scenario& scenario);

// The body motion of a scenario: its route walked in `walk`'s duration with
// its static start (or, without a route, `walk` inside the scenario's box).
// speed_mps > 0 walks the route at that speed instead of fitting it into
// the duration.
struct ScenarioMotionOptions {
  double duration_s = 60.0;     // s, including the static start
  double static_start_s = 2.0;  // s
  double speed_mps = 0.0;       // m/s; 0 fits the route into the duration
  WalkOptions walk;             // the random walk of route-less scenarios (box set by the scenario)
  timestamp_ns_t start_ns = 1'000'000'000'000'000'000;  // first stamp, ns
  uint64_t seed = 0;
};
BodyTrajectory GenerateScenarioMotion(const Scenario& scenario,
                                      const ScenarioMotionOptions& options);

// Smallest distance (m) from `point` to a surface over 26 directions (the
// axes, face and space diagonals); infinity if some direction escapes the
// scene (the point is outside a closed scene).
double SurfaceClearance(const Scene& scene, const Eigen::Vector3d& point);

// A door-like texture (frame, two panels, handle) covering 1 x 2 m at 256
// texels/m (256 x 512 texels); the same seed gives the same door.
Texture MakeDoorTexture(uint64_t seed);

}  // namespace viosfm
