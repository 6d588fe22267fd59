#include "viosfm/geometry/triangulation.h"

#include <gtest/gtest.h>

#include <numbers>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// A camera at `center` looking roughly at the origin, with a random roll.
Rigid3d LookAtOrigin(const Eigen::Vector3d& center, Random& random) {
  const Eigen::Vector3d z = (-center).normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d(random.Normal(), random.Normal(), random.Normal()));
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d world_from_cam_rotation;
  world_from_cam_rotation << x, y, z;
  const Rigid3d world_from_cam(world_from_cam_rotation, center);
  return world_from_cam.Inverse();
}

struct Scene {
  std::vector<Rigid3d> cams_from_world;
  std::vector<Eigen::Vector3d> points;
};

Scene MakeScene(Random& random, int num_cameras, int num_points) {
  Scene scene;
  for (int i = 0; i < num_cameras; ++i) {
    const Eigen::Vector3d center(random.Uniform(-3, 3), random.Uniform(-3, 3),
                                 random.Uniform(-8, -5));
    scene.cams_from_world.push_back(LookAtOrigin(center, random));
  }
  for (int i = 0; i < num_points; ++i) {
    scene.points.emplace_back(random.Uniform(-1, 1), random.Uniform(-1, 1), random.Uniform(-1, 1));
  }
  return scene;
}

Eigen::Vector2d ProjectNormalized(const Rigid3d& cam_from_world, const Eigen::Vector3d& point) {
  return (cam_from_world * point).hnormalized();
}

TEST(Triangulation, DltRecoversExactPointFromNoiseFreeViews) {
  Random random(11);
  for (int num_views : {2, 3, 5, 10}) {
    const Scene scene = MakeScene(random, num_views, 50);
    std::vector<Matrix3x4d> matrices;
    for (const Rigid3d& pose : scene.cams_from_world) matrices.push_back(pose.ToMatrix());
    for (const Eigen::Vector3d& point : scene.points) {
      std::vector<Eigen::Vector2d> observations;
      for (const Rigid3d& pose : scene.cams_from_world) {
        observations.push_back(ProjectNormalized(pose, point));
      }
      const auto triangulated = TriangulateDlt(matrices, observations);
      ASSERT_TRUE(triangulated.has_value());
      EXPECT_LT((*triangulated - point).norm(), 1e-9) << num_views;
      for (const Rigid3d& pose : scene.cams_from_world) {
        EXPECT_TRUE(HasPositiveDepth(pose, *triangulated));
        EXPECT_TRUE(HasPositiveDepth(pose.ToMatrix(), *triangulated));
      }
    }
  }
}

TEST(Triangulation, MidpointRecoversExactPointFromNoiseFreeViews) {
  Random random(12);
  const Scene scene = MakeScene(random, 2, 200);
  for (const Eigen::Vector3d& point : scene.points) {
    const auto triangulated =
        TriangulateMidpoint(scene.cams_from_world[0], scene.cams_from_world[1],
                            ProjectNormalized(scene.cams_from_world[0], point),
                            ProjectNormalized(scene.cams_from_world[1], point));
    ASSERT_TRUE(triangulated.has_value());
    EXPECT_LT((*triangulated - point).norm(), 1e-9);
  }
}

TEST(Triangulation, NoisyObservationsStayWithinBound) {
  // Cameras ~6.5 m from points within 1 m of the origin, baselines of a few
  // metres; observation noise 1e-3 (normalised units, ~0.5 px at f = 500).
  // A ray error of 1e-3 rad moves a point by ~depth * 1e-3 / sin(angle):
  // a few cm here. Bounds: 10 cm per point and 3 cm RMS (this seed gives
  // RMS 0.9-2.5 cm and at most 7.7 cm).
  Random random(13);
  for (int num_views : {2, 4, 8}) {
    const Scene scene = MakeScene(random, num_views, 200);
    std::vector<Matrix3x4d> matrices;
    for (const Rigid3d& pose : scene.cams_from_world) matrices.push_back(pose.ToMatrix());
    double sum_sq_dlt = 0.0;
    double sum_sq_mid = 0.0;
    int count = 0;
    for (const Eigen::Vector3d& point : scene.points) {
      const double angle = TriangulationAngle(ProjectionCenter(scene.cams_from_world[0]),
                                              ProjectionCenter(scene.cams_from_world[1]), point);
      if (angle < 0.2) continue;  // well-conditioned pairs only for the bound
      std::vector<Eigen::Vector2d> observations;
      for (const Rigid3d& pose : scene.cams_from_world) {
        observations.push_back(ProjectNormalized(pose, point) +
                               Eigen::Vector2d(random.Normal(0, 1e-3), random.Normal(0, 1e-3)));
      }
      const auto dlt = TriangulateDlt(matrices, observations);
      const auto mid = TriangulateMidpoint(scene.cams_from_world[0], scene.cams_from_world[1],
                                           observations[0], observations[1]);
      ASSERT_TRUE(dlt.has_value());
      ASSERT_TRUE(mid.has_value());
      EXPECT_LT((*dlt - point).norm(), 0.1);
      EXPECT_LT((*mid - point).norm(), 0.1);
      sum_sq_dlt += (*dlt - point).squaredNorm();
      sum_sq_mid += (*mid - point).squaredNorm();
      ++count;
    }
    ASSERT_GT(count, 20);
    EXPECT_LT(std::sqrt(sum_sq_dlt / count), 0.03) << num_views;
    EXPECT_LT(std::sqrt(sum_sq_mid / count), 0.03) << num_views;
  }
}

TEST(Triangulation, DegenerateCasesReturnNullopt) {
  const Rigid3d cam1;  // at the origin, looking along +z
  const Rigid3d cam2(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-1, 0, 0));  // centre (1,0,0)
  const std::vector<Matrix3x4d> matrices = {cam1.ToMatrix(), cam2.ToMatrix()};
  // Fewer than two views, mismatched sizes.
  EXPECT_FALSE(TriangulateDlt({cam1.ToMatrix()}, {Eigen::Vector2d(0, 0)}).has_value());
  EXPECT_FALSE(TriangulateDlt(matrices, {Eigen::Vector2d(0, 0)}).has_value());
  // Parallel rays (point at infinity): the same direction from both centres.
  const Eigen::Vector2d direction(0.1, -0.2);
  EXPECT_FALSE(TriangulateDlt(matrices, {direction, direction}).has_value());
  EXPECT_FALSE(TriangulateMidpoint(cam1, cam2, direction, direction).has_value());
  // Identical cameras and observations: every point on the ray fits.
  EXPECT_FALSE(
      TriangulateDlt({cam1.ToMatrix(), cam1.ToMatrix()}, {direction, direction}).has_value());
  EXPECT_FALSE(TriangulateMidpoint(cam1, cam1, direction, direction).has_value());
  // Rays along the baseline from both centres: the same line, no unique point.
  EXPECT_FALSE(
      TriangulateDlt(
          {Rigid3d(So3Exp(Eigen::Vector3d(0, std::numbers::pi / 2, 0)), Eigen::Vector3d::Zero())
               .ToMatrix(),
           (Rigid3d(So3Exp(Eigen::Vector3d(0, std::numbers::pi / 2, 0)), Eigen::Vector3d::Zero()) *
            Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-1, 0, 0)))
               .ToMatrix()},
          {Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0)})
          .has_value());
  // Non-finite input.
  EXPECT_FALSE(TriangulateDlt(matrices, {Eigen::Vector2d(std::nan(""), 0), direction}).has_value());
}

TEST(Triangulation, AngleAndDepth) {
  const Eigen::Vector3d center1(0, 0, 0);
  const Eigen::Vector3d center2(2, 0, 0);
  EXPECT_NEAR(TriangulationAngle(center1, center2, Eigen::Vector3d(1, 0, 1)), std::numbers::pi / 2,
              1e-15);
  EXPECT_NEAR(TriangulationAngle(center1, center2, Eigen::Vector3d(1, 0, std::sqrt(3.0))),
              std::numbers::pi / 3, 1e-15);
  EXPECT_NEAR(TriangulationAngle(center1, center1, Eigen::Vector3d(1, 2, 3)), 0.0, 1e-15);
  EXPECT_EQ(TriangulationAngle(center1, center2, center1), 0.0);

  const Rigid3d cam_from_world(So3Exp(Eigen::Vector3d(0, std::numbers::pi, 0)),
                               Eigen::Vector3d(0, 0, 1));  // looks along -z, centre (0,0,1)
  EXPECT_TRUE(HasPositiveDepth(cam_from_world, Eigen::Vector3d(0.3, 0.2, -4)));
  EXPECT_FALSE(HasPositiveDepth(cam_from_world, Eigen::Vector3d(0.3, 0.2, 4)));
  EXPECT_FALSE(HasPositiveDepth(cam_from_world, Eigen::Vector3d(5, 0, 1)));  // depth 0
}

}  // namespace
}  // namespace viosfm
