#include "viosfm/io/euroc_replay.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "viosfm/io/euroc.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::WriteTextFile;

// A recording of 1 s: 5 images at 5 Hz (the first at 0.05 s), IMU at 100 Hz.
fs::path Recording(const std::string& name) {
  const fs::path root = testing::MakeScratchFolder(name);
  fs::create_directories(root / "mav0/cam0/data");
  fs::create_directories(root / "mav0/imu0");
  WriteTextFile(root / "mav0/cam0/sensor.yaml",
                "%YAML:1.0\nT_BS:\n  cols: 4\n  rows: 4\n"
                "  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n"
                "rate_hz: 5\nresolution: [64, 48]\ncamera_model: pinhole\n"
                "intrinsics: [50, 50, 32, 24]\n");
  WriteTextFile(root / "mav0/imu0/sensor.yaml",
                "%YAML:1.0\nrate_hz: 100\ngyroscope_noise_density: 1e-4\n"
                "gyroscope_random_walk: 2e-5\naccelerometer_noise_density: 3e-3\n"
                "accelerometer_random_walk: 4e-3\n");
  std::string images = "#timestamp [ns],filename\n";
  for (int k = 0; k < 5; ++k) {
    const std::string stamp = std::to_string(50'000'000 + k * 200'000'000);
    images += stamp + "," + stamp + ".png\n";
    WriteTextFile(root / "mav0/cam0/data" / (stamp + ".png"), "image " + stamp);
  }
  WriteTextFile(root / "mav0/cam0/data.csv", images);
  std::string imu = "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n";
  for (int k = 0; k <= 100; ++k) {
    imu += std::to_string(k * 10'000'000) + ",0.1,0,0," + std::to_string(k) + ",0,9.81\n";
  }
  WriteTextFile(root / "mav0/imu0/data.csv", imu);
  return root;
}

// Written again as recorded: the same files, byte for byte, at the pace of
// the stamps (at 4 times real time, the last IMU row comes 0.25 s in).
TEST(ReplayEurocRecording, WritesTheRecordingAgainAtItsPace) {
  const fs::path source = Recording("replay_source");
  const fs::path target = testing::MakeScratchFolder("replay_target");
  EurocReplayOptions options;
  options.speed = 4.0;
  const auto start = std::chrono::steady_clock::now();
  ReplayEurocRecording(source, target, options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(seconds, 0.24);
  for (const char* file : {"mav0/cam0/data.csv", "mav0/imu0/data.csv", "mav0/cam0/sensor.yaml",
                           "mav0/imu0/sensor.yaml", "mav0/cam0/data/450000000.png"}) {
    EXPECT_EQ(ReadTextFile(target / file), ReadTextFile(source / file)) << file;
  }
  EXPECT_EQ(ReadEurocDataset(target).images.size(), 5u);
  // A second replay into the same folder would mix two recordings.
  EXPECT_THAT([&] { ReplayEurocRecording(source, target, options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("holds a recording already")));
  EXPECT_THAT([&] { ReplayEurocRecording(target / "nothing", target / "x"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("dataset folder not found")));
}

}  // namespace
}  // namespace viosfm
