// Trajectory file formats. Read functions throw InputError naming the file,
// line and what was expected; write functions write atomically.
//
//  TUM:   "timestamp tx ty tz qx qy qz qw" per line, seconds, '#' comments;
//         pose is world_from_frame; quaternion last (qx qy qz qw).
//  EuRoC ground truth (state_groundtruth_estimate0/data.csv): "#timestamp [ns],
//         p_RS_R_x, p_RS_R_y, p_RS_R_z, q_RS_w, q_RS_x, q_RS_y, q_RS_z,
//         v_RS_R_x, ..., b_w_RS_S_x, ..., b_a_RS_S_x, ..." (ns, qw first;
//         only the first 8 columns are required).
//  KITTI: 12 numbers per line, the row-major top 3x4 of world_from_frame; no
//         stamps (rows are indexed 0, 1, ...).
#pragma once

#include <filesystem>
#include <string>

#include "viosfm/scene/trajectory.h"

namespace viosfm {

enum class TrajectoryFormat { kTum, kEuroc, kKitti };

// "tum", "euroc", "kitti" (case-insensitive); throws InputError otherwise.
TrajectoryFormat ParseTrajectoryFormat(const std::string& name);
std::string TrajectoryFormatName(TrajectoryFormat format);
// Guesses from the content of the first data line: 8 columns -> TUM,
// 12 -> KITTI, a comma-separated line with >= 8 fields -> EuRoC.
// Throws InputError if no guess fits.
TrajectoryFormat GuessTrajectoryFormat(const std::filesystem::path& path);

Trajectory ReadTumTrajectory(const std::filesystem::path& path);
Trajectory ReadEurocTrajectory(const std::filesystem::path& path);
Trajectory ReadKittiTrajectory(const std::filesystem::path& path);
Trajectory ReadTrajectory(const std::filesystem::path& path, TrajectoryFormat format);

void WriteTumTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);
void WriteEurocTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);
void WriteKittiTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);
void WriteTrajectory(const std::filesystem::path& path, const Trajectory& trajectory,
                     TrajectoryFormat format);

}  // namespace viosfm
