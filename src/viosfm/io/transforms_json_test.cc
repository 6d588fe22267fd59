#include "viosfm/io/transforms_json.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

// A camera at (1, 2, 3) looking along world +x, with its image x axis along
// world -y (so image y is world -z: upright, z up). In OpenGL axes its right,
// up and back vectors are world -y, +z and -x: those are the columns of
// transform_matrix, worked out by hand.
TEST(TransformsJson, FollowsNerfstudiosConventions) {
  const fs::path folder = testing::MakeScratchFolder("transforms_conventions");
  Eigen::Matrix3d world_from_cam;
  world_from_cam.col(0) = Eigen::Vector3d(0, -1, 0);
  world_from_cam.col(1) = Eigen::Vector3d(0, 0, -1);
  world_from_cam.col(2) = Eigen::Vector3d(1, 0, 0);
  TransformsJson transforms;
  transforms.camera = MakeCamera(CameraModelId::kOpenCV, 752, 480,
                                 {458.654, 457.296, 367.215, 248.375, -0.28, 0.07, 1e-4, 2e-5});
  transforms.frames.push_back(
      {"images/1.png",
       Rigid3d(Eigen::Quaterniond(world_from_cam), Eigen::Vector3d(1, 2, 3)).Inverse()});
  transforms.ply_file_path = "sparse_pc.ply";
  WriteTransformsJson(folder / "transforms.json", transforms);

  const nlohmann::json json = nlohmann::json::parse(ReadTextFile(folder / "transforms.json"));
  EXPECT_EQ(json["camera_model"], "OPENCV");
  EXPECT_EQ(json["fl_x"], 458.654);
  EXPECT_EQ(json["fl_y"], 457.296);
  EXPECT_EQ(json["cx"], 367.715);  // + 0.5: the image corner is the origin
  EXPECT_EQ(json["cy"], 248.875);
  EXPECT_EQ(json["w"], 752);
  EXPECT_EQ(json["h"], 480);
  EXPECT_EQ(json["k1"], -0.28);
  EXPECT_EQ(json["k2"], 0.07);
  EXPECT_EQ(json["p1"], 1e-4);
  EXPECT_EQ(json["p2"], 2e-5);
  EXPECT_EQ(json["ply_file_path"], "sparse_pc.ply");
  ASSERT_EQ(json["frames"].size(), 1u);
  EXPECT_EQ(json["frames"][0]["file_path"], "images/1.png");
  const double expected[4][4] = {{0, 0, -1, 1}, {-1, 0, 0, 2}, {0, 1, 0, 3}, {0, 0, 0, 1}};
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      EXPECT_NEAR(json["frames"][0]["transform_matrix"][r][c].get<double>(), expected[r][c], 1e-15)
          << r << " " << c;
    }
  }
}

// Random poses far from the origin and every camera model with an
// equivalent: read back to 1e-9 (m and rad), intrinsics exactly.
TEST(TransformsJson, RoundTripsPoses) {
  const fs::path folder = testing::MakeScratchFolder("transforms_roundtrip");
  Random random(5);
  for (const Camera& camera :
       {MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 501, 319.5, 239.5}),
        MakeCamera(CameraModelId::kOpenCVFisheye, 848, 800,
                   {286, 287, 425, 398, -0.01, 0.05, -0.05, 0.01}),
        MakeCamera(CameraModelId::kOpenCV, 752, 480, {458, 457, 367, 248, -0.28, 0.07, 1e-4, 0})}) {
    TransformsJson transforms;
    transforms.camera = camera;
    for (int i = 0; i < 50; ++i) {
      const Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
      const Eigen::Vector3d t(random.Uniform(-1e4, 1e4), random.Uniform(-1e4, 1e4),
                              random.Uniform(-10, 10));
      transforms.frames.push_back({"images/" + std::to_string(i) + ".png", Rigid3d(q, t)});
    }
    WriteTransformsJson(folder / "t.json", transforms);
    const TransformsJson read = ReadTransformsJson(folder / "t.json");
    EXPECT_EQ(read.camera.model_id, camera.model_id);
    ASSERT_EQ(read.camera.params.size(), camera.params.size());
    for (size_t k = 0; k < camera.params.size(); ++k) {
      EXPECT_NEAR(read.camera.params[k], camera.params[k], 1e-12);
    }
    EXPECT_EQ(read.camera.width, camera.width);
    ASSERT_EQ(read.frames.size(), transforms.frames.size());
    for (size_t i = 0; i < read.frames.size(); ++i) {
      const Rigid3d& a = read.frames[i].cam_from_world;
      const Rigid3d& b = transforms.frames[i].cam_from_world;
      EXPECT_EQ(read.frames[i].file_path, transforms.frames[i].file_path);
      EXPECT_LT(a.rotation.angularDistance(b.rotation), 1e-9);
      EXPECT_LT((a.Inverse().translation - b.Inverse().translation).norm(), 1e-9);
    }
  }
}

TEST(TransformsJson, RejectsWhatItCannotRepresentOrRead) {
  const fs::path folder = testing::MakeScratchFolder("transforms_bad");
  TransformsJson transforms;
  transforms.camera = MakeCamera(CameraModelId::kFOV, 10, 10, {5, 5, 5, 5, 0.1});
  EXPECT_NE(testing::InputErrorMessage([&] {
              WriteTransformsJson(folder / "a.json", transforms);
            }).find("no transforms.json equivalent"),
            std::string::npos);
  testing::WriteTextFile(folder / "b.json",
                         R"({"fl_x": 1, "fl_y": 1, "cx": 1, "cy": 1, "w": 2, "h": 2,
                             "frames": [{"file_path": "x.png",
                                         "transform_matrix": [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  EXPECT_NE(testing::InputErrorMessage([&] {
              ReadTransformsJson(folder / "b.json");
            }).find("frame 0: transform_matrix is not a rigid"),
            std::string::npos);
  testing::WriteTextFile(folder / "c.json", R"({"fl_x": 1, "frames": []})");
  EXPECT_NE(testing::InputErrorMessage([&] {
              ReadTransformsJson(folder / "c.json");
            }).find("expected a number \"fl_y\""),
            std::string::npos);
}

}  // namespace
}  // namespace viosfm
