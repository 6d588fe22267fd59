#include "viosfm/sim/trajectory.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace viosfm {
namespace {

constexpr timestamp_ns_t kMs = 1'000'000;

WalkOptions TestWalk() {
  WalkOptions options;
  options.duration_s = 20.0;
  options.static_start_s = 2.0;
  options.seed = 7;
  return options;
}

TEST(CubicBSpline, DerivativesMatchFiniteDifferences) {
  std::vector<Eigen::Vector3d> points = {{0, 0, 0}, {1, 2, 0}, {3, 1, 1},
                                         {4, 4, 2}, {2, 5, 1}, {0, 3, 0}};
  const CubicBSpline<3> spline(0.0, 0.5, points);
  EXPECT_DOUBLE_EQ(spline.EndTime(), 1.5);
  for (double t = 0.01; t < 1.49; t += 0.037) {
    const double h = 1e-5;
    const Eigen::Vector3d numeric_velocity =
        (spline.Evaluate(t + h) - spline.Evaluate(t - h)) / (2 * h);
    const Eigen::Vector3d numeric_accel =
        (spline.Evaluate(t + h, 1) - spline.Evaluate(t - h, 1)) / (2 * h);
    EXPECT_LT((spline.Evaluate(t, 1) - numeric_velocity).norm(), 1e-6) << t;
    EXPECT_LT((spline.Evaluate(t, 2) - numeric_accel).norm(), 1e-5) << t;
  }
  // Continuity of value and first two derivatives across a knot.
  for (int order = 0; order < 3; ++order) {
    EXPECT_LT((spline.Evaluate(0.5 - 1e-9, order) - spline.Evaluate(0.5 + 1e-9, order)).norm(),
              1e-6);
  }
}

TEST(BodyTrajectory, AngularVelocityMatchesRotationDerivative) {
  const BodyTrajectory trajectory = GenerateWalk(TestWalk());
  for (timestamp_ns_t t = trajectory.start_ns() + 2500 * kMs; t < trajectory.end_ns() - kMs;
       t += 731 * kMs) {
    const timestamp_ns_t h = 10'000;  // 10 us
    const Eigen::Quaterniond before = trajectory.WorldFromBody(t - h).rotation;
    const Eigen::Quaterniond after = trajectory.WorldFromBody(t + h).rotation;
    const Eigen::AngleAxisd delta(before.inverse() * after);
    const Eigen::Vector3d numeric = delta.axis() * delta.angle() / NsToSeconds(2 * h);
    EXPECT_LT((trajectory.AngularVelocityInBody(t) - numeric).norm(), 1e-5);
    const Eigen::Vector3d numeric_velocity =
        (trajectory.PositionInWorld(t + h) - trajectory.PositionInWorld(t - h)) /
        NsToSeconds(2 * h);
    EXPECT_LT((trajectory.VelocityInWorld(t) - numeric_velocity).norm(), 1e-6);
  }
}

TEST(BodyTrajectory, StaticStartIsMotionlessAndMeasuresGravity) {
  const WalkOptions options = TestWalk();
  const BodyTrajectory trajectory = GenerateWalk(options);
  const timestamp_ns_t static_end = trajectory.start_ns() + SecondsToNs(options.static_start_s);
  for (timestamp_ns_t t = trajectory.start_ns(); t <= static_end; t += 100 * kMs) {
    EXPECT_LT(trajectory.VelocityInWorld(t).norm(), 1e-12);
    EXPECT_LT(trajectory.AngularVelocityInBody(t).norm(), 1e-12);
    EXPECT_NEAR(trajectory.SpecificForceInBody(t).norm(), kStandardGravity, 1e-12);
  }
  // And it moves afterwards: at least 60 % of the nominal distance.
  const double length = trajectory.PathLength(static_end, trajectory.end_ns());
  EXPECT_GT(length, 0.6 * options.speed_mps * (options.duration_s - options.static_start_s));
}

TEST(BodyTrajectory, WalkStaysInsideTheBoxAndIsReproducible) {
  WalkOptions options = TestWalk();
  options.duration_s = 120.0;
  const BodyTrajectory a = GenerateWalk(options);
  const BodyTrajectory b = GenerateWalk(options);
  EXPECT_GE(NsToSeconds(a.end_ns() - a.start_ns()), options.duration_s - 1e-6);
  for (timestamp_ns_t t = a.start_ns(); t < a.end_ns(); t += 50 * kMs) {
    const Eigen::Vector3d p = a.PositionInWorld(t);
    EXPECT_TRUE((p - options.box_min).minCoeff() > -1e-9 &&
                (options.box_max - p).minCoeff() > -1e-9)
        << p.transpose();
    EXPECT_EQ(p, b.PositionInWorld(t));
  }
  options.seed = 8;
  EXPECT_NE(GenerateWalk(options).PositionInWorld(a.end_ns()), a.PositionInWorld(a.end_ns()));
}

TEST(WalkOptions, ValidateNamesTheField) {
  WalkOptions options;
  options.knot_spacing_s = 0.0;
  EXPECT_EQ(options.Validate(), "knot_spacing_s must be > 0");
  options = WalkOptions();
  options.static_start_s = 100.0;
  EXPECT_NE(options.Validate().find("static_start_s"), std::string::npos);
}

RouteWalkOptions LRoute() {
  RouteWalkOptions options;
  options.waypoints = {{0, 0, 1.4}, {10, 0, 1.4}, {10, 5, 1.4}};
  options.duration_s = 20.0;
  options.static_start_s = 2.0;
  options.seed = 3;
  return options;
}

// Distance from p to the polyline (sampled every 1 cm).
double DistanceToRoute(const std::vector<Eigen::Vector3d>& route, const Eigen::Vector3d& p) {
  double best = 1e9;
  for (double s = 0; s <= PolylineLength(route); s += 0.01) {
    best = std::min(best, (PolylinePoint(route, s) - p).norm());
  }
  return best;
}

TEST(RouteWalk, FollowsTheRouteAfterAStaticStart) {
  const RouteWalkOptions options = LRoute();
  const BodyTrajectory walk = GenerateRouteWalk(options);
  const timestamp_ns_t t0 = walk.start_ns();
  // Exactly still during the static start.
  EXPECT_EQ(walk.PositionInWorld(t0), walk.PositionInWorld(t0 + 1'500'000'000));
  EXPECT_EQ(walk.VelocityInWorld(t0 + 1'000'000'000), Eigen::Vector3d::Zero());
  EXPECT_EQ(walk.AngularVelocityInBody(t0 + 1'000'000'000), Eigen::Vector3d::Zero());
  // Fitted: the walk reaches the route's end; it never strays from it.
  EXPECT_LT((walk.PositionInWorld(walk.end_ns()) - options.waypoints.back()).norm(), 0.5);
  Eigen::Vector3d max_rate = Eigen::Vector3d::Zero();
  for (timestamp_ns_t t = t0; t <= walk.end_ns(); t += 100'000'000) {
    EXPECT_LT(DistanceToRoute(options.waypoints, walk.PositionInWorld(t)),
              options.max_lateral_m + 0.2);
    max_rate = max_rate.cwiseMax(walk.AngularVelocityInBody(t).cwiseAbs());
  }
  // Rotation about every body axis (excitation for VIO initialisation).
  EXPECT_GT(max_rate.minCoeff(), 0.05);
  // The heading follows the route: facing +x on the first leg.
  const Eigen::Vector3d forward =
      walk.WorldFromBody(t0 + 6'000'000'000).rotation * Eigen::Vector3d::UnitX();
  EXPECT_GT(forward.x(), 0.8);
}

TEST(RouteWalk, WalksAtAGivenSpeedAndCapsTheFittedSpeed) {
  RouteWalkOptions options = LRoute();
  options.speed_mps = 0.5;
  const BodyTrajectory slow = GenerateRouteWalk(options);
  // 18 s of walking at 0.5 m/s, along the route (plus wander).
  EXPECT_NEAR(slow.PathLength(slow.start_ns(), slow.end_ns()), 9.0, 1.5);
  options.speed_mps = 0.0;
  options.duration_s = 4.0;  // 15 m in 2 s would be 7.5 m/s: capped at 2 m/s
  const BodyTrajectory capped = GenerateRouteWalk(options);
  EXPECT_LT(capped.PathLength(capped.start_ns(), capped.end_ns()), 2.0 * 2.0 * 1.3);
  options.waypoints.resize(1);
  EXPECT_NE(options.Validate().find("waypoints"), std::string::npos);
}

}  // namespace
}  // namespace viosfm
