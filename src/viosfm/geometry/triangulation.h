// Two- and multi-view triangulation of a point from normalised image
// coordinates (K^-1 applied and distortion removed, i.e. (x/z, y/z) in the
// camera frame), and the checks that go with it.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "viosfm/geometry/rigid3.h"

namespace viosfm {

// Linear (DLT) triangulation from two or more views, solved by SVD of the
// stacked, row-normalised constraints x * P.row(2) - P.row(0), ...
// cams_from_world[i] is the 3x4 matrix [R | t] of view i and
// points_normalized[i] its observation. Returns nullopt if the sizes differ,
// there are fewer than two views, the solution is not unique (e.g. all rays
// identical) or the point is at infinity (parallel rays).
std::optional<Eigen::Vector3d> TriangulateDlt(
    const std::vector<Matrix3x4d>& cams_from_world,
    const std::vector<Eigen::Vector2d>& points_normalized);

// Two-view midpoint triangulation: the midpoint of the shortest segment
// between the two viewing rays (from the camera centres through the
// observations). Returns nullopt for (nearly) parallel rays. It does not
// check that the point lies in front of the cameras (see HasPositiveDepth).
std::optional<Eigen::Vector3d> TriangulateMidpoint(const Rigid3d& cam1_from_world,
                                                   const Rigid3d& cam2_from_world,
                                                   const Eigen::Vector2d& point1_normalized,
                                                   const Eigen::Vector2d& point2_normalized);

// Angle (radians, in [0, pi]) between the rays from center1 and center2 to
// point. Zero if the point coincides with a centre.
double TriangulationAngle(const Eigen::Vector3d& center1, const Eigen::Vector3d& center2,
                          const Eigen::Vector3d& point);

// Whether the point lies strictly in front of the camera (depth z > eps).
bool HasPositiveDepth(const Rigid3d& cam_from_world, const Eigen::Vector3d& point_in_world);
// Same for a 3x4 [R | t] matrix.
bool HasPositiveDepth(const Matrix3x4d& cam_from_world, const Eigen::Vector3d& point_in_world);

}  // namespace viosfm
