#include "viosfm/sim/trajectory.h"

#include <algorithm>
#include <cmath>

#include "viosfm/util/random.h"

namespace viosfm {

BodyTrajectory::BodyTrajectory(timestamp_ns_t start_ns, CubicBSpline<3> position,
                               CubicBSpline<3> yaw_pitch_roll)
    : start_ns_(start_ns),
      position_(std::move(position)),
      yaw_pitch_roll_(std::move(yaw_pitch_roll)) {}

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

double PolylineLength(const std::vector<Eigen::Vector3d>& points) {
  double length = 0.0;
  for (size_t k = 1; k < points.size(); ++k) length += (points[k] - points[k - 1]).norm();
  return length;
}

Eigen::Vector3d PolylinePoint(const std::vector<Eigen::Vector3d>& points, double s) {
  VIOSFM_CHECK(!points.empty());
  if (s <= 0.0) return points.front();
  for (size_t k = 1; k < points.size(); ++k) {
    const double segment = (points[k] - points[k - 1]).norm();
    if (s <= segment && segment > 0.0)
      return points[k - 1] + (s / segment) * (points[k] - points[k - 1]);
    s -= segment;
  }
  return points.back();
}

std::string RouteWalkOptions::Validate() const {
  if (waypoints.size() < 2) return "waypoints: the route needs >= 2 points";
  if (!(PolylineLength(waypoints) > 0.0)) return "waypoints: the route has zero length";
  if (!(duration_s > 0)) return "duration_s must be > 0";
  if (!(static_start_s >= 0 && static_start_s < duration_s)) {
    return "static_start_s must be in [0, duration_s)";
  }
  if (!(speed_mps >= 0)) return "speed_mps must be >= 0";
  if (!(max_fit_speed_mps > 0)) return "max_fit_speed_mps must be > 0";
  if (!(pace_stddev >= 0 && pace_stddev < 0.5)) return "pace_stddev must be in [0, 0.5)";
  if (!(knot_spacing_s > 0)) return "knot_spacing_s must be > 0";
  if (!(lateral_wander_m >= 0 && max_lateral_m >= 0)) {
    return "lateral_wander_m and max_lateral_m must be >= 0";
  }
  if (!(vertical_wander_m >= 0)) return "vertical_wander_m must be >= 0";
  if (!(heading_lookahead_m > 0)) return "heading_lookahead_m must be > 0";
  return "";
}

BodyTrajectory GenerateRouteWalk(const RouteWalkOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  Random random(options.seed);
  const double dt = options.knot_spacing_s;
  const int num_segments = static_cast<int>(std::ceil(options.duration_s / dt));
  const int num_static = static_cast<int>(std::floor(options.static_start_s / dt));
  const int first_moving = num_static + 3;  // control points before it repeat the start
  const int num_points = num_segments + 3;
  const std::vector<Eigen::Vector3d>& route = options.waypoints;
  const double route_length = PolylineLength(route);

  // Arc length at every control point: random pace, scaled to the route.
  std::vector<double> arc(num_points, 0.0);
  {
    std::vector<double> steps(num_points, 0.0);
    double total = 0.0;
    for (int i = first_moving; i < num_points; ++i) {
      steps[i] = std::clamp(1.0 + random.Normal(0.0, options.pace_stddev), 0.4, 1.6);
      total += steps[i];
    }
    const double fitted_scale =
        std::min(total > 0.0 ? route_length / total : 0.0, options.max_fit_speed_mps * dt);
    const double scale = options.speed_mps > 0.0 ? options.speed_mps * dt : fitted_scale;
    for (int i = 1; i < num_points; ++i) {
      arc[i] = std::min(route_length, arc[i - 1] + scale * steps[i]);
    }
  }
  const auto heading_at = [&](double s) -> Eigen::Vector3d {
    const Eigen::Vector3d ahead = PolylinePoint(route, s + options.heading_lookahead_m);
    const Eigen::Vector3d behind = PolylinePoint(route, s - options.heading_lookahead_m);
    return ahead - behind;
  };
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> angles;
  double lateral = 0.0;
  double look_phase = random.Uniform(0.0, 2.0 * M_PI);
  const Eigen::Vector3d start_direction = heading_at(0.0);
  const double start_yaw = std::atan2(start_direction.y(), start_direction.x());
  Eigen::Vector3d angle(start_yaw, 0.0, 0.0);
  for (int i = 0; i < num_points; ++i) {
    Eigen::Vector3d position = PolylinePoint(route, arc[i]);
    if (i >= first_moving) {
      const Eigen::Vector3d direction = heading_at(arc[i]);
      const double horizontal = std::hypot(direction.x(), direction.y());
      const double heading = std::atan2(direction.y(), direction.x());
      lateral = std::clamp(0.7 * lateral + random.Normal(0.0, options.lateral_wander_m),
                           -options.max_lateral_m, options.max_lateral_m);
      position += lateral * Eigen::Vector3d(-std::sin(heading), std::cos(heading), 0.0);
      position.z() += random.Normal(0.0, options.vertical_wander_m);
      look_phase += random.Uniform(0.2, 0.6);
      double yaw = heading + options.look_around_rad * std::sin(look_phase);
      yaw = angle[0] + std::remainder(yaw - angle[0], 2.0 * M_PI);
      const double slope = std::atan2(direction.z(), std::max(horizontal, 1e-9));
      angle = Eigen::Vector3d(
          yaw,
          -options.slope_pitch_factor * slope + random.Normal(0.0, options.pitch_roll_stddev_rad),
          random.Normal(0.0, options.pitch_roll_stddev_rad));
    }
    positions.push_back(position);
    angles.push_back(angle);
  }
  return BodyTrajectory(options.start_ns, CubicBSpline<3>(0.0, dt, positions),
                        CubicBSpline<3>(0.0, dt, angles));
}

}  // namespace viosfm
