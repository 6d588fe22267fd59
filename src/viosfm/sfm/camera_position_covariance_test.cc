#include "viosfm/sfm/camera_position_covariance.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "viosfm/estimators/absolute_pose.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

constexpr double kFocal = 500.0;

// Image 1 at the origin looking along +z and image 2 one metre to the right
// and 0.3 m up, turned 10 degrees about y; `num_points` points 2 to 6 m
// ahead seen by both (image 3 sees only the first two). Keypoints are the
// exact projections plus `noise_px` of Gaussian noise (seed 7).
Reconstruction TwoViewScene(int num_points, double noise_px) {
  Reconstruction reconstruction;
  Camera camera = MakeCamera(CameraModelId::kPinhole, 752, 480, {kFocal, kFocal, 376.0, 240.0});
  camera.camera_id = 1;
  reconstruction.AddCamera(camera);
  const std::vector<Rigid3d> poses = {
      Rigid3d(),
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.17, Eigen::Vector3d::UnitY())),
              Eigen::Vector3d(-1.0, -0.3, 0.0)),
      Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.5, 0.0, 0.0))};
  Random random(7);
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < num_points; ++k) {
    points.emplace_back(random.Uniform(-1.5, 1.5), random.Uniform(-1.0, 1.0),
                        random.Uniform(2.0, 6.0));
  }
  for (size_t i = 0; i < poses.size(); ++i) {
    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.camera_id = 1;
    image.name = std::to_string(i + 1) + ".png";
    image.cam_from_world = poses[i];
    image.registered = true;
    const size_t seen = i == 2 ? 2 : points.size();
    for (size_t k = 0; k < seen; ++k) {
      Point2D point2D;
      point2D.xy = *Project(camera, poses[i] * points[k]) +
                   Eigen::Vector2d(random.Normal(0.0, noise_px), random.Normal(0.0, noise_px));
      image.points2D.push_back(point2D);
    }
    reconstruction.AddImage(image);
  }
  for (size_t k = 0; k < points.size(); ++k) {
    Point3D point;
    point.xyz = points[k];
    point.track.push_back({1, static_cast<point2D_t>(k)});
    point.track.push_back({2, static_cast<point2D_t>(k)});
    if (k < 2) point.track.push_back({3, static_cast<point2D_t>(k)});
    reconstruction.AddPoint3D(point);
  }
  return reconstruction;
}

// The covariance against its definition: the spread of the camera centre
// that Levenberg-Marquardt (estimators/absolute_pose.h) finds from keypoints
// with 1 px of noise, over 1500 draws, points held.
TEST(CameraPositionCovariance, MatchesTheSpreadOfRefinedPoses) {
  const Reconstruction scene = TwoViewScene(40, 0.0);
  CameraPositionCovarianceOptions options;
  options.keypoint_sigma_px = 1.0;
  const CameraPositionCovariances computed = ComputeCameraPositionCovariances(scene, options);
  EXPECT_DOUBLE_EQ(computed.keypoint_sigma_px, 1.0);
  ASSERT_EQ(computed.by_image.count(2), 1u);
  const Eigen::Matrix3d expected = computed.by_image.at(2);

  const Image& image = scene.GetImage(2);
  std::vector<Eigen::Vector3d> points_in_world;
  std::vector<Eigen::Vector2d> exact_pixels;
  for (const Point2D& point2D : image.points2D) {
    points_in_world.push_back(scene.GetPoint3D(point2D.point3D_id).xyz);
    exact_pixels.push_back(point2D.xy);
  }
  Random random(11);
  const int draws = 1500;
  std::vector<Eigen::Vector3d> centres;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int d = 0; d < draws; ++d) {
    std::vector<Eigen::Vector2d> normalized;
    for (const Eigen::Vector2d& pixel : exact_pixels) {
      const Eigen::Vector2d noisy = pixel + Eigen::Vector2d(random.Normal(), random.Normal());
      normalized.emplace_back((noisy.x() - 376.0) / kFocal, (noisy.y() - 240.0) / kFocal);
    }
    const Rigid3d refined =
        RefineAbsolutePose(normalized, points_in_world, image.cam_from_world, 50);
    centres.push_back(ProjectionCenter(refined));
    mean += centres.back();
  }
  mean /= draws;
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& centre : centres) {
    spread += (centre - mean) * (centre - mean).transpose();
  }
  spread /= draws - 1;
  // 1500 draws: a variance to about 4 % (one standard error).
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(expected(axis, axis) / spread(axis, axis), 1.0, 0.15) << "axis " << axis;
  }
  EXPECT_NEAR(expected.trace() / spread.trace(), 1.0, 0.1);
  EXPECT_GT(expected.trace(), 1e-8);  // not a degenerate zero
}

TEST(CameraPositionCovariance, KeypointSigmaScaleTermAndTooFewObservations) {
  // The model's own sigma: the keypoints' noise (1.5 px per coordinate)
  // within the spread of a 40-point sample, noise shared by both images.
  const Reconstruction noisy = TwoViewScene(40, 1.5);
  const CameraPositionCovariances own = ComputeCameraPositionCovariances(noisy, {});
  EXPECT_NEAR(own.keypoint_sigma_px, 1.5, 0.25);
  // Image 3 has two observations: no entry.
  EXPECT_EQ(own.by_image.count(3), 0u);
  EXPECT_EQ(own.by_image.count(1), 1u);

  // The scale term: s^2 d d^T along the offset from image 1 (the gauge).
  CameraPositionCovarianceOptions with_scale;
  with_scale.keypoint_sigma_px = own.keypoint_sigma_px;
  with_scale.scale_sigma = 0.01;
  const CameraPositionCovariances scaled = ComputeCameraPositionCovariances(noisy, with_scale);
  const Eigen::Vector3d offset =
      noisy.GetImage(2).ProjectionCenter() - noisy.GetImage(1).ProjectionCenter();
  const Eigen::Matrix3d added = scaled.by_image.at(2) - own.by_image.at(2);
  EXPECT_LT((added - 1e-4 * offset * offset.transpose()).norm(), 1e-12);
  EXPECT_LT((scaled.by_image.at(1) - own.by_image.at(1)).norm(), 1e-15);

  // A model without observations has no sigma and no entries.
  Reconstruction empty;
  EXPECT_TRUE(ComputeCameraPositionCovariances(empty, {}).by_image.empty());
}

}  // namespace
}  // namespace viosfm
