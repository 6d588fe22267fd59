#include "viosfm/sim/renderer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/sim/trajectory.h"

namespace viosfm {
namespace {

RenderOptions CleanOptions() {
  RenderOptions options;
  options.noise_sigma = 0.0;
  options.vignetting = 0.0;
  options.distance_falloff = 0.0;
  return options;
}

cv::Mat ToMat(const GreyImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.pixels.data()))
      .clone();
}

// Camera looking along the body's x axis at the start of the default walk.
Rigid3d WalkStartCamFromWorld() {
  const BodyTrajectory walk = GenerateWalk(WalkOptions{});
  return (walk.WorldFromBody(walk.start_ns()) * SimulationOptions::DefaultBodyFromCam()).Inverse();
}

const Scene& Room() {
  static const Scene scene = MakeRoomScene(RoomSceneOptions{});
  return scene;
}

TEST(RayTable, RaysProjectBackOntoTheirPixels) {
  const Camera camera = SimulationOptions::DefaultCamera();
  const RayTable rays(camera);
  ASSERT_EQ(rays.width(), 752);
  ASSERT_EQ(rays.height(), 480);
  double max_error = 0.0;
  for (int y = 0; y < rays.height(); y += 17) {
    for (int x = 0; x < rays.width(); x += 13) {
      const auto pixel = Project(camera, rays.Direction(x, y).cast<double>());
      ASSERT_TRUE(pixel.has_value());
      max_error = std::max(max_error, (*pixel - Eigen::Vector2d(x, y)).norm());
      EXPECT_NEAR(rays.Direction(x, y).norm(), 1.0f, 1e-6f);
    }
  }
  EXPECT_LT(max_error, 1e-3);
  // Pixel angle near the centre is about 1 / focal length.
  EXPECT_NEAR(rays.PixelAngle(367, 248), 1.0 / 458.0, 1e-5);
}

// A checkerboard wall seen by the distorted EuRoC camera: the checker corners
// found in the image (cv::cornerSubPix) lie where Project() puts them.
TEST(Renderer, CheckerCornersAreWhereTheCameraModelProjectsThem) {
  const Camera camera = SimulationOptions::DefaultCamera();
  Scene scene;
  const int square = 64;                // texels
  const double texels_per_metre = 320;  // squares of 0.2 m
  TexturedQuad wall;
  wall.origin = Eigen::Vector3d(-4.0, -3.0, 2.5);
  wall.axis_u = Eigen::Vector3d(8.0, 0.0, 0.0);
  wall.axis_v = Eigen::Vector3d(0.0, 6.0, 0.0);
  wall.texels_per_metre = texels_per_metre;
  wall.texture_id = scene.AddTexture(MakeCheckerboardTexture(1024, 1024, square));
  scene.AddQuad(wall);
  // Slightly rotated and shifted camera.
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(0.12, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(-0.08, Eigen::Vector3d::UnitX()) *
                                    Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()))
                                       .toRotationMatrix();
  const Rigid3d cam_from_world(rotation, Eigen::Vector3d(0.03, -0.07, 0.1));
  const GreyImage image = Render(scene, camera, cam_from_world, CleanOptions());
  const cv::Mat mat = ToMat(image);

  const double square_m = square / texels_per_metre;
  const int margin = 8;
  double max_error = 0.0;
  double max_error_border = 0.0;
  double max_error_interior = 0.0;
  Eigen::Vector2d mean_offset = Eigen::Vector2d::Zero();
  int num_corners = 0;
  int num_border_corners = 0;
  for (int i = 1; i * square_m < 8.0; ++i) {
    for (int j = 1; j * square_m < 6.0; ++j) {
      const Eigen::Vector3d point = scene.PointOnQuad(0, i * square_m, j * square_m);
      const auto projected = Project(camera, cam_from_world * point);
      if (!projected) continue;
      const Eigen::Vector2d expected = *projected;
      if (expected.x() < margin || expected.y() < margin ||
          expected.x() > camera.width - 1 - margin || expected.y() > camera.height - 1 - margin) {
        continue;
      }
      std::vector<cv::Point2f> corner = {cv::Point2f(static_cast<float>(expected.x() + 0.8),
                                                     static_cast<float>(expected.y() - 0.6))};
      cv::cornerSubPix(
          mat, corner, cv::Size(5, 5), cv::Size(-1, -1),
          cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
      const double error = (Eigen::Vector2d(corner[0].x, corner[0].y) - expected).norm();
      max_error = std::max(max_error, error);
      mean_offset += Eigen::Vector2d(corner[0].x, corner[0].y) - expected;
      ++num_corners;
      const double to_border =
          std::min({expected.x(), expected.y(), camera.width - 1 - expected.x(),
                    camera.height - 1 - expected.y()});
      if (to_border > 60.0) max_error_interior = std::max(max_error_interior, error);
      if (to_border < 30.0) {
        ++num_border_corners;
        max_error_border = std::max(max_error_border, error);
      }
    }
  }
  std::cout << "checker corners: " << num_corners << " (" << num_border_corners
            << " within 30 px of the border), max error " << max_error << " px, near border "
            << max_error_border << " px, > 60 px from it " << max_error_interior << " px\n";
  mean_offset /= std::max(num_corners, 1);
  std::cout << "mean offset (found - projected): " << mean_offset.transpose() << " px\n";
  EXPECT_LT(mean_offset.norm(), 0.05);
  EXPECT_GT(num_corners, 150);
  EXPECT_GT(num_border_corners, 10);
  EXPECT_LT(max_error, 0.5);
}

TEST(Renderer, SameSeedSameBytesForAnyThreadCount) {
  const RayTable rays(SimulationOptions::DefaultCamera());
  const Rigid3d cam_from_world = WalkStartCamFromWorld();
  RenderOptions options;  // with noise and vignetting
  options.seed = 42;
  options.num_threads = 1;
  const GreyImage one_thread = Render(Room(), rays, cam_from_world, options);
  options.num_threads = 2;
  const GreyImage two_threads = Render(Room(), rays, cam_from_world, options);
  const GreyImage again = Render(Room(), rays, cam_from_world, options);
  EXPECT_EQ(one_thread.pixels, two_threads.pixels);
  EXPECT_EQ(two_threads.pixels, again.pixels);
  options.seed = 43;
  const GreyImage other_seed = Render(Room(), rays, cam_from_world, options);
  EXPECT_NE(other_seed.pixels, two_threads.pixels);
  // The noise has the requested standard deviation (difference of two
  // independent noise draws: sigma * sqrt(2), before 8-bit rounding).
  double sum_sq = 0.0;
  for (size_t k = 0; k < other_seed.pixels.size(); ++k) {
    const double d = static_cast<double>(other_seed.pixels[k]) - two_threads.pixels[k];
    sum_sq += d * d;
  }
  EXPECT_NEAR(std::sqrt(sum_sq / other_seed.pixels.size()), options.noise_sigma * std::sqrt(2.0),
              0.3);
}

TEST(Renderer, RoomViewFromTheWalkStartIsRichInSiftFeatures) {
  const GreyImage image =
      Render(Room(), SimulationOptions::DefaultCamera(), WalkStartCamFromWorld(), RenderOptions{});
  // Every ray hits a surface (closed room), and the image uses a wide range.
  const auto [lo, hi] = std::minmax_element(image.pixels.begin(), image.pixels.end());
  EXPECT_LT(*lo, 40);
  EXPECT_GT(*hi, 200);
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create()->detect(ToMat(image), keypoints);
  std::cout << "SIFT keypoints on the walk-start view: " << keypoints.size() << "\n";
  EXPECT_GE(keypoints.size(), 500u);
}

double MeanAbsoluteDifference(const GreyImage& a, const GreyImage& b) {
  double sum = 0.0;
  for (size_t k = 0; k < a.pixels.size(); ++k) {
    sum += std::abs(static_cast<double>(a.pixels[k]) - b.pixels[k]);
  }
  return sum / a.pixels.size();
}

// A far, slanted textured plane: the mip-mapped render matches a 4x4
// supersampled (box-filtered) render; without mip-mapping it aliases.
TEST(Renderer, MipMappingAvoidsAliasingOnAFarPlane) {
  Scene scene;
  ProceduralTextureOptions texture_options;
  texture_options.width = 1024;
  texture_options.height = 1024;
  texture_options.seed = 9;
  TexturedQuad plane;  // 80 m x 80 m, 128 texels/m (tiled), at 15..40 m
  plane.origin = Eigen::Vector3d(-40.0, -40.0, 0.0);
  plane.axis_u = Eigen::Vector3d(80.0, 0.0, 0.0);
  plane.axis_v = Eigen::Vector3d(0.0, 80.0, 0.0);
  plane.texels_per_metre = 128.0;
  plane.texture_id = scene.AddTexture(MakeProceduralTexture(texture_options));
  scene.AddQuad(plane);
  // Camera 20 m from the plane, optical axis tilted 40 degrees from its normal.
  const Eigen::Matrix3d world_from_cam =
      Eigen::AngleAxisd(M_PI - 0.7, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Rigid3d cam_from_world = Rigid3d(world_from_cam, Eigen::Vector3d(0.0, 0.0, 20.0)).Inverse();

  const int width = 160;
  const int height = 120;
  const double focal = 150.0;
  const Camera camera = MakeCamera(CameraModelId::kPinhole, width, height,
                                   {focal, focal, 0.5 * (width - 1), 0.5 * (height - 1)});
  const int factor = 4;
  // Pixel centres (0, 0) convention: fine pixel centres of coarse pixel x are
  // factor * x + 0.5 * (factor - 1) + {-1.5, -0.5, 0.5, 1.5}.
  const Camera fine_camera = MakeCamera(
      CameraModelId::kPinhole, width * factor, height * factor,
      {focal * factor, focal * factor, 0.5 * (width * factor - 1), 0.5 * (height * factor - 1)});
  const RenderOptions options = CleanOptions();
  const GreyImage fine = Render(scene, fine_camera, cam_from_world, options);
  GreyImage reference(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double sum = 0.0;
      for (int dy = 0; dy < factor; ++dy) {
        for (int dx = 0; dx < factor; ++dx) sum += fine.at(factor * x + dx, factor * y + dy);
      }
      reference.at(x, y) = static_cast<uint8_t>(std::lround(sum / (factor * factor)));
    }
  }
  const GreyImage mipmapped = Render(scene, camera, cam_from_world, options);
  RenderOptions no_mip_options = options;
  no_mip_options.mipmapping = false;
  const GreyImage aliased = Render(scene, camera, cam_from_world, no_mip_options);
  const double mip_difference = MeanAbsoluteDifference(mipmapped, reference);
  const double aliased_difference = MeanAbsoluteDifference(aliased, reference);
  std::cout << "mean |render - 4x supersampled|: mip-mapped " << mip_difference
            << ", without mip-mapping " << aliased_difference << " grey levels\n";
  EXPECT_LT(mip_difference, 6.0);
  EXPECT_GT(aliased_difference, 2.0 * mip_difference);
}

TEST(Renderer, MotionBlurAveragesSubFrames) {
  const RayTable rays(SimulationOptions::DefaultCamera());
  const Rigid3d cam_from_world = WalkStartCamFromWorld();
  RenderOptions options = CleanOptions();
  const GreyImage sharp = Render(Room(), rays, cam_from_world, options);
  // Same pose at open and close: the sharp image (up to rounding).
  const GreyImage still =
      RenderWithMotionBlur(Room(), rays, cam_from_world, cam_from_world, options);
  int max_difference = 0;
  for (size_t k = 0; k < sharp.pixels.size(); ++k) {
    max_difference = std::max(max_difference, std::abs(sharp.pixels[k] - still.pixels[k]));
  }
  EXPECT_LE(max_difference, 1);
  // Turning by 2 degrees during the exposure smooths horizontal gradients.
  const Rigid3d turned(
      Eigen::AngleAxisd(0.035, Eigen::Vector3d::UnitY()) * cam_from_world.rotation,
      Eigen::AngleAxisd(0.035, Eigen::Vector3d::UnitY()) * cam_from_world.translation);
  options.motion_blur_samples = 8;
  const GreyImage blurred = RenderWithMotionBlur(Room(), rays, cam_from_world, turned, options);
  const auto gradient_energy = [](const GreyImage& image) {
    double sum = 0.0;
    for (int y = 0; y < image.height; ++y) {
      for (int x = 1; x < image.width; ++x) sum += std::abs(image.at(x, y) - image.at(x - 1, y));
    }
    return sum;
  };
  EXPECT_LT(gradient_energy(blurred), 0.7 * gradient_energy(sharp));
}

// Column (sub-pixel) in `row` where the intensity first rises through
// `level`, by linear interpolation between the bracketing pixels; -1 if it
// never does.
double RisingEdgeColumn(const GreyImage& image, int row, double level) {
  for (int x = 1; x < image.width; ++x) {
    const double a = image.pixels[static_cast<size_t>(row) * image.width + x - 1];
    const double b = image.pixels[static_cast<size_t>(row) * image.width + x];
    if (a < level && b >= level) return x - 1 + (level - a) / (b - a);
  }
  return -1.0;
}

TEST(Renderer, RollingShutterRowsSeeTheSceneFromTheirOwnPoses) {
  // A wall 2 m ahead, dark for x < 0 and bright for x > 0 (a vertical step
  // edge at x = 0), seen by a pinhole camera that yaws (rotates about its y
  // axis) while the rows are read out: row y from the angle
  // theta_y = 0.002 (y - 59.5) rad. The edge point (0, s, 2) is at camera
  // (2 sin(theta), s, 2 cos(theta)), so the edge is drawn in row y at
  // column fx tan(theta_y) + cx, a slanted line; a global shutter (every
  // row at theta 0) draws it straight at cx.
  Camera camera;
  camera.model_id = CameraModelId::kPinhole;
  camera.width = 160;
  camera.height = 120;
  camera.params = {100.0, 100.0, 79.5, 59.5};
  const RayTable rays(camera);
  std::vector<float> texels(64 * 64);
  for (int j = 0; j < 64; ++j) {
    for (int i = 0; i < 64; ++i) texels[j * 64 + i] = i < 32 ? 0.1f : 0.9f;
  }
  Scene scene;
  TexturedQuad wall;
  wall.origin = Eigen::Vector3d(-2, -2, 2);
  wall.axis_u = Eigen::Vector3d(4, 0, 0);
  wall.axis_v = Eigen::Vector3d(0, 4, 0);
  wall.texture_id = scene.AddTexture(Texture(64, 64, std::move(texels)));
  wall.texels_per_metre = 16.0;  // texel column 32 (the edge) at x = 0
  scene.AddQuad(wall);
  const double rate = 0.002;  // rad a row
  std::vector<Rigid3d> cam_from_world_of_row(camera.height);
  for (int y = 0; y < static_cast<int>(camera.height); ++y) {
    cam_from_world_of_row[y] =
        Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(rate * (y - 59.5), Eigen::Vector3d::UnitY())),
                Eigen::Vector3d::Zero());
  }
  const RenderOptions options = CleanOptions();
  const GreyImage rolling = RenderRowByRow(scene, rays, cam_from_world_of_row, {}, options);
  const GreyImage global = Render(scene, rays, Rigid3d(), options);
  const double level = 0.5 * 255.0;
  double max_error = 0.0;
  for (int y = 0; y < static_cast<int>(camera.height); ++y) {
    const double expected = 100.0 * std::tan(rate * (y - 59.5)) + 79.5;
    max_error = std::max(max_error, std::abs(RisingEdgeColumn(rolling, y, level) - expected));
    EXPECT_NEAR(RisingEdgeColumn(global, y, level), 79.5, 0.05) << "row " << y;
  }
  // The edge moves by 2 * 100 * tan(0.119) = 24 pixels from top to bottom.
  EXPECT_LT(max_error, 0.05);
  // One pose for every row gives Render's image byte for byte.
  const std::vector<Rigid3d> same(camera.height, cam_from_world_of_row[0]);
  EXPECT_EQ(RenderRowByRow(scene, rays, same, {}, options).pixels,
            Render(scene, rays, cam_from_world_of_row[0], options).pixels);
}

TEST(Renderer, OptionsValidation) {
  RenderOptions options;
  EXPECT_TRUE(options.Check());
  options.num_threads = 0;
  EXPECT_NE(options.Validate().find("num_threads"), std::string::npos);
  options = RenderOptions{};
  options.vignetting = 1.0;
  EXPECT_NE(options.Validate().find("vignetting"), std::string::npos);
}

// Rendering speed, run by hand:
//   test_sim_renderer_test --gtest_also_run_disabled_tests --gtest_filter=*Speed*
TEST(Renderer, DISABLED_Speed) {
  const RayTable rays(SimulationOptions::DefaultCamera());
  const Rigid3d cam_from_world = WalkStartCamFromWorld();
  for (int threads : {1, 2}) {
    RenderOptions options;
    options.num_threads = threads;
    const int frames = 20;
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < frames; ++k) {
      options.seed = k;
      Render(Room(), rays, cam_from_world, options);
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << threads << " thread(s): " << frames / seconds << " frames/s at 752x480\n";
  }
}

}  // namespace
}  // namespace viosfm
