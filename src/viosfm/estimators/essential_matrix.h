// Minimal and non-minimal solvers for the essential matrix, and its
// decomposition into a relative pose.
//
// Convention (as geometry/epipolar.h): for a point seen at normalised
// (undistorted, K^-1 applied) coordinates x1 in camera 1 and x2 in camera 2,
// x2^T E x1 = 0 and E = [t]x R for cam2_from_cam1 = (R, t).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "viosfm/geometry/rigid3.h"

namespace viosfm {

// Five-point solver (Stewenius, Engels, Nister 2006, re-derived here): the
// essential matrices consistent with five or more correspondences. With five
// points E lies in the 4-dimensional null space of the epipolar constraints;
// with more, in the span of the four right singular vectors of smallest
// singular value (a least-squares variant). The ten cubic constraints
// det(E) = 0 and 2 E E^T E - tr(E E^T) E = 0 are reduced by Gauss-Jordan
// elimination and the solutions read off the eigenvectors of a 10x10 action
// matrix. Returns up to 10 real solutions, each scaled to unit Frobenius
// norm; empty for fewer than five points or a degenerate configuration.
std::vector<Eigen::Matrix3d> EssentialMatrixFivePoint(const std::vector<Eigen::Vector2d>& points1,
                                                      const std::vector<Eigen::Vector2d>& points2);

// Linear eight-point estimate from eight or more correspondences (normalised
// coordinates), projected onto the essential manifold (singular values
// (1, 1, 0)). Empty for fewer than eight points.
std::vector<Eigen::Matrix3d> EssentialMatrixEightPoint(const std::vector<Eigen::Vector2d>& points1,
                                                       const std::vector<Eigen::Vector2d>& points2);

// The four (R, t) candidates of an essential matrix, |t| = 1:
// (R1, t), (R1, -t), (R2, t), (R2, -t).
std::array<Rigid3d, 4> DecomposeEssentialMatrix(const Eigen::Matrix3d& essential);

// Depths (d1, d2) with d2 x2 = d1 R x1 + t along the two rays (least
// squares); false for (nearly) parallel rays.
bool TriangulateDepths(const Rigid3d& cam2_from_cam1, const Eigen::Vector2d& point1,
                       const Eigen::Vector2d& point2, double* depth1, double* depth2);

// The candidate of DecomposeEssentialMatrix with the most correspondences
// triangulated in front of both cameras (cheirality). A point counts when
// both depths are positive and below kMaxCheiralityDepth baselines (points
// at infinity say nothing about the sign of t). Returns cam2_from_cam1 with
// |t| = 1; num_in_front (if not null) receives the count of the chosen
// candidate. The vectors must have equal sizes.
Rigid3d RelativePoseFromEssential(const Eigen::Matrix3d& essential,
                                  const std::vector<Eigen::Vector2d>& points1,
                                  const std::vector<Eigen::Vector2d>& points2,
                                  int* num_in_front = nullptr);

inline constexpr double kMaxCheiralityDepth = 1000.0;  // baselines

// The 5 local parameters of a relative pose with |t| = 1 (RefineRelativePose
// steps in them): delta = (rotation increment (3), step tangent to t (2));
// the result is (Exp(delta_0..2) R, normalise(t + delta_3 u1 + delta_4 u2))
// with (u1, u2) an orthonormal basis of the plane tangent to t.
Rigid3d RelativePosePlus(const Rigid3d& pose, const Eigen::Matrix<double, 5, 1>& delta);

// The orthonormal basis (u1, u2) of the plane tangent to the unit vector t
// that RelativePosePlus steps along, as columns.
Eigen::Matrix<double, 3, 2> DirectionTangentBasis(const Eigen::Vector3d& t);

// Signed Sampson errors r_i = x2^T E x1 / sqrt(|(E x1)_12|^2 + |(E^T x2)_12|^2)
// of the correspondences (normalised coordinates) under E = [t]x R of
// cam2_from_cam1 (|t| = 1), and, if `jacobian` is not null, their
// derivatives with respect to RelativePosePlus's delta at 0 (analytic).
void RelativePoseSampsonResiduals(const Rigid3d& cam2_from_cam1,
                                  const std::vector<Eigen::Vector2d>& points1,
                                  const std::vector<Eigen::Vector2d>& points2,
                                  Eigen::VectorXd* residuals,
                                  Eigen::Matrix<double, Eigen::Dynamic, 5>* jacobian);

// Refines cam2_from_cam1 (|t| = 1 kept) by Levenberg-Marquardt on the Sampson
// errors of the correspondences, over the 5 degrees of freedom of the
// essential matrix (rotation increment and a 2D step tangent to t). Runs at
// most max_iterations and returns the refined pose (the input if fewer than
// five correspondences).
Rigid3d RefineRelativePose(const Rigid3d& cam2_from_cam1,
                           const std::vector<Eigen::Vector2d>& points1,
                           const std::vector<Eigen::Vector2d>& points2, int max_iterations = 20);

}  // namespace viosfm
