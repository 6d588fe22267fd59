// Uniform cubic B-spline in R^N with analytic derivatives.
//
// With control points P_0..P_{n-1} and knot spacing dt, the curve is defined
// on [t0, t0 + (n - 3) dt]. On segment i (u = (t - t0)/dt - i in [0, 1)):
//   p(u) = [1 u u^2 u^3] M [P_i; P_{i+1}; P_{i+2}; P_{i+3}],
//   M = 1/6 [[1 4 1 0]; [-3 0 3 0]; [3 -6 3 0]; [-1 3 -3 1]].
// It is C2: position, velocity and acceleration are continuous, the
// acceleration is piecewise linear. Four equal control points give an
// exactly constant stretch (used for static starts).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

#include "viosfm/util/errors.h"

namespace viosfm {

template <int N>
class CubicBSpline {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;

  CubicBSpline() = default;
  CubicBSpline(double t0, double dt, std::vector<Vector> control_points)
      : t0_(t0), dt_(dt), control_points_(std::move(control_points)) {
    VIOSFM_CHECK_GT(dt_, 0.0);
    VIOSFM_CHECK_GE(control_points_.size(), size_t{4});
  }

  double StartTime() const { return t0_; }
  double EndTime() const { return t0_ + (static_cast<double>(control_points_.size()) - 3) * dt_; }

  // Derivative of the given order (0: value, 1: d/dt, 2: d2/dt2) at t,
  // clamped to [StartTime(), EndTime()].
  Vector Evaluate(double t, int order = 0) const {
    const double s =
        std::clamp((t - t0_) / dt_, 0.0, static_cast<double>(control_points_.size()) - 3.0);
    const int segment =
        std::min(static_cast<int>(std::floor(s)), static_cast<int>(control_points_.size()) - 4);
    const double u = s - segment;
    double weights[4];
    switch (order) {
      case 0:
        weights[0] = (1 - u) * (1 - u) * (1 - u) / 6.0;
        weights[1] = (3 * u * u * u - 6 * u * u + 4) / 6.0;
        weights[2] = (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6.0;
        weights[3] = u * u * u / 6.0;
        break;
      case 1:
        weights[0] = -(1 - u) * (1 - u) / 2.0 / dt_;
        weights[1] = (3 * u * u - 4 * u) / 2.0 / dt_;
        weights[2] = (-3 * u * u + 2 * u + 1) / 2.0 / dt_;
        weights[3] = u * u / 2.0 / dt_;
        break;
      case 2:
        weights[0] = (1 - u) / (dt_ * dt_);
        weights[1] = (3 * u - 2) / (dt_ * dt_);
        weights[2] = (-3 * u + 1) / (dt_ * dt_);
        weights[3] = u / (dt_ * dt_);
        break;
      default: VIOSFM_CHECK(false) << "unsupported derivative order " << order;
    }
    Vector value = Vector::Zero();
    for (int k = 0; k < 4; ++k) value += weights[k] * control_points_[segment + k];
    return value;
  }

  const std::vector<Vector>& control_points() const { return control_points_; }

 private:
  double t0_ = 0.0;
  double dt_ = 1.0;
  std::vector<Vector> control_points_;
};

}  // namespace viosfm
