// The verified geometry of an image pair, as COLMAP 3.8 stores it in the
// two_view_geometries table of its database: a configuration (COLMAP's enum
// values), the inlier matches, the fundamental, essential and homography
// matrices and the relative pose cam2_from_cam1.
//
// Convention (COLMAP's): for a match (x1 in image 1, x2 in image 2) in
// homogeneous pixels, x2^T F x1 = 0 and x2 ~ H x1; E relates normalised
// coordinates the same way; cam2_from_cam1 maps points from camera 1's frame
// to camera 2's.
#pragma once

#include <Eigen/Core>
#include <string>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/features.h"

namespace viosfm {

// COLMAP 3.8's TwoViewGeometry::ConfigurationType, with its integer values
// (these are what the database's `config` column holds).
enum class TwoViewGeometryConfig : int {
  kUndefined = 0,
  kDegenerate = 1,         // too few inliers for any model
  kCalibrated = 2,         // essential matrix (known intrinsics)
  kUncalibrated = 3,       // fundamental matrix
  kPlanar = 4,             // homography of a plane
  kPanoramic = 5,          // homography of a pure rotation
  kPlanarOrPanoramic = 6,  // homography, plane or rotation not resolved
  kWatermark = 7,          // pure 2D translation near the image border
  kMultiple = 8,           // several models (multiple motions)
};

// "CALIBRATED", ... (COLMAP's names); "UNKNOWN(<value>)" for other values.
std::string TwoViewGeometryConfigName(TwoViewGeometryConfig config);
// Whether an integer read from a file is one of the values above.
bool IsKnownTwoViewGeometryConfig(int value);

struct TwoViewGeometry {
  TwoViewGeometryConfig config = TwoViewGeometryConfig::kUndefined;
  // Pairs of keypoint indices (image 1, image 2) consistent with the geometry.
  FeatureMatches inlier_matches;
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  // Relative pose; translation has unit norm when estimated from E alone.
  Rigid3d cam2_from_cam1;

  // The same geometry with the two images swapped: F^T, E^T, H^-1,
  // cam1_from_cam2 and each match's indices exchanged (COLMAP's Invert()).
  // A zero (unset) H stays zero.
  TwoViewGeometry Inverted() const;
};

}  // namespace viosfm
