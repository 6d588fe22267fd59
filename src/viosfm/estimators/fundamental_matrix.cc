#include "viosfm/estimators/fundamental_matrix.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// Null-space basis of the epipolar constraints on Hartley-normalised points.
Eigen::MatrixXd NormalizedConstraints(const std::vector<Eigen::Vector2d>& points1,
                                      const std::vector<Eigen::Vector2d>& points2, size_t count,
                                      const Eigen::Matrix3d& transform1,
                                      const Eigen::Matrix3d& transform2) {
  Eigen::MatrixXd constraints(count, 9);
  for (size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d x1 = transform1 * points1[i].homogeneous();
    const Eigen::Vector3d x2 = transform2 * points2[i].homogeneous();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) constraints(i, 3 * r + c) = x2[r] * x1[c];
    }
  }
  return constraints;
}

Eigen::Matrix3d Denormalize(const Eigen::Matrix3d& normalized, const Eigen::Matrix3d& transform1,
                            const Eigen::Matrix3d& transform2) {
  const Eigen::Matrix3d fundamental = transform2.transpose() * normalized * transform1;
  return fundamental / fundamental.norm();
}

}  // namespace

Eigen::Matrix3d HartleyNormalization(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& point : points) centroid += point;
  if (!points.empty()) centroid /= static_cast<double>(points.size());
  double mean_distance = 0.0;
  for (const Eigen::Vector2d& point : points) mean_distance += (point - centroid).norm();
  if (!points.empty()) mean_distance /= static_cast<double>(points.size());
  const double scale = mean_distance > 0.0 ? std::sqrt(2.0) / mean_distance : 1.0;
  Eigen::Matrix3d transform;
  transform << scale, 0, -scale * centroid.x(), 0, scale, -scale * centroid.y(), 0, 0, 1;
  return transform;
}

std::vector<Eigen::Matrix3d> FundamentalMatrixEightPoint(
    const std::vector<Eigen::Vector2d>& points1, const std::vector<Eigen::Vector2d>& points2) {
  VIOSFM_CHECK_EQ(points1.size(), points2.size());
  if (points1.size() < 8) return {};
  const Eigen::Matrix3d transform1 = HartleyNormalization(points1);
  const Eigen::Matrix3d transform2 = HartleyNormalization(points2);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(
      NormalizedConstraints(points1, points2, points1.size(), transform1, transform2),
      Eigen::ComputeFullV);
  const Eigen::Matrix3d linear = Matrix3FromRowMajor(svd.matrixV().col(8));
  // Rank 2: the nearest matrix in Frobenius norm with a zero singular value.
  const Eigen::JacobiSVD<Eigen::Matrix3d> rank(linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d singular = rank.singularValues();
  singular[2] = 0.0;
  const Eigen::Matrix3d normalized =
      rank.matrixU() * singular.asDiagonal() * rank.matrixV().transpose();
  return {Denormalize(normalized, transform1, transform2)};
}

std::vector<Eigen::Matrix3d> FundamentalMatrixSevenPoint(
    const std::vector<Eigen::Vector2d>& points1, const std::vector<Eigen::Vector2d>& points2) {
  VIOSFM_CHECK_EQ(points1.size(), points2.size());
  if (points1.size() < 7) return {};
  const std::vector<Eigen::Vector2d> first1(points1.begin(), points1.begin() + 7);
  const std::vector<Eigen::Vector2d> first2(points2.begin(), points2.begin() + 7);
  const Eigen::Matrix3d transform1 = HartleyNormalization(first1);
  const Eigen::Matrix3d transform2 = HartleyNormalization(first2);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(
      NormalizedConstraints(first1, first2, 7, transform1, transform2), Eigen::ComputeFullV);
  const Eigen::Matrix3d f1 = Matrix3FromRowMajor(svd.matrixV().col(7));
  const Eigen::Matrix3d f2 = Matrix3FromRowMajor(svd.matrixV().col(8));
  // det(f2 + a (f1 - f2)) = c3 a^3 + c2 a^2 + c1 a + c0, recovered exactly
  // from its values at a = 0, 1, -1, 2.
  const Eigen::Matrix3d difference = f1 - f2;
  const auto det_at = [&](double a) { return (f2 + a * difference).determinant(); };
  const double p0 = det_at(0.0);
  const double p1 = det_at(1.0);
  const double pm1 = det_at(-1.0);
  const double p2 = det_at(2.0);
  const double c0 = p0;
  const double c2 = 0.5 * (p1 + pm1) - c0;
  const double odd = 0.5 * (p1 - pm1);  // c1 + c3
  const double c3 = (p2 - c0 - 4.0 * c2 - 2.0 * odd) / 6.0;
  const double c1 = odd - c3;
  std::vector<Eigen::Matrix3d> solutions;
  for (const double a : SolveCubicReal(c3, c2, c1, c0)) {
    solutions.push_back(Denormalize(f2 + a * difference, transform1, transform2));
  }
  return solutions;
}

std::vector<double> SolveCubicReal(double c3, double c2, double c1, double c0) {
  const double scale = std::max({std::abs(c3), std::abs(c2), std::abs(c1), std::abs(c0)});
  if (!(scale > 0.0)) return {};
  const double tiny = 1e-14 * scale;
  std::vector<double> roots;
  if (std::abs(c3) <= tiny) {
    if (std::abs(c2) <= tiny) {
      if (std::abs(c1) > tiny) roots.push_back(-c0 / c1);
      return roots;
    }
    const double discriminant = c1 * c1 - 4.0 * c2 * c0;
    if (discriminant < 0.0) return roots;
    // Numerically stable quadratic formula.
    const double q = -0.5 * (c1 + std::copysign(std::sqrt(discriminant), c1));
    roots.push_back(q / c2);
    if (q != 0.0) roots.push_back(c0 / q);
    return roots;
  }
  Eigen::Matrix3d companion = Eigen::Matrix3d::Zero();
  companion(0, 0) = -c2 / c3;
  companion(0, 1) = -c1 / c3;
  companion(0, 2) = -c0 / c3;
  companion(1, 0) = 1.0;
  companion(2, 1) = 1.0;
  const Eigen::EigenSolver<Eigen::Matrix3d> eigen(companion, false);
  for (int i = 0; i < 3; ++i) {
    const std::complex<double> value = eigen.eigenvalues()[i];
    if (std::abs(value.imag()) > 1e-8 * std::max(1.0, std::abs(value.real()))) continue;
    // One Newton step polishes the root (kept only if it reduces the residual).
    const auto evaluate = [&](double a) { return ((c3 * a + c2) * a + c1) * a + c0; };
    double a = value.real();
    const double df = (3.0 * c3 * a + 2.0 * c2) * a + c1;
    if (df != 0.0) {
      const double polished = a - evaluate(a) / df;
      if (std::abs(evaluate(polished)) < std::abs(evaluate(a))) a = polished;
    }
    roots.push_back(a);
  }
  return roots;
}

}  // namespace viosfm
