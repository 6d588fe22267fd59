#include "viosfm/sfm/filters.h"

#include <cmath>
#include <sstream>
#include <vector>

#include "viosfm/scene/reprojection.h"
#include "viosfm/sfm/triangulator.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

std::string PointFilterOptions::Validate() const {
  if (!(max_reprojection_error_px > 0.0)) return "max_reprojection_error_px must be > 0";
  if (!(min_triangulation_angle_deg >= 0.0 && min_triangulation_angle_deg < 180.0)) {
    return "min_triangulation_angle_deg must be in [0, 180)";
  }
  return "";
}

std::string PointFilterStatistics::Summary() const {
  std::ostringstream out;
  out << "points " << num_points_before << " -> " << num_points_after << " (observations removed "
      << num_observations_removed << ", points removed: few observations "
      << num_points_removed_few_observations << ", small angle " << num_points_removed_small_angle
      << ")";
  return out.str();
}

size_t FilterObservationsWithLargeReprojectionError(Reconstruction* reconstruction,
                                                    double max_reprojection_error_px) {
  VIOSFM_CHECK(reconstruction != nullptr);
  size_t num_removed = 0;
  std::vector<TrackElement> bad;
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    const Point3D& point3D = reconstruction->GetPoint3D(point3D_id);
    bad.clear();
    for (const TrackElement& element : point3D.track) {
      const Image& image = reconstruction->GetImage(element.image_id);
      if (!image.registered) continue;
      const double error =
          ReprojectionErrorPx(reconstruction->GetCamera(image.camera_id), image.cam_from_world,
                              point3D.xyz, image.points2D.at(element.point2D_idx).xy);
      if (!(error <= max_reprojection_error_px)) bad.push_back(element);
    }
    // Deleting may delete the point (fewer than two observations left); its
    // remaining keypoints are then free and need no deletion.
    for (const TrackElement& element : bad) {
      if (!reconstruction->ExistsPoint3D(point3D_id)) break;
      reconstruction->DeleteObservation(element.image_id, element.point2D_idx);
      ++num_removed;
    }
  }
  return num_removed;
}

size_t FilterPointsWithSmallTriangulationAngle(Reconstruction* reconstruction,
                                               double min_triangulation_angle_deg) {
  VIOSFM_CHECK(reconstruction != nullptr);
  const double min_angle_rad = min_triangulation_angle_deg * kDegToRad;
  size_t num_removed = 0;
  std::vector<Eigen::Vector3d> centers;
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    const Point3D& point3D = reconstruction->GetPoint3D(point3D_id);
    centers.clear();
    for (const TrackElement& element : point3D.track) {
      const Image& image = reconstruction->GetImage(element.image_id);
      if (image.registered) centers.push_back(image.ProjectionCenter());
    }
    if (MaxTriangulationAngle(centers, point3D.xyz) < min_angle_rad) {
      reconstruction->DeletePoint3D(point3D_id);
      ++num_removed;
    }
  }
  return num_removed;
}

size_t FilterPointsWithFewObservations(Reconstruction* reconstruction) {
  VIOSFM_CHECK(reconstruction != nullptr);
  size_t num_removed = 0;
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    if (reconstruction->GetPoint3D(point3D_id).track.size() < 2) {
      reconstruction->DeletePoint3D(point3D_id);
      ++num_removed;
    }
  }
  return num_removed;
}

PointFilterStatistics FilterPoints(Reconstruction* reconstruction,
                                   const PointFilterOptions& options) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(options.Check()) << options.Validate();
  PointFilterStatistics stats;
  stats.num_points_before = reconstruction->NumPoints3D();
  stats.num_observations_removed = FilterObservationsWithLargeReprojectionError(
      reconstruction, options.max_reprojection_error_px);
  // Points DeleteObservation removed, plus any that had fewer than two
  // observations to begin with.
  stats.num_points_removed_few_observations =
      stats.num_points_before - reconstruction->NumPoints3D();
  stats.num_points_removed_few_observations += FilterPointsWithFewObservations(reconstruction);
  stats.num_points_removed_small_angle =
      FilterPointsWithSmallTriangulationAngle(reconstruction, options.min_triangulation_angle_deg);

  UpdateReprojectionErrors(reconstruction);
  stats.num_points_after = reconstruction->NumPoints3D();
  return stats;
}

}  // namespace viosfm
