#include "viosfm/sfm/camera_position_covariance.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <vector>

#include "viosfm/geometry/lie.h"
#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

// Root mean square of the reprojection errors' coordinates (px) over the
// registered images' observations in front of their cameras; 0 without any.
double KeypointSigma(const Reconstruction& reconstruction) {
  double sum_squares = 0.0;
  size_t coordinates = 0;
  for (const image_t image_id : reconstruction.RegImageIds()) {
    const Image& image = reconstruction.GetImage(image_id);
    const Camera& camera = reconstruction.GetCamera(image.camera_id);
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      const Eigen::Vector3d in_cam =
          image.cam_from_world * reconstruction.GetPoint3D(point2D.point3D_id).xyz;
      const std::optional<Eigen::Vector2d> pixel = Project(camera, in_cam);
      if (!pixel) continue;
      sum_squares += (*pixel - point2D.xy).squaredNorm();
      coordinates += 2;
    }
  }
  return coordinates > 0 ? std::sqrt(sum_squares / static_cast<double>(coordinates)) : 0.0;
}

}  // namespace

CameraPositionCovariances ComputeCameraPositionCovariances(
    const Reconstruction& reconstruction, const CameraPositionCovarianceOptions& options) {
  CameraPositionCovariances result;
  result.keypoint_sigma_px =
      options.keypoint_sigma_px > 0.0 ? options.keypoint_sigma_px : KeypointSigma(reconstruction);
  if (result.keypoint_sigma_px <= 0.0) return result;
  std::vector<image_t> registered = reconstruction.RegImageIds();
  std::sort(registered.begin(), registered.end());
  if (registered.empty()) return result;
  const Eigen::Vector3d gauge_centre =
      reconstruction.GetImage(registered.front()).ProjectionCenter();

  for (const image_t image_id : registered) {
    const Image& image = reconstruction.GetImage(image_id);
    const Camera& camera = reconstruction.GetCamera(image.camera_id);
    const Eigen::Matrix3d world_to_cam = image.cam_from_world.rotation.toRotationMatrix();
    // Parameters: the centre c (world) and a rotation d applied in the camera
    // frame, x = exp(d) R (X - c): dx/dc = -R, dx/dd = -Hat(x).
    Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
    int observations = 0;
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      const Eigen::Vector3d in_cam =
          image.cam_from_world * reconstruction.GetPoint3D(point2D.point3D_id).xyz;
      if (in_cam.z() <= 0.0) continue;
      Eigen::Matrix<double, 3, 6> d_point;
      d_point.leftCols<3>() = -world_to_cam;
      d_point.rightCols<3>() = -Hat(in_cam);
      const Eigen::Matrix<double, 2, 6> jacobian =
          ProjectJacobianWrtPoint(camera, in_cam) * d_point;
      information += jacobian.transpose() * jacobian;
      ++observations;
    }
    if (observations < 3) continue;
    information /= result.keypoint_sigma_px * result.keypoint_sigma_px;
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(information);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
        ldlt.vectorD().minCoeff() <= 1e-12 * ldlt.vectorD().maxCoeff()) {
      continue;
    }
    const Eigen::Matrix<double, 6, 6> covariance =
        ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
    Eigen::Matrix3d position = covariance.topLeftCorner<3, 3>();
    const Eigen::Vector3d offset = image.ProjectionCenter() - gauge_centre;
    position += options.scale_sigma * options.scale_sigma * offset * offset.transpose();
    result.by_image.emplace(image_id, 0.5 * (position + position.transpose()));
  }
  return result;
}

}  // namespace viosfm
