#include "viosfm/sim/scene_model.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <set>

#include "viosfm/io/image_io.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

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

// A folder of three 64 x 64 PNGs of seeded random grey values, written
// out of name order, and a file that is not an image; returns the images in
// name order.
std::vector<GreyImage> WritePhotoFolder(const std::filesystem::path& folder) {
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> grey(0, 255);
  std::vector<GreyImage> images(3, GreyImage(64, 64));
  for (GreyImage& image : images) {
    for (uint8_t& pixel : image.pixels) pixel = static_cast<uint8_t>(grey(rng));
  }
  WriteGreyPng(folder / "c.png", images[2]);
  WriteGreyPng(folder / "a.png", images[0]);
  WriteGreyPng(folder / "b.png", images[1]);
  std::ofstream(folder / "notes.txt") << "not an image\n";
  return images;
}

// (i0, j0) such that texel (i, j) of `window` is texel (i0 + i, j0 + j) of
// `photo` (wrapping); (-1, -1) if there is none.
Eigen::Vector2i FindWindow(const Texture& window, const Texture& photo) {
  for (int j0 = 0; j0 < photo.height(); ++j0) {
    for (int i0 = 0; i0 < photo.width(); ++i0) {
      bool same = true;
      for (int j = 0; j < window.height() && same; ++j) {
        for (int i = 0; i < window.width() && same; ++i) {
          same = window.Texel(0, i, j) == photo.Texel(0, i0 + i, j0 + j);
        }
      }
      if (same) return Eigen::Vector2i(i0, j0);
    }
  }
  return Eigen::Vector2i(-1, -1);
}

TEST(PhotoTextures, LoadsTheImagesOfAFolderInNameOrder) {
  const std::filesystem::path folder = testing::MakeScratchFolder("photo_textures");
  const std::vector<GreyImage> images = WritePhotoFolder(folder);
  const std::vector<Texture> photos = LoadPhotoTextures(folder, 64);
  ASSERT_EQ(photos.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    for (int j : {0, 31, 63}) {
      for (int i : {0, 40, 63}) {
        EXPECT_FLOAT_EQ(photos[k].Texel(0, i, j), images[k].at(i, 63 - j) / 255.0f) << k;
      }
    }
  }
  const std::filesystem::path empty = testing::MakeScratchFolder("photo_textures_empty");
  std::ofstream(empty / "readme.md") << "no images here\n";
  try {
    LoadPhotoTextures(empty, 64);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(empty.string()), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("no image"), std::string::npos) << error.what();
  }
  EXPECT_THROW(LoadPhotoTextures(empty / "missing", 64), InputError);
}

TEST(PhotoTextures, RoomShowsThePhotosWhereTheyAreDrawn) {
  const std::filesystem::path folder = testing::MakeScratchFolder("photo_textures_room");
  WritePhotoFolder(folder);
  RoomSceneOptions options;
  options.photos = std::make_shared<const std::vector<Texture>>(LoadPhotoTextures(folder, 64));
  const std::vector<Texture>& photos = *options.photos;
  const Scene scene = MakeRoomScene(options);
  // Every surface has its own texture: surface k shows a window of photo
  // k mod 3, and surfaces sharing a photo start at different offsets.
  ASSERT_EQ(scene.textures().size(), scene.quads().size());
  std::vector<Eigen::Vector2i> offsets;
  std::set<std::pair<int, int>> distinct;
  for (size_t k = 0; k < scene.textures().size(); ++k) {
    const Texture& texture = scene.texture(static_cast<int>(k));
    EXPECT_LE(texture.width(), 64);
    offsets.push_back(FindWindow(texture, photos[k % 3]));
    ASSERT_GE(offsets.back().x(), 0) << "surface " << k << " is not a window of photo " << k % 3;
    distinct.insert({offsets.back().x(), offsets.back().y()});
  }
  EXPECT_GT(distinct.size(), scene.textures().size() / 2);

  // Render the wall x = 4 (surface 5) close up: level 0 of the texture, no
  // noise or shading, so a pixel is the bilinear interpolation of the photo.
  const Camera camera = MakeCamera(CameraModelId::kPinhole, 80, 60, {1000, 1000, 39.5, 29.5});
  Eigen::Matrix3d world_from_cam_rotation;
  world_from_cam_rotation << 0, 0, 1,  //
      -1, 0, 0,                        //
      0, -1, 0;
  const Eigen::Vector3d center(1.0, 0.3, 1.7);
  const Rigid3d cam_from_world(world_from_cam_rotation.transpose(),
                               -world_from_cam_rotation.transpose() * center);
  RenderOptions render;
  render.noise_sigma = 0;
  render.vignetting = 0;
  render.distance_falloff = 0;
  render.num_threads = 1;
  const RayTable rays(camera);
  const GreyImage image = Render(scene, rays, cam_from_world, render);
  int checked = 0;
  for (int y = 0; y < 60; y += 7) {
    for (int x = 0; x < 80; x += 9) {
      const Eigen::Vector3d direction =
          world_from_cam_rotation * rays.Direction(x, y).cast<double>().normalized();
      const std::optional<RayHit> hit = scene.Intersect(center, direction);
      ASSERT_TRUE(hit.has_value());
      ASSERT_EQ(hit->quad_id, 5);
      const TexturedQuad& quad = scene.quads()[hit->quad_id];
      const Eigen::Vector2i offset = offsets[quad.texture_id];
      const Texture& photo = photos[quad.texture_id % 3];
      // Bilinear between texel centres, in photo texels.
      const double s =
          (hit->u + quad.texture_offset.x()) * quad.texels_per_metre - 0.5 + offset.x();
      const double t =
          (hit->v + quad.texture_offset.y()) * quad.texels_per_metre - 0.5 + offset.y();
      const int i = static_cast<int>(std::floor(s));
      const int j = static_cast<int>(std::floor(t));
      const double a = s - i;
      const double b = t - j;
      const double expected =
          255.0 * ((1 - b) * ((1 - a) * photo.Texel(0, i, j) + a * photo.Texel(0, i + 1, j)) +
                   b * ((1 - a) * photo.Texel(0, i, j + 1) + a * photo.Texel(0, i + 1, j + 1)));
      EXPECT_NEAR(image.at(x, y), expected, 1.0) << "pixel " << x << ", " << y;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 81);
}

}  // namespace
}  // namespace viosfm
