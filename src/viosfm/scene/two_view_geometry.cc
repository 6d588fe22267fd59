#include "viosfm/scene/two_view_geometry.h"

#include <utility>

namespace viosfm {

std::string TwoViewGeometryConfigName(TwoViewGeometryConfig config) {
  switch (config) {
    case TwoViewGeometryConfig::kUndefined: return "UNDEFINED";
    case TwoViewGeometryConfig::kDegenerate: return "DEGENERATE";
    case TwoViewGeometryConfig::kCalibrated: return "CALIBRATED";
    case TwoViewGeometryConfig::kUncalibrated: return "UNCALIBRATED";
    case TwoViewGeometryConfig::kPlanar: return "PLANAR";
    case TwoViewGeometryConfig::kPanoramic: return "PANORAMIC";
    case TwoViewGeometryConfig::kPlanarOrPanoramic: return "PLANAR_OR_PANORAMIC";
    case TwoViewGeometryConfig::kWatermark: return "WATERMARK";
    case TwoViewGeometryConfig::kMultiple: return "MULTIPLE";
  }
  return "UNKNOWN(" + std::to_string(static_cast<int>(config)) + ")";
}

bool IsKnownTwoViewGeometryConfig(int value) {
  return value >= static_cast<int>(TwoViewGeometryConfig::kUndefined) &&
         value <= static_cast<int>(TwoViewGeometryConfig::kMultiple);
}

TwoViewGeometry TwoViewGeometry::Inverted() const {
  TwoViewGeometry inverted;
  inverted.config = config;
  inverted.F = F.transpose();
  inverted.E = E.transpose();
  // A homography that was never estimated is all zeros; keep it so rather
  // than inverting a singular matrix.
  inverted.H = H.isZero(0.0) ? H : Eigen::Matrix3d(H.inverse());
  inverted.cam2_from_cam1 = cam2_from_cam1.Inverse();
  inverted.inlier_matches.reserve(inlier_matches.size());
  for (const FeatureMatch& match : inlier_matches) {
    inverted.inlier_matches.push_back({match.point2D_idx2, match.point2D_idx1});
  }
  return inverted;
}

}  // namespace viosfm
