#include "viosfm/scene/reprojection.h"

#include <cmath>
#include <limits>
#include <optional>

#include "viosfm/geometry/triangulation.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

double ObservationError(const Reconstruction& reconstruction, const Image& image,
                        const TrackElement& element, const Point3D& point3D) {
  return ReprojectionErrorPx(reconstruction.GetCamera(image.camera_id), image.cam_from_world,
                             point3D.xyz, image.points2D.at(element.point2D_idx).xy);
}

}  // namespace

double ReprojectionErrorPx(const Camera& camera, const Rigid3d& cam_from_world,
                           const Eigen::Vector3d& point_in_world, const Eigen::Vector2d& pixel) {
  if (!HasPositiveDepth(cam_from_world, point_in_world)) return kInfinity;
  const std::optional<Eigen::Vector2d> projected = Project(camera, cam_from_world * point_in_world);
  if (!projected) return kInfinity;
  return (*projected - pixel).norm();
}

double MeanReprojectionError(const Reconstruction& reconstruction) {
  double sum = 0.0;
  size_t count = 0;
  for (const auto& [point3D_id, point3D] : reconstruction.Points3D()) {
    for (const TrackElement& element : point3D.track) {
      const Image& image = reconstruction.GetImage(element.image_id);
      if (!image.registered) continue;
      const double error = ObservationError(reconstruction, image, element, point3D);
      if (!std::isfinite(error)) continue;
      sum += error;
      ++count;
    }
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

double UpdateReprojectionErrors(Reconstruction* reconstruction) {
  VIOSFM_CHECK(reconstruction != nullptr);
  double sum = 0.0;
  size_t count = 0;
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    Point3D& point3D = reconstruction->GetPoint3D(point3D_id);
    double point_sum = 0.0;
    size_t point_count = 0;
    bool behind = false;
    for (const TrackElement& element : point3D.track) {
      const Image& image = reconstruction->GetImage(element.image_id);
      if (!image.registered) continue;
      const double error = ObservationError(*reconstruction, image, element, point3D);
      if (!std::isfinite(error)) {
        behind = true;
        continue;
      }
      point_sum += error;
      ++point_count;
    }
    sum += point_sum;
    count += point_count;
    if (behind) {
      point3D.error = kInfinity;
    } else if (point_count == 0) {
      point3D.error = -1.0;
    } else {
      point3D.error = point_sum / static_cast<double>(point_count);
    }
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

}  // namespace viosfm
