#include "viosfm/pipeline/metric_scale.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <iostream>
#include <numbers>
#include <string>

#include "viosfm/scene/reprojection.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// A reconstruction whose world frame is tilted by 0.4 degrees about an axis
// in the horizontal plane: levelling with the gravity it sees turns it
// back, and every image still sees every point where it did.
TEST(MetricScale, LevelWithGravityTurnsTheWorldSoThatGravityPointsDown) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.6, -0.8, 0.0);
  const double tilt_rad = 0.4 * std::numbers::pi / 180.0;
  // tilted_from_level: the reconstruction's world frame against a level one.
  const Eigen::Quaterniond tilted_from_level(Eigen::AngleAxisd(tilt_rad, axis));
  const Eigen::Vector3d gravity_in_tilted = tilted_from_level * Eigen::Vector3d(0, 0, -9.81);

  Reconstruction reconstruction;
  Camera camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {400.0, 400.0, 320.0, 240.0});
  camera.camera_id = 1;
  reconstruction.AddCamera(camera);
  Random random(3);
  for (image_t id = 1; id <= 3; ++id) {
    Image image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = "image" + std::to_string(id);
    image.cam_from_world =
        Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.2 * id, Eigen::Vector3d::UnitY())),
                Eigen::Vector3d(0.3 * id, -0.1, 2.0));
    image.registered = true;
    image.points2D.resize(1);
    reconstruction.AddImage(std::move(image));
  }
  const Eigen::Vector3d xyz(random.Uniform(-0.5, 0.5), random.Uniform(-0.5, 0.5), 1.0);
  Point3D point;
  point.xyz = xyz;
  for (image_t id = 1; id <= 3; ++id) {
    Image& image = reconstruction.GetImage(id);
    image.points2D[0].xy = *Project(reconstruction.GetCamera(1), image.cam_from_world * xyz);
    point.track.push_back({id, 0});
  }
  reconstruction.AddPoint3D(point);
  const double error_before = MeanReprojectionError(reconstruction);

  const double turned_deg = LevelWithGravity(gravity_in_tilted, &reconstruction);
  EXPECT_NEAR(turned_deg, 0.4, 1e-9);
  // The point turned by level_from_tilted = tilted_from_level^-1.
  const Eigen::Vector3d level_xyz = tilted_from_level.conjugate() * xyz;
  EXPECT_LT((reconstruction.GetPoint3D(reconstruction.Point3DIds().front()).xyz - level_xyz).norm(),
            1e-12);
  EXPECT_NEAR(MeanReprojectionError(reconstruction), error_before, 1e-9);
  EXPECT_LT(error_before, 1e-9);
  // Levelling a level world changes nothing.
  EXPECT_NEAR(LevelWithGravity(Eigen::Vector3d(0, 0, -1), &reconstruction), 0.0, 1e-12);
}

// A 30 s walk's IMU and a reconstruction of its frames at 10 Hz whose
// positions are the truth divided by true_scale (the scale a VIO gave it).
struct ScaledWalk {
  Sequence sequence;
  Reconstruction reconstruction;
};
ScaledWalk MakeScaledWalk(double true_scale, double duration_s = 30.0,
                          double position_jitter_m = 0.0) {
  WalkOptions walk;
  walk.duration_s = duration_s;
  walk.seed = 4;
  const BodyTrajectory trajectory = GenerateWalk(walk);
  ScaledWalk scaled;
  ImuSynthesisOptions imu;
  imu.seed = 5;
  scaled.sequence.imu =
      SynthesizeImu(trajectory, trajectory.start_ns(), trajectory.end_ns(), imu).samples;
  scaled.sequence.rig.imu_noise = imu.noise;  // body_from_cam identity, no time offset
  Camera camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {400.0, 400.0, 320.0, 240.0});
  camera.camera_id = 1;
  scaled.reconstruction.AddCamera(camera);
  Random random(6);
  image_t id = 1;
  for (timestamp_ns_t t = trajectory.start_ns() + SecondsToNs(0.5);
       t < trajectory.end_ns() - SecondsToNs(0.5); t += SecondsToNs(0.1), ++id) {
    Rigid3d world_from_body = trajectory.WorldFromBody(t);
    world_from_body.translation /= true_scale;
    for (int axis = 0; axis < 3; ++axis) {
      world_from_body.translation[axis] += random.Normal(0.0, position_jitter_m);
    }
    Image image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = "image" + std::to_string(id);
    image.timestamp_ns = t;
    image.cam_from_world = world_from_body.Inverse();
    image.registered = true;
    scaled.reconstruction.AddImage(std::move(image));
  }
  return scaled;
}

// A VIO whose scale is far off (a start in motion whose initialisation got
// it wrong, as on the real handheld recording): the IMU's scale lies many
// sigmas from the VIO's 1 +- 2 %, refutes it, and is applied alone, outside
// the [1/1.2, 1.2] a usable scale keeps to. A VIO 1 % off is fused as
// before, and not refuted.
TEST(MetricScale, AnImuScaleManySigmasFromTheVioRefutesIt) {
  const double kVioScaleSigma = 0.02;
  ScaledWalk far = MakeScaledWalk(2.3);
  const Eigen::Vector3d position_before =
      far.reconstruction.GetImage(10).cam_from_world.Inverse().translation;
  const MetricScaleSummary refuted = ApplyImuMetricScale(
      far.sequence, far.sequence.rig, kVioScaleSigma, ImuScaleOptions(), &far.reconstruction);
  std::cout << "2.3 times too small: " << refuted.message << "\n";
  EXPECT_FALSE(refuted.imu.usable);
  ASSERT_TRUE(refuted.vio_scale_refuted) << refuted.message;
  EXPECT_NEAR(refuted.applied_scale, 2.3, 0.023) << refuted.message;
  EXPECT_EQ(refuted.applied_scale_sigma, refuted.imu.scale_sigma);
  EXPECT_NE(refuted.message.find("refuted"), std::string::npos);
  // The cameras moved out by the applied scale (and levelled: a turn about
  // the origin keeps distances).
  const Eigen::Vector3d position_after =
      far.reconstruction.GetImage(10).cam_from_world.Inverse().translation;
  EXPECT_NEAR(position_after.norm(), refuted.applied_scale * position_before.norm(), 1e-9);

  ScaledWalk near = MakeScaledWalk(1.01);
  const MetricScaleSummary fused = ApplyImuMetricScale(
      near.sequence, near.sequence.rig, kVioScaleSigma, ImuScaleOptions(), &near.reconstruction);
  std::cout << "1 % too small: " << fused.message << "\n";
  EXPECT_FALSE(fused.vio_scale_refuted) << fused.message;
  ASSERT_TRUE(fused.imu.usable) << fused.message;
  EXPECT_NEAR(fused.applied_scale, 1.01, 0.002) << fused.message;
  EXPECT_NE(fused.message.find("fused with the VIO's scale"), std::string::npos);
  // A right scale whose frames jitter by 1 cm over a 6 s walk, the fit told
  // so (position_sigma_m): too few frames lie 1 s apart for the spaced fit,
  // and the consecutive frames' scale, shrunk by the jitter, comes out
  // 0.31 +- 0.04 with a residual of 0.6. It must not refute the VIO's (it
  // is not from frames far enough apart), and nothing is applied.
  ScaledWalk jittered = MakeScaledWalk(1.0, 6.0, 0.01);
  ImuScaleOptions told;
  told.position_sigma_m = 0.01;
  const MetricScaleSummary shrunk = ApplyImuMetricScale(
      jittered.sequence, jittered.sequence.rig, kVioScaleSigma, told, &jittered.reconstruction);
  std::cout << "jittered: " << shrunk.message << "\n";
  EXPECT_LT(shrunk.imu.scale, 0.5) << shrunk.message;  // the test's premise
  EXPECT_FALSE(shrunk.imu.spaced_used);
  EXPECT_FALSE(shrunk.vio_scale_refuted) << shrunk.message;
  EXPECT_EQ(shrunk.applied_scale, 1.0);
}

// Where the final adjustment's IMU factors held, their scale is the IMU's
// estimate when the linear fit confirms it: a factors' scale two of the
// fit's sigmas away moves the applied scale by those two sigmas (less the
// VIO's small share of the fusion); four sigmas away, or with
// use_factor_scale off, it is not used and the applied scale is the fit's.
TEST(MetricScale, TheFactorsScaleIsTheImusWhereTheFitConfirmsIt) {
  const double kVioScaleSigma = 0.02;
  const double kTrueScale = 1.01;
  ScaledWalk plain = MakeScaledWalk(kTrueScale);
  const MetricScaleSummary fit_only = ApplyImuMetricScale(
      plain.sequence, plain.sequence.rig, kVioScaleSigma, ImuScaleOptions(), &plain.reconstruction);
  ASSERT_TRUE(fit_only.imu.usable) << fit_only.message;
  EXPECT_FALSE(fit_only.factor_scale_used);
  const double fit_sigma = fit_only.imu.scale_sigma * fit_only.imu.scale;  // absolute
  ASSERT_GT(fit_sigma, 0.0);
  // The VIO's share of the fusion: the IMU's weight is vio_var / (imu_var + vio_var).
  const double imu_weight =
      kVioScaleSigma * kVioScaleSigma / (kVioScaleSigma * kVioScaleSigma + fit_sigma * fit_sigma);

  // A fresh walk each time: ApplyImuMetricScale scales its reconstruction.
  ScaledWalk near;
  const auto apply = [&](double factor_scale, const ImuScaleOptions& options) {
    near = MakeScaledWalk(kTrueScale);
    return ApplyImuMetricScale(near.sequence, near.sequence.rig, kVioScaleSigma, options,
                               &near.reconstruction, factor_scale);
  };
  const MetricScaleSummary used = apply(fit_only.imu.scale + 2.0 * fit_sigma, ImuScaleOptions());
  std::cout << "two sigmas away: " << used.message << "\n";
  EXPECT_TRUE(used.factor_scale_used) << used.message;
  EXPECT_NEAR(used.applied_scale - fit_only.applied_scale, 2.0 * fit_sigma * imu_weight,
              0.05 * fit_sigma)
      << used.message;
  EXPECT_NE(used.message.find("taken as the IMU's"), std::string::npos);
  // The model was scaled by what was applied: the cameras moved out by it.
  EXPECT_NEAR(near.reconstruction.GetImage(10).cam_from_world.Inverse().translation.norm() /
                  plain.reconstruction.GetImage(10).cam_from_world.Inverse().translation.norm(),
              used.applied_scale / fit_only.applied_scale, 1e-9);

  const MetricScaleSummary refused = apply(fit_only.imu.scale + 4.0 * fit_sigma, ImuScaleOptions());
  std::cout << "four sigmas away: " << refused.message << "\n";
  EXPECT_FALSE(refused.factor_scale_used) << refused.message;
  EXPECT_EQ(refused.applied_scale, fit_only.applied_scale);
  EXPECT_NE(refused.message.find("not used"), std::string::npos);

  ImuScaleOptions without;
  without.use_factor_scale = false;
  const MetricScaleSummary ablated = apply(fit_only.imu.scale + 2.0 * fit_sigma, without);
  EXPECT_FALSE(ablated.factor_scale_used);
  EXPECT_EQ(ablated.applied_scale, fit_only.applied_scale);
}

}  // namespace
}  // namespace viosfm
