// A rigid pose as one Ceres parameter block, shared by every layer that
// optimises poses (ba/ for the bundle adjustment, vio/ for the sliding
// window): the block layout [qx, qy, qz, qw, tx, ty, tz] (Eigen's
// quaternion memory order, Hamilton convention) and its manifold.
#pragma once

#include <ceres/manifold.h>

#include <array>

#include "viosfm/geometry/rigid3.h"

namespace viosfm {

// A pose as one parameter block: [qx, qy, qz, qw, tx, ty, tz].
using PoseParameters = std::array<double, 7>;
PoseParameters ToPoseParameters(const Rigid3d& pose);
// The pose of a block (its quaternion normalised).
Rigid3d FromPoseParameters(const PoseParameters& pose);

// The manifold of a pose block: EigenQuaternionManifold x R^3 (6 degrees of
// freedom; the quaternion stays unit). The caller owns it (ceres::Problem
// does once it is set).
ceres::Manifold* CreatePoseManifold();

}  // namespace viosfm
