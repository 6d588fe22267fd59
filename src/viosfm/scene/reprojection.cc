#include "viosfm/scene/reprojection.h"

#include <cmath>
#include <limits>
#include <optional>

#include "viosfm/geometry/triangulation.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"

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

namespace {

// Each point's sum and count of finite reprojection errors over its
// observations in registered images, and whether one was not finite (the
// point behind a camera), computed on up to num_threads threads.
struct PointErrors {
  double sum = 0.0;
  size_t count = 0;
  bool behind = false;
};

std::vector<PointErrors> ComputePointErrors(const Reconstruction& reconstruction,
                                            const std::vector<point3D_t>& point3D_ids,
                                            int num_threads) {
  std::vector<PointErrors> errors(point3D_ids.size());
  ParallelForChunks(
      static_cast<int64_t>(point3D_ids.size()), num_threads, 1024, [&](int64_t begin, int64_t end) {
        for (int64_t k = begin; k < end; ++k) {
          if (!reconstruction.ExistsPoint3D(point3D_ids[k])) continue;
          const Point3D& point3D = reconstruction.GetPoint3D(point3D_ids[k]);
          PointErrors& point = errors[k];
          for (const TrackElement& element : point3D.track) {
            const Image& image = reconstruction.GetImage(element.image_id);
            if (!image.registered) continue;
            const double error = ObservationError(reconstruction, image, element, point3D);
            if (!std::isfinite(error)) {
              point.behind = true;
              continue;
            }
            point.sum += error;
            ++point.count;
          }
        }
      });
  return errors;
}

}  // namespace

double MeanReprojectionError(const Reconstruction& reconstruction, int num_threads) {
  // Per point, then over the points in order: the same sum for any number
  // of threads.
  double sum = 0.0;
  size_t count = 0;
  for (const PointErrors& point :
       ComputePointErrors(reconstruction, reconstruction.Point3DIds(), num_threads)) {
    sum += point.sum;
    count += point.count;
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

double MeanReprojectionErrorInImages(const Reconstruction& reconstruction,
                                     const std::vector<image_t>& image_ids, int num_threads) {
  // Per image, then over the images in order: the same sum for any number
  // of threads.
  std::vector<PointErrors> errors(image_ids.size());
  ParallelForChunks(
      static_cast<int64_t>(image_ids.size()), num_threads, 16, [&](int64_t begin, int64_t end) {
        for (int64_t k = begin; k < end; ++k) {
          if (!reconstruction.ExistsImage(image_ids[k])) continue;
          const Image& image = reconstruction.GetImage(image_ids[k]);
          if (!image.registered) continue;
          const Camera& camera = reconstruction.GetCamera(image.camera_id);
          for (const Point2D& point2D : image.points2D) {
            if (!point2D.HasPoint3D()) continue;
            const double error =
                ReprojectionErrorPx(camera, image.cam_from_world,
                                    reconstruction.GetPoint3D(point2D.point3D_id).xyz, point2D.xy);
            if (!std::isfinite(error)) continue;
            errors[k].sum += error;
            ++errors[k].count;
          }
        }
      });
  double sum = 0.0;
  size_t count = 0;
  for (const PointErrors& image : errors) {
    sum += image.sum;
    count += image.count;
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

double UpdateReprojectionErrors(Reconstruction* reconstruction, int num_threads) {
  VIOSFM_CHECK(reconstruction != nullptr);
  return UpdateReprojectionErrors(reconstruction, reconstruction->Point3DIds(), num_threads);
}

double UpdateReprojectionErrors(Reconstruction* reconstruction,
                                const std::vector<point3D_t>& point3D_ids, int num_threads) {
  VIOSFM_CHECK(reconstruction != nullptr);
  const std::vector<PointErrors> errors =
      ComputePointErrors(*reconstruction, point3D_ids, num_threads);
  double sum = 0.0;
  size_t count = 0;
  for (size_t k = 0; k < point3D_ids.size(); ++k) {
    if (!reconstruction->ExistsPoint3D(point3D_ids[k])) continue;
    const PointErrors& point = errors[k];
    sum += point.sum;
    count += point.count;
    Point3D& point3D = reconstruction->GetPoint3D(point3D_ids[k]);
    if (point.behind) {
      point3D.error = kInfinity;
    } else if (point.count == 0) {
      point3D.error = -1.0;
    } else {
      point3D.error = point.sum / static_cast<double>(point.count);
    }
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

}  // namespace viosfm
