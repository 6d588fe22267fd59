#include "viosfm/sim/scene_model.h"

#include <gtest/gtest.h>

#include <set>

#include "viosfm/sim/trajectory.h"

namespace viosfm {
namespace {

Scene TwoParallelQuads() {
  Scene scene;
  const int texture = scene.AddTexture(MakeCheckerboardTexture(16, 16, 4));
  TexturedQuad near_quad;  // z = 2, x in [-1, 1], y in [-1, 1]
  near_quad.origin = Eigen::Vector3d(-1, -1, 2);
  near_quad.axis_u = Eigen::Vector3d(2, 0, 0);
  near_quad.axis_v = Eigen::Vector3d(0, 2, 0);
  near_quad.texture_id = texture;
  TexturedQuad far_quad = near_quad;  // z = 5, larger
  far_quad.origin = Eigen::Vector3d(-5, -5, 5);
  far_quad.axis_u = Eigen::Vector3d(10, 0, 0);
  far_quad.axis_v = Eigen::Vector3d(0, 10, 0);
  scene.AddQuad(far_quad);
  scene.AddQuad(near_quad);
  return scene;
}

TEST(SceneModel, NearestHitWithSurfaceCoordinates) {
  const Scene scene = TwoParallelQuads();
  const Eigen::Vector3d origin(0.2, 0.3, 0.0);
  const Eigen::Vector3d direction = Eigen::Vector3d(0.1, 0.0, 1.0).normalized();
  const auto hit = scene.Intersect(origin, direction);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->quad_id, 1);
  EXPECT_NEAR(hit->t, 2.0 / direction.z(), 1e-12);
  EXPECT_NEAR(hit->u, 0.2 + 0.2 + 1.0, 1e-12);
  EXPECT_NEAR(hit->v, 1.3, 1e-12);
  EXPECT_NEAR(hit->cos_incidence, direction.z(), 1e-12);
  EXPECT_TRUE(
      scene.PointOnQuad(hit->quad_id, hit->u, hit->v).isApprox(origin + hit->t * direction, 1e-12));

  // Past the edge of the near quad: the far one.
  const Eigen::Vector3d side = Eigen::Vector3d(0.7, 0.0, 1.0).normalized();
  const auto far_hit = scene.Intersect(origin, side);
  ASSERT_TRUE(far_hit.has_value());
  EXPECT_EQ(far_hit->quad_id, 0);
  EXPECT_NEAR(far_hit->u, 0.2 + 5.0 * 0.7 + 5.0, 1e-12);

  // Away from both, and from behind the near plane (two-sided).
  EXPECT_FALSE(scene.Intersect(origin, -Eigen::Vector3d::UnitZ()).has_value());
  const auto behind = scene.Intersect(Eigen::Vector3d(0, 0, 3), -Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(behind.has_value());
  EXPECT_EQ(behind->quad_id, 1);
  EXPECT_NEAR(behind->t, 1.0, 1e-12);
}

TEST(SceneModel, RoomHasOwnTextureForEverySurfaceWithoutRepeats) {
  const Scene scene = MakeRoomScene(RoomSceneOptions{});
  EXPECT_EQ(scene.quads().size(), 6u + 8u * 5u);
  std::set<int> texture_ids;
  for (const TexturedQuad& quad : scene.quads()) {
    texture_ids.insert(quad.texture_id);
    const Texture& texture = scene.texture(quad.texture_id);
    EXPECT_GE(texture.width(), quad.axis_u.norm() * quad.texels_per_metre);
    EXPECT_GE(texture.height(), quad.axis_v.norm() * quad.texels_per_metre);
  }
  EXPECT_EQ(texture_ids.size(), scene.quads().size());
}

// Smallest hit distance over rays in 26 directions (cube neighbours).
double Clearance(const Scene& scene, const Eigen::Vector3d& point, bool* all_hit) {
  double clearance = 1e9;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const auto hit = scene.Intersect(point, Eigen::Vector3d(dx, dy, dz).normalized());
        if (!hit) {
          *all_hit = false;
          continue;
        }
        clearance = std::min(clearance, hit->t);
      }
    }
  }
  return clearance;
}

TEST(SceneModel, RoomIsClosedAndTheWalkBoxIsClearOfFurniture) {
  const Scene scene = MakeRoomScene(RoomSceneOptions{});
  const WalkOptions walk_options;
  bool all_hit = true;
  // The corners and edge midpoints of the walk box.
  for (double x : {walk_options.box_min.x(), 0.0, walk_options.box_max.x()}) {
    for (double y : {walk_options.box_min.y(), 0.0, walk_options.box_max.y()}) {
      for (double z : {walk_options.box_min.z(), walk_options.box_max.z()}) {
        EXPECT_GT(Clearance(scene, Eigen::Vector3d(x, y, z), &all_hit), 0.25)
            << "at " << x << " " << y << " " << z;
      }
    }
  }
  // The default walk itself.
  const BodyTrajectory walk = GenerateWalk(walk_options);
  for (timestamp_ns_t t = walk.start_ns(); t <= walk.end_ns(); t += 250'000'000) {
    EXPECT_GT(Clearance(scene, walk.PositionInWorld(t), &all_hit), 0.25);
  }
  EXPECT_TRUE(all_hit);
}

TEST(SceneModel, RoomTexturesFollowTheSeed) {
  RoomSceneOptions options;
  options.furniture = false;
  const Scene a = MakeRoomScene(options);
  const Scene b = MakeRoomScene(options);
  options.seed = 1;
  const Scene c = MakeRoomScene(options);
  ASSERT_EQ(a.quads().size(), 6u);
  EXPECT_EQ(a.texture(0).Texel(0, 5, 7), b.texture(0).Texel(0, 5, 7));
  EXPECT_NE(a.texture(0).Texel(0, 5, 7), c.texture(0).Texel(0, 5, 7));
  EXPECT_NE(a.texture(0).Texel(0, 5, 7), a.texture(1).Texel(0, 5, 7));
}

TEST(SceneModel, OptionsValidation) {
  RoomSceneOptions options;
  EXPECT_TRUE(options.Check());
  options.room_max.z() = 1.0;
  EXPECT_NE(options.Validate().find("high"), std::string::npos);
}

}  // namespace
}  // namespace viosfm
