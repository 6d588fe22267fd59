#include "viosfm/report/viewer_3d.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

// The scene data the page embeds (var VIOSFM_SCENE = {...};).
nlohmann::json SceneData(const std::string& html) {
  const std::string prefix = "var VIOSFM_SCENE = ";
  const size_t start = html.find(prefix);
  EXPECT_NE(start, std::string::npos);
  if (start == std::string::npos) return {};
  const size_t end = html.find(";\n", start);
  return nlohmann::json::parse(html.substr(start + prefix.size(), end - start - prefix.size()));
}

std::vector<uint8_t> DecodeBase64(const std::string& text) {
  static const std::string kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<uint8_t> out;
  uint32_t buffer = 0;
  int bits = 0;
  for (const char c : text) {
    const size_t value = kAlphabet.find(c);
    if (value == std::string::npos) continue;
    buffer = (buffer << 6) | static_cast<uint32_t>(value);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<uint8_t>((buffer >> bits) & 0xff));
    }
  }
  return out;
}

// Base64 little-endian float32 triples, plus `center`.
std::vector<Eigen::Vector3d> DecodePositions(const std::string& text,
                                             const Eigen::Vector3d& center) {
  const std::vector<uint8_t> bytes = DecodeBase64(text);
  std::vector<Eigen::Vector3d> out;
  for (size_t i = 0; i + 12 <= bytes.size(); i += 12) {
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) {
      uint32_t bits = 0;
      for (int b = 0; b < 4; ++b) bits |= static_cast<uint32_t>(bytes[i + 4 * k + b]) << (8 * b);
      p[k] = static_cast<double>(std::bit_cast<float>(bits)) + center[k];
    }
    out.push_back(p);
  }
  return out;
}

fs::path StandInThreeJs(const std::string& name) {
  const fs::path folder = testing::MakeScratchFolder(name);
  fs::create_directories(folder / "examples" / "js" / "controls");
  testing::WriteTextFile(folder / "three.min.js", "var THREE={};var s='</script>';");
  testing::WriteTextFile(folder / "examples" / "js" / "controls" / "OrbitControls.js", "// oc");
  return folder;
}

TEST(Viewer3d, DecimationKeepsEveryKthPoint) {
  EXPECT_EQ(DecimationIndices(10, 3), (std::vector<size_t>{0, 4, 8}));
  EXPECT_EQ(DecimationIndices(4, 10), (std::vector<size_t>{0, 1, 2, 3}));
  EXPECT_EQ(DecimationIndices(1'000'001, 200'000).size(), 166'667u);  // k = 6
  EXPECT_TRUE(DecimationIndices(0, 5).empty());
}

// With a stand-in three.js: the scripts are embedded (a "</script" inside
// one is neutralised), the data is there, and at most max_points points.
TEST(Viewer3d, EmbedsScriptsAndData) {
  Viewer3dOptions options;
  options.three_js_dir = StandInThreeJs("viewer3d");
  options.max_points = 3;
  ASSERT_TRUE(HasThreeJs(options));
  Viewer3dScene scene;
  for (int i = 0; i < 10; ++i) scene.points.push_back(Eigen::Vector3d(1e6 + i, 2e6, 3.0));
  scene.path = {Eigen::Vector3d(1e6, 2e6, 3.0), Eigen::Vector3d(1e6 + 1, 2e6, 3.0)};
  scene.path_errors_m = {0.0, 0.02};
  const std::string html = RenderViewer3d(scene, options);
  EXPECT_NE(html.find("var s='<\\/script>';"), std::string::npos);
  EXPECT_EQ(html.find("var s='</script>'"), std::string::npos);
  const nlohmann::json data = SceneData(html);
  EXPECT_EQ(data["total_points"], 10);
  EXPECT_EQ(data["num_points"], 3);
  EXPECT_EQ(data["num_path"], 2);
  EXPECT_NE(html.find("0 to 0.02 m"), std::string::npos);
  // The centre is the median of the kept points (1e6 + 4, 2e6, 3); the
  // points are stored relative to it and decode back to 1e6 + {0, 4, 8}.
  EXPECT_EQ(data["center"], nlohmann::json({1e6 + 4, 2e6, 3.0}));
  const std::vector<Eigen::Vector3d> points =
      DecodePositions(data["points"], Eigen::Vector3d(1e6 + 4, 2e6, 3.0));
  ASSERT_EQ(points.size(), 3u);
  EXPECT_DOUBLE_EQ(points[2].x(), 1e6 + 8);

  options.three_js_dir = options.three_js_dir / "absent";
  EXPECT_FALSE(HasThreeJs(options));
}

TEST(Viewer3d, GridSpacingIsRoundAndAboutAFifthOfTheRadius) {
  EXPECT_DOUBLE_EQ(GridSpacing(1.0), 0.2);
  EXPECT_DOUBLE_EQ(GridSpacing(7.0), 2.0);
  EXPECT_DOUBLE_EQ(GridSpacing(20.0), 5.0);
  EXPECT_DOUBLE_EQ(GridSpacing(30.0), 10.0);
  EXPECT_DOUBLE_EQ(GridSpacing(0.04), 0.01);
}

// A camera at C looking along the world's +x, its image's top edge up (+z):
// its frustum starts at C, its image corners lie a fifth of a grid cell
// ahead, the top-left one to the left (+y) and up, and the tick on the top
// edge is its highest point. The world's z is up against gravity.
TEST(Viewer3d, FrustumsFollowThePoseAndTheImage) {
  Viewer3dOptions options;
  options.three_js_dir = StandInThreeJs("viewer3d_frustum");
  Viewer3dScene scene;
  for (int i = 0; i < 100; ++i) {
    scene.points.push_back(Eigen::Vector3d(10.0 + 0.1 * i, 0.05 * i, -1.0 + 0.02 * i));
  }
  scene.camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 500, 320, 240});
  const Eigen::Vector3d c(12.0, 1.0, 0.5);
  Eigen::Matrix3d world_from_cam_rotation;
  world_from_cam_rotation.col(0) = Eigen::Vector3d(0, -1, 0);  // image right
  world_from_cam_rotation.col(1) = Eigen::Vector3d(0, 0, -1);  // image down
  world_from_cam_rotation.col(2) = Eigen::Vector3d(1, 0, 0);   // viewing direction
  Viewer3dFrame frame;
  frame.cam_from_world = Rigid3d(world_from_cam_rotation, c).Inverse();
  frame.name = "1000.png";
  frame.time_s = 0.0;
  frame.image_path = testing::MakeScratchFolder("viewer3d_frustum_images") / "absent.png";
  scene.frames.push_back(frame);
  scene.path = {c};
  const std::string html = RenderViewer3d(scene, options);
  const nlohmann::json data = SceneData(html);
  const Eigen::Vector3d center(data["center"][0], data["center"][1], data["center"][2]);
  const double depth = 0.2 * data["grid"]["spacing"].get<double>();
  const std::vector<Eigen::Vector3d> frustum = DecodePositions(data["frustums"], center);
  ASSERT_EQ(frustum.size(), 6u);
  EXPECT_LT((frustum[0] - c).norm(), 1e-5);
  // Top-left pixel (0, 0): ray (-0.64, -0.48, 1) in the camera.
  EXPECT_LT((frustum[1] - (c + depth * Eigen::Vector3d(1.0, 0.64, 0.48))).norm(), 1e-5);
  // Bottom-right pixel (640, 480).
  EXPECT_LT((frustum[3] - (c + depth * Eigen::Vector3d(1.0, -0.64, -0.48))).norm(), 1e-5);
  for (int k = 1; k <= 4; ++k) EXPECT_GT(frustum[5].z(), frustum[k].z()) << k;
  EXPECT_TRUE(data["gravity_up"].get<bool>());
  ASSERT_EQ(data["frames"].size(), 1u);
  EXPECT_EQ(data["frames"][0]["name"], "1000.png");
  EXPECT_EQ(data["frames"][0]["thumbnail"], "");  // the image is absent
  EXPECT_NE(html.find("z blue (up, against gravity)"), std::string::npos);
  // Grid lines on whole multiples of the spacing, the floor at the points'
  // 2nd height percentile.
  const double spacing = data["grid"]["spacing"];
  const double grid_x = data["grid"]["center"][0].get<double>() + center.x();
  EXPECT_NEAR(std::remainder(grid_x, spacing), 0.0, 1e-9);
  EXPECT_NEAR(data["grid"]["z"].get<double>() + center.z(), -1.0 + 0.02 * 2, 1e-9);
}

// Frames along a line 0.1 m apart, the camera turning by 40 degrees at
// the 10th: with 0.35 m between frustums every 4th frame is drawn, and the
// turned one too.
TEST(Viewer3d, FrustumsAreSpreadByDistanceAndTurn) {
  std::vector<Viewer3dFrame> frames(20);
  for (int i = 0; i < 20; ++i) {
    const double yaw = (i >= 10 ? 40.0 : 0.0) * M_PI / 180.0;
    frames[i].cam_from_world =
        Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())),
                Eigen::Vector3d(0.1 * i, 0, 0))
            .Inverse();
  }
  EXPECT_EQ(SpreadFrames(frames, 0.35, 30.0, 300), (std::vector<size_t>{0, 4, 8, 10, 14, 18}));
  EXPECT_EQ(SpreadFrames(frames, 0.35, 30.0, 3), (std::vector<size_t>{0, 8, 14}));
  EXPECT_EQ(SpreadFrames(frames, 0.0, 30.0, 300).size(), 20u);
}

TEST(Viewer3d, ThumbnailsAreSmallJpegsOfTheImage) {
  const fs::path folder = testing::MakeScratchFolder("viewer3d_thumbnail");
  cv::Mat image(480, 640, CV_8UC3, cv::Scalar(0, 0, 255));  // red
  ASSERT_TRUE(cv::imwrite((folder / "frame.png").string(), image));
  const std::vector<uint8_t> jpeg = MakeThumbnailJpeg(folder / "frame.png", 64);
  const cv::Mat small = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  ASSERT_FALSE(small.empty());
  EXPECT_EQ(small.cols, 64);
  EXPECT_EQ(small.rows, 48);
  EXPECT_GT(small.at<cv::Vec3b>(24, 32)[2], 200);
  EXPECT_LT(small.at<cv::Vec3b>(24, 32)[0], 60);
  EXPECT_TRUE(MakeThumbnailJpeg(folder / "absent.png", 64).empty());
  testing::WriteTextFile(folder / "not_an_image.png", "text");
  EXPECT_TRUE(MakeThumbnailJpeg(folder / "not_an_image.png", 64).empty());
}

}  // namespace
}  // namespace viosfm
