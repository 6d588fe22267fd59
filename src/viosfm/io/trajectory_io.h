// Trajectory file formats. Read functions throw InputError naming the file,
// line and what was expected; write functions write atomically.
//
//  TUM:   "timestamp tx ty tz qx qy qz qw" per line, seconds, whitespace
//         separated, '#' comments; pose is world_from_frame; quaternion last
//         (qx qy qz qw). Stamps are parsed digit-exactly into ns.
//  EuRoC ground truth (state_groundtruth_estimate0/data.csv): "#timestamp [ns],
//         p_RS_R_x, p_RS_R_y, p_RS_R_z, q_RS_w, q_RS_x, q_RS_y, q_RS_z,
//         v_RS_R_x, ..., b_w_RS_S_x, ..., b_a_RS_S_x, ..." (ns, qw first;
//         8 or 17 columns, see ReadEurocGroundTruth in io/euroc.h).
//  KITTI: 12 numbers per line, the row-major top 3x4 of world_from_frame; no
//         stamps (rows are indexed 0, 1, ...; has_timestamps = false).
//  COLMAP: a model folder (text or binary, see io/colmap_model.h), read only:
//         the registered images as world_from_cam poses, stamped from their
//         names (EuRoC-style "<ns>.png", see TimestampFromImageName).
//
// Every reader requires non-decreasing stamps (a repeated stamp is kept, with
// a warning, as evo keeps it: the TUM fr2/desk ground truth has one) and
// rotations within the one tolerance of every reader (io/rotation_checks.h):
// a quaternion of norm 1 +- 1e-3 (then normalised), a KITTI rotation block
// orthonormal to 1e-3 with determinant +1 (a mirrored frame is rejected). Writers use enough digits
// (17 significant, 9 decimal places of seconds for TUM) that write -> read reproduces every number.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "viosfm/scene/trajectory.h"

namespace viosfm {

enum class TrajectoryFormat { kTum, kEuroc, kKitti, kColmap };

// "tum", "euroc", "kitti", "colmap" (case-insensitive); throws InputError otherwise.
TrajectoryFormat ParseTrajectoryFormat(const std::string& name);
std::string TrajectoryFormatName(TrajectoryFormat format);
// The option texts (util/option_fields.h).
inline std::string OptionText(TrajectoryFormat value) {
  return TrajectoryFormatName(value);
}
inline void ParseOptionText(const std::string& text, TrajectoryFormat* value) {
  *value = ParseTrajectoryFormat(text);
}
// A folder -> COLMAP; a file: guesses from its first data line: 8
// whitespace-separated columns -> TUM, 12 -> KITTI, a comma-separated line
// with >= 8 fields -> EuRoC. Throws InputError if no guess fits.
TrajectoryFormat GuessTrajectoryFormat(const std::filesystem::path& path);

Trajectory ReadTumTrajectory(const std::filesystem::path& path);
Trajectory ReadEurocTrajectory(const std::filesystem::path& path);
Trajectory ReadKittiTrajectory(const std::filesystem::path& path);
// Registered images whose name starts with `name_prefix` (e.g. "cam0/"; empty:
// all), sorted by stamp. If no image name holds a stamp, they are sorted by
// name and indexed 0, 1, ... (has_timestamps = false); if only some do, or
// two images share a stamp, that is an InputError.
Trajectory ReadColmapTrajectory(const std::filesystem::path& folder,
                                const std::string& name_prefix = "");
Trajectory ReadTrajectory(const std::filesystem::path& path, TrajectoryFormat format);

void WriteTumTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);
// Writes the 8-column form (stamp, position, quaternion w first).
void WriteEurocTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);
void WriteKittiTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);
// kColmap cannot be written (InputError).
void WriteTrajectory(const std::filesystem::path& path, const Trajectory& trajectory,
                     TrajectoryFormat format);

// Parses one pose written TUM-style without a stamp: "tx ty tz qx qy qz qw"
// (whitespace or comma separated) into b_from_a. `what` names the source in
// the InputError thrown on a malformed text (e.g. "--body-from-cam").
Rigid3d ParsePoseTxyzQxyzw(std::string_view text, const std::string& what);

}  // namespace viosfm
