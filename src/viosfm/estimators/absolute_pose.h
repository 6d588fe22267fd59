// Absolute pose of a calibrated camera from 2D-3D correspondences (PnP):
// the P3P minimal solver, a linear (DLT) non-minimal solver for local
// optimisation, RANSAC (ransac.h) optionally seeded by a predicted pose, and
// a Levenberg-Marquardt refinement of the reprojection error.
//
// Image points are undistorted normalised coordinates (x/z, y/z of the ray);
// errors in pixels are converted with the camera's focal length (the mean of
// fx and fy), as two_view_geometry.h does.
//
// P3P (Grunert 1841, in the form of Haralick et al., IJCV 1994): with unit
// rays f1..f3, world points P1..P3, a = |P2 - P3|, b = |P1 - P3|,
// c = |P1 - P2| and the ray angles cos_alpha = f2.f3, cos_beta = f1.f3,
// cos_gamma = f1.f2, the depths s_i along the rays satisfy the three laws of
// cosines. With s2 = u s1 and s3 = v s1, u is a rational function of v and
// v a root of one quartic; each real positive root gives the camera points
// s_i f_i, and the pose is their rigid alignment to the world points (at
// most four solutions).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/estimators/ransac.h"
#include "viosfm/geometry/rigid3.h"

namespace viosfm {

// RANSAC estimators: x = normalised image points, y = world points, model
// cam_from_world; residual = squared reprojection error in normalised
// coordinates (a point at or behind the camera: 1e12).
struct P3PEstimator {
  using X_t = Eigen::Vector2d;
  using Y_t = Eigen::Vector3d;
  using M_t = Rigid3d;
  static constexpr int kMinNumSamples = 3;
  static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y);
  static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                        std::vector<double>* squared_residuals);
};

// Local optimisation: the DLT of the 3x4 projection matrix (6 or more
// points), its rotation made orthonormal, then refined (RefineAbsolutePose).
struct AbsolutePoseDltEstimator {
  using X_t = Eigen::Vector2d;
  using Y_t = Eigen::Vector3d;
  using M_t = Rigid3d;
  static constexpr int kMinNumSamples = 6;
  static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y);
  static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                        std::vector<double>* squared_residuals);
};

// Levenberg-Marquardt on the reprojection errors (normalised coordinates) of
// all given correspondences, from `initial`, with a Huber loss of scale
// huber_normalized (<= 0: plain squares). At most max_iterations.
Rigid3d RefineAbsolutePose(const std::vector<Eigen::Vector2d>& points_normalized,
                           const std::vector<Eigen::Vector3d>& points_in_world,
                           const Rigid3d& initial, int max_iterations = 20,
                           double huber_normalized = 0.0);

struct AbsolutePoseOptions {
  // Largest reprojection error of an inlier, pixels. Default 8 (the 2D-3D
  // matches of a frame include points triangulated by other frames, with
  // their own errors; COLMAP's registration allows 12).
  double max_error_px = 8.0;
  // A pose needs at least this many inliers. Default 15 (two-view
  // geometry's minimum).
  int min_num_inliers = 15;
  // RANSAC confidence and trial bounds. Defaults 0.999, 30 and 2000.
  double confidence = 0.999;
  int min_num_trials = 30;
  int max_num_trials = 2000;
  // Refine the RANSAC pose on its inliers (Levenberg-Marquardt). Default true.
  bool refine = true;
  uint64_t seed = kDefaultRandomSeed;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct AbsolutePoseResult {
  bool success = false;  // a pose with at least min_num_inliers inliers
  Rigid3d cam_from_world;
  size_t num_inliers = 0;
  std::vector<char> inlier_mask;  // per correspondence
  int num_trials = 0;
  // With a predicted pose: its inliers (before any refinement).
  size_t num_predicted_inliers = 0;
};

// PnP-RANSAC: P3P samples (and, when given, `predicted` scored first: a good
// prediction is kept and cuts the number of trials), LO with the DLT, then
// refinement on the inliers. focal_length_px converts max_error_px.
AbsolutePoseResult EstimateAbsolutePose(const std::vector<Eigen::Vector2d>& points_normalized,
                                        const std::vector<Eigen::Vector3d>& points_in_world,
                                        double focal_length_px, const AbsolutePoseOptions& options,
                                        const std::optional<Rigid3d>& predicted = std::nullopt);

// Correspondences that `cam_from_world` reprojects within max_error_px.
size_t CountAbsolutePoseInliers(const std::vector<Eigen::Vector2d>& points_normalized,
                                const std::vector<Eigen::Vector3d>& points_in_world,
                                const Rigid3d& cam_from_world, double focal_length_px,
                                double max_error_px);

}  // namespace viosfm
