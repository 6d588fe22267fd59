#include "viosfm/pipeline/metric_scale.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>

#include "viosfm/scene/reprojection.h"
#include "viosfm/sensor/camera_models.h"
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

}  // namespace
}  // namespace viosfm
