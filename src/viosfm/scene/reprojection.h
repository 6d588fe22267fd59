// Reprojection errors of a reconstruction's observations, in pixels.
#pragma once

#include <Eigen/Core>
#include <vector>

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
// 0 without observations. Up to num_threads threads; the same result for any
// number.
double MeanReprojectionError(const Reconstruction& reconstruction, int num_threads = 1);
// The same over the observations in the images `image_ids` (registered ones;
// the others are skipped): its cost is theirs, not the whole model's.
double MeanReprojectionErrorInImages(const Reconstruction& reconstruction,
                                     const std::vector<image_t>& image_ids, int num_threads = 1);

// Writes each point's mean reprojection error (px, over its observations in
// registered images) to Point3D::error: +infinity if the point is behind a
// camera that observes it, -1 if it has no observation in a registered image.
// Returns MeanReprojectionError.
double UpdateReprojectionErrors(Reconstruction* reconstruction, int num_threads = 1);
// The same for the points `point3D_ids` only (ids that no longer exist are
// skipped); returns the mean over their observations.
double UpdateReprojectionErrors(Reconstruction* reconstruction,
                                const std::vector<point3D_t>& point3D_ids, int num_threads = 1);

}  // namespace viosfm
