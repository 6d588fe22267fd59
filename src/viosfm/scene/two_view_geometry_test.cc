#include "viosfm/scene/two_view_geometry.h"

#include <gtest/gtest.h>

namespace viosfm {
namespace {

TEST(TwoViewGeometry, ConfigValuesAreColmaps) {
  EXPECT_EQ(static_cast<int>(TwoViewGeometryConfig::kCalibrated), 2);
  EXPECT_EQ(static_cast<int>(TwoViewGeometryConfig::kUncalibrated), 3);
  EXPECT_EQ(static_cast<int>(TwoViewGeometryConfig::kPlanarOrPanoramic), 6);
  EXPECT_EQ(static_cast<int>(TwoViewGeometryConfig::kMultiple), 8);
  EXPECT_EQ(TwoViewGeometryConfigName(TwoViewGeometryConfig::kWatermark), "WATERMARK");
  EXPECT_TRUE(IsKnownTwoViewGeometryConfig(0));
  EXPECT_TRUE(IsKnownTwoViewGeometryConfig(8));
  EXPECT_FALSE(IsKnownTwoViewGeometryConfig(9));
  EXPECT_FALSE(IsKnownTwoViewGeometryConfig(-1));
}

TEST(TwoViewGeometry, InvertedSwapsTheImages) {
  TwoViewGeometry geometry;
  geometry.config = TwoViewGeometryConfig::kCalibrated;
  geometry.inlier_matches = {{1, 7}, {4, 2}};
  geometry.cam2_from_cam1 =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())),
              Eigen::Vector3d(0.5, -0.2, 0.1));
  geometry.F << 0, -3, 2, 3, 0, -1, -2, 1, 0;
  geometry.E = geometry.F * 2.0;
  geometry.H << 2, 0.1, 3, 0, 1.5, -2, 0.001, 0, 1;

  const TwoViewGeometry inverted = geometry.Inverted();
  EXPECT_EQ(inverted.config, geometry.config);
  ASSERT_EQ(inverted.inlier_matches.size(), 2u);
  EXPECT_EQ(inverted.inlier_matches[0].point2D_idx1, 7u);
  EXPECT_EQ(inverted.inlier_matches[0].point2D_idx2, 1u);
  EXPECT_EQ(inverted.inlier_matches[1].point2D_idx1, 2u);
  EXPECT_EQ(inverted.inlier_matches[1].point2D_idx2, 4u);
  EXPECT_TRUE(inverted.F.isApprox(geometry.F.transpose()));
  EXPECT_TRUE(inverted.E.isApprox(geometry.E.transpose()));
  EXPECT_TRUE((inverted.H * geometry.H).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  const Rigid3d identity = inverted.cam2_from_cam1 * geometry.cam2_from_cam1;
  EXPECT_LT(identity.rotation.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  EXPECT_LT(identity.translation.norm(), 1e-12);

  // Inverting twice gives the original back.
  const TwoViewGeometry twice = inverted.Inverted();
  EXPECT_TRUE(twice.H.isApprox(geometry.H, 1e-12));
  EXPECT_EQ(twice.inlier_matches[1].point2D_idx1, 4u);
}

TEST(TwoViewGeometry, UnsetHomographyStaysZero) {
  const TwoViewGeometry inverted = TwoViewGeometry{}.Inverted();
  EXPECT_TRUE(inverted.H.isZero(0.0));
  EXPECT_TRUE(inverted.F.isZero(0.0));
}

}  // namespace
}  // namespace viosfm
