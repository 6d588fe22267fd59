// Synthetic two-view data with a known answer, for the estimators' tests
// (header-only; not part of the library's API).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/util/random.h"

namespace viosfm::testing {

struct SyntheticTwoView {
  Rigid3d cam2_from_cam1;
  std::vector<Eigen::Vector3d> points_in_cam1;
  std::vector<Eigen::Vector2d> points1;  // normalised coordinates in camera 1
  std::vector<Eigen::Vector2d> points2;  // normalised coordinates in camera 2
};

inline Eigen::Vector3d RandomUnitVector(Random& random) {
  return Eigen::Vector3d(random.Normal(), random.Normal(), random.Normal()).normalized();
}

// A random relative pose (rotation angle up to ~0.4 rad, baseline
// `baseline` in a random direction) and num_points points 2 to 10 baselines
// in front of camera 1, inside a 100 degree field of view of both cameras.
inline SyntheticTwoView MakeRandomTwoView(Random& random, int num_points, double baseline = 1.0) {
  SyntheticTwoView view;
  view.cam2_from_cam1 = Rigid3d(So3Exp(RandomUnitVector(random) * random.Uniform(0.05, 0.4)),
                                RandomUnitVector(random) * baseline);
  while (static_cast<int>(view.points_in_cam1.size()) < num_points) {
    const double depth = random.Uniform(2.0, 10.0) * baseline;
    const Eigen::Vector3d point(random.Uniform(-1, 1) * depth, random.Uniform(-1, 1) * depth,
                                depth);
    const Eigen::Vector3d point_in_cam2 = view.cam2_from_cam1 * point;
    if (point_in_cam2.z() < 0.5 * baseline) continue;
    const Eigen::Vector2d point2 = point_in_cam2.hnormalized();
    if (point2.cwiseAbs().maxCoeff() > 1.2) continue;
    view.points_in_cam1.push_back(point);
    view.points1.push_back(point.hnormalized());
    view.points2.push_back(point2);
  }
  return view;
}

// E / |E| with the sign that makes its largest-magnitude entry positive.
inline Eigen::Matrix3d NormalizeEpipolarMatrix(const Eigen::Matrix3d& matrix) {
  Eigen::Index row = 0;
  Eigen::Index col = 0;
  matrix.cwiseAbs().maxCoeff(&row, &col);
  const double sign = matrix(row, col) < 0.0 ? -1.0 : 1.0;
  return sign * matrix / matrix.norm();
}

// Smallest |normalised(a) - normalised(b)| over the candidates.
inline double MinEpipolarMatrixDistance(const std::vector<Eigen::Matrix3d>& candidates,
                                        const Eigen::Matrix3d& truth) {
  double best = INFINITY;
  for (const Eigen::Matrix3d& candidate : candidates) {
    best = std::min(best,
                    (NormalizeEpipolarMatrix(candidate) - NormalizeEpipolarMatrix(truth)).norm());
  }
  return best;
}

inline double RotationErrorDeg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return a.angularDistance(b) * 180.0 / M_PI;
}

inline double DirectionErrorDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

}  // namespace viosfm::testing
