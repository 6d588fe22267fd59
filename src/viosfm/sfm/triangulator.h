// Multi-view triangulation of feature tracks, and adding the points of a set
// of tracks to a reconstruction (new points and new observations of existing
// points) - the step after each batch of images is registered.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/scene/reprojection.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sfm/tracks.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/types.h"

namespace viosfm {

struct TriangulationOptions {
  // A point is kept only if some pair of its views sees it under at least
  // this angle, degrees, > 0. Default 1.5 (COLMAP's).
  double min_angle_deg = 1.5;
  // Every view kept must reproject the point within this distance of its
  // keypoint, pixels, > 0. Default 4 (COLMAP's).
  double max_reprojection_error_px = 4.0;
  // Refine the DLT point by Gauss-Newton on the squared pixel reprojection
  // errors of the views used. Default true.
  bool refine = true;
  // Gauss-Newton iterations at most, >= 1. Default 10.
  int max_refine_iterations = 10;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"min_angle_deg", "deg, smallest triangulation angle", kRunOnly}, self.min_angle_deg);
    visit({"max_reprojection_error_px", "px, largest reprojection error", kRunOnly},
          self.max_reprojection_error_px);
    visit({"refine", "refine each point by Gauss-Newton", kRunOnly}, self.refine);
    visit({"max_refine_iterations", "iterations of the refinement", kRunOnly},
          self.max_refine_iterations);
  }
};

// One view of a track: its camera (intrinsics, not owned; must outlive the
// call), pose and keypoint in raw (distorted) pixels.
struct TriangulationView {
  const Camera* camera = nullptr;
  Rigid3d cam_from_world;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
};

struct TrackTriangulation {
  Eigen::Vector3d point_in_world = Eigen::Vector3d::Zero();
  // Indices (increasing) of the input views the point was accepted with;
  // the others were dropped as outliers.
  std::vector<size_t> inlier_views;
  // Reprojection error per inlier view, pixels, and their mean.
  std::vector<double> errors_px;
  double mean_error_px = 0.0;
  // Largest pairwise triangulation angle among the inlier views, degrees.
  double max_angle_deg = 0.0;
};

// Triangulates one track: DLT on the undistorted normalised coordinates of
// the views, optional Gauss-Newton refinement, then the checks - positive
// depth and reprojection error within the threshold in every view used. If a
// check fails, the worst view (behind the camera first, else the largest
// error) is dropped and the rest triangulated again, down to two views.
// Finally the largest pairwise triangulation angle of the views kept must
// reach min_angle_deg. Returns nullopt if no subset passes. CHECKs options
// and that every view has a camera; throws InputError for a camera model
// that cannot project.
std::optional<TrackTriangulation> TriangulateTrack(const std::vector<TriangulationView>& views,
                                                   const TriangulationOptions& options = {});

// Largest pairwise triangulation angle (radians) of a point seen from the
// given camera centres; 0 for fewer than two.
double MaxTriangulationAngle(const std::vector<Eigen::Vector3d>& centers,
                             const Eigen::Vector3d& point_in_world);
// Whether MaxTriangulationAngle(centers, point_in_world) >= min_angle_rad
// (in [0, pi]), stopping at the first pair clearly that wide: a long
// track's first rays usually are, where the largest angle looks at every pair.
bool ReachesTriangulationAngle(const std::vector<Eigen::Vector3d>& centers,
                               const Eigen::Vector3d& point_in_world, double min_angle_rad);

struct TriangulationStatistics {
  // Tracks with at least two free observations in the given images and no
  // 3D point yet, tried; and those that became points.
  size_t num_tracks_tried = 0;
  size_t num_points_added = 0;
  // Observations of the new points.
  size_t num_new_point_observations = 0;
  // Tracks already having a 3D point that gained observations, and those
  // observations.
  size_t num_points_extended = 0;
  size_t num_extension_observations = 0;
  // Observations not attached: outliers of new points and candidates for
  // extension that failed the depth or reprojection check.
  size_t num_rejected_observations = 0;
  // The points added or extended, in the order they were.
  std::vector<point3D_t> changed_point_ids;

  std::string Summary() const;
};

// For each track, considering only its observations in `image_ids` (images
// with known poses, usually the registered ones; they must exist and their
// keypoint indices must be in range, CHECK):
//  - if no observation observes a 3D point and at least two are free, the
//    track is triangulated (TriangulateTrack) and a point added with its
//    inlier observations (its `error` set to their mean reprojection error);
//  - if some observation observes a 3D point, the point observed most often
//    in the track (smallest id on ties) is extended by the track's free
//    observations in images it is not seen in yet, where the point is in
//    front of the camera and reprojects within max_reprojection_error_px.
// Points are added in track order, so a run is deterministic. Colours are
// left unset (the reconstruction holds no pixels).
TriangulationStatistics TriangulateReconstruction(Reconstruction* reconstruction,
                                                  const std::vector<Track>& tracks,
                                                  const std::vector<image_t>& image_ids,
                                                  const TriangulationOptions& options = {});

// Keeps each point within one track: a point whose observations lie in
// several of `tracks` (made from a part of a track that later matches split
// as a conflict, tracks.h) keeps those of the track holding most of them
// (the smallest track index on ties) and loses the others, as it loses any
// observation no track holds; a point left with fewer than two is deleted.
// Returns the observations removed.
size_t SplitPointsByTracks(Reconstruction* reconstruction, const std::vector<Track>& tracks);

// Joins the points a track's observations are split between (points made
// from parts of a track before the matches that join them were known, as
// when the mapper runs beside the verification): each other point of the
// track goes into the point the track observes most often (smallest id on
// ties), when none of its observations is in an image that point is seen
// in already and each reprojects the point in front of its camera within
// options.max_reprojection_error_px; otherwise it stays on its own.
// Returns the points others were joined into, once per join.
std::vector<point3D_t> MergeTrackPoints(Reconstruction* reconstruction,
                                        const std::vector<Track>& tracks,
                                        const TriangulationOptions& options = {});

}  // namespace viosfm
