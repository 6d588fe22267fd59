// Reprojection errors of a reconstruction's observations, in pixels.
#pragma once

#include <Eigen/Core>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

// Reprojection error of a point in a view, pixels; infinity if the point is
// not in front of the camera.
double ReprojectionErrorPx(const Camera& camera, const Rigid3d& cam_from_world,
                           const Eigen::Vector3d& point_in_world, const Eigen::Vector2d& pixel);

// Mean reprojection error (px) over all observations of 3D points in
// registered images; observations behind their camera are not counted.
// 0 without observations.
double MeanReprojectionError(const Reconstruction& reconstruction);

// Writes each point's mean reprojection error (px, over its observations in
// registered images) to Point3D::error: +infinity if the point is behind a
// camera that observes it, -1 if it has no observation in a registered image.
// Returns MeanReprojectionError.
double UpdateReprojectionErrors(Reconstruction* reconstruction);

}  // namespace viosfm
