#include "viosfm/geometry/pose_parameters.h"

#include <ceres/product_manifold.h>

namespace viosfm {

PoseParameters ToPoseParameters(const Rigid3d& pose) {
  const Eigen::Quaterniond rotation = pose.rotation.normalized();
  return {rotation.x(),         rotation.y(),         rotation.z(),        rotation.w(),
          pose.translation.x(), pose.translation.y(), pose.translation.z()};
}

Rigid3d FromPoseParameters(const PoseParameters& pose) {
  return Rigid3d(Eigen::Quaterniond(pose[3], pose[0], pose[1], pose[2]).normalized(),
                 Eigen::Vector3d(pose[4], pose[5], pose[6]));
}

ceres::Manifold* CreatePoseManifold() {
  return new ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>();
}

}  // namespace viosfm
