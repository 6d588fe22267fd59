#include "viosfm/sim/trajectory.h"

#include <cmath>

#include "viosfm/util/random.h"

namespace viosfm {

BodyTrajectory::BodyTrajectory(timestamp_ns_t start_ns, CubicBSpline<3> position,
                               CubicBSpline<3> yaw_pitch_roll)
    : start_ns_(start_ns), position_(std::move(position)), yaw_pitch_roll_(std::move(yaw_pitch_roll)) {}

timestamp_ns_t BodyTrajectory::end_ns() const {
  return start_ns_ + SecondsToNs(std::min(position_.EndTime(), yaw_pitch_roll_.EndTime()));
}

Eigen::Matrix3d RotationFromYawPitchRoll(const Eigen::Vector3d& ypr) {
  return (Eigen::AngleAxisd(ypr[0], Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(ypr[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(ypr[2], Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d BodyRatesFromEulerRates(const Eigen::Vector3d& ypr, const Eigen::Vector3d& rates) {
  const double pitch = ypr[1];
  const double roll = ypr[2];
  const double yaw_rate = rates[0];
  const double pitch_rate = rates[1];
  const double roll_rate = rates[2];
  return Eigen::Vector3d(
      roll_rate - yaw_rate * std::sin(pitch),
      pitch_rate * std::cos(roll) + yaw_rate * std::sin(roll) * std::cos(pitch),
      -pitch_rate * std::sin(roll) + yaw_rate * std::cos(roll) * std::cos(pitch));
}

Rigid3d BodyTrajectory::WorldFromBody(timestamp_ns_t t) const {
  const double s = Seconds(t);
  return Rigid3d(Eigen::Quaterniond(RotationFromYawPitchRoll(yaw_pitch_roll_.Evaluate(s))),
                 position_.Evaluate(s));
}

Eigen::Vector3d BodyTrajectory::PositionInWorld(timestamp_ns_t t) const {
  return position_.Evaluate(Seconds(t));
}

Eigen::Vector3d BodyTrajectory::VelocityInWorld(timestamp_ns_t t) const {
  return position_.Evaluate(Seconds(t), 1);
}

Eigen::Vector3d BodyTrajectory::AccelerationInWorld(timestamp_ns_t t) const {
  return position_.Evaluate(Seconds(t), 2);
}

Eigen::Vector3d BodyTrajectory::AngularVelocityInBody(timestamp_ns_t t) const {
  const double s = Seconds(t);
  return BodyRatesFromEulerRates(yaw_pitch_roll_.Evaluate(s), yaw_pitch_roll_.Evaluate(s, 1));
}

Eigen::Vector3d BodyTrajectory::SpecificForceInBody(timestamp_ns_t t) const {
  const double s = Seconds(t);
  const Eigen::Matrix3d world_from_body = RotationFromYawPitchRoll(yaw_pitch_roll_.Evaluate(s));
  const Eigen::Vector3d gravity(0.0, 0.0, -kStandardGravity);
  return world_from_body.transpose() * (position_.Evaluate(s, 2) - gravity);
}

Trajectory BodyTrajectory::Sample(const std::vector<timestamp_ns_t>& stamps) const {
  Trajectory trajectory;
  trajectory.poses.reserve(stamps.size());
  for (const timestamp_ns_t t : stamps) trajectory.poses.push_back({t, WorldFromBody(t)});
  return trajectory;
}

double BodyTrajectory::PathLength(timestamp_ns_t from, timestamp_ns_t to) const {
  constexpr timestamp_ns_t kStep = 1'000'000;
  double length = 0.0;
  Eigen::Vector3d previous = PositionInWorld(from);
  for (timestamp_ns_t t = from; t < to;) {
    t = std::min(to, t + kStep);
    const Eigen::Vector3d current = PositionInWorld(t);
    length += (current - previous).norm();
    previous = current;
  }
  return length;
}

std::string WalkOptions::Validate() const {
  if (!(duration_s > 0)) return "duration_s must be > 0";
  if (!(static_start_s >= 0 && static_start_s < duration_s)) {
    return "static_start_s must be in [0, duration_s)";
  }
  if (!(speed_mps >= 0)) return "speed_mps must be >= 0";
  if (!(knot_spacing_s > 0)) return "knot_spacing_s must be > 0";
  if (!((box_max - box_min).minCoeff() > 0)) return "box_max must exceed box_min on every axis";
  if (!((start_position - box_min).minCoeff() >= 0 && (box_max - start_position).minCoeff() >= 0)) {
    return "start_position must lie inside [box_min, box_max]";
  }
  return "";
}

BodyTrajectory GenerateWalk(const WalkOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  Random random(options.seed);
  const double dt = options.knot_spacing_s;
  // Knots cover [0, duration] with 3 extra control points (cubic B-spline).
  const int num_segments = static_cast<int>(std::ceil(options.duration_s / dt));
  const int num_static = static_cast<int>(std::floor(options.static_start_s / dt));
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> angles;
  Eigen::Vector3d position = options.start_position;
  double heading = options.start_heading_rad;
  double look_phase = random.Uniform(0.0, 2.0 * M_PI);
  Eigen::Vector3d angle(heading, 0.0, 0.0);
  const double step = options.speed_mps * dt;
  const Eigen::Vector3d center = 0.5 * (options.box_min + options.box_max);
  const Eigen::Vector3d half = 0.5 * (options.box_max - options.box_min);
  // The first control points are repeated so that the static stretch is
  // exactly motionless.
  for (int i = 0; i < num_segments + 3; ++i) {
    if (i > num_static + 2) {
      heading += random.Normal(0.0, options.turn_stddev_rad);
      Eigen::Vector3d next =
          position + step * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
      // Steer back towards the centre when the next step would leave the box.
      for (int attempt = 0; attempt < 16; ++attempt) {
        const Eigen::Vector3d offset = (next - center).cwiseQuotient(half);
        if (std::abs(offset.x()) < 0.85 && std::abs(offset.y()) < 0.85) break;
        const Eigen::Vector3d to_center = center - position;
        heading = std::atan2(to_center.y(), to_center.x()) + random.Normal(0.0, 0.4);
        next = position + step * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
      }
      next.z() = std::clamp(position.z() + random.Normal(0.0, options.height_stddev_m),
                            options.box_min.z(), options.box_max.z());
      position = next;
      look_phase += random.Uniform(0.2, 0.6);
      double yaw = heading + options.look_around_rad * std::sin(look_phase);
      // Keep the yaw continuous (no 2 pi jumps between control points).
      yaw = angle[0] + std::remainder(yaw - angle[0], 2.0 * M_PI);
      angle = Eigen::Vector3d(yaw, random.Normal(0.0, options.pitch_roll_stddev_rad),
                              random.Normal(0.0, options.pitch_roll_stddev_rad));
    }
    positions.push_back(position);
    angles.push_back(angle);
  }
  // Spline time 0 is at the start of the curve, i.e. at the second knot.
  return BodyTrajectory(options.start_ns, CubicBSpline<3>(0.0, dt, positions),
                        CubicBSpline<3>(0.0, dt, angles));
}

}  // namespace viosfm
