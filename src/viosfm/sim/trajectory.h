// Continuous-time ground-truth motion of the body (IMU) frame, with exact
// analytic velocity, acceleration and angular velocity for IMU synthesis.
//
// Position is a cubic B-spline in the world frame (z up, gravity along -z).
// Orientation is world_from_body = Rz(yaw) * Ry(pitch) * Rx(roll), with the
// three angles as a cubic B-spline. The body frame is x forward, y left, z up.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/sim/spline.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

class BodyTrajectory {
 public:
  BodyTrajectory() = default;
  // Knot times are seconds after start_ns.
  BodyTrajectory(timestamp_ns_t start_ns, CubicBSpline<3> position, CubicBSpline<3> yaw_pitch_roll);

  timestamp_ns_t start_ns() const { return start_ns_; }
  timestamp_ns_t end_ns() const;

  Rigid3d WorldFromBody(timestamp_ns_t t) const;
  Eigen::Vector3d PositionInWorld(timestamp_ns_t t) const;
  Eigen::Vector3d VelocityInWorld(timestamp_ns_t t) const;
  Eigen::Vector3d AccelerationInWorld(timestamp_ns_t t) const;
  Eigen::Vector3d AngularVelocityInBody(timestamp_ns_t t) const;
  // What an ideal accelerometer measures: R^T (a - g), g = (0, 0, -9.81).
  Eigen::Vector3d SpecificForceInBody(timestamp_ns_t t) const;

  // Poses of the body at the given stamps.
  Trajectory Sample(const std::vector<timestamp_ns_t>& stamps) const;
  // Distance travelled between two stamps (numerical, 1 ms steps).
  double PathLength(timestamp_ns_t from, timestamp_ns_t to) const;

 private:
  double Seconds(timestamp_ns_t t) const { return NsToSeconds(t - start_ns_); }

  timestamp_ns_t start_ns_ = 0;
  CubicBSpline<3> position_;
  CubicBSpline<3> yaw_pitch_roll_;
};

// Rotation Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Matrix3d RotationFromYawPitchRoll(const Eigen::Vector3d& yaw_pitch_roll);
// Body angular velocity from ZYX Euler angles and their rates.
Eigen::Vector3d BodyRatesFromEulerRates(const Eigen::Vector3d& yaw_pitch_roll,
                                        const Eigen::Vector3d& rates);

// A random, smooth walk inside an axis-aligned box: the handheld / MAV-like
// motion of the simulated scenarios.
struct WalkOptions {
  double duration_s = 60.0;                  // s, total length including the static start
  double static_start_s = 0.0;               // s, motionless at the start (as EuRoC sequences are)
  double speed_mps = 0.8;                    // m/s, mean horizontal speed
  double knot_spacing_s = 0.5;               // s, B-spline knot spacing
  double turn_stddev_rad = 0.35;             // rad per knot, heading random walk
  double height_stddev_m = 0.15;             // m, vertical wander
  double look_around_rad = 0.35;             // rad, amplitude of yaw oscillation about the heading
  double pitch_roll_stddev_rad = 0.08;       // rad, pitch/roll wander
  Eigen::Vector3d box_min{-3.0, -3.0, 0.8};  // m, where the body may go
  Eigen::Vector3d box_max{3.0, 3.0, 2.0};
  Eigen::Vector3d start_position{0.0, 0.0, 1.4};  // m
  double start_heading_rad = 0.0;
  timestamp_ns_t start_ns = 1'000'000'000'000'000'000;  // first stamp, ns
  uint64_t seed = 0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

BodyTrajectory GenerateWalk(const WalkOptions& options);

// A handheld walk along a polyline route (a floor plan's corridors, stairs):
// the body follows the route with a varying pace, small sideways and
// vertical wander, heading along the (smoothed) route direction plus a
// look-around yaw oscillation, pitching with the slope, and pitch/roll
// wander, so that acceleration and rotation about every axis vary.
struct RouteWalkOptions {
  std::vector<Eigen::Vector3d> waypoints;  // m, body positions along the route (>= 2)
  double duration_s = 60.0;                // s, total length including the static start
  double static_start_s = 0.0;             // s, motionless at the first waypoint
  // m/s, mean speed; 0 (default) fits the whole route into the moving time,
  // at most max_fit_speed_mps (a short walk then ends part-way). With a
  // speed, the walk stops at the route's end if time remains.
  double speed_mps = 0.0;
  double max_fit_speed_mps = 2.0;       // m/s, cap of the fitted speed
  double pace_stddev = 0.2;             // relative std of the distance walked per knot
  double knot_spacing_s = 0.5;          // s, B-spline knot spacing
  double lateral_wander_m = 0.08;       // m, std of the sideways offset (AR(1), bounded)
  double max_lateral_m = 0.25;          // m, bound of the sideways offset
  double vertical_wander_m = 0.04;      // m, std of the height offset per knot
  double heading_lookahead_m = 0.7;     // m, heading = direction over +-this route length
  double look_around_rad = 0.25;        // rad, amplitude of the yaw oscillation
  double pitch_roll_stddev_rad = 0.06;  // rad, pitch/roll wander per knot
  double slope_pitch_factor = 0.5;      // pitch = -factor * route slope angle (looks up stairs)
  timestamp_ns_t start_ns = 1'000'000'000'000'000'000;  // first stamp, ns
  uint64_t seed = 0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

BodyTrajectory GenerateRouteWalk(const RouteWalkOptions& options);

// Length of a polyline (m) and the point at arc length s (clamped to the ends).
double PolylineLength(const std::vector<Eigen::Vector3d>& points);
Eigen::Vector3d PolylinePoint(const std::vector<Eigen::Vector3d>& points, double s);

}  // namespace viosfm
