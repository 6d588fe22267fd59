// Robust two-view geometry of an image pair from its tentative matches:
// essential matrix RANSAC for calibrated cameras, fundamental matrix RANSAC
// otherwise.
//
// Errors are Sampson errors, the first-order approximation of the distance
// of a correspondence to the epipolar geometry. The calibrated path computes
// it on normalised coordinates and scales it by the mean focal length of the
// two cameras, so max_error_px is (approximately) in pixels; the
// uncalibrated path computes it directly in pixels.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/estimators/ransac.h"
#include "viosfm/geometry/epipolar.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/two_view_geometry.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

// RANSAC estimators (see ransac.h) on correspondences x (image 1) and y
// (image 2); residuals are squared Sampson errors.
struct EssentialMatrixFivePointEstimator {
  using X_t = Eigen::Vector2d;  // normalised coordinates in image 1
  using Y_t = Eigen::Vector2d;  // normalised coordinates in image 2
  using M_t = Eigen::Matrix3d;
  static constexpr int kMinNumSamples = 5;
  static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y);
  static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                        std::vector<double>* squared_residuals);
  static double SquaredResidual(const X_t& x, const Y_t& y, const M_t& model) {
    return SampsonError(model, x, y);
  }
};

// Local optimisation for the essential matrix: the least-squares five-point
// solutions and, with eight or more points, the linear eight-point estimate
// (RANSAC keeps whichever scores best).
struct EssentialMatrixLocalEstimator {
  using X_t = Eigen::Vector2d;
  using Y_t = Eigen::Vector2d;
  using M_t = Eigen::Matrix3d;
  static constexpr int kMinNumSamples = 5;
  static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y);
  static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                        std::vector<double>* squared_residuals);
  static double SquaredResidual(const X_t& x, const Y_t& y, const M_t& model) {
    return SampsonError(model, x, y);
  }
};

struct FundamentalMatrixSevenPointEstimator {
  using X_t = Eigen::Vector2d;  // pixels in image 1
  using Y_t = Eigen::Vector2d;  // pixels in image 2
  using M_t = Eigen::Matrix3d;
  static constexpr int kMinNumSamples = 7;
  static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y);
  static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                        std::vector<double>* squared_residuals);
  static double SquaredResidual(const X_t& x, const Y_t& y, const M_t& model) {
    return SampsonError(model, x, y);
  }
};

struct FundamentalMatrixEightPointEstimator {
  using X_t = Eigen::Vector2d;
  using Y_t = Eigen::Vector2d;
  using M_t = Eigen::Matrix3d;
  static constexpr int kMinNumSamples = 8;
  static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y);
  static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                        std::vector<double>* squared_residuals);
  static double SquaredResidual(const X_t& x, const Y_t& y, const M_t& model) {
    return SampsonError(model, x, y);
  }
};

struct TwoViewGeometryOptions {
  // Largest Sampson error of an inlier, pixels. Default 4 (COLMAP's).
  double max_error_px = 4.0;
  // A pair needs at least this many inliers to be kept. Default 15 (COLMAP's).
  int min_num_inliers = 15;
  // RANSAC confidence in (0, 1). Default 0.999 (COLMAP's).
  double confidence = 0.999;
  // RANSAC trial bounds. Defaults 30 and 10000.
  int min_num_trials = 30;
  int max_num_trials = 10000;
  // LO-RANSAC re-fitting on inliers. Default true.
  bool local_optimization = true;
  // Seed of the RANSAC sampler. Default kDefaultRandomSeed (0).
  uint64_t seed = kDefaultRandomSeed;
  // Calibrated path: refine the relative pose on the inliers by
  // Levenberg-Marquardt on the Sampson error (RefineRelativePose). Default true.
  bool refine_relative_pose = true;

  // The RANSAC options with max_error given in the estimator's unit.
  RansacOptions MakeRansacOptions(double max_error) const;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct TwoViewGeometryResult {
  // kCalibrated / kUncalibrated when the pair has at least min_num_inliers
  // inliers, kDegenerate otherwise.
  TwoViewGeometryConfig config = TwoViewGeometryConfig::kUndefined;
  Eigen::Matrix3d essential = Eigen::Matrix3d::Zero();    // unit norm; calibrated only
  Eigen::Matrix3d fundamental = Eigen::Matrix3d::Zero();  // unit norm; pixels of K
  // Calibrated only: relative pose with |t| = 1, chosen by cheirality.
  Rigid3d cam2_from_cam1;
  int num_points_in_front = 0;  // inliers in front of both cameras under cam2_from_cam1
  int num_tentative_matches = 0;
  int num_trials = 0;
  FeatureMatches inlier_matches;  // subset of the input matches, input order

  int num_inliers() const { return static_cast<int>(inlier_matches.size()); }
  // As stored in COLMAP's two_view_geometries table (H left zero).
  TwoViewGeometry ToTwoViewGeometry() const;
  bool accepted() const {
    return config == TwoViewGeometryConfig::kCalibrated ||
           config == TwoViewGeometryConfig::kUncalibrated;
  }
};

// Calibrated pair: points*_normalized are the undistorted normalised
// coordinates of all keypoints of each image (indexed by point2D_idx),
// matches index into them. The inlier threshold on the Sampson error in
// normalised coordinates is max_error_px / f, f the mean focal length of the
// two cameras (MeanFocalLength). fundamental = K2^-T E K1^-1 with the
// cameras' pinhole matrices.
TwoViewGeometryResult EstimateCalibratedTwoViewGeometry(
    const std::vector<Eigen::Vector2d>& points1_normalized,
    const std::vector<Eigen::Vector2d>& points2_normalized, const FeatureMatches& matches,
    const Camera& camera1, const Camera& camera2, const TwoViewGeometryOptions& options);

// Uncalibrated pair: points in pixels (undistorted if the lens is known),
// seven-point RANSAC with eight-point local optimisation, Sampson error in
// pixels.
TwoViewGeometryResult EstimateUncalibratedTwoViewGeometry(
    const std::vector<Eigen::Vector2d>& points1_px, const std::vector<Eigen::Vector2d>& points2_px,
    const FeatureMatches& matches, const TwoViewGeometryOptions& options);

}  // namespace viosfm
