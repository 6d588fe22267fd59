// Solvers for the fundamental matrix (x2^T F x1 = 0, pixels).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace viosfm {

// Similarity transform T (3x3) that moves the centroid of the points to the
// origin and scales their mean distance from it to sqrt(2) (Hartley's
// normalisation). Identity scale if all points coincide.
Eigen::Matrix3d HartleyNormalization(const std::vector<Eigen::Vector2d>& points);

// Normalised eight-point algorithm from eight or more correspondences, rank
// 2 enforced by zeroing the smallest singular value. Returns one matrix of
// unit Frobenius norm, or nothing for fewer than eight points.
std::vector<Eigen::Matrix3d> FundamentalMatrixEightPoint(
    const std::vector<Eigen::Vector2d>& points1, const std::vector<Eigen::Vector2d>& points2);

// Seven-point algorithm (normalised): F = a F1 + (1 - a) F2 over the 2D null
// space, det(F) = 0 gives a cubic in a with one or three real roots. Uses
// the first seven correspondences. Returns 1 to 3 matrices of unit
// Frobenius norm (nothing for fewer than seven points).
std::vector<Eigen::Matrix3d> FundamentalMatrixSevenPoint(
    const std::vector<Eigen::Vector2d>& points1, const std::vector<Eigen::Vector2d>& points2);

// Real roots of c3 a^3 + c2 a^2 + c1 a + c0 (of the lower-degree polynomial
// if the leading coefficients vanish).
std::vector<double> SolveCubicReal(double c3, double c2, double c1, double c0);

}  // namespace viosfm
