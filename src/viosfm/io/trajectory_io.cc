#include "viosfm/io/trajectory_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "viosfm/io/colmap_model.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/rotation_checks.h"
#include "viosfm/io/text_lines.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

double ParseField(const fs::path& path, int64_t line, std::string_view field, size_t column,
                  const char* name) {
  const std::optional<double> value = ParseDouble(field);
  if (!value || !std::isfinite(*value)) {
    throw InputError(path.string(), line,
                     "column " + std::to_string(column + 1) + " (" + name +
                         "): expected a finite number, got '" + std::string(field) + "'");
  }
  return *value;
}

// A quaternion read from a file: a unit quaternion within
// kFileRotationTolerance (io/rotation_checks.h), normalised. An already unit
// quaternion is kept bit for bit, so that write -> read is lossless.
Eigen::Quaterniond UnitQuaternion(const fs::path& path, int64_t line, Eigen::Quaterniond q) {
  if (const std::string problem = CheckFileQuaternion(q); !problem.empty()) {
    throw InputError(path.string(), line,
                     "expected a unit quaternion (qx qy qz qw in columns 5-8): " + problem);
  }
  if (std::abs(q.squaredNorm() - 1.0) > 2e-15) q.normalize();
  return q;
}

// Stamps must not decrease. A repeated stamp (real ground-truth files have
// them, e.g. TUM fr2/desk) is kept, as evo keeps it, with a warning.
void AppendPose(const fs::path& path, int64_t line, Trajectory& trajectory, StampedPose pose) {
  if (!trajectory.poses.empty()) {
    const timestamp_ns_t previous = trajectory.poses.back().timestamp_ns;
    if (pose.timestamp_ns < previous) {
      throw InputError(path.string(), line,
                       "expected a timestamp not smaller than the previous one (" +
                           FormatNsAsSeconds(previous) + " s), got " +
                           FormatNsAsSeconds(pose.timestamp_ns) + " s");
    }
    if (pose.timestamp_ns == previous) {
      VIOSFM_LOG(WARNING) << path.string() << ":" << line << ": repeated timestamp "
                          << FormatNsAsSeconds(previous) << " s (both poses kept)";
    }
  }
  trajectory.poses.push_back(std::move(pose));
}

void RequireNotEmpty(const fs::path& path, const Trajectory& trajectory) {
  if (trajectory.empty())
    throw InputError(path.string(), 0, "expected at least one pose, found none");
}

}  // namespace

TrajectoryFormat ParseTrajectoryFormat(const std::string& name) {
  const std::string lower = ToLower(Trim(name));
  if (lower == "tum") return TrajectoryFormat::kTum;
  if (lower == "euroc") return TrajectoryFormat::kEuroc;
  if (lower == "kitti") return TrajectoryFormat::kKitti;
  if (lower == "colmap") return TrajectoryFormat::kColmap;
  throw InputError("unknown trajectory format '" + name +
                   "': expected tum, euroc, kitti or colmap");
}

std::string TrajectoryFormatName(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum: return "tum";
    case TrajectoryFormat::kEuroc: return "euroc";
    case TrajectoryFormat::kKitti: return "kitti";
    case TrajectoryFormat::kColmap: return "colmap";
  }
  return "unknown";
}

TrajectoryFormat GuessTrajectoryFormat(const fs::path& path) {
  if (fs::is_directory(path)) return TrajectoryFormat::kColmap;
  RequireFile(path, "trajectory file");
  std::ifstream stream(path);
  if (!stream) throw InputError(path.string(), 0, "cannot open for reading");
  std::string line;
  int64_t line_number = 0;
  while (std::getline(stream, line)) {
    ++line_number;
    const std::string_view trimmed = Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    if (trimmed.find(',') != std::string_view::npos) {
      if (Split(trimmed, ",").size() >= 8) return TrajectoryFormat::kEuroc;
    } else {
      const size_t columns = Split(trimmed, " \t", /*skip_empty=*/true).size();
      if (columns == 8) return TrajectoryFormat::kTum;
      if (columns == 12) return TrajectoryFormat::kKitti;
    }
    throw InputError(path.string(), line_number,
                     "cannot guess the trajectory format: expected 8 whitespace-separated "
                     "columns (TUM), 12 (KITTI) or >= 8 comma-separated fields (EuRoC)");
  }
  throw InputError(path.string(), 0, "cannot guess the trajectory format: no data line");
}

Trajectory ReadTumTrajectory(const fs::path& path) {
  static constexpr const char* kNames[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  Trajectory trajectory;
  trajectory.has_timestamps = true;
  ForEachDataLine(path, "trajectory file", [&](int64_t line, std::string_view text) {
    const std::vector<std::string_view> fields = SplitFields(text, " \t");
    if (fields.size() != 8) {
      throw InputError(path.string(), line,
                       "expected 8 columns (timestamp tx ty tz qx qy qz qw), got " +
                           std::to_string(fields.size()));
    }
    const std::optional<timestamp_ns_t> stamp = ParseSecondsToNs(fields[0]);
    if (!stamp || !IsTimestampInRange(*stamp)) {
      throw InputError(
          path.string(), line,
          "column 1 (timestamp): expected decimal seconds within +-2^62 ns (146 years) of the "
          "epoch, got '" +
              std::string(fields[0]) + "'");
    }
    double values[8];
    for (size_t i = 1; i < 8; ++i) values[i] = ParseField(path, line, fields[i], i, kNames[i]);
    StampedPose pose;
    pose.timestamp_ns = *stamp;
    pose.world_from_frame.translation = Eigen::Vector3d(values[1], values[2], values[3]);
    pose.world_from_frame.rotation =
        UnitQuaternion(path, line, Eigen::Quaterniond(values[7], values[4], values[5], values[6]));
    AppendPose(path, line, trajectory, std::move(pose));
  });
  RequireNotEmpty(path, trajectory);
  return trajectory;
}

Trajectory ReadEurocTrajectory(const fs::path& path) {
  const std::vector<GroundTruthState> states = ReadEurocGroundTruth(path);
  Trajectory trajectory;
  trajectory.has_timestamps = true;
  trajectory.poses.reserve(states.size());
  for (const GroundTruthState& state : states) {
    trajectory.poses.push_back({state.timestamp_ns, state.world_from_body});
  }
  RequireNotEmpty(path, trajectory);
  return trajectory;
}

Trajectory ReadKittiTrajectory(const fs::path& path) {
  Trajectory trajectory;
  trajectory.has_timestamps = false;
  ForEachDataLine(path, "trajectory file", [&](int64_t line, std::string_view text) {
    const std::vector<std::string_view> fields = SplitFields(text, " \t");
    if (fields.size() != 12) {
      throw InputError(
          path.string(), line,
          "expected 12 numbers (row-major 3x4 pose), got " + std::to_string(fields.size()));
    }
    Matrix3x4d matrix;
    for (size_t i = 0; i < 12; ++i) {
      matrix(i / 4, i % 4) = ParseField(path, line, fields[i], i, "pose matrix entry");
    }
    if (const std::string problem = CheckFileRotationMatrix(matrix.leftCols<3>());
        !problem.empty()) {
      throw InputError(path.string(), line,
                       "expected a rotation matrix in the left 3x3 block: " + problem);
    }
    StampedPose pose;
    pose.timestamp_ns = static_cast<timestamp_ns_t>(trajectory.poses.size());
    pose.world_from_frame = Rigid3d::FromMatrix(matrix);
    trajectory.poses.push_back(std::move(pose));
  });
  RequireNotEmpty(path, trajectory);
  return trajectory;
}

Trajectory ReadColmapTrajectory(const fs::path& folder, const std::string& name_prefix) {
  const Reconstruction reconstruction = ReadColmapModel(folder);
  struct Entry {
    std::optional<timestamp_ns_t> stamp;
    std::string name;
    Rigid3d world_from_cam;
  };
  std::vector<Entry> entries;
  for (const auto& [image_id, image] : reconstruction.Images()) {
    if (!image.registered || !StartsWith(image.name, name_prefix)) continue;
    const std::optional<timestamp_ns_t> stamp =
        image.timestamp_ns ? image.timestamp_ns : TimestampFromImageName(image.name);
    entries.push_back({stamp, image.name, image.cam_from_world.Inverse()});
  }
  if (entries.empty()) {
    throw InputError(folder.string(), 0,
                     "expected registered images" +
                         (name_prefix.empty() ? std::string() : " named '" + name_prefix + "*'") +
                         ", found none");
  }
  const size_t num_stamped = static_cast<size_t>(std::count_if(
      entries.begin(), entries.end(), [](const Entry& entry) { return entry.stamp.has_value(); }));
  if (num_stamped != 0 && num_stamped != entries.size()) {
    const auto unstamped = std::find_if(entries.begin(), entries.end(),
                                        [](const Entry& entry) { return !entry.stamp; });
    throw InputError(folder.string(), 0,
                     "expected every image name to hold a timestamp (\"<ns>.png\") or none, but '" +
                         unstamped->name + "' has none while " + std::to_string(num_stamped) +
                         " others have one");
  }
  const bool stamped = num_stamped != 0;
  std::sort(entries.begin(), entries.end(), [stamped](const Entry& a, const Entry& b) {
    return stamped ? *a.stamp < *b.stamp : a.name < b.name;
  });
  Trajectory trajectory;
  trajectory.has_timestamps = stamped;
  for (size_t i = 0; i < entries.size(); ++i) {
    if (stamped && i > 0 && *entries[i].stamp == *entries[i - 1].stamp) {
      throw InputError(folder.string(), 0,
                       "images '" + entries[i - 1].name + "' and '" + entries[i].name +
                           "' have the same timestamp: select one camera with a name prefix");
    }
    trajectory.poses.push_back(
        {stamped ? *entries[i].stamp : static_cast<timestamp_ns_t>(i), entries[i].world_from_cam});
  }
  return trajectory;
}

Trajectory ReadTrajectory(const fs::path& path, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum: return ReadTumTrajectory(path);
    case TrajectoryFormat::kEuroc: return ReadEurocTrajectory(path);
    case TrajectoryFormat::kKitti: return ReadKittiTrajectory(path);
    case TrajectoryFormat::kColmap: return ReadColmapTrajectory(path);
  }
  throw InputError(path.string(), 0, "unknown trajectory format");
}

void WriteTumTrajectory(const fs::path& path, const Trajectory& trajectory) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "# timestamp tx ty tz qx qy qz qw\n";
    for (const StampedPose& pose : trajectory.poses) {
      const Eigen::Vector3d& t = pose.world_from_frame.translation;
      const Eigen::Quaterniond& q = pose.world_from_frame.rotation;
      out << FormatNsAsSeconds(pose.timestamp_ns, 9) << ' ' << FormatRoundTrip(t.x()) << ' '
          << FormatRoundTrip(t.y()) << ' ' << FormatRoundTrip(t.z()) << ' '
          << FormatRoundTrip(q.x()) << ' ' << FormatRoundTrip(q.y()) << ' '
          << FormatRoundTrip(q.z()) << ' ' << FormatRoundTrip(q.w()) << '\n';
    }
  });
}

void WriteEurocTrajectory(const fs::path& path, const Trajectory& trajectory) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],"
           "q_RS_y [],q_RS_z []\n";
    for (const StampedPose& pose : trajectory.poses) {
      const Eigen::Vector3d& t = pose.world_from_frame.translation;
      const Eigen::Quaterniond& q = pose.world_from_frame.rotation;
      out << pose.timestamp_ns << ',' << FormatRoundTrip(t.x()) << ',' << FormatRoundTrip(t.y())
          << ',' << FormatRoundTrip(t.z()) << ',' << FormatRoundTrip(q.w()) << ','
          << FormatRoundTrip(q.x()) << ',' << FormatRoundTrip(q.y()) << ','
          << FormatRoundTrip(q.z()) << '\n';
    }
  });
}

void WriteKittiTrajectory(const fs::path& path, const Trajectory& trajectory) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    for (const StampedPose& pose : trajectory.poses) {
      const Matrix3x4d matrix = pose.world_from_frame.ToMatrix();
      for (int i = 0; i < 12; ++i) {
        out << (i == 0 ? "" : " ") << FormatRoundTrip(matrix(i / 4, i % 4));
      }
      out << '\n';
    }
  });
}

void WriteTrajectory(const fs::path& path, const Trajectory& trajectory, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum: return WriteTumTrajectory(path, trajectory);
    case TrajectoryFormat::kEuroc: return WriteEurocTrajectory(path, trajectory);
    case TrajectoryFormat::kKitti: return WriteKittiTrajectory(path, trajectory);
    case TrajectoryFormat::kColmap: break;
  }
  throw InputError(path.string(), 0, "cannot write a trajectory as a COLMAP model");
}

Rigid3d ParsePoseTxyzQxyzw(std::string_view text, const std::string& what) {
  const std::vector<std::string_view> fields = Split(Trim(text), " \t,", /*skip_empty=*/true);
  if (fields.size() != 7) {
    throw InputError(what + ": expected 7 numbers \"tx ty tz qx qy qz qw\", got " +
                     std::to_string(fields.size()) + " in '" + std::string(text) + "'");
  }
  double values[7];
  for (size_t i = 0; i < 7; ++i) {
    const std::optional<double> value = ParseDouble(fields[i]);
    if (!value || !std::isfinite(*value)) {
      throw InputError(what + ": expected a number as value " + std::to_string(i + 1) +
                       " of \"tx ty tz qx qy qz qw\", got '" + std::string(fields[i]) + "'");
    }
    values[i] = *value;
  }
  const Eigen::Quaterniond q(values[6], values[3], values[4], values[5]);
  if (const std::string problem = CheckFileQuaternion(q); !problem.empty()) {
    throw InputError(what + ": expected a unit quaternion qx qy qz qw: " + problem);
  }
  return Rigid3d(q.normalized(), Eigen::Vector3d(values[0], values[1], values[2]));
}

}  // namespace viosfm
