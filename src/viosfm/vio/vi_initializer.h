// Visual-inertial initialisation of the monocular VIO from a moving start
// (the static start is handled by static_init.h), in the spirit of Qin &
// Shen, "Robust initialization of monocular visual-inertial estimation on
// aerial robots" (IROS 2017), as used by VINS-Mono:
//
//  1. Vision-only structure from motion up to scale over a window of
//     keyframes: the reference pair is the earliest keyframe that has enough
//     correspondences with the last one and enough parallax (five-point
//     essential matrix in RANSAC, cheirality, median triangulation angle);
//     its points are triangulated, the other keyframes are registered by
//     PnP (Ceres, from the neighbour's pose) and more points triangulated,
//     and a bundle adjustment (Ceres, Huber loss) refines the window.
//  2. Gyro bias: the preintegrated rotations between consecutive keyframes
//     are compared with the visual ones (through body_from_cam), the bias
//     solved by linear least squares with the bias Jacobian, and the
//     preintegrations repropagated (twice).
//  3. Linear alignment: with the visual frame V (the reference camera's
//     frame, up-to-scale translations c_k), the body positions are
//     p_k = s * c_k + R_V_ck * t_cam_from_body, and the preintegration
//     constraints between consecutive keyframes
//       s (c_k+1 - c_k) - v_k dt - g dt^2 / 2 = R_V_bk dp_k - (R_V_ck+1 - R_V_ck) t_cam_from_body
//       v_k+1 - v_k - g dt                    = R_V_bk dv_k
//     are linear in the velocities v_k (in V), the gravity g (in V) and the
//     scale s; they are solved by least squares (accel bias zero).
//  4. Gravity refinement: |g| = gravity_magnitude is imposed by solving the
//     same system for a 2-DoF correction of g in the tangent plane of its
//     current direction, a few times.
//  5. The result is rotated into a gravity-aligned world: z up, origin at
//     the body of the first keyframe, and the yaw of the first keyframe's
//     body zero (its x axis projected on the horizontal plane is the world
//     x axis).
//
// Failures that happen on good input (too little parallax, too little IMU
// excitation, a negative or implausible scale, a gravity norm far from
// gravity_magnitude) are reported with success == false and a message; the
// result then holds nothing usable.
//
// The computation is deterministic (RANSAC seeded from the options, Ceres
// single-threaded).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/vio/frame_features.h"
#include "viosfm/vio/imu_preintegration.h"

namespace viosfm {

struct ViInitOptions {
  // Keyframes used: the LAST window_size frames given are used (all when
  // fewer are given). Default 10.
  int window_size = 10;
  // Fewest keyframes needed. Default 4.
  int min_num_frames = 4;
  // Focal length (pixels) that converts the pixel thresholds below to
  // normalised coordinates. Default 460 (VINS-Mono's virtual focal length,
  // about EuRoC cam0's).
  double focal_length_px = 460.0;
  // px, a keyframe pair qualifies as the reference pair when the mean
  // displacement of its shared features is at least this. Default 10
  // (rotation is not compensated here; the triangulation angle below is the
  // rotation-free test).
  double min_parallax_px = 10.0;
  // deg, the median triangulation angle of the reference pair's inliers must
  // be at least this (pure rotation and tiny baselines fail here). Default 1.5.
  double min_triangulation_angle_deg = 1.5;
  // Fewest correspondences (and essential-matrix inliers) of the reference
  // pair. Default 30.
  int min_pair_correspondences = 30;
  // px, RANSAC inlier threshold (Sampson distance) of the essential matrix.
  // Default 1.0.
  double essential_max_error_px = 1.0;
  // px, observations whose reprojection error exceeds this after the bundle
  // adjustment are dropped. Default 3.0.
  double max_reprojection_error_px = 3.0;
  // deg, a landmark is triangulated only when two of its rays make at least
  // this angle. Default 1.0.
  double min_landmark_triangulation_angle_deg = 1.0;
  // Fewest landmarks a keyframe must see to be registered by PnP. Default 10.
  int min_pnp_correspondences = 10;
  // Bundle adjustment iterations (each of the two passes). Default 50.
  int max_ba_iterations = 50;
  // m/s^2, smallest standard deviation of the mean specific force between
  // consecutive keyframes, rotated into one frame (i.e. of the acceleration
  // in the world): below it the scale is not observable. Default 0.15.
  double min_accel_stddev = 0.15;
  // m/s^2, largest | |g| - gravity_magnitude | of the gravity from the linear
  // alignment (before |g| is imposed). Default 1.0.
  double max_gravity_norm_error = 1.0;
  // m/s^2, gravity magnitude imposed by the refinement. Default 9.81.
  double gravity_magnitude = kStandardGravity;
  // Iterations of the gravity refinement on the sphere. Default 4.
  int gravity_refinement_iterations = 4;
  // m, the metric distance between the reference pair's cameras must lie in
  // [min_baseline_m, max_baseline_m] (catches implausible scales). Defaults
  // 0.02 and 50.
  double min_baseline_m = 0.02;
  double max_baseline_m = 50.0;
  // Seed of the RANSAC sampler. Default 0.
  uint64_t seed = 0;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

struct ViInitResult {
  bool success = false;
  // Why it failed, or a summary of the estimate.
  std::string message;

  // One per keyframe used (the last window_size frames given), in order;
  // gyro_bias is the estimated one, accel_bias zero. Empty on failure.
  std::vector<ImuState> states;
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();   // rad/s
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();  // m/s^2, always zero
  // (0, 0, -gravity_magnitude) by construction.
  Eigen::Vector3d gravity_in_world = Eigen::Vector3d(0.0, 0.0, -kStandardGravity);
  // Metres per unit of the up-to-scale visual reconstruction (whose reference
  // pair baseline is 1).
  double scale = 0.0;
  // Triangulated landmarks, metric, in the world frame.
  std::unordered_map<uint64_t, Eigen::Vector3d> points_in_world;

  // Diagnostics.
  int reference_frame = -1;          // index (in `states`) paired with the last keyframe
  double median_parallax_deg = 0.0;  // of the reference pair
  double accel_stddev = 0.0;         // m/s^2, see ViInitOptions::min_accel_stddev
  double gravity_norm_linear = 0.0;  // m/s^2, |g| of the linear alignment
  double reprojection_rms_px = 0.0;  // after the bundle adjustment (focal_length_px)
  double alignment_rms = 0.0;        // RMS residual of the final alignment (m, m/s)
};

// frames: the keyframes (time ordered; only the last options.window_size are
// used); imu: samples ordered by strictly increasing stamp covering
// [first keyframe, last keyframe]; body_from_cam: camera extrinsics;
// noise: IMU noise model (for the preintegration).
ViInitResult InitializeVisualInertial(const std::vector<FrameFeatures>& frames,
                                      const std::vector<ImuSample>& imu,
                                      const Rigid3d& body_from_cam, const ImuNoise& noise,
                                      const ViInitOptions& options = {});

}  // namespace viosfm
