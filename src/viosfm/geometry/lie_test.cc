#include "viosfm/geometry/lie.h"

#include <ceres/jet.h>  // header-only: checks the templated maps with dual numbers
#include <gtest/gtest.h>

#include <functional>
#include <numbers>
#include <vector>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::Vector3d RandomUnitVector(Random& random) {
  Eigen::Vector3d v(random.Normal(), random.Normal(), random.Normal());
  return v.normalized();
}

// Rotation vectors with angles spread over small, medium and near-pi ranges.
std::vector<Eigen::Vector3d> TestRotationVectors(uint64_t seed, double max_angle) {
  Random random(seed);
  std::vector<Eigen::Vector3d> vectors;
  for (const double angle : {0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 0.05, 0.0999, 0.1, 0.1001}) {
    vectors.push_back(angle * RandomUnitVector(random));
  }
  for (int i = 0; i < 200; ++i) {
    vectors.push_back(random.Uniform(0.0, max_angle) * RandomUnitVector(random));
  }
  for (int i = 0; i < 20; ++i) {
    vectors.push_back(std::exp(random.Uniform(-25.0, -2.0)) * RandomUnitVector(random));
  }
  return vectors;
}

double RotationDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return So3Log(a.inverse() * b).norm();
}

TEST(Lie, HatVee) {
  const Eigen::Vector3d a(0.3, -1.2, 2.5);
  const Eigen::Vector3d b(-0.7, 0.4, 1.1);
  EXPECT_LT((Hat(a) * b - a.cross(b)).norm(), 1e-15);
  EXPECT_LT((Vee(Hat(a)) - a).norm(), 1e-15);
  EXPECT_LT((Hat(a) + Hat(a).transpose()).norm(), 1e-15);
}

TEST(Lie, So3ExpMatchesAngleAxis) {
  const Eigen::Vector3d omega(0.4, -0.2, 0.9);
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(omega.norm(), omega.normalized()));
  EXPECT_LT(RotationDistance(So3Exp(omega), expected), 1e-15);
  EXPECT_NEAR(So3Exp(omega).norm(), 1.0, 1e-15);
  EXPECT_LT((So3Log(expected) - omega).norm(), 1e-15);
}

TEST(Lie, So3ExpLogRoundTrip) {
  for (const Eigen::Vector3d& omega : TestRotationVectors(1, kPi - 1e-6)) {
    const Eigen::Vector3d back = So3Log(So3Exp(omega));
    EXPECT_LT((back - omega).norm(), 1e-14 + 1e-14 * omega.norm()) << omega.transpose();
  }
}

TEST(Lie, So3LogNearPi) {
  Random random(2);
  for (const double epsilon : {1e-3, 1e-6, 1e-9, 1e-12, 0.0}) {
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d axis = RandomUnitVector(random);
      const Eigen::Vector3d omega = (kPi - epsilon) * axis;
      const Eigen::Quaterniond q = So3Exp(omega);
      const Eigen::Vector3d back = So3Log(q);
      EXPECT_LE(back.norm(), kPi + 1e-15);
      EXPECT_NEAR(back.norm(), kPi - epsilon, 1e-14);
      // At exactly pi the axis sign is ambiguous; otherwise it must match.
      if (epsilon > 0) {
        EXPECT_LT((back - omega).norm(), 1e-13) << epsilon;
      } else {
        EXPECT_LT(std::min((back - omega).norm(), (back + omega).norm()), 1e-13);
      }
      EXPECT_LT(RotationDistance(So3Exp(back), q), 1e-13);
    }
  }
}

TEST(Lie, So3LogWrapsAnglesAbovePi) {
  Random random(3);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d axis = RandomUnitVector(random);
    const double angle = random.Uniform(kPi + 1e-3, 2 * kPi - 1e-3);
    const Eigen::Vector3d back = So3Log(So3Exp(angle * axis));
    EXPECT_LT((back - (angle - 2 * kPi) * axis).norm(), 1e-13);
    // Negated quaternion: same rotation, same log.
    const Eigen::Quaterniond q = So3Exp(angle * axis);
    const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
    EXPECT_LT((So3Log(minus_q) - back).norm(), 1e-13);
  }
}

TEST(Lie, So3LogIgnoresQuaternionNorm) {
  const Eigen::Vector3d omega(0.3, 0.5, -1.1);
  Eigen::Quaterniond q = So3Exp(omega);
  q.coeffs() *= 3.7;
  EXPECT_LT((So3Log(q) - omega).norm(), 1e-14);
  Eigen::Quaterniond small = So3Exp(Eigen::Vector3d(1e-10, 0, 0));
  small.coeffs() *= 0.25;
  EXPECT_LT((So3Log(small) - Eigen::Vector3d(1e-10, 0, 0)).norm(), 1e-24);
}

// Central finite difference of f : R^3 -> R^3 at zero.
Eigen::Matrix3d NumericJacobian(const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f) {
  constexpr double kStep = 1e-6;
  Eigen::Matrix3d jacobian;
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d delta = kStep * Eigen::Vector3d::Unit(j);
    jacobian.col(j) = (f(delta) - f(-delta)) / (2 * kStep);
  }
  return jacobian;
}

TEST(Lie, So3JacobiansMatchFiniteDifferences) {
  for (const Eigen::Vector3d& phi : TestRotationVectors(4, 3.0)) {
    const Eigen::Quaterniond r = So3Exp(phi);
    // Exp(phi + d) = Exp(phi) Exp(Jr d)  =>  Log(R^-1 Exp(phi + d)) ~ Jr d.
    const Eigen::Matrix3d jr = NumericJacobian(
        [&](const Eigen::Vector3d& d) { return So3Log(r.inverse() * So3Exp(phi + d)); });
    // Exp(phi + d) = Exp(Jl d) Exp(phi).
    const Eigen::Matrix3d jl = NumericJacobian(
        [&](const Eigen::Vector3d& d) { return So3Log(So3Exp(phi + d) * r.inverse()); });
    // Log(Exp(phi) Exp(d)) ~ phi + Jr^-1 d.
    const Eigen::Matrix3d jr_inv =
        NumericJacobian([&](const Eigen::Vector3d& d) { return So3Log(r * So3Exp(d)); });
    // Log(Exp(d) Exp(phi)) ~ phi + Jl^-1 d.
    const Eigen::Matrix3d jl_inv =
        NumericJacobian([&](const Eigen::Vector3d& d) { return So3Log(So3Exp(d) * r); });
    const double tolerance = 1e-6;
    EXPECT_LT((So3RightJacobian(phi) - jr).norm(), tolerance) << phi.transpose();
    EXPECT_LT((So3LeftJacobian(phi) - jl).norm(), tolerance) << phi.transpose();
    EXPECT_LT((So3RightJacobianInverse(phi) - jr_inv).norm(), tolerance) << phi.transpose();
    EXPECT_LT((So3LeftJacobianInverse(phi) - jl_inv).norm(), tolerance) << phi.transpose();
    // Exact identities.
    EXPECT_LT(
        (So3RightJacobian(phi) * So3RightJacobianInverse(phi) - Eigen::Matrix3d::Identity()).norm(),
        1e-12);
    EXPECT_LT(
        (So3LeftJacobian(phi) * So3LeftJacobianInverse(phi) - Eigen::Matrix3d::Identity()).norm(),
        1e-12);
    EXPECT_LT((So3LeftJacobian(phi) - r.toRotationMatrix() * So3RightJacobian(phi)).norm(), 1e-13);
  }
}

TEST(Lie, So3JacobiansAreContinuousAcrossSeriesSwitch) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  const Eigen::Vector3d below = (0.1 - 1e-12) * axis;
  const Eigen::Vector3d above = (0.1 + 1e-12) * axis;
  // The Jacobians change by ~1e-12 between the two angles themselves.
  EXPECT_LT((So3RightJacobian(below) - So3RightJacobian(above)).norm(), 3e-12);
  EXPECT_LT((So3RightJacobianInverse(below) - So3RightJacobianInverse(above)).norm(), 3e-12);
}

Vector6d RandomTwist(Random& random, double max_angle) {
  Vector6d xi;
  xi.head<3>() = random.Uniform(0.0, max_angle) * RandomUnitVector(random);
  xi.tail<3>() =
      Eigen::Vector3d(random.Uniform(-5, 5), random.Uniform(-5, 5), random.Uniform(-5, 5));
  return xi;
}

TEST(Lie, Se3ExpLogRoundTrip) {
  Random random(5);
  for (int i = 0; i < 300; ++i) {
    const double max_angle = i < 100 ? 1e-6 : (i < 200 ? 1.0 : kPi - 1e-4);
    const Vector6d xi = RandomTwist(random, max_angle);
    const Rigid3d transform = Se3Exp(xi);
    EXPECT_LT((Se3Log(transform) - xi).norm(), 1e-11) << xi.transpose();
    const Rigid3d back = Se3Exp(Se3Log(transform));
    EXPECT_LT(RotationDistance(back.rotation, transform.rotation), 1e-13);
    EXPECT_LT((back.translation - transform.translation).norm(), 1e-12);
  }
}

TEST(Lie, Se3ExpIsMatrixExponential) {
  // A screw motion: quarter turn about z while advancing 2 along z, starting at
  // the axis through (1, 0, 0): the point (1, 0, 0) stays on the axis.
  const Eigen::Vector3d phi(0, 0, kPi / 2);
  const Eigen::Vector3d axis_point(1, 0, 0);
  const Eigen::Vector3d advance(0, 0, 2);
  // Tangent of the screw: rho = -phi x axis_point + advance (unit time).
  Vector6d xi;
  xi.head<3>() = phi;
  xi.tail<3>() = -phi.cross(axis_point) + advance;
  const Rigid3d transform = Se3Exp(xi);
  EXPECT_LT((transform * axis_point - (axis_point + advance)).norm(), 1e-14);
  EXPECT_LT((transform * Eigen::Vector3d(2, 0, 0) - Eigen::Vector3d(1, 1, 2)).norm(), 1e-14);
  // Pure translation.
  Vector6d translation = Vector6d::Zero();
  translation.tail<3>() << 1, 2, 3;
  EXPECT_LT((Se3Exp(translation).translation - Eigen::Vector3d(1, 2, 3)).norm(), 1e-15);
}

TEST(Lie, Se3AdjointConjugation) {
  Random random(6);
  for (int i = 0; i < 100; ++i) {
    const Rigid3d transform = Se3Exp(RandomTwist(random, 3.0));
    const Vector6d xi = RandomTwist(random, 1.0);
    const Rigid3d lhs = Se3Exp(Se3Adjoint(transform) * xi);
    const Rigid3d rhs = transform * Se3Exp(xi) * transform.Inverse();
    EXPECT_LT(RotationDistance(lhs.rotation, rhs.rotation), 1e-12);
    EXPECT_LT((lhs.translation - rhs.translation).norm(), 1e-11);
    // Ad(T^-1) = Ad(T)^-1 and Ad(A B) = Ad(A) Ad(B).
    EXPECT_LT(
        (Se3Adjoint(transform.Inverse()) * Se3Adjoint(transform) - Matrix6d::Identity()).norm(),
        1e-12);
  }
}

TEST(Lie, TemplatedLogMatchesDoubleAndHasExactDerivatives) {
  using Jet = ceres::Jet<double, 4>;
  Random random(7);
  for (int i = 0; i < 50; ++i) {
    const double angle = i == 0 ? 0.0 : (i < 10 ? 1e-9 * i : random.Uniform(0.0, 3.0));
    const Eigen::Quaterniond q = So3Exp(angle * RandomUnitVector(random));
    Jet q_xyzw[4];
    for (int k = 0; k < 4; ++k) q_xyzw[k] = Jet(q.coeffs()[k], k);
    Jet omega[3];
    QuaternionLogXyzw(q_xyzw, omega);
    const Eigen::Vector3d expected = So3Log(q);
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(omega[r].a, expected[r], 1e-15);
    // Derivative w.r.t. the raw coefficients, by central differences.
    constexpr double kStep = 1e-7;
    for (int k = 0; k < 4; ++k) {
      Eigen::Quaterniond plus = q;
      Eigen::Quaterniond minus = q;
      plus.coeffs()[k] += kStep;
      minus.coeffs()[k] -= kStep;
      const Eigen::Vector3d numeric = (So3Log(plus) - So3Log(minus)) / (2 * kStep);
      for (int r = 0; r < 3; ++r) {
        EXPECT_TRUE(std::isfinite(omega[r].v[k]));
        EXPECT_NEAR(omega[r].v[k], numeric[r], 1e-6) << "angle " << angle << " k " << k;
      }
    }
  }
}

TEST(Lie, TemplatedExpMatchesDouble) {
  using Jet = ceres::Jet<double, 3>;
  const Eigen::Matrix<Jet, 3, 1> zero(Jet(0.0, 0), Jet(0.0, 1), Jet(0.0, 2));
  const Eigen::Quaternion<Jet> q = QuaternionExp(zero);
  EXPECT_EQ(q.w().a, 1.0);
  // d(vec)/d(omega) = I / 2 at the identity.
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(q.vec()[r].v[c], r == c ? 0.5 : 0.0, 1e-15);
  }
  const Eigen::Vector3d omega(0.2, -1.0, 0.4);
  const Eigen::Quaterniond expected = So3Exp(omega);
  EXPECT_LT((QuaternionExp<double>(omega).coeffs() - expected.coeffs()).norm(), 1e-15);
}

}  // namespace
}  // namespace viosfm
