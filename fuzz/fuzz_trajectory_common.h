// Round-trip checks shared by the trajectory fuzzers: what a reader accepts,
// its writer must write so that the reader gives the same poses back
// (io/trajectory_io.h promises that write -> read reproduces every number).
#pragma once

#include <cmath>
#include <string>

#include "fuzz_util.h"
#include "viosfm/io/trajectory_io.h"

namespace viosfm::fuzz {

inline bool SameDouble(double a, double b) {
  return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b) ||
         (a == 0.0 && b == 0.0);  // -0 is written as "-0" and read back as -0 anyway
}

// Reads `text` as `format`; if accepted, writes it in the same format and
// reads it back: stamps and translations must be bit-identical, rotations
// equal to `rotation_tolerance` (rad; 0 = bit-identical quaternions).
inline void TrajectoryRoundTrip(std::string_view text, TrajectoryFormat format,
                                double rotation_tolerance) {
  const std::filesystem::path input = ScratchFolder() / "input.txt";
  const std::filesystem::path output = ScratchFolder() / "output.txt";
  WriteBytes(input, text);
  Trajectory trajectory;
  if (!AcceptsInput([&] { trajectory = ReadTrajectory(input, format); })) return;
  // The format guess must not fail on a file its reader accepts... unless the
  // reader accepts lines the guess rejects by design (it looks at the first
  // data line only); an InputError is fine, nothing else.
  AcceptsInput([&] { GuessTrajectoryFormat(input); });
  WriteTrajectory(output, trajectory, format);
  const Trajectory again = ReadTrajectory(output, format);
  Require(again.size() == trajectory.size(), "round trip keeps the number of poses");
  Require(again.has_timestamps == trajectory.has_timestamps, "round trip keeps has_timestamps");
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const Rigid3d& a = trajectory.poses[i].world_from_frame;
    const Rigid3d& b = again.poses[i].world_from_frame;
    Require(trajectory.poses[i].timestamp_ns == again.poses[i].timestamp_ns,
            "round trip keeps every stamp");
    for (int k = 0; k < 3; ++k) {
      Require(SameDouble(a.translation[k], b.translation[k]), "round trip keeps translations");
    }
    if (rotation_tolerance == 0.0) {
      for (int k = 0; k < 4; ++k) {
        Require(SameDouble(a.rotation.coeffs()[k], b.rotation.coeffs()[k]),
                "round trip keeps quaternions bit for bit");
      }
    } else {
      Require(a.rotation.angularDistance(b.rotation) <= rotation_tolerance,
              "round trip keeps rotations");
    }
  }
}

}  // namespace viosfm::fuzz
