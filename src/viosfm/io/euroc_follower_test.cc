#include "viosfm/io/euroc_follower.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::WriteTextFile;

// The calibration of a recording about to start: no rows yet.
fs::path StartRecording(const std::string& name, const std::string& camera_rate = "rate_hz: 10\n") {
  const fs::path root = testing::MakeScratchFolder(name);
  fs::create_directories(root / "mav0/cam0/data");
  fs::create_directories(root / "mav0/imu0");
  WriteTextFile(root / "mav0/cam0/sensor.yaml",
                "%YAML:1.0\n"
                "T_BS:\n  cols: 4\n  rows: 4\n"
                "  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n" +
                    camera_rate +
                    "resolution: [640, 480]\ncamera_model: pinhole\n"
                    "intrinsics: [500, 501, 320, 240]\n");
  WriteTextFile(root / "mav0/imu0/sensor.yaml",
                "%YAML:1.0\nrate_hz: 200\ngyroscope_noise_density: 1e-4\n"
                "gyroscope_random_walk: 2e-5\naccelerometer_noise_density: 3e-3\n"
                "accelerometer_random_walk: 4e-3\n");
  return root;
}

void Append(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::app | std::ios::binary);
  out << text;
}

// Rows come as they are appended, complete lines only; an image row waits
// for its file, and the rows after it with it.
TEST(EurocFollower, RowsComeAsTheyAreAppended) {
  const fs::path root = StartRecording("follow_rows");
  EurocFollower follower(root);
  EXPECT_EQ(follower.header().rig.camera.width, 640u);
  EXPECT_DOUBLE_EQ(follower.header().rig.camera_rate_hz, 10.0);
  EXPECT_TRUE(follower.Poll().empty());  // the lists do not exist yet

  const fs::path images = root / "mav0/cam0/data.csv";
  const fs::path imu = root / "mav0/imu0/data.csv";
  Append(imu, "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n1000,0,0,0,0,0,9.81\n2000,0,0,0,0,0,9.8");
  Append(images, "#timestamp [ns],filename\n");
  EurocFollower::Rows rows = follower.Poll();
  ASSERT_EQ(rows.imu.size(), 1u);  // the second line has no newline yet
  EXPECT_EQ(rows.imu[0].timestamp_ns, 1000);
  Append(imu, "1\n3000,0,0,0.5,0,0,9.81\n");
  WriteTextFile(root / "mav0/cam0/data/a.png", "x");
  Append(images, "1500,a.png\n2500,b.png\n3500,c.png\n");
  WriteTextFile(root / "mav0/cam0/data/c.png", "x");
  rows = follower.Poll();
  ASSERT_EQ(rows.imu.size(), 2u);
  EXPECT_DOUBLE_EQ(rows.imu[0].accel.z(), 9.81);
  EXPECT_DOUBLE_EQ(rows.imu[1].gyro.z(), 0.5);
  // b.png is not written yet: it waits, and c.png behind it.
  ASSERT_EQ(rows.images.size(), 1u);
  EXPECT_EQ(rows.images[0].path.filename(), "a.png");
  EXPECT_TRUE(follower.Poll().empty());
  WriteTextFile(root / "mav0/cam0/data/b.png", "x");
  rows = follower.Poll();
  ASSERT_EQ(rows.images.size(), 2u);
  EXPECT_EQ(rows.images[0].timestamp_ns, 2500);
  EXPECT_EQ(rows.images[1].timestamp_ns, 3500);
  // The end: the last line is read without its newline.
  Append(imu, "4000,0,0,0,0,0,9.81");
  rows = follower.Finish();
  ASSERT_EQ(rows.imu.size(), 1u);
  EXPECT_EQ(rows.imu[0].timestamp_ns, 4000);
}

// Bad rows are refused as ReadEurocDataset refuses them, by file and line;
// a list that shrinks, and an image still missing at the end, too.
TEST(EurocFollower, BadRowsNameTheirFileAndLine) {
  {
    const fs::path root = StartRecording("follow_bad_order");
    EurocFollower follower(root);
    Append(root / "mav0/imu0/data.csv", "2000,0,0,0,0,0,9.81\n1000,0,0,0,0,0,9.81\n");
    EXPECT_THAT([&] { follower.Poll(); },
                ::testing::ThrowsMessage<InputError>(
                    HasSubstr("mav0/imu0/data.csv:2: timestamps must strictly increase")));
  }
  {
    const fs::path root = StartRecording("follow_bad_field");
    EurocFollower follower(root);
    Append(root / "mav0/cam0/data.csv", "1000,a.png\n2000\n");
    EXPECT_THAT([&] { follower.Poll(); },
                ::testing::ThrowsMessage<InputError>(HasSubstr("data.csv:2: expected 2")));
  }
  {
    const fs::path root = StartRecording("follow_shrinks");
    EurocFollower follower(root);
    Append(root / "mav0/imu0/data.csv", "1000,0,0,0,0,0,9.81\n2000,0,0,0,0,0,9.81\n");
    follower.Poll();
    WriteTextFile(root / "mav0/imu0/data.csv", "1000,0,0,0,0,0,9.81\n");
    EXPECT_THAT([&] { follower.Poll(); },
                ::testing::ThrowsMessage<InputError>(HasSubstr("shrank")));
  }
  {
    const fs::path root = StartRecording("follow_missing_image");
    EurocFollower follower(root);
    Append(root / "mav0/cam0/data.csv", "1000,a.png\n");
    EXPECT_TRUE(follower.Poll().images.empty());
    EXPECT_THAT([&] { follower.Finish(); }, ::testing::ThrowsMessage<InputError>(HasSubstr(
                                                "data.csv:1: listed image a.png does not exist")));
  }
  EXPECT_THAT([&] { EurocFollower follower(StartRecording("follow_no_rate", "")); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("needs the camera's rate_hz")));
}

}  // namespace
}  // namespace viosfm
