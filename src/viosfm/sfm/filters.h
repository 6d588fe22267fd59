// Filtering 3D points after bundle adjustment: observations that reproject
// too far from their keypoint, points seen under too small an angle, points
// left with fewer than two observations.
//
// Only observations in registered images are judged (and count towards the
// angle); observations in unregistered images are left as they are.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "viosfm/scene/reconstruction.h"
#include "viosfm/util/option_fields.h"

namespace viosfm {

struct PointFilterOptions {
  // Observations reprojecting farther than this from their keypoint (or
  // behind the camera) are deleted, pixels, > 0. Default 4 (COLMAP's
  // filter_max_reproj_error).
  double max_reprojection_error_px = 4.0;
  // Points whose largest pairwise triangulation angle over their registered
  // observations is below this are deleted, degrees, >= 0. Default 1.5
  // (COLMAP's filter_min_tri_angle).
  double min_triangulation_angle_deg = 1.5;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"max_reprojection_error_px", "px, observations farther are removed", kRunOnly},
          self.max_reprojection_error_px);
    visit({"min_triangulation_angle_deg", "deg, points seen under less are removed", kRunOnly},
          self.min_triangulation_angle_deg);
  }
};

struct PointFilterStatistics {
  size_t num_points_before = 0;
  // Observations deleted for their reprojection error (or negative depth).
  size_t num_observations_removed = 0;
  // Points deleted because fewer than two observations remained.
  size_t num_points_removed_few_observations = 0;
  // Points deleted for their small triangulation angle.
  size_t num_points_removed_small_angle = 0;
  size_t num_points_after = 0;

  std::string Summary() const;
};

// Each of the three filters below looks at the points `point3D_ids` only
// (ids that no longer exist are skipped; Reconstruction::Point3DIds() for
// all), checked on up to num_threads threads with the same result for any
// number.

// Deletes observations with a reprojection error above the threshold.
// Returns the number deleted; a point left with fewer than two observations
// is deleted with them (Reconstruction::DeleteObservation).
size_t FilterObservationsWithLargeReprojectionError(Reconstruction* reconstruction,
                                                    double max_reprojection_error_px,
                                                    const std::vector<point3D_t>& point3D_ids,
                                                    int num_threads = 1);

// Deletes points whose largest triangulation angle is below the threshold.
// Returns the number of points deleted.
size_t FilterPointsWithSmallTriangulationAngle(Reconstruction* reconstruction,
                                               double min_triangulation_angle_deg,
                                               const std::vector<point3D_t>& point3D_ids,
                                               int num_threads = 1);

// Deletes points with fewer than two observations. Returns the number deleted.
size_t FilterPointsWithFewObservations(Reconstruction* reconstruction,
                                       const std::vector<point3D_t>& point3D_ids);

// All three, in that order, and sets each remaining point's `error` to the
// mean reprojection error of its registered observations (on up to
// num_threads threads, the same result for any number). CHECKs options.
PointFilterStatistics FilterPoints(Reconstruction* reconstruction,
                                   const PointFilterOptions& options = {}, int num_threads = 1);
// All three over the points `point3D_ids` only. Filtering is per point: on
// a reconstruction already filtered, checking only the points whose
// position, track or observing poses changed since gives the same result as
// checking all of them.
PointFilterStatistics FilterPoints(Reconstruction* reconstruction,
                                   const PointFilterOptions& options,
                                   const std::vector<point3D_t>& point3D_ids, int num_threads = 1);

// Which keypoints of some images observe a 3D point, to measure what a
// filtering and a re-triangulation changed since: CountChanged counts the
// keypoints that observe a point and did not, or did and do not. A keypoint
// whose observation was deleted and then attached again (to a point
// triangulated anew, or to the same one) is not a change. The images must
// still exist with the same keypoints (CHECK).
class ObservedKeypoints {
 public:
  ObservedKeypoints(const Reconstruction& reconstruction, std::vector<image_t> image_ids);
  size_t CountChanged(const Reconstruction& reconstruction) const;

 private:
  std::vector<image_t> image_ids_;
  std::vector<std::vector<char>> observed_;
};

}  // namespace viosfm
