#include "viosfm/sfm/filters.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "viosfm/scene/reprojection.h"
#include "viosfm/sfm/triangulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"

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

namespace {

// One point's registered observations judged: those to delete, and the sum
// and count of the finite errors of those kept (and whether one kept was
// behind its camera), from which its error after the deletions follows.
struct JudgedPoint {
  std::vector<TrackElement> bad;
  double kept_sum = 0.0;
  size_t kept_count = 0;
  bool kept_behind = false;
};

// Every point's observations judged against the threshold, point by point
// on up to num_threads threads (reading only).
std::vector<JudgedPoint> JudgeReprojection(const Reconstruction& model,
                                           double max_reprojection_error_px,
                                           const std::vector<point3D_t>& point3D_ids,
                                           int num_threads) {
  std::vector<JudgedPoint> judged(point3D_ids.size());
  ParallelForChunks(
      static_cast<int64_t>(point3D_ids.size()), num_threads, 1024, [&](int64_t begin, int64_t end) {
        for (int64_t k = begin; k < end; ++k) {
          if (!model.ExistsPoint3D(point3D_ids[k])) continue;
          const Point3D& point3D = model.GetPoint3D(point3D_ids[k]);
          JudgedPoint& point = judged[k];
          for (const TrackElement& element : point3D.track) {
            const Image& image = model.GetImage(element.image_id);
            if (!image.registered) continue;
            const double error =
                ReprojectionErrorPx(model.GetCamera(image.camera_id), image.cam_from_world,
                                    point3D.xyz, image.points2D.at(element.point2D_idx).xy);
            if (!(error <= max_reprojection_error_px)) {
              point.bad.push_back(element);
            } else if (!std::isfinite(error)) {
              point.kept_behind = true;
            } else {
              point.kept_sum += error;
              ++point.kept_count;
            }
          }
        }
      });
  return judged;
}

// Deletes the judged bad observations in order; returns how many.
size_t DeleteBadObservations(Reconstruction* reconstruction,
                             const std::vector<point3D_t>& point3D_ids,
                             const std::vector<JudgedPoint>& judged) {
  size_t num_removed = 0;
  for (size_t k = 0; k < point3D_ids.size(); ++k) {
    // Deleting may delete the point (fewer than two observations left); its
    // remaining keypoints are then free and need no deletion.
    for (const TrackElement& element : judged[k].bad) {
      if (!reconstruction->ExistsPoint3D(point3D_ids[k])) break;
      reconstruction->DeleteObservation(element.image_id, element.point2D_idx);
      ++num_removed;
    }
  }
  return num_removed;
}

}  // namespace

size_t FilterObservationsWithLargeReprojectionError(Reconstruction* reconstruction,
                                                    double max_reprojection_error_px,
                                                    const std::vector<point3D_t>& point3D_ids,
                                                    int num_threads) {
  VIOSFM_CHECK(reconstruction != nullptr);
  return DeleteBadObservations(
      reconstruction, point3D_ids,
      JudgeReprojection(*reconstruction, max_reprojection_error_px, point3D_ids, num_threads));
}

size_t FilterPointsWithSmallTriangulationAngle(Reconstruction* reconstruction,
                                               double min_triangulation_angle_deg,
                                               const std::vector<point3D_t>& point3D_ids,
                                               int num_threads) {
  VIOSFM_CHECK(reconstruction != nullptr);
  const double min_angle_rad = min_triangulation_angle_deg * kDegToRad;
  // Which points to delete, on up to num_threads threads, then deleted in order.
  std::vector<char> small(point3D_ids.size(), 0);
  const Reconstruction& model = *reconstruction;
  ParallelForChunks(static_cast<int64_t>(point3D_ids.size()), num_threads, 1024,
                    [&](int64_t begin, int64_t end) {
                      std::vector<Eigen::Vector3d> centers;
                      for (int64_t k = begin; k < end; ++k) {
                        if (!model.ExistsPoint3D(point3D_ids[k])) continue;
                        const Point3D& point3D = model.GetPoint3D(point3D_ids[k]);
                        centers.clear();
                        for (const TrackElement& element : point3D.track) {
                          const Image& image = model.GetImage(element.image_id);
                          if (image.registered) centers.push_back(image.ProjectionCenter());
                        }
                        small[k] = !ReachesTriangulationAngle(centers, point3D.xyz, min_angle_rad);
                      }
                    });
  size_t num_removed = 0;
  for (size_t k = 0; k < point3D_ids.size(); ++k) {
    if (!small[k] || !reconstruction->ExistsPoint3D(point3D_ids[k])) continue;
    reconstruction->DeletePoint3D(point3D_ids[k]);
    ++num_removed;
  }
  return num_removed;
}

size_t FilterPointsWithFewObservations(Reconstruction* reconstruction,
                                       const std::vector<point3D_t>& point3D_ids) {
  VIOSFM_CHECK(reconstruction != nullptr);
  size_t num_removed = 0;
  for (const point3D_t point3D_id : point3D_ids) {
    if (!reconstruction->ExistsPoint3D(point3D_id)) continue;
    if (reconstruction->GetPoint3D(point3D_id).track.size() < 2) {
      reconstruction->DeletePoint3D(point3D_id);
      ++num_removed;
    }
  }
  return num_removed;
}

PointFilterStatistics FilterPoints(Reconstruction* reconstruction,
                                   const PointFilterOptions& options, int num_threads) {
  VIOSFM_CHECK(reconstruction != nullptr);
  return FilterPoints(reconstruction, options, reconstruction->Point3DIds(), num_threads);
}

PointFilterStatistics FilterPoints(Reconstruction* reconstruction,
                                   const PointFilterOptions& options,
                                   const std::vector<point3D_t>& point3D_ids, int num_threads) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(options.Check()) << options.Validate();
  PointFilterStatistics stats;
  stats.num_points_before = reconstruction->NumPoints3D();
  const std::vector<JudgedPoint> judged = JudgeReprojection(
      *reconstruction, options.max_reprojection_error_px, point3D_ids, num_threads);
  stats.num_observations_removed = DeleteBadObservations(reconstruction, point3D_ids, judged);
  // Points DeleteObservation removed, plus any that had fewer than two
  // observations to begin with.
  stats.num_points_removed_few_observations =
      stats.num_points_before - reconstruction->NumPoints3D();
  stats.num_points_removed_few_observations +=
      FilterPointsWithFewObservations(reconstruction, point3D_ids);
  stats.num_points_removed_small_angle = FilterPointsWithSmallTriangulationAngle(
      reconstruction, options.min_triangulation_angle_deg, point3D_ids, num_threads);

  // Each remaining point's error, as UpdateReprojectionErrors computes it:
  // its kept observations' errors are those judged (nothing moved since),
  // summed in the track's order, which the deletions keep.
  for (size_t k = 0; k < point3D_ids.size(); ++k) {
    if (!reconstruction->ExistsPoint3D(point3D_ids[k])) continue;
    const JudgedPoint& point = judged[k];
    Point3D& point3D = reconstruction->GetPoint3D(point3D_ids[k]);
    if (point.kept_behind) {
      point3D.error = std::numeric_limits<double>::infinity();
    } else if (point.kept_count == 0) {
      point3D.error = -1.0;
    } else {
      point3D.error = point.kept_sum / static_cast<double>(point.kept_count);
    }
  }
  stats.num_points_after = reconstruction->NumPoints3D();
  return stats;
}

ObservedKeypoints::ObservedKeypoints(const Reconstruction& reconstruction,
                                     std::vector<image_t> image_ids)
    : image_ids_(std::move(image_ids)), observed_(image_ids_.size()) {
  for (size_t r = 0; r < image_ids_.size(); ++r) {
    const Image& image = reconstruction.GetImage(image_ids_[r]);
    observed_[r].resize(image.points2D.size());
    for (size_t k = 0; k < image.points2D.size(); ++k) {
      observed_[r][k] = image.points2D[k].HasPoint3D() ? 1 : 0;
    }
  }
}

size_t ObservedKeypoints::CountChanged(const Reconstruction& reconstruction) const {
  size_t changed = 0;
  for (size_t r = 0; r < image_ids_.size(); ++r) {
    const Image& image = reconstruction.GetImage(image_ids_[r]);
    VIOSFM_CHECK_EQ(image.points2D.size(), observed_[r].size());
    for (size_t k = 0; k < image.points2D.size(); ++k) {
      changed += (image.points2D[k].HasPoint3D() ? 1 : 0) != observed_[r][k] ? 1 : 0;
    }
  }
  return changed;
}

}  // namespace viosfm
