#include "viosfm/sfm/triangulator.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/triangulation.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Gauss-Newton stops when a step moves the point by less than this fraction
// of its distance from the origin (plus one metre).
constexpr double kRefineStepTolerance = 1e-12;

double SquaredCost(const std::vector<TriangulationView>& views, const std::vector<size_t>& active,
                   const Eigen::Vector3d& point) {
  double cost = 0.0;
  for (size_t i : active) {
    const double error =
        ReprojectionErrorPx(*views[i].camera, views[i].cam_from_world, point, views[i].pixel);
    if (!std::isfinite(error)) return kInfinity;
    cost += error * error;
  }
  return cost;
}

// Gauss-Newton on the sum of squared pixel reprojection errors of the active
// views; a step is taken only if it lowers the cost.
Eigen::Vector3d RefinePoint(const std::vector<TriangulationView>& views,
                            const std::vector<size_t>& active, Eigen::Vector3d point,
                            int max_iterations) {
  double cost = SquaredCost(views, active, point);
  if (!std::isfinite(cost)) return point;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
    for (size_t i : active) {
      const TriangulationView& view = views[i];
      const Eigen::Vector3d point_in_cam = view.cam_from_world * point;
      const std::optional<Eigen::Vector2d> projected = Project(*view.camera, point_in_cam);
      if (!projected) return point;
      const Eigen::Vector2d residual = *projected - view.pixel;
      const Eigen::Matrix<double, 2, 3> jacobian =
          ProjectJacobianWrtPoint(*view.camera, point_in_cam) *
          view.cam_from_world.rotation.toRotationMatrix();
      hessian += jacobian.transpose() * jacobian;
      gradient += jacobian.transpose() * residual;
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(hessian);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) break;
    const Eigen::Vector3d step = -ldlt.solve(gradient);
    if (!step.allFinite()) break;
    const Eigen::Vector3d candidate = point + step;
    const double candidate_cost = SquaredCost(views, active, candidate);
    if (!(candidate_cost < cost)) break;
    point = candidate;
    cost = candidate_cost;
    if (step.norm() < kRefineStepTolerance * (1.0 + point.norm())) break;
  }
  return point;
}

// Counts one more `id` in `counts` (id, count), in order of first sight.
template <class Id>
void CountId(Id id, std::vector<std::pair<Id, size_t>>* counts) {
  auto it = std::find_if(counts->begin(), counts->end(),
                         [id](const auto& entry) { return entry.first == id; });
  if (it == counts->end()) {
    counts->emplace_back(id, 1);
  } else {
    ++it->second;
  }
}

}  // namespace

std::string TriangulationOptions::Validate() const {
  if (!(min_angle_deg > 0.0 && min_angle_deg < 180.0)) return "min_angle_deg must be in (0, 180)";
  if (!(max_reprojection_error_px > 0.0) || !std::isfinite(max_reprojection_error_px)) {
    return "max_reprojection_error_px must be > 0 and finite";
  }
  if (max_refine_iterations < 1) return "max_refine_iterations must be >= 1";
  return "";
}

namespace {

// The unit rays from the centres to the point (none from a centre at it).
std::vector<Eigen::Vector3d> UnitRays(const std::vector<Eigen::Vector3d>& centers,
                                      const Eigen::Vector3d& point_in_world) {
  std::vector<Eigen::Vector3d> rays;
  rays.reserve(centers.size());
  for (const Eigen::Vector3d& center : centers) {
    const Eigen::Vector3d ray = point_in_world - center;
    const double norm = ray.norm();
    if (norm > 0.0) rays.push_back(ray / norm);
  }
  return rays;
}

}  // namespace

double MaxTriangulationAngle(const std::vector<Eigen::Vector3d>& centers,
                             const Eigen::Vector3d& point_in_world) {
  // The largest angle is the smallest cosine between unit rays.
  const std::vector<Eigen::Vector3d> rays = UnitRays(centers, point_in_world);
  if (rays.size() < 2) return 0.0;
  size_t best_i = 0;
  size_t best_j = 1;
  double min_cosine = kInfinity;
  for (size_t i = 0; i < rays.size(); ++i) {
    for (size_t j = i + 1; j < rays.size(); ++j) {
      const double cosine = rays[i].dot(rays[j]);
      if (cosine < min_cosine) {
        min_cosine = cosine;
        best_i = i;
        best_j = j;
      }
    }
  }
  // atan2 of the best pair is accurate also for tiny angles (acos is not).
  return std::atan2(rays[best_i].cross(rays[best_j]).norm(), rays[best_i].dot(rays[best_j]));
}

bool ReachesTriangulationAngle(const std::vector<Eigen::Vector3d>& centers,
                               const Eigen::Vector3d& point_in_world, double min_angle_rad) {
  // A pair whose cosine is below the threshold's by more than rounding
  // decides; otherwise the largest angle is computed as MaxTriangulationAngle
  // does, so the answer is the same as comparing it.
  constexpr double kCosineMargin = 1e-12;
  const double cosine_threshold = std::cos(min_angle_rad) - kCosineMargin;
  const std::vector<Eigen::Vector3d> rays = UnitRays(centers, point_in_world);
  for (size_t i = 0; i < rays.size(); ++i) {
    for (size_t j = i + 1; j < rays.size(); ++j) {
      if (rays[i].dot(rays[j]) < cosine_threshold) return true;
    }
  }
  return MaxTriangulationAngle(centers, point_in_world) >= min_angle_rad;
}

std::optional<TrackTriangulation> TriangulateTrack(const std::vector<TriangulationView>& views,
                                                   const TriangulationOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  const size_t num_views = views.size();
  std::vector<Eigen::Vector2d> normalized(num_views);
  std::vector<Matrix3x4d> matrices(num_views);
  std::vector<size_t> active;
  active.reserve(num_views);
  for (size_t i = 0; i < num_views; ++i) {
    VIOSFM_CHECK(views[i].camera != nullptr) << "view " << i << " has no camera";
    normalized[i] = ImageToCam(*views[i].camera, views[i].pixel);
    matrices[i] = views[i].cam_from_world.ToMatrix();
    // A fisheye pixel beyond 90 degrees has no normalised coordinates.
    if (normalized[i].allFinite()) active.push_back(i);
  }

  std::optional<Eigen::Vector3d> accepted;
  std::vector<double> errors;
  while (active.size() >= 2) {
    std::vector<Matrix3x4d> active_matrices;
    std::vector<Eigen::Vector2d> active_normalized;
    for (size_t i : active) {
      active_matrices.push_back(matrices[i]);
      active_normalized.push_back(normalized[i]);
    }
    const std::optional<Eigen::Vector3d> dlt = TriangulateDlt(active_matrices, active_normalized);
    if (!dlt) return std::nullopt;
    Eigen::Vector3d point = *dlt;
    if (options.refine) point = RefinePoint(views, active, point, options.max_refine_iterations);

    // The worst view: behind the camera (most negative depth first), else
    // the largest reprojection error.
    errors.assign(active.size(), 0.0);
    size_t worst = 0;
    double worst_depth = kInfinity;
    double worst_error = -1.0;
    bool all_pass = true;
    for (size_t k = 0; k < active.size(); ++k) {
      const TriangulationView& view = views[active[k]];
      const double depth = (view.cam_from_world * point).z();
      errors[k] = ReprojectionErrorPx(*view.camera, view.cam_from_world, point, view.pixel);
      const bool in_front = std::isfinite(errors[k]);
      if (!in_front || errors[k] > options.max_reprojection_error_px) all_pass = false;
      const bool worse = !in_front ? (worst_error < kInfinity || depth < worst_depth)
                                   : (worst_error < kInfinity && errors[k] > worst_error);
      if (worse) {
        worst = k;
        worst_error = errors[k];
        worst_depth = in_front ? kInfinity : depth;
      }
    }
    if (all_pass) {
      accepted = point;
      break;
    }
    active.erase(active.begin() + static_cast<std::ptrdiff_t>(worst));
  }
  if (!accepted) return std::nullopt;

  std::vector<Eigen::Vector3d> centers;
  centers.reserve(active.size());
  for (size_t i : active) centers.push_back(ProjectionCenter(views[i].cam_from_world));
  const double max_angle_deg = MaxTriangulationAngle(centers, *accepted) * kDegreesPerRadian;
  if (!(max_angle_deg >= options.min_angle_deg)) return std::nullopt;

  TrackTriangulation result;
  result.point_in_world = *accepted;
  result.inlier_views = active;
  result.errors_px = errors;
  double sum = 0.0;
  for (double error : errors) sum += error;
  result.mean_error_px = sum / static_cast<double>(errors.size());
  result.max_angle_deg = max_angle_deg;
  return result;
}

std::string TriangulationStatistics::Summary() const {
  std::ostringstream out;
  out << "new points " << num_points_added << " of " << num_tracks_tried << " tracks tried ("
      << num_new_point_observations << " observations), extended points " << num_points_extended
      << " (+" << num_extension_observations << " observations), rejected observations "
      << num_rejected_observations;
  return out.str();
}

TriangulationStatistics TriangulateReconstruction(Reconstruction* reconstruction,
                                                  const std::vector<Track>& tracks,
                                                  const std::vector<image_t>& image_ids,
                                                  const TriangulationOptions& options) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(options.Check()) << options.Validate();
  std::vector<image_t> allowed = image_ids;
  std::sort(allowed.begin(), allowed.end());
  allowed.erase(std::unique(allowed.begin(), allowed.end()), allowed.end());
  for (image_t image_id : allowed) {
    VIOSFM_CHECK(reconstruction->ExistsImage(image_id)) << "no image " << image_id;
  }
  const auto is_allowed = [&allowed](image_t image_id) {
    return std::binary_search(allowed.begin(), allowed.end(), image_id);
  };

  TriangulationStatistics stats;
  std::vector<TrackElement> candidates;
  std::vector<std::pair<point3D_t, size_t>> point_counts;
  std::vector<TriangulationView> views;
  for (const Track& track : tracks) {
    candidates.clear();
    point_counts.clear();
    for (const TrackElement& element : track.elements) {
      if (!reconstruction->ExistsImage(element.image_id)) continue;
      const Image& image = reconstruction->GetImage(element.image_id);
      VIOSFM_CHECK_LT(element.point2D_idx, image.points2D.size())
          << "track element of image " << element.image_id << " out of range";
      if (!is_allowed(element.image_id)) continue;
      const point3D_t point3D_id = image.points2D[element.point2D_idx].point3D_id;
      if (point3D_id != kInvalidPoint3DId) {
        CountId(point3D_id, &point_counts);
      } else {
        candidates.push_back(element);
      }
    }

    if (point_counts.empty()) {
      if (candidates.size() < 2) continue;
      ++stats.num_tracks_tried;
      views.clear();
      for (const TrackElement& element : candidates) {
        const Image& image = reconstruction->GetImage(element.image_id);
        views.push_back({&reconstruction->GetCamera(image.camera_id), image.cam_from_world,
                         image.points2D[element.point2D_idx].xy});
      }
      const std::optional<TrackTriangulation> triangulation = TriangulateTrack(views, options);
      if (!triangulation) {
        stats.num_rejected_observations += candidates.size();
        continue;
      }
      Point3D point3D;
      point3D.xyz = triangulation->point_in_world;
      point3D.error = triangulation->mean_error_px;
      for (size_t i : triangulation->inlier_views) point3D.track.push_back(candidates[i]);
      stats.changed_point_ids.push_back(reconstruction->AddPoint3D(std::move(point3D)));
      ++stats.num_points_added;
      stats.num_new_point_observations += triangulation->inlier_views.size();
      stats.num_rejected_observations += candidates.size() - triangulation->inlier_views.size();
      continue;
    }

    // Extend the point the track observes most often.
    point3D_t point3D_id = point_counts.front().first;
    size_t best_count = point_counts.front().second;
    for (const auto& [id, count] : point_counts) {
      if (count > best_count || (count == best_count && id < point3D_id)) {
        point3D_id = id;
        best_count = count;
      }
    }
    const Eigen::Vector3d xyz = reconstruction->GetPoint3D(point3D_id).xyz;
    size_t num_added = 0;
    for (const TrackElement& element : candidates) {
      const std::vector<TrackElement>& point_track = reconstruction->GetPoint3D(point3D_id).track;
      const bool image_seen =
          std::any_of(point_track.begin(), point_track.end(),
                      [&element](const TrackElement& e) { return e.image_id == element.image_id; });
      if (image_seen) continue;
      const Image& image = reconstruction->GetImage(element.image_id);
      const double error =
          ReprojectionErrorPx(reconstruction->GetCamera(image.camera_id), image.cam_from_world, xyz,
                              image.points2D[element.point2D_idx].xy);
      if (error <= options.max_reprojection_error_px) {
        reconstruction->AddObservation(point3D_id, element);
        ++num_added;
      } else {
        ++stats.num_rejected_observations;
      }
    }
    if (num_added > 0) {
      stats.changed_point_ids.push_back(point3D_id);
      ++stats.num_points_extended;
      stats.num_extension_observations += num_added;
    }
  }
  return stats;
}

std::vector<point3D_t> MergeTrackPoints(Reconstruction* reconstruction,
                                        const std::vector<Track>& tracks,
                                        const TriangulationOptions& options) {
  VIOSFM_CHECK(reconstruction != nullptr);
  VIOSFM_CHECK(options.Check()) << options.Validate();
  std::vector<point3D_t> merged_into;
  std::vector<std::pair<point3D_t, size_t>> point_counts;
  for (const Track& track : tracks) {
    point_counts.clear();
    for (const TrackElement& element : track.elements) {
      if (!reconstruction->ExistsImage(element.image_id)) continue;
      const Image& image = reconstruction->GetImage(element.image_id);
      if (element.point2D_idx >= image.points2D.size()) continue;
      const point3D_t point3D_id = image.points2D[element.point2D_idx].point3D_id;
      if (point3D_id != kInvalidPoint3DId) CountId(point3D_id, &point_counts);
    }
    if (point_counts.size() < 2) continue;
    std::sort(point_counts.begin(), point_counts.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second > b.second : a.first < b.first;
    });
    const point3D_t into = point_counts.front().first;
    for (size_t k = 1; k < point_counts.size(); ++k) {
      const point3D_t from = point_counts[k].first;
      const Point3D& target = reconstruction->GetPoint3D(into);
      const std::vector<TrackElement> moved = reconstruction->GetPoint3D(from).track;
      const bool fits = std::all_of(moved.begin(), moved.end(), [&](const TrackElement& element) {
        const bool image_seen =
            std::any_of(target.track.begin(), target.track.end(),
                        [&](const TrackElement& e) { return e.image_id == element.image_id; });
        if (image_seen) return false;
        const Image& image = reconstruction->GetImage(element.image_id);
        if ((image.cam_from_world * target.xyz).z() <= 0.0) return false;
        return ReprojectionErrorPx(reconstruction->GetCamera(image.camera_id), image.cam_from_world,
                                   target.xyz, image.points2D[element.point2D_idx].xy) <=
               options.max_reprojection_error_px;
      });
      if (!fits) continue;
      reconstruction->DeletePoint3D(from);
      for (const TrackElement& element : moved) reconstruction->AddObservation(into, element);
      merged_into.push_back(into);
    }
  }
  return merged_into;
}

size_t SplitPointsByTracks(Reconstruction* reconstruction, const std::vector<Track>& tracks) {
  VIOSFM_CHECK(reconstruction != nullptr);
  constexpr size_t kNoTrack = SIZE_MAX;
  // The track of every keypoint of the model's images.
  std::unordered_map<image_t, std::vector<size_t>> track_of_keypoint;
  for (const image_t image_id : reconstruction->ImageIds()) {
    track_of_keypoint[image_id].assign(reconstruction->GetImage(image_id).points2D.size(),
                                       kNoTrack);
  }
  for (size_t t = 0; t < tracks.size(); ++t) {
    for (const TrackElement& element : tracks[t].elements) {
      const auto it = track_of_keypoint.find(element.image_id);
      if (it != track_of_keypoint.end() && element.point2D_idx < it->second.size()) {
        it->second[element.point2D_idx] = t;
      }
    }
  }
  size_t num_removed = 0;
  std::vector<std::pair<size_t, size_t>> track_counts;
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    const std::vector<TrackElement> observations = reconstruction->GetPoint3D(point3D_id).track;
    track_counts.clear();
    for (const TrackElement& element : observations) {
      CountId(track_of_keypoint.at(element.image_id)[element.point2D_idx], &track_counts);
    }
    if (track_counts.size() == 1 && track_counts.front().first != kNoTrack) continue;
    size_t keep = kNoTrack;
    size_t best = 0;
    for (const auto& [t, count] : track_counts) {
      if (t != kNoTrack && (count > best || (count == best && t < keep))) {
        keep = t;
        best = count;
      }
    }
    for (const TrackElement& element : observations) {
      if (track_of_keypoint.at(element.image_id)[element.point2D_idx] == keep) continue;
      // Deleting the last but one observation deletes the point: the rest
      // is then unlinked already.
      if (!reconstruction->ExistsPoint3D(point3D_id)) break;
      reconstruction->DeleteObservation(element.image_id, element.point2D_idx);
      ++num_removed;
    }
  }
  return num_removed;
}

}  // namespace viosfm
