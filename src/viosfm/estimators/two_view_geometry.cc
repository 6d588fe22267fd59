#include "viosfm/estimators/two_view_geometry.h"

#include <cmath>
#include <utility>

#include "viosfm/estimators/essential_matrix.h"
#include "viosfm/estimators/fundamental_matrix.h"
#include "viosfm/geometry/epipolar.h"
#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

void SampsonResiduals(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y,
                      const Eigen::Matrix3d& matrix, std::vector<double>* squared_residuals) {
  squared_residuals->resize(x.size());
  for (size_t i = 0; i < x.size(); ++i) (*squared_residuals)[i] = SampsonError(matrix, x[i], y[i]);
}

// The matched points of both images, in match order.
void GatherMatchedPoints(const std::vector<Eigen::Vector2d>& points1,
                         const std::vector<Eigen::Vector2d>& points2, const FeatureMatches& matches,
                         std::vector<Eigen::Vector2d>* matched1,
                         std::vector<Eigen::Vector2d>* matched2) {
  matched1->resize(matches.size());
  matched2->resize(matches.size());
  for (size_t i = 0; i < matches.size(); ++i) {
    VIOSFM_CHECK_LT(matches[i].point2D_idx1, points1.size());
    VIOSFM_CHECK_LT(matches[i].point2D_idx2, points2.size());
    (*matched1)[i] = points1[matches[i].point2D_idx1];
    (*matched2)[i] = points2[matches[i].point2D_idx2];
  }
}

FeatureMatches SelectInliers(const FeatureMatches& matches, const std::vector<char>& mask) {
  FeatureMatches inliers;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (mask[i]) inliers.push_back(matches[i]);
  }
  return inliers;
}

}  // namespace

std::vector<Eigen::Matrix3d> EssentialMatrixFivePointEstimator::Estimate(
    const std::vector<X_t>& x, const std::vector<Y_t>& y) {
  return EssentialMatrixFivePoint(x, y);
}

void EssentialMatrixFivePointEstimator::Residuals(const std::vector<X_t>& x,
                                                  const std::vector<Y_t>& y, const M_t& model,
                                                  std::vector<double>* squared_residuals) {
  SampsonResiduals(x, y, model, squared_residuals);
}

std::vector<Eigen::Matrix3d> EssentialMatrixLocalEstimator::Estimate(const std::vector<X_t>& x,
                                                                     const std::vector<Y_t>& y) {
  std::vector<Eigen::Matrix3d> models = EssentialMatrixFivePoint(x, y);
  for (const Eigen::Matrix3d& model : EssentialMatrixEightPoint(x, y)) models.push_back(model);
  return models;
}

void EssentialMatrixLocalEstimator::Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y,
                                              const M_t& model,
                                              std::vector<double>* squared_residuals) {
  SampsonResiduals(x, y, model, squared_residuals);
}

std::vector<Eigen::Matrix3d> FundamentalMatrixSevenPointEstimator::Estimate(
    const std::vector<X_t>& x, const std::vector<Y_t>& y) {
  return FundamentalMatrixSevenPoint(x, y);
}

void FundamentalMatrixSevenPointEstimator::Residuals(const std::vector<X_t>& x,
                                                     const std::vector<Y_t>& y, const M_t& model,
                                                     std::vector<double>* squared_residuals) {
  SampsonResiduals(x, y, model, squared_residuals);
}

std::vector<Eigen::Matrix3d> FundamentalMatrixEightPointEstimator::Estimate(
    const std::vector<X_t>& x, const std::vector<Y_t>& y) {
  return FundamentalMatrixEightPoint(x, y);
}

void FundamentalMatrixEightPointEstimator::Residuals(const std::vector<X_t>& x,
                                                     const std::vector<Y_t>& y, const M_t& model,
                                                     std::vector<double>* squared_residuals) {
  SampsonResiduals(x, y, model, squared_residuals);
}

TwoViewGeometry TwoViewGeometryResult::ToTwoViewGeometry() const {
  TwoViewGeometry geometry;
  geometry.config = config;
  geometry.inlier_matches = inlier_matches;
  geometry.F = fundamental;
  geometry.E = essential;
  geometry.cam2_from_cam1 = cam2_from_cam1;
  return geometry;
}

RansacOptions TwoViewGeometryOptions::MakeRansacOptions(double max_error) const {
  RansacOptions ransac;
  ransac.max_error = max_error;
  ransac.confidence = confidence;
  ransac.min_num_trials = min_num_trials;
  ransac.max_num_trials = max_num_trials;
  ransac.local_optimization = local_optimization;
  ransac.seed = seed;
  return ransac;
}

std::string TwoViewGeometryOptions::Validate() const {
  if (!(max_error_px > 0.0) || !std::isfinite(max_error_px)) {
    return "max_error_px must be > 0 and finite";
  }
  if (min_num_inliers < 0) return "min_num_inliers must be >= 0";
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must be in (0, 1)";
  if (min_num_trials < 0) return "min_num_trials must be >= 0";
  if (max_num_trials < 1) return "max_num_trials must be >= 1";
  if (min_num_trials > max_num_trials) return "min_num_trials must be <= max_num_trials";
  return "";
}

TwoViewGeometryResult EstimateCalibratedTwoViewGeometry(
    const std::vector<Eigen::Vector2d>& points1_normalized,
    const std::vector<Eigen::Vector2d>& points2_normalized, const FeatureMatches& matches,
    const Camera& camera1, const Camera& camera2, const TwoViewGeometryOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  TwoViewGeometryResult result;
  result.num_tentative_matches = static_cast<int>(matches.size());
  result.config = TwoViewGeometryConfig::kDegenerate;
  if (matches.size() <
      static_cast<size_t>(
          std::max(options.min_num_inliers, EssentialMatrixFivePointEstimator::kMinNumSamples))) {
    return result;
  }
  std::vector<Eigen::Vector2d> matched1;
  std::vector<Eigen::Vector2d> matched2;
  GatherMatchedPoints(points1_normalized, points2_normalized, matches, &matched1, &matched2);

  const double focal = 0.5 * (MeanFocalLength(camera1) + MeanFocalLength(camera2));
  VIOSFM_CHECK_GT(focal, 0.0);
  const Ransac<EssentialMatrixFivePointEstimator, EssentialMatrixLocalEstimator> ransac(
      options.MakeRansacOptions(options.max_error_px / focal));
  const auto report = ransac.Estimate(matched1, matched2);
  result.num_trials = report.num_trials;
  if (!report.success) return result;
  result.inlier_matches = SelectInliers(matches, report.inlier_mask);
  result.essential = report.model;
  result.fundamental = FundamentalFromEssential(report.model, CalibrationMatrix(camera1),
                                                CalibrationMatrix(camera2));
  result.fundamental /= result.fundamental.norm();

  std::vector<Eigen::Vector2d> inliers1;
  std::vector<Eigen::Vector2d> inliers2;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (!report.inlier_mask[i]) continue;
    inliers1.push_back(matched1[i]);
    inliers2.push_back(matched2[i]);
  }
  result.cam2_from_cam1 = RelativePoseFromEssential(report.model, inliers1, inliers2);
  if (options.refine_relative_pose) {
    // Maximum-likelihood polish on the inliers; the inlier set is then
    // re-derived from the refined essential matrix.
    result.cam2_from_cam1 = RefineRelativePose(result.cam2_from_cam1, inliers1, inliers2);
    result.essential = EssentialFromRelativePose(result.cam2_from_cam1);
    result.essential /= result.essential.norm();
    const double max_squared = std::pow(options.max_error_px / focal, 2);
    FeatureMatches refined_matches;
    inliers1.clear();
    inliers2.clear();
    for (size_t i = 0; i < matches.size(); ++i) {
      if (SampsonError(result.essential, matched1[i], matched2[i]) > max_squared) continue;
      refined_matches.push_back(matches[i]);
      inliers1.push_back(matched1[i]);
      inliers2.push_back(matched2[i]);
    }
    result.inlier_matches = std::move(refined_matches);
    result.fundamental = FundamentalFromEssential(result.essential, CalibrationMatrix(camera1),
                                                  CalibrationMatrix(camera2));
    result.fundamental /= result.fundamental.norm();
  }
  RelativePoseFromEssential(result.essential, inliers1, inliers2, &result.num_points_in_front);
  if (result.num_inliers() >= options.min_num_inliers)
    result.config = TwoViewGeometryConfig::kCalibrated;
  return result;
}

TwoViewGeometryResult EstimateUncalibratedTwoViewGeometry(
    const std::vector<Eigen::Vector2d>& points1_px, const std::vector<Eigen::Vector2d>& points2_px,
    const FeatureMatches& matches, const TwoViewGeometryOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  TwoViewGeometryResult result;
  result.num_tentative_matches = static_cast<int>(matches.size());
  result.config = TwoViewGeometryConfig::kDegenerate;
  if (matches.size() <
      static_cast<size_t>(std::max(options.min_num_inliers,
                                   FundamentalMatrixEightPointEstimator::kMinNumSamples))) {
    return result;
  }
  std::vector<Eigen::Vector2d> matched1;
  std::vector<Eigen::Vector2d> matched2;
  GatherMatchedPoints(points1_px, points2_px, matches, &matched1, &matched2);
  const Ransac<FundamentalMatrixSevenPointEstimator, FundamentalMatrixEightPointEstimator> ransac(
      options.MakeRansacOptions(options.max_error_px));
  const auto report = ransac.Estimate(matched1, matched2);
  result.num_trials = report.num_trials;
  if (!report.success) return result;
  result.inlier_matches = SelectInliers(matches, report.inlier_mask);
  result.fundamental = report.model;
  if (result.num_inliers() >= options.min_num_inliers) {
    result.config = TwoViewGeometryConfig::kUncalibrated;
  }
  return result;
}

}  // namespace viosfm
