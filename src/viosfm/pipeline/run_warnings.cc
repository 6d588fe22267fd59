#include "viosfm/pipeline/run_warnings.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "viosfm/pipeline/pipeline_summary.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

// The widest line: the console's, less an indent of 4.
constexpr size_t kMaxLineLength = kMaxConsoleLineLength - 4;

// A line cut to kMaxLineLength ("..." at its end when cut).
std::string Fit(const std::string& line) {
  if (line.size() <= kMaxLineLength) return line;
  return line.substr(0, kMaxLineLength - 3) + "...";
}

// The first clause of a message (up to its first ';' or " ("), for a reason
// given in a few words.
std::string FirstClause(const std::string& message) {
  const size_t end = std::min(message.find(';'), message.find(" ("));
  return message.substr(0, end);
}

// Why the IMU's scale fit was not used: its message's verdict, after the
// figures ("IMU scale 0.87 +- 0.02 from 298 frame pairs (...): too
// uncertain (...), not used"), else its first clause.
std::string ImuScaleVerdict(const std::string& message) {
  const size_t at = message.rfind("): ");
  return at == std::string::npos ? FirstClause(message) : message.substr(at + 3);
}

std::string TimeOffsetLine(const OwnVioDecisions& vio) {
  if (!vio.time_offset_estimated || vio.time_offset_ns == vio.calibration_time_offset_ns) return "";
  return "time offset: camera-IMU " +
         FormatDouble("%.1f", static_cast<double>(vio.calibration_time_offset_ns) * 1e-6) + " -> " +
         FormatDouble("%.1f", static_cast<double>(vio.time_offset_ns) * 1e-6) +
         " ms (the VIO's estimate replaced the calibration's)";
}

std::string ImuNoiseLine(const OwnVioDecisions& vio) {
  const ImuNoise& given = vio.imu_noise_given;
  const ImuNoise& used = vio.imu_noise_used;
  std::vector<std::string> parts;
  if (used.accel_noise_density != given.accel_noise_density) {
    parts.push_back("accel " + FormatDouble("%.3g", given.accel_noise_density) + " -> " +
                    FormatDouble("%.3g", used.accel_noise_density));
  }
  if (used.gyro_noise_density != given.gyro_noise_density) {
    parts.push_back("gyro " + FormatDouble("%.3g", given.gyro_noise_density) + " -> " +
                    FormatDouble("%.3g", used.gyro_noise_density));
  }
  const bool walks = used.accel_random_walk != given.accel_random_walk ||
                     used.gyro_random_walk != given.gyro_random_walk;
  if (parts.empty() && !walks) return "";
  std::string line = "IMU noise replaced";
  line += vio.imu_noise_measured ? " (measured at rest): " : " (bounded by the data): ";
  for (size_t i = 0; i < parts.size(); ++i) line += (i > 0 ? ", " : "") + parts[i];
  if (walks) line += parts.empty() ? "random walks changed" : "; random walks scaled";
  return line;
}

std::string ScaleLine(const PipelineSummary& s) {
  if (s.mapper.images_only)
    return "metric scale: none (images only: the model's scale is arbitrary)";
  const MetricScaleSummary& m = s.metric_scale;
  if (!m.estimated)
    return "metric scale: the VIO's, unchecked (no IMU fit: " +
           (m.message.empty() ? std::string("no IMU") : FirstClause(m.message)) + ")";
  std::string source;
  if (m.vio_scale_refuted) {
    source = "the IMU's alone (it refuted the VIO's)";
  } else if (m.imu.usable && m.factor_scale_used) {
    source = "the IMU factors' fused with the VIO's";
  } else if (m.imu.usable) {
    source = "the IMU's fused with the VIO's";
  } else {
    source = "the VIO's (IMU fit " + ImuScaleVerdict(m.imu.message) + ")";
  }
  return "metric scale: " + source + ", +-" + FormatDouble("%.2f", 100.0 * m.applied_scale_sigma) +
         " %";
}

}  // namespace

std::vector<std::string> RunWarnings(const PipelineSummary& s) {
  std::vector<std::string> lines;
  const auto add = [&lines](const std::string& line) {
    if (!line.empty()) lines.push_back(Fit(line));
  };
  if (s.own_vio.ran) {
    add(TimeOffsetLine(s.own_vio));
    add(ImuNoiseLine(s.own_vio));
  }
  add(ScaleLine(s));
  if (s.num_frames_unposed > 0) {
    add("frames without a pose: " + std::to_string(s.num_frames_unposed) + " of " +
        std::to_string(s.num_frames_selected) + " selected (why: summary.json unposed_frames)");
  }
  if (s.num_frames_vio_only > 0) {
    add("frames placed by the VIO alone: " + std::to_string(s.num_frames_vio_only) +
        " (the images do not support their pose)");
  }
  if (s.num_vio_segments > 1) {
    add("VIO segments: " + std::to_string(s.num_vio_segments) + ", " +
        std::to_string(s.mapper.num_vio_segments_joined) + " joined by the images" +
        (s.own_vio.num_resets > 0 ? " (" + std::to_string(s.own_vio.num_resets) + " VIO resets)"
                                  : std::string()));
  }
  if (s.own_vio.num_imu_only_stretches > 0) {
    add("VIO on the IMU alone: " + std::to_string(s.own_vio.num_imu_only_stretches) +
        " stretch(es), " + std::to_string(s.own_vio.num_imu_only_frames) + " frames, longest " +
        FormatDouble("%.2f", s.own_vio.longest_imu_only_s) + " s");
  }
  if (s.mapper.frames_per_model.size() > 1) {
    add("separate models: " + std::to_string(s.mapper.frames_per_model.size() - 1) +
        " beside model/ (" + std::to_string(s.mapper.num_frames_in_other_models) +
        " frames, models/1/, ...)");
  }
  return lines;
}

}  // namespace viosfm
