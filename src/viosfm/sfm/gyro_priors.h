// The gyro's word on the reconstruction's rotations: relative-rotation
// priors between consecutive registered frames, preintegrated from the
// gyro with the biases that the reconstruction's own rotations give.
//
// Where the images see nothing (a dark or bare stairwell, a turn toward a
// white wall), the frames are held only by the VIO's relative poses, and a
// stretch held by them alone turns with the VIO's drift (a second floor
// turned against the first across a stairwell without points). A gyro
// integrated over the
// same stretch, with the bias that the well-imaged stretches on either
// side give (the images' rotations are far better than any VIO's), is off
// by a few tenths of a milliradian per second of gap: the bias error times
// the time, plus the gyro's white noise.
//
// For consecutive frames i, j (body rotations R_i, R_j from the
// reconstruction), with the gyro preintegrated between them (dR, with bias
// Jacobian J = dR_dbg), the gyro bias b of each window solves
//   J b = Log(dR^T R_i^T R_j)
// in the least squares (as the visual-inertial initialisations of Qin &
// Shen, IROS 2017, and Mur-Artal & Tardos, RA-L 2017, do over a few
// seconds; here over every window of bias_window_s). The prior is then the
// preintegrated rotation at that bias, as the camera's cam2_from_cam1, with
// the covariance of the preintegration's white noise, the bias's own
// uncertainty and random walk over the window, and a floor for what the
// gyro model leaves out (misalignment, timing); inflated where the
// reconstruction's rotations disagree with the priors more than that allows
// (a real rig's rolling shutter and clock offset). See
// docs/history/benchmarks-2026.md, section "The gyro's rotations in the final adjustment".
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/sensor/sensor_rig.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"
#include "viosfm/vio/imu_preintegration.h"

namespace viosfm {

struct GyroPriorOptions {
  // Relative-rotation priors from the gyro in the final bundle adjustment,
  // when the dataset has an IMU. Default true.
  bool enabled = true;
  // s, one gyro bias per window. Default 20 (the bias walks; over 20 s an
  // ADIS16448's by about 1e-4 rad/s).
  double bias_window_s = 20.0;
  // rad, standard deviation of a registered frame's rotation from the
  // images, for the bias's least squares. Default 0.001.
  double frame_rotation_sigma_rad = 0.001;
  // rad, added to every prior's standard deviation (each axis): what the
  // gyro model leaves out (the camera-IMU rotation's error, timing,
  // rolling shutter). Default 0.0002.
  double rotation_floor_rad = 0.0002;
  // Pairs further apart than this are not given a prior (s). Default 5: the
  // gyro's bias fit leans on the longest pairs, where the model's own
  // rotation error is largest, and longer gaps made the keyframe sequences
  // worse.
  double max_gap_s = 5.0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"enabled", "the gyro's relative rotations in the final bundle adjustment", kRunOnly},
          self.enabled);
    visit({"bias_window_s", "s, one gyro bias per window", kRunOnly}, self.bias_window_s);
    visit({"frame_rotation_sigma_rad", "rad, a frame's rotation noise for the bias fit", kRunOnly},
          self.frame_rotation_sigma_rad);
    visit({"rotation_floor_rad", "rad, added to every gyro prior's sigma", kRunOnly},
          self.rotation_floor_rad);
    visit({"max_gap_s", "s, no gyro prior between frames further apart", kRunOnly}, self.max_gap_s);
  }
};

// One pair of consecutive frames with the gyro preintegrated between them:
// the input of the bias fit.
struct GyroPair {
  const ImuPreintegration* preintegration = nullptr;
  Eigen::Matrix3d world_from_body_i;  // rotations
  Eigen::Matrix3d world_from_body_j;
  int window = 0;
};

// The gyro bias of each of `num_windows` windows from the pairs' rotations
// (a window without pairs takes the nearest window's; all zero without any
// pair); `bias_sigma` (if not null) gets each window's bias standard
// deviation (rad/s, each axis): the frames' rotation noise at the two ends
// of the window's pairs over the time between them, and the bias's walk.
std::vector<Eigen::Vector3d> EstimateGyroBiases(const std::vector<GyroPair>& pairs, int num_windows,
                                                double frame_rotation_sigma_rad,
                                                const ImuNoise& noise,
                                                std::vector<double>* bias_sigma = nullptr);

// A registered frame: its image, camera pose and time on the camera's clock,
// and whether the images support its pose. Only pairs of supported frames
// enter the bias fit: a frame placed by the VIO alone turns with the VIO's
// drift, which the fit would take for a bias.
struct GyroFrame {
  image_t image_id = kInvalidImageId;
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d cam_from_world;
  bool supported = true;
};

struct GyroPriors {
  // Rotation-only priors (RelativePosePrior::from_gyro) between
  // consecutive frames covered by the IMU.
  std::vector<RelativePosePrior> priors;
  std::vector<Eigen::Vector3d> gyro_biases;  // per window
  // Median over the priors of the whitened rotation residual's norm at the
  // reconstruction's rotations (1.54 when they agree as the covariance
  // says), and the factor the priors' sigmas were multiplied by: that
  // median over 1.54, where it is larger (the rig's imperfections the
  // covariance leaves out), else 1.
  double median_whitened_residual = 0.0;
  double sigma_factor = 1.0;
  std::string message;  // one line for the log
};

// `frames` in strictly increasing time; `imu` in increasing time. The
// priors' sigma factor is at least `min_sigma_factor` (>= 1): a model that
// earlier priors already pulled toward the gyro no longer shows how far
// the rig is from it, so a later adjustment keeps the first one's factor.
GyroPriors MakeGyroPriors(const std::vector<GyroFrame>& frames, const std::vector<ImuSample>& imu,
                          const SensorRig& rig, const GyroPriorOptions& options,
                          double min_sigma_factor = 1.0);

}  // namespace viosfm
