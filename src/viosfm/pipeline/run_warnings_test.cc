#include "viosfm/pipeline/run_warnings.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>

#include "viosfm/pipeline/pipeline_summary.h"

namespace viosfm {
namespace {

bool Contains(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

// The real recording's decisions: its VIO moved the time offset and
// replaced the IMU noise, the IMU fit was not usable, three frames have no
// pose, two segments of which one was joined, and two IMU-only stretches.
PipelineSummary RecordingLikeSummary() {
  PipelineSummary s;
  s.num_frames_selected = 299;
  s.num_frames_unposed = 3;
  s.num_vio_segments = 2;
  s.mapper.num_vio_segments_joined = 1;
  s.own_vio.ran = true;
  s.own_vio.time_offset_estimated = true;
  s.own_vio.calibration_time_offset_ns = 0;
  s.own_vio.time_offset_ns = -47'332'495;
  s.own_vio.imu_noise_given.accel_noise_density = 0.183;
  s.own_vio.imu_noise_used.accel_noise_density = 0.015;
  s.own_vio.imu_noise_used.accel_random_walk = 0.002;
  s.own_vio.imu_noise_measured = true;
  s.own_vio.num_imu_only_frames = 7;
  s.own_vio.num_imu_only_stretches = 2;
  s.own_vio.longest_imu_only_s = 0.25;
  s.own_vio.num_resets = 1;
  s.metric_scale.estimated = true;
  s.metric_scale.imu.usable = false;
  s.metric_scale.imu.message =
      "IMU scale 0.86733 +- 0.01919 from 298 frame pairs (residual 0.89 times the expected) "
      "(frames at least 1.00 s apart: 0.99270 +- 0.05839, within 2.0 sigma): too uncertain "
      "(more than 0.5 %; too little motion or IMU), not used";
  s.metric_scale.applied_scale_sigma = 0.02;
  return s;
}

TEST(RunWarnings, OneShortLinePerDecision) {
  const std::vector<std::string> lines = RunWarnings(RecordingLikeSummary());
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_EQ(lines[0],
            "time offset: camera-IMU 0.0 -> -47.3 ms (the VIO's estimate replaced "
            "the calibration's)");
  EXPECT_EQ(lines[1],
            "IMU noise replaced (measured at rest): accel 0.183 -> 0.015; random "
            "walks scaled");
  EXPECT_EQ(lines[2],
            "metric scale: the VIO's (IMU fit too uncertain (more than 0.5 %; too "
            "little motion or IMU), not used), +-2.00 %");
  EXPECT_EQ(lines[3],
            "frames without a pose: 3 of 299 selected (why: summary.json unposed_frames)");
  EXPECT_EQ(lines[4], "VIO segments: 2, 1 joined by the images (1 VIO resets)");
  EXPECT_EQ(lines[5], "VIO on the IMU alone: 2 stretch(es), 7 frames, longest 0.25 s");
  for (const std::string& line : lines) EXPECT_LE(line.size(), kMaxConsoleLineLength - 4) << line;
}

// A run that changed nothing says only where its scale came from; an
// images-only run that its scale is arbitrary.
TEST(RunWarnings, QuietRunGivesTheScaleOnly) {
  PipelineSummary s;
  s.own_vio.ran = true;
  s.num_vio_segments = 1;
  s.metric_scale.estimated = true;
  s.metric_scale.imu.usable = true;
  s.metric_scale.factor_scale_used = true;
  s.metric_scale.applied_scale_sigma = 0.00197;
  EXPECT_EQ(RunWarnings(s), std::vector<std::string>{
                                "metric scale: the IMU factors' fused with the VIO's, +-0.20 %"});
  s.mapper.images_only = true;
  EXPECT_TRUE(Contains(RunWarnings(s).front(), "images only"));
}

TEST(RunWarnings, LongReasonsAreCut) {
  PipelineSummary s = RecordingLikeSummary();
  s.metric_scale.imu.message = std::string(300, 'x');
  const std::vector<std::string> lines = RunWarnings(s);
  EXPECT_EQ(lines[2].size(), kMaxConsoleLineLength - 4);
  EXPECT_EQ(lines[2].substr(lines[2].size() - 3), "...");
}

// The console's summary: every line at most 120 characters, the decisions
// last; summary.json carries them as `warnings`.
TEST(RunWarnings, ConsoleSummaryIsNarrowAndEndsWithTheDecisions) {
  const PipelineSummary s = RecordingLikeSummary();
  const std::string text = s.ToString();
  std::istringstream in(text);
  std::string line, last;
  size_t num_lines = 0;
  while (std::getline(in, line)) {
    EXPECT_LE(line.size(), kMaxConsoleLineLength) << line;
    ++num_lines;
    last = line;
  }
  EXPECT_GT(num_lines, 15u);
  EXPECT_EQ(last, "  VIO on the IMU alone: 2 stretch(es), 7 frames, longest 0.25 s");
  EXPECT_TRUE(Contains(text, "\ndecisions (summary.json: warnings):\n  time offset: "));
  const nlohmann::json json = nlohmann::json::parse(PipelineSummaryToJson(s));
  ASSERT_TRUE(json["warnings"].is_array());
  EXPECT_EQ(json["warnings"].size(), 6u);
  EXPECT_EQ(json["warnings"][3], RunWarnings(s)[3]);
}

}  // namespace
}  // namespace viosfm
