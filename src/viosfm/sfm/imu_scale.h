// The metric scale of a reconstruction from the IMU: what an IMU buys
// beyond the shape.
//
// The reconstruction's shape is what the images give, far better than a
// VIO's; its scale comes from the VIO's relative poses, and a VIO's scale is
// often off by one or two percent (its online estimate sees a few seconds of
// excitation at a time). With the whole sequence's IMU, the shape's scale is
// solved for directly, as in visual-inertial initialisation (Qin & Shen,
// IROS 2017; Mur-Artal & Tardos, RA-L 2017) but over every registered frame:
// for consecutive frames i, j of the (rigidly registered, gravity-aligned)
// body trajectory, with rotations R and positions p in the reconstruction's
// units, preintegrated IMU deltas (dR, dv, dp) between them and unknown
// scale s, velocities v, gravity g (|g| = 9.81, direction refined from the
// reconstruction's up) and accelerometer bias b_a (one per bias window),
//   s (p_j - p_i) - v_i dt - g dt^2 / 2 - R_i J_p b_a = R_i dp
//   v_j - v_i - g dt             - R_i J_v b_a = R_i dv
// are linear (the scale column is the displacement itself); each pair is weighted by the
// preintegration's covariance and the bias random walk over the pair and its window (long gaps
// count little). The gyro bias is solved first from the rotations (the reconstruction's against the
// preintegrated ones). The result carries the scale's standard deviation from the least squares,
// inflated by the residual where the equations disagree more than their covariance allows (a
// reconstruction bent or tilted in places pulls the scale) and narrowed where they agree better
// than assumed (the a-posteriori variance factor); the caller applies it only when that is small.
//
// Over a short pair the displacement the acceleration adds (a t^2 / 2:
// 1.5 mm for 0.3 m/s^2 over 0.1 s) is no larger than a real
// reconstruction's jitter between neighbouring frames (about a millimetre),
// and a least squares whose column carries that noise shrinks the scale
// towards zero (errors in the variables). The fit is therefore repeated on frames at least
// spacing_check_interval_s apart, and the spaced frames' estimate (less precise, not shrunk) is the
// result whenever it is precise enough to be used (max_scale_sigma) or disagrees with the
// consecutive frames' by more than the noise allows: a shrinkage too small for that check still
// leaves the scale a few tenths of a per cent short. See docs/history/benchmarks-2026.md, section
// "The metric scale from frames 1 s apart". Only where the spaced frames' scale is too uncertain
// and agrees does the consecutive frames' stand.
#pragma once

#include <string>
#include <vector>

#include "viosfm/scene/trajectory.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/util/option_fields.h"

namespace viosfm {

struct ImuScaleOptions {
  // s, one accelerometer (and gyro) bias per window of this length. Default
  // 20 (the bias walks; EuRoC's ADIS16448 by about 0.01 m/s^2 in 20 s).
  double bias_window_s = 20.0;
  // Standard deviations of a registered frame's position (m) and rotation
  // (rad) from the images, added to every equation (a rotation error turns
  // the preintegrated velocity and position, gravity included: over long
  // gaps it dominates). Defaults 0.002 m and 0.001 rad.
  double position_sigma_m = 0.002;
  double rotation_sigma_rad = 0.001;
  // s, the spacing of the jitter check: the fit is repeated on frames at
  // least this far apart (the displacement the motion adds grows with the
  // square of the time: 100 times 0.1 s's at 1 s). Default 1: from about
  // 0.5 s apart the jitter no longer shrinks the scale, on the real handheld
  // recording and in the simulator. See docs/history/benchmarks-2026.md,
  // section "Real handheld recording: `realsense_room_30s`".
  double spacing_check_interval_s = 1.0;
  // When the spaced frames' scale is too uncertain to be used, the
  // consecutive frames' stands if it is within this many combined standard
  // deviations of it. Default 3.
  double max_spacing_disagreement = 3.0;
  // Iterations of the gravity-direction refinement. Default 4.
  int gravity_iterations = 4;
  // The estimate is usable when the scale's standard deviation is at most
  // this (relative). Default 0.005.
  double max_scale_sigma = 0.005;
  // Usable scales lie in [1 / max_scale_factor, max_scale_factor].
  // Default 1.2.
  double max_scale_factor = 1.2;
  // A VIO's scale is refuted by the IMU (metric_scale.h), and the IMU's
  // applied alone even where it is not usable by the bounds above, when the
  // IMU's scale lies more than vio_refuted_sigmas combined standard
  // deviations from the VIO's (1), its own relative sigma is at most
  // max_refuting_scale_sigma, its residual_ratio at most
  // max_refuting_residual_ratio, and it is the scale of the frames far
  // enough apart (spaced_used): the consecutive frames' is shrunk towards
  // zero by their jitter, and looks precise while it is. Defaults 5, 0.25
  // and 2: a VIO started in motion can be off by a factor, which its IMU fit
  // shows many sigmas away, and a scale known to 25 % is far nearer the
  // truth than that. (The residual bound of a usable scale,
  // max_residual_ratio, guards percents, not factors.)
  // See docs/history/benchmarks-2026.md, section "Starting in motion".
  double vio_refuted_sigmas = 5.0;
  double max_refuting_scale_sigma = 0.25;
  double max_refuting_residual_ratio = 2.0;
  // Not usable when the whitened residual exceeds its expected size by this
  // factor (ImuScaleResult::residual_ratio): the trajectory's shape is then
  // worse than the equations assume (bent or tilted in places) and pulls
  // the scale systematically; no inflated sigma captures that. Default 1:
  // ground truth and good reconstructions stay well below it, a bent one
  // goes above it.
  double max_residual_ratio = 1.0;
  // Where the final bundle adjustment's IMU factors held
  // (sfm/inertial_terms.h), their metric scale of the model is the IMU's
  // estimate, and this fit checks it: it is used when the fit is usable and
  // lies within max_factor_disagreement of the fit's standard deviations
  // from it (with the fit's sigma), else the fit's is. The factors solve
  // the scale with the shape, the velocities and a pair of biases every
  // second; this linear fit holds the shape and one accelerometer bias per
  // bias_window_s. Defaults true and 3: on the simulated trust sequences the
  // factors' scale is the more accurate and lies within the fit's noise.
  // See docs/history/benchmarks-2026.md, section "The scale from the IMU factors".
  bool use_factor_scale = true;
  double max_factor_disagreement = 3.0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"bias_window_s", "s, one accelerometer and gyro bias per window", kRunOnly},
          self.bias_window_s);
    visit({"max_scale_sigma", "usable when the scale's relative sigma is at most this", kRunOnly},
          self.max_scale_sigma);
    visit({"spacing_check_interval_s", "s, the frame spacing of the jitter check", kRunOnly},
          self.spacing_check_interval_s);
    visit({"max_spacing_disagreement",
           "sigmas the consecutive and the spaced frames' scales may differ by", kRunOnly},
          self.max_spacing_disagreement);
    visit({"position_sigma_m", "m, noise of a registered frame's position", kRunOnly},
          self.position_sigma_m);
    visit({"rotation_sigma_rad", "rad, noise of a registered frame's rotation", kRunOnly},
          self.rotation_sigma_rad);
    visit({"gravity_iterations", "refinements of the gravity direction", kRunOnly},
          self.gravity_iterations);
    visit({"max_scale_factor", "usable when the scale is within [1/this, this]", kRunOnly},
          self.max_scale_factor);
    visit({"vio_refuted_sigmas", "sigmas from the VIO's scale beyond which the IMU's refutes it",
           kRunOnly},
          self.vio_refuted_sigmas);
    visit({"max_refuting_scale_sigma",
           "largest relative sigma of an IMU scale that refutes the VIO's", kRunOnly},
          self.max_refuting_scale_sigma);
    visit({"max_refuting_residual_ratio",
           "largest residual ratio of an IMU scale that refutes the VIO's", kRunOnly},
          self.max_refuting_residual_ratio);
    visit({"max_residual_ratio",
           "usable when the fit's residual is at most this times the expected", kRunOnly},
          self.max_residual_ratio);
    visit({"use_factor_scale",
           "the final adjustment's IMU factors' scale, where they held, in place of the fit's",
           kRunOnly},
          self.use_factor_scale);
    visit({"max_factor_disagreement",
           "fit sigmas the factors' scale may lie from the fit's and still be used", kRunOnly},
          self.max_factor_disagreement);
  }
};

struct ImuScaleResult {
  bool usable = false;  // see ImuScaleOptions; `message` says why not
  std::string message;
  // Metres per unit of the trajectory: multiply its positions by `scale`.
  double scale = 1.0;
  double scale_sigma = 0.0;  // relative standard deviation of `scale`
  Eigen::Vector3d gravity_in_world = Eigen::Vector3d::Zero();
  int num_frames = 0;  // frames used (with IMU around them)
  int num_pairs = 0;
  // sqrt(whitened residual / degrees of freedom) of the least squares: 1
  // when the equations agree as well as their covariance says; scale_sigma
  // is multiplied by it (the a-posteriori variance factor).
  double residual_ratio = 0.0;
  // The jitter check (ImuScaleOptions::spacing_check_interval_s): the
  // spaced frames' scale and relative sigma (0 when there were too few),
  // whether it disagreed with the consecutive frames', and whether it is
  // `scale` (when it disagreed, or when its sigma is at most
  // max_scale_sigma).
  double spaced_scale = 0.0;
  double spaced_scale_sigma = 0.0;
  bool spacing_disagrees = false;
  bool spaced_used = false;
};

// `world_from_body`: the registered frames' body poses (time ordered, at
// least 4 frames covered by `imu`, strictly increasing stamps, CHECK for the
// order); `imu`: samples in increasing time; `noise`: the IMU's noise.
ImuScaleResult EstimateImuScale(const Trajectory& world_from_body,
                                const std::vector<ImuSample>& imu, const ImuNoise& noise,
                                const ImuScaleOptions& options = {});

}  // namespace viosfm
