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
//
// A realistic VIO (EmulateRealisticVio) draws its errors from the model of
// scene/vio_uncertainty.h instead, on a dense time grid (a VIO's output
// rate, not the frames an SfM run uses): yaw, tilt and position random walks
// growing with time, distance and rotation travelled, a metric scale error,
// white and slowly varying (Gauss-Markov) frame noise, and optional
// re-initialisations: the VIO loses track, gives no pose for a while, and
// restarts in a new world frame (origin at the body, yaw of the body zero,
// as VINS-Mono and OpenVINS do), its drift starting afresh.
#pragma once

#include <string>
#include <vector>

#include "viosfm/scene/trajectory.h"
#include "viosfm/scene/vio_uncertainty.h"

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

struct RealisticVioOptions {
  // Drift and noise rates (the model's defaults: an external VIO on
  // EuRoC-class data, see scene/vio_uncertainty.h). Its scale_sigma is not
  // used: the scale error is scale_error.
  VioUncertaintyModel model;
  // The VIO's displacements are (1 + scale_error) times the true ones.
  // Default 0.02 (a real monocular VIO's order of scale error).
  double scale_error = 0.02;
  // Seconds after the first pose at which the VIO loses track and
  // re-initialises; default none.
  std::vector<double> reinit_times_s;
  // Seconds without a pose after each loss (the re-initialisation); 0: the
  // pose jumps into the new world frame from one pose to the next, with no
  // gap that would reveal it. Default 1.
  double reinit_gap_s = 1.0;
  uint64_t seed = 2;

  // All drift and noise terms (and the scale error) multiplied by `factor`.
  RealisticVioOptions Scaled(double factor) const;
  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct EmulatedVio {
  Trajectory world_from_frame;  // the poses the VIO gives (none while re-initialising)
  std::vector<int> segments;    // per pose: 0, then +1 after every re-initialisation
};

// `ground_truth` is world_from_frame in time order, densely sampled (the
// walks grow per step). Stamps within a re-initialisation's gap have no pose.
EmulatedVio EmulateRealisticVio(const Trajectory& ground_truth, const RealisticVioOptions& options);

// The realistic VIO of a ground truth of any spacing (the photos of a
// survey, keyframes seconds apart): the ground truth is interpolated (linear
// positions, slerped rotations) on a grid of at least `rate_hz` that passes
// through every one of its stamps, and the VIO emulated on that grid, as a
// VIO gives its poses at its own rate. The result has a pose at every stamp
// of the grid (none within a re-initialisation's gap), so at each stamp of
// `ground_truth` too. `ground_truth` needs at least two poses with
// increasing stamps (CHECK); rate_hz > 0.
EmulatedVio EmulateRealisticVioOnGrid(const Trajectory& ground_truth,
                                      const RealisticVioOptions& options, double rate_hz);

}  // namespace viosfm
