#include "viosfm/estimators/two_view_geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "viosfm/estimators/synthetic_test_scenes.h"
#include "viosfm/geometry/epipolar.h"
#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

using testing::DirectionErrorDeg;
using testing::MakeRandomTwoView;
using testing::RotationErrorDeg;

Camera TestCamera() {
  return MakeCamera(CameraModelId::kPinhole, 752, 480, {458.654, 457.296, 367.215, 248.375});
}

// A random scene with pixel noise on every point and a fraction of matches
// replaced by random points of image 2.
struct NoisyPair {
  testing::SyntheticTwoView view;
  std::vector<Eigen::Vector2d> points1;  // normalised, noisy
  std::vector<Eigen::Vector2d> points2;
  FeatureMatches matches;
  std::vector<char> is_inlier;
  int num_inliers = 0;
};

NoisyPair MakeNoisyPair(uint64_t seed, int count, double outlier_ratio, double noise_px,
                        double focal) {
  Random random(seed);
  NoisyPair pair;
  pair.view = MakeRandomTwoView(random, count);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d noise1(random.Normal(0, noise_px), random.Normal(0, noise_px));
    const Eigen::Vector2d noise2(random.Normal(0, noise_px), random.Normal(0, noise_px));
    pair.points1.push_back(pair.view.points1[i] + noise1 / focal);
    const bool inlier = random.Uniform() >= outlier_ratio;
    pair.points2.push_back(inlier ? Eigen::Vector2d(pair.view.points2[i] + noise2 / focal)
                                  : Eigen::Vector2d(random.Uniform(-1, 1), random.Uniform(-1, 1)));
    pair.is_inlier.push_back(inlier);
    pair.num_inliers += inlier;
    pair.matches.push_back({static_cast<point2D_t>(i), static_cast<point2D_t>(i)});
  }
  return pair;
}

// (correct inliers found, outliers accepted) for the result's inlier matches.
std::pair<int, int> CountInliers(const NoisyPair& pair, const TwoViewGeometryResult& result) {
  int correct = 0;
  int wrong = 0;
  for (const FeatureMatch& match : result.inlier_matches) {
    (pair.is_inlier[match.point2D_idx1] ? correct : wrong) += 1;
  }
  return {correct, wrong};
}

TEST(CalibratedTwoViewGeometry, RecoversPoseWith30PercentOutliers) {
  const Camera camera = TestCamera();
  const double focal = MeanFocalLength(camera);
  double worst_rotation = 0.0;
  double worst_direction = 0.0;
  for (uint64_t seed = 0; seed < 10; ++seed) {
    const NoisyPair pair = MakeNoisyPair(seed, 200, 0.3, 0.5, focal);
    TwoViewGeometryOptions options;
    options.seed = seed;
    const TwoViewGeometryResult result = EstimateCalibratedTwoViewGeometry(
        pair.points1, pair.points2, pair.matches, camera, camera, options);
    ASSERT_EQ(result.config, TwoViewGeometryConfig::kCalibrated) << "seed " << seed;
    const double rotation_error =
        RotationErrorDeg(result.cam2_from_cam1.rotation, pair.view.cam2_from_cam1.rotation);
    const double direction_error =
        DirectionErrorDeg(result.cam2_from_cam1.translation, pair.view.cam2_from_cam1.translation);
    worst_rotation = std::max(worst_rotation, rotation_error);
    worst_direction = std::max(worst_direction, direction_error);
    EXPECT_LT(rotation_error, 0.1) << "seed " << seed;
    EXPECT_LT(direction_error, 1.0) << "seed " << seed;
    const auto [correct, wrong] = CountInliers(pair, result);
    EXPECT_GE(correct, 0.95 * pair.num_inliers) << "seed " << seed;
    EXPECT_LE(wrong, 5) << "seed " << seed;
    EXPECT_EQ(result.num_tentative_matches, 200);
    EXPECT_GE(result.num_points_in_front, 0.95 * result.num_inliers());
    // F agrees with E through the calibration.
    const Eigen::Matrix3d k = CalibrationMatrix(camera);
    const Eigen::Vector2d pixel1 = (k * pair.view.points1[0].homogeneous()).hnormalized();
    const Eigen::Vector2d pixel2 = (k * pair.view.points2[0].homogeneous()).hnormalized();
    EXPECT_LT(EpipolarLineDistance(result.fundamental, pixel1, pixel2), 3.0);
  }
  std::cout << "10 scenes, 200 matches, 30% outliers, 0.5 px noise: worst rotation error "
            << worst_rotation << " deg, worst translation direction error " << worst_direction
            << " deg\n";
}

TEST(CalibratedTwoViewGeometry, ConvertsToTheDatabaseRecord) {
  const Camera camera = TestCamera();
  const NoisyPair pair = MakeNoisyPair(13, 100, 0.2, 0.5, MeanFocalLength(camera));
  const auto result = EstimateCalibratedTwoViewGeometry(pair.points1, pair.points2, pair.matches,
                                                        camera, camera, TwoViewGeometryOptions());
  ASSERT_TRUE(result.accepted());
  const TwoViewGeometry geometry = result.ToTwoViewGeometry();
  EXPECT_EQ(geometry.config, TwoViewGeometryConfig::kCalibrated);
  EXPECT_EQ(geometry.inlier_matches.size(), result.inlier_matches.size());
  EXPECT_EQ(geometry.E, result.essential);
  EXPECT_EQ(geometry.F, result.fundamental);
  EXPECT_EQ(geometry.H, Eigen::Matrix3d::Zero());
  EXPECT_EQ(geometry.cam2_from_cam1.translation, result.cam2_from_cam1.translation);
}

TEST(CalibratedTwoViewGeometry, SameSeedSameResult) {
  const Camera camera = TestCamera();
  const NoisyPair pair = MakeNoisyPair(11, 150, 0.4, 1.0, MeanFocalLength(camera));
  TwoViewGeometryOptions options;
  options.seed = 5;
  const auto first = EstimateCalibratedTwoViewGeometry(pair.points1, pair.points2, pair.matches,
                                                       camera, camera, options);
  const auto second = EstimateCalibratedTwoViewGeometry(pair.points1, pair.points2, pair.matches,
                                                        camera, camera, options);
  EXPECT_EQ(first.essential, second.essential);
  EXPECT_EQ(first.num_trials, second.num_trials);
  ASSERT_EQ(first.num_inliers(), second.num_inliers());
  for (int i = 0; i < first.num_inliers(); ++i) {
    EXPECT_EQ(first.inlier_matches[i].point2D_idx1, second.inlier_matches[i].point2D_idx1);
  }
}

TEST(CalibratedTwoViewGeometry, TooFewMatchesIsDegenerate) {
  const Camera camera = TestCamera();
  const NoisyPair pair = MakeNoisyPair(12, 14, 0.0, 0.0, MeanFocalLength(camera));
  const auto result = EstimateCalibratedTwoViewGeometry(pair.points1, pair.points2, pair.matches,
                                                        camera, camera, TwoViewGeometryOptions());
  EXPECT_EQ(result.config, TwoViewGeometryConfig::kDegenerate);
  EXPECT_EQ(result.num_inliers(), 0);
  EXPECT_FALSE(result.accepted());
}

TEST(UncalibratedTwoViewGeometry, RecoversFundamentalWith30PercentOutliers) {
  const Camera camera = TestCamera();
  const Eigen::Matrix3d k = CalibrationMatrix(camera);
  const auto to_pixels = [&](const std::vector<Eigen::Vector2d>& normalized) {
    std::vector<Eigen::Vector2d> pixels;
    for (const auto& point : normalized) pixels.push_back((k * point.homogeneous()).hnormalized());
    return pixels;
  };
  for (uint64_t seed = 20; seed < 25; ++seed) {
    const NoisyPair pair = MakeNoisyPair(seed, 200, 0.3, 0.5, MeanFocalLength(camera));
    TwoViewGeometryOptions options;
    options.seed = seed;
    const auto result = EstimateUncalibratedTwoViewGeometry(
        to_pixels(pair.points1), to_pixels(pair.points2), pair.matches, options);
    ASSERT_EQ(result.config, TwoViewGeometryConfig::kUncalibrated) << "seed " << seed;
    EXPECT_NEAR(result.fundamental.determinant(), 0.0, 1e-12);
    const auto [correct, wrong] = CountInliers(pair, result);
    EXPECT_GE(correct, 0.95 * pair.num_inliers) << "seed " << seed;
    EXPECT_LE(wrong, 5) << "seed " << seed;
    // The noise-free correspondences lie close to the estimated epipolar lines.
    const auto exact1 = to_pixels(pair.view.points1);
    const auto exact2 = to_pixels(pair.view.points2);
    std::vector<double> distances;
    for (size_t i = 0; i < exact1.size(); ++i) {
      distances.push_back(EpipolarLineDistance(result.fundamental, exact1[i], exact2[i]));
    }
    std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
    EXPECT_LT(distances[distances.size() / 2], 1.0) << "seed " << seed;
  }
}

TEST(TwoViewGeometryOptions, ValidateNamesTheBadField) {
  EXPECT_TRUE(TwoViewGeometryOptions().Check());
  TwoViewGeometryOptions options;
  options.max_error_px = 0.0;
  EXPECT_NE(options.Validate().find("max_error_px"), std::string::npos);
  options = TwoViewGeometryOptions();
  options.min_num_inliers = -1;
  EXPECT_NE(options.Validate().find("min_num_inliers"), std::string::npos);
  EXPECT_EQ(TwoViewGeometryOptions().max_error_px, 4.0);
  EXPECT_EQ(TwoViewGeometryOptions().min_num_inliers, 15);
}

}  // namespace
}  // namespace viosfm
