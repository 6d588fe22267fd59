// Emulated visual-inertial odometry: ground truth corrupted the way a real
// VIO drifts, so that the SfM stages can be tested apart from any VIO.
//
// Roll and pitch are observable through gravity and do not drift; position
// and yaw do, as random walks whose variance grows with distance travelled.
// Frame by frame:
//   yaw_drift_k = yaw_drift_{k-1} + N(0, yaw_walk^2 * d_k)
//   p_k = p_{k-1} + Rz(yaw_drift_k) (1 + scale_error) (p_gt_k - p_gt_{k-1}) + N(0, pos_walk^2 d_k)
//   R_k = Rz(yaw_drift_k) R_gt_k
// with d_k the distance travelled since frame k-1; then independent per-frame
// jitter is added to the output (not accumulated).
#pragma once

#include <string>

#include "viosfm/scene/trajectory.h"

namespace viosfm {

struct VioDriftOptions {
  double position_walk_m_per_sqrt_m = 0.01;  // m / sqrt(m travelled)
  double yaw_walk_rad_per_sqrt_m = 0.002;    // rad / sqrt(m travelled)
  double scale_error = 0.0;                  // relative, e.g. 0.01 = 1 % too long
  double position_jitter_m = 0.003;          // m, per-frame white noise (std)
  double rotation_jitter_rad = 0.002;        // rad, per-frame white noise (std)
  uint64_t seed = 2;

  // All drift terms multiplied by `factor` (to sweep the drift level).
  VioDriftOptions Scaled(double factor) const;
  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// `ground_truth` is world_from_frame (body or camera) in time order; the
// result has the same stamps.
Trajectory EmulateVioDrift(const Trajectory& ground_truth, const VioDriftOptions& options);

}  // namespace viosfm
