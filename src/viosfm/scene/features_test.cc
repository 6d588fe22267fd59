#include "viosfm/scene/features.h"

#include <gtest/gtest.h>

namespace viosfm {
namespace {

TEST(Features, PairIdsFollowColmap) {
  EXPECT_EQ(ImagePairToPairId(1, 2), 2147483647ull + 2);
  EXPECT_EQ(ImagePairToPairId(2, 1), ImagePairToPairId(1, 2));
  EXPECT_EQ(PairIdToImagePair(ImagePairToPairId(7, 3)), std::make_pair(image_t{3}, image_t{7}));
  EXPECT_EQ(PairIdToImagePair(ImagePairToPairId(123456, 2000000)),
            std::make_pair(image_t{123456}, image_t{2000000}));
}

TEST(Features, KeypointShapeRoundTrips) {
  const FeatureKeypoint keypoint = FeatureKeypoint::FromScaleOrientation(10.5f, 20.5f, 3.0f, 0.7f);
  EXPECT_NEAR(keypoint.Scale(), 3.0f, 1e-6f);
  EXPECT_NEAR(keypoint.Orientation(), 0.7f, 1e-6f);
}

}  // namespace
}  // namespace viosfm
