// How far a VIO's poses can be trusted: a model of the error of the relative
// pose the VIO gives between two of its frames, and the segments of a VIO
// trajectory (stretches between re-initialisations, across which a relative
// pose means nothing).
//
// The error model. A VIO's pose error is a drift that grows along the way
// (random walks in time, distance travelled and rotation travelled; the
// IMU's bias and scale-factor errors and the slow loss of old landmarks
// integrate into it), a metric scale error, and noise of its own frame by
// frame (white, plus a slowly varying part with a correlation time). Roll
// and pitch are observable through gravity and drift far less than yaw (the
// world's z axis is taken to be up, as every gravity-aligned VIO output is).
//
// For frames 1 and 2 of one segment, with world_from_cam rotations R1, R2,
// camera centres c1, c2 and d = c2 - c1, the error of the VIO's cam2_from_cam1
// is measured as the residual of ba/cost_functions.h's RelativePoseError,
// r = [Log(R_E); t_E] (rad, m, in camera 2's frame). To first order,
//   Log(R_E) = R2^T (n_rot2 - n_rot1 + w_rot)
//   t_E      = R2^T (n_pos2 - n_pos1 + w_pos + [d]x n_rot1 + s d)
// with n_* the frames' own noise (world frame), w_* the drift accumulated
// between the frames and s the relative scale error (scale_sigma; for the
// relative-pose priors, which share a segment's constant scale error, only
// its variation, relative_scale_sigma: WithinSegment). The drift between the
// frames, after dt seconds, D metres and A radians travelled:
//   tilt (x, y):  var = tilt_walk^2 dt
//   yaw (z):      var V = yaw_per_sqrt_s^2 dt + yaw_per_sqrt_m^2 D + yaw_per_sqrt_rad^2 A
//   position:     var = position_per_sqrt_s^2 dt + position_per_sqrt_m^2 D (each axis)
// and the yaw drift, accumulated along the way, also turns the displacement:
// lateral error u (z x d) with var(u) = V / 3 and cov(u, yaw) = V / 2 (a
// random walk integrated along a straight path). The frame noise has
// variance sigma_w^2 + sigma_c^2 per axis and frame, and the two frames'
// noise correlation sigma_c^2 exp(-dt / tau). RelativePoseCovariance
// returns the 6x6 covariance of r; sim/vio_emulator.h draws VIO
// trajectories from the same model (its test checks this covariance
// against a Monte-Carlo of the emulator).
//
// Defaults. Published monocular VIO on EuRoC V1_01 (58.6 m in 144 s):
// OpenVINS about 0.11 m ATE and 0.5 degrees (github.com/rpng/open_vins
// evaluations; average over EuRoC 0.18 m, 1.1 degrees), VINS-Mono 0.05-0.10
// m (Qin et al., T-RO 2018, without loop closure); a VIO with yaw and
// position random walks growing with distance, a 2 % scale error and
// millimetre noise has about 0.10 m ATE on V1_01's keyframes.
// The defaults reproduce that order: over V1_01's 58.6 m and 144 s the yaw
// walks sqrt(0.003^2 58.6 + 0.0005^2 144 + 0.003^2 A) ~ 0.03 rad (1.7
// degrees at most, end to end; ATE-aligned far less), the position 0.08 m,
// the scale 2 %, the frames 2 mm and 1 mrad apart from it. They are rates
// of an external VIO of unknown quality, on the pessimistic side: a model
// that trusts the VIO too much pulls the reconstruction toward its drift, one
// that trusts it too little only gives the images more say. viosfm's own
// VIO uses them too: its marginal covariance is overconfident against the
// simulator's truth (yaw error 2.5-4.5 times its sigma), these rates are
// not (docs/benchmarks.md, scripts/vio-covariance-consistency.py).
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// The rates of the model above (standard deviations; "per sqrt X": the
// variance grows linearly with X).
struct VioUncertaintyModel {
  double position_per_sqrt_m = 0.01;   // m / sqrt(m travelled), each axis. Default 0.01
  double position_per_sqrt_s = 0.002;  // m / sqrt(s), each axis. Default 0.002
  double yaw_per_sqrt_m = 0.003;       // rad / sqrt(m travelled). Default 0.003
  double yaw_per_sqrt_s = 0.0005;      // rad / sqrt(s). Default 0.0005
  double yaw_per_sqrt_rad = 0.003;     // rad / sqrt(rad turned). Default 0.003
  double tilt_per_sqrt_s = 0.0001;     // rad / sqrt(s), roll and pitch. Default 0.0001
  double scale_sigma = 0.02;           // relative error of displacements. Default 0.02
  // The part of the scale error that varies from one pair of frames of a
  // segment to another (relative, per pair), beyond the constant part that
  // all of the segment's relative poses share. The constant part (up to
  // scale_sigma) cannot be averaged out over many relative poses: it is the
  // scale the model takes from the VIO, which the IMU's scale fit then
  // corrects. So the relative-pose priors carry only this part
  // (WithinSegment). Default 0.005: on the keyframe-like simulated
  // sequences, 0.02 per prior (the whole scale error on every prior, as if
  // independent) let the keyframes' lengths float (corridor 28 mm ATE), and
  // 0.0001 held them so rigidly that the room lost 46 %; 0.005 gives the
  // corridor 20 mm and the room what it had (docs/benchmarks.md).
  double relative_scale_sigma = 0.005;
  double position_noise_m = 0.002;    // m, white noise per frame and axis. Default 0.002
  double rotation_noise_rad = 0.001;  // rad, white noise per frame and axis. Default 0.001
  // Slowly varying frame noise (first-order Gauss-Markov) with correlation
  // time noise_correlation_s. Defaults 0.002 m, 0.001 rad, 1 s.
  double correlated_position_noise_m = 0.002;
  double correlated_rotation_noise_rad = 0.001;
  double noise_correlation_s = 1.0;

  // The model with every rate multiplied by `factor` (> 0), the correlation
  // time kept.
  VioUncertaintyModel Scaled(double factor) const;
  // The model of the relative poses within one segment, given the
  // segment's scale: scale_sigma replaced by relative_scale_sigma (see there).
  VioUncertaintyModel WithinSegment() const;
  // Every rate zero except a floor of frame noise (1e-4 m, 1e-4 rad): an
  // (almost) exact VIO.
  static VioUncertaintyModel Exact();

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
  // Every rate as (name, value) text, for options.json.
  std::vector<std::pair<std::string, std::string>> ToKeyValues() const;

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"position_per_sqrt_m", "m / sqrt(m travelled), each axis", kShapesStoredData},
          self.position_per_sqrt_m);
    visit({"position_per_sqrt_s", "m / sqrt(s), each axis", kShapesStoredData},
          self.position_per_sqrt_s);
    visit({"yaw_per_sqrt_m", "rad / sqrt(m travelled)", kShapesStoredData}, self.yaw_per_sqrt_m);
    visit({"yaw_per_sqrt_s", "rad / sqrt(s)", kShapesStoredData}, self.yaw_per_sqrt_s);
    visit({"yaw_per_sqrt_rad", "rad / sqrt(rad turned)", kShapesStoredData}, self.yaw_per_sqrt_rad);
    visit({"tilt_per_sqrt_s", "rad / sqrt(s), roll and pitch", kShapesStoredData},
          self.tilt_per_sqrt_s);
    visit({"scale_sigma", "relative error of displacements", kShapesStoredData}, self.scale_sigma);
    visit({"relative_scale_sigma",
           "relative scale error varying between pairs of frames of a segment (priors)", kRunOnly},
          self.relative_scale_sigma);
    visit({"position_noise_m", "m, white noise per frame and axis", kShapesStoredData},
          self.position_noise_m);
    visit({"rotation_noise_rad", "rad, white noise per frame and axis", kShapesStoredData},
          self.rotation_noise_rad);
    visit({"correlated_position_noise_m", "m, slowly varying frame noise", kShapesStoredData},
          self.correlated_position_noise_m);
    visit({"correlated_rotation_noise_rad", "rad, slowly varying frame noise", kShapesStoredData},
          self.correlated_rotation_noise_rad);
    visit({"noise_correlation_s", "s, correlation time of the slowly varying noise",
           kShapesStoredData},
          self.noise_correlation_s);
  }
};

// What the model needs to know of one VIO pose besides the pose itself.
struct VioOdometer {
  int segment = 0;            // index of the segment (see SegmentVioTrajectory)
  double distance_m = 0.0;    // path length from the segment's first pose
  double rotation_rad = 0.0;  // rotation angle travelled from the segment's first pose
  // The time gaps in the VIO's poses before this one within its segment
  // (SegmentsFromTimeGaps): a VIO file does not say where it
  // re-initialised, so a long gap is only a candidate break, which the
  // images confirm or refute (sfm/vio_gaps.h). Frames with different
  // counts lie on two sides of a gap.
  int gap = 0;
};

// One frame as the model sees it: the VIO's pose of the camera and its
// odometer.
struct VioSample {
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d world_from_cam;
  VioOdometer odometer;
};

// Covariance (rad^2, m^2) of the residual r = [Log(R_E); t_E] of the VIO's
// relative pose cam2_from_cam1 between frames 1 and 2 of one segment (see
// the top of the file); its order in time does not matter. CHECKs that both
// frames are in the same segment.
Eigen::Matrix<double, 6, 6> RelativePoseCovariance(const VioUncertaintyModel& model,
                                                   const VioSample& frame1,
                                                   const VioSample& frame2);

// The part of RelativePoseCovariance that the drift between the two frames
// and the scale's variation make, without the frames' own noise: positive
// semi-definite only (zero for two frames at one time and place).
Eigen::Matrix<double, 6, 6> RelativePoseDriftCovariance(const VioUncertaintyModel& model,
                                                        const VioSample& frame1,
                                                        const VioSample& frame2);

// The lower-triangular S with S^T S = covariance^-1 (so |S r|^2 is r's
// Mahalanobis distance): what weights a residual. CHECKs that the
// covariance is positive definite.
Eigen::Matrix<double, 6, 6> SqrtInformationFromCovariance(
    const Eigen::Matrix<double, 6, 6>& covariance);

// Standard deviations summarising a covariance of r: the square roots of the
// largest eigenvalues of its rotation (rad) and translation (m) blocks.
struct RelativePoseSigmas {
  double rotation_rad = 0.0;
  double translation_m = 0.0;
};
RelativePoseSigmas LargestSigmas(const Eigen::Matrix<double, 6, 6>& covariance);

// The number of gaps between consecutive stamps longer than max_gap_ns
// before every pose of a VIO trajectory (time ordered): where a VIO may have
// lost track and re-initialised (it gives no poses for a while and then
// poses in a new world frame), or only given keyframes; a segment index
// when every such gap is a break, a VioOdometer::gap when the images judge
// them. max_gap_ns <= 0: none.
std::vector<int> SegmentsFromTimeGaps(const Trajectory& trajectory, timestamp_ns_t max_gap_ns);

// The odometer of every pose of `world_from_frame` (time ordered) given its
// segment indices (non-decreasing, one per pose; empty: one segment): path
// length and rotation angle summed from each segment's first pose. CHECKs
// the sizes.
std::vector<VioOdometer> ComputeVioOdometers(const Trajectory& world_from_frame,
                                             const std::vector<int>& segments);

}  // namespace viosfm
