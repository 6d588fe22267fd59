// The monocular visual-inertial odometry: front end (feature_tracker.h),
// initialisation (static_init.h for a static start, vi_initializer.h
// otherwise) and the sliding-window back end (sliding_window.h), run over a
// Sequence; one state and status per input frame.
//
// Initialisation:
//  (a) static start (DetectStaticStart over the image time span): gravity,
//      gyro bias and zero velocity are known; while the platform stands
//      still the state is held (world_from_body = the gravity-aligned
//      rotation with yaw 0 at the origin, status kInitializing); at the first
//      frame after the static interval the window starts from that state
//      with a tight prior, and the first landmarks are triangulated as the
//      motion begins. The status turns kTracking once enough landmarks are
//      seen. If the images end during the static interval, the visual part
//      is never initialised (VioSummary::message says so).
//  (b) otherwise, keyframes are collected until InitializeVisualInertial
//      succeeds on them; the frames before have status kInitializing and
//      the identity pose.
// After kLost the window restarts from the last good state carried forward
// by the IMU (velocity with a loose prior).
#pragma once

#include <array>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "viosfm/io/frame_cache.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/vio/feature_tracker.h"
#include "viosfm/vio/imu_noise_check.h"
#include "viosfm/vio/sliding_window.h"
#include "viosfm/vio/static_init.h"
#include "viosfm/vio/time_offset.h"
#include "viosfm/vio/vi_initializer.h"

namespace viosfm {

// "never", "always", "when_dark": the option texts (util/option_fields.h).
std::string OptionText(ContrastEqualization equalization);
void ParseOptionText(const std::string& text, ContrastEqualization* equalization);

struct VioOptions {
  FeatureTrackerOptions tracker;
  SlidingWindowOptions window;
  StaticInitOptions static_init;
  ViInitOptions vi_init;
  // Camera-IMU time offset estimated from the first frames (time_offset.h).
  TimeOffsetOptions time_offset;
  // What is done with implausible IMU noise figures (imu_noise_check.h).
  ImuNoiseCheckOptions imu_noise;
  // Try the static start first (default true).
  bool use_static_init = true;
  // Prior of the first state after a static start (InitialStateSigmas defaults).
  InitialStateSigmas static_start_sigmas;
  // Prior of the first state after a visual-inertial initialisation or a
  // reset: position and yaw are the gauge (tight), velocity loose.
  InitialStateSigmas restart_sigmas{1e-3, 1e-3, 0.05, 0.5, 0.01, 0.2};
  // Feed the tracker a gyro rotation prior between frames (default true).
  bool gyro_rotation_prior = true;
  // Pose the frames of a moving start once it is initialised (default true):
  // the initialisation's keyframes take its states, the other frames a pose
  // from their corners on its landmarks (PnP-RANSAC seeded by the IMU's
  // propagation from the nearest keyframe), or, where too few corners see
  // them, that propagation when the keyframe is at most
  // moving_start_max_imu_s away; farther frames keep no pose.
  bool pose_moving_start = true;
  // s, see pose_moving_start. Default 0.5: a tenth of the accelerometer bias
  // the initialisation leaves (0.1 m/s^2) moves the position by 1.3 cm.
  double moving_start_max_imu_s = 0.5;
  // s, the camera's rolling-shutter readout time (first row to last; the
  // stamp is the middle row's exposure); each observation is moved to the
  // stamp's time (rolling_shutter.h). Default 0: not given; the readout is
  // then estimated with the time offset (time_offset.estimate_readout), and
  // a global shutter assumed when the images do not show one.
  double rolling_shutter_readout_s = 0.0;
  // s, the longest interval between IMU samples the preintegration bridges
  // (with readings interpolated linearly and counted as far noisier than
  // measured ones, imu_preintegration.h); a longer gap breaks the VIO: the
  // window and everything it carries are dropped at the first frame after
  // the gap's start, nothing is propagated across it, and the frames after
  // it start a new segment from a visual-inertial initialisation of their
  // own (joined to the first by the images only). Default 0.6: dropouts of
  // half a second are bridged without a lost track on the real handheld
  // recording (see docs/benchmarks.md, "VIO on a real flight"); over longer
  // ones what the body did is too unknown for the IMU to carry the state.
  double max_imu_gap_s = 0.6;
  // Process only the first max_frames images (0: all). Default 0.
  int max_frames = 0;
  // Progress bar over the frames (default true; drawn on a terminal only).
  bool show_progress = true;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
  // Every option as "group.name" -> value text (for a run's options.json).
  std::vector<std::pair<std::string, std::string>> ToKeyValues() const;

  // The fields of the sub-structs are described here (tracker., window.,
  // static_init., vi_init., time_offset., imu_noise.).
  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"tracker.max_num_features", "corners tracked per image", kShapesStoredData},
          self.tracker.max_num_features);
    visit(
        {"tracker.min_distance_px", "px, minimum distance between two corners", kShapesStoredData},
        self.tracker.min_distance_px);
    visit({"tracker.min_corner_quality",
           "shi-Tomasi quality relative to the image's strongest corner", kShapesStoredData},
          self.tracker.min_corner_quality);
    visit({"tracker.detection_pyramid_level", "pyramid level on which new corners are detected",
           kShapesStoredData},
          self.tracker.detection_pyramid_level);
    visit({"tracker.border_margin_px", "px, corners closer to the image border are dropped",
           kShapesStoredData},
          self.tracker.border_margin_px);
    visit({"tracker.tracking_pyramid_level",
           "pyramid level KLT tracks on (-1: the one nearest the reference focal length)",
           kShapesStoredData},
          self.tracker.tracking_pyramid_level);
    visit({"tracker.klt_window_size", "px, side of the KLT window (at the reference focal length)",
           kShapesStoredData},
          self.tracker.klt_window_size);
    visit({"tracker.klt_max_level", "pyramid levels above the tracked image", kShapesStoredData},
          self.tracker.klt_max_level);
    visit({"tracker.klt_backward_max_level",
           "pyramid levels of the backward track of the forward-backward check", kShapesStoredData},
          self.tracker.klt_backward_max_level);
    visit({"tracker.klt_max_iterations", "KLT iteration limit at each level", kShapesStoredData},
          self.tracker.klt_max_iterations);
    visit({"tracker.klt_epsilon_px", "px, KLT stopping step", kShapesStoredData},
          self.tracker.klt_epsilon_px);
    visit({"tracker.max_forward_backward_error_px", "px, largest forward-backward tracking error",
           kShapesStoredData},
          self.tracker.max_forward_backward_error_px);
    visit({"tracker.ransac", "RANSAC between consecutive images", kShapesStoredData},
          self.tracker.ransac);
    visit({"tracker.ransac_essential", "the RANSAC on the essential matrix (else fundamental)",
           kShapesStoredData},
          self.tracker.ransac_essential);
    visit({"tracker.ransac_threshold_px",
           "px, RANSAC inlier threshold (at the reference focal length)", kShapesStoredData},
          self.tracker.ransac_threshold_px);
    visit({"tracker.ransac_confidence", "RANSAC confidence", kShapesStoredData},
          self.tracker.ransac_confidence);
    visit({"tracker.ransac_min_tracks", "RANSAC runs only with at least this many tracks",
           kShapesStoredData},
          self.tracker.ransac_min_tracks);
    visit({"tracker.equalization", "contrast equalisation: never, always or when_dark",
           kShapesStoredData},
          self.tracker.equalization);
    visit({"tracker.dark_mean_intensity", "grey level (0-255) below which an image is dark",
           kShapesStoredData},
          self.tracker.dark_mean_intensity);
    visit({"tracker.clahe_clip_limit", "CLAHE clip limit", kShapesStoredData},
          self.tracker.clahe_clip_limit);
    visit({"tracker.clahe_tile_grid_size", "CLAHE tiles per image side", kShapesStoredData},
          self.tracker.clahe_tile_grid_size);
    visit({"tracker.keyframe_parallax_px",
           "px, mean parallax to the last keyframe that makes a keyframe", kShapesStoredData},
          self.tracker.keyframe_parallax_px);
    visit({"tracker.keyframe_min_tracked_ratio",
           "keyframe when fewer of max_num_features are shared", kShapesStoredData},
          self.tracker.keyframe_min_tracked_ratio);
    visit({"window.window_size", "keyframes kept in the window (besides the newest frame)",
           kShapesStoredData},
          self.window.window_size);
    visit({"window.keyframe_parallax_px",
           "px, mean parallax to the last keyframe that makes a keyframe", kShapesStoredData},
          self.window.keyframe_parallax_px);
    visit({"window.keyframe_min_shared_tracks",
           "fewer tracks shared with the last keyframe make a keyframe", kShapesStoredData},
          self.window.keyframe_min_shared_tracks);
    visit(
        {"window.max_keyframe_interval_s", "s, longest time between keyframes", kShapesStoredData},
        self.window.max_keyframe_interval_s);
    visit({"window.pixel_sigma_px", "px, standard deviation of a feature position",
           kShapesStoredData},
          self.window.pixel_sigma_px);
    visit({"window.cauchy_loss_scale", "cauchy loss scale on the whitened reprojection residual",
           kShapesStoredData},
          self.window.cauchy_loss_scale);
    visit({"window.min_triangulation_angle_deg", "deg, ray angle needed to triangulate a landmark",
           kShapesStoredData},
          self.window.min_triangulation_angle_deg);
    visit({"window.min_depth_m", "m, nearest accepted landmark", kShapesStoredData},
          self.window.min_depth_m);
    visit({"window.max_depth_m", "m, farthest accepted landmark", kShapesStoredData},
          self.window.max_depth_m);
    visit({"window.max_reprojection_error_px", "px, landmarks with a larger error are dropped",
           kShapesStoredData},
          self.window.max_reprojection_error_px);
    visit({"window.max_landmarks",
           "most landmarks in one optimisation (the longest-observed first)", kShapesStoredData},
          self.window.max_landmarks);
    visit({"window.max_num_iterations", "ceres iterations per frame", kShapesStoredData},
          self.window.max_num_iterations);
    visit({"window.num_threads", "threads of the Ceres solver", kRunOnly}, self.window.num_threads);
    visit({"window.min_tracked_landmarks", "fewer landmarks seen by the newest frame: kImuOnly",
           kShapesStoredData},
          self.window.min_tracked_landmarks);
    visit({"window.max_imu_only_s", "s, kImuOnly for longer than this: kLost", kShapesStoredData},
          self.window.max_imu_only_s);
    visit({"window.max_speed_mps", "m/s, plausibility limit of the speed", kShapesStoredData},
          self.window.max_speed_mps);
    visit({"window.max_gyro_bias", "rad/s, plausibility limit of the gyro bias", kShapesStoredData},
          self.window.max_gyro_bias);
    visit(
        {"window.max_accel_bias", "m/s^2, plausibility limit of the accel bias", kShapesStoredData},
        self.window.max_accel_bias);
    visit({"window.max_position_correction_m", "m, plausibility limit of a position correction",
           kShapesStoredData},
          self.window.max_position_correction_m);
    visit({"window.fallback_triangulation_angle_deg", "deg, ray angle used while landmarks are few",
           kShapesStoredData},
          self.window.fallback_triangulation_angle_deg);
    visit({"window.fallback_target_landmarks", "landmarks below which the fallback angle is used",
           kShapesStoredData},
          self.window.fallback_target_landmarks);
    visit({"window.compute_covariance", "the newest pose's marginal covariance", kShapesStoredData},
          self.window.compute_covariance);
    visit({"window.preintegration.gyro_bias_repropagation_threshold",
           "rad/s, gyro bias change that re-propagates", kShapesStoredData},
          self.window.preintegration.gyro_bias_repropagation_threshold);
    visit({"window.preintegration.accel_bias_repropagation_threshold",
           "m/s^2, accel bias change that re-propagates", kShapesStoredData},
          self.window.preintegration.accel_bias_repropagation_threshold);
    visit({"static_init.window_s", "s, length of one detection window", kShapesStoredData},
          self.static_init.window_s);
    visit({"static_init.step_s", "s, shift between consecutive windows", kShapesStoredData},
          self.static_init.step_s);
    visit({"static_init.smoothing_s", "s, readings are averaged over blocks of this length",
           kShapesStoredData},
          self.static_init.smoothing_s);
    visit({"static_init.max_accel_stddev", "m/s^2, largest spread of the block-mean accel vectors",
           kShapesStoredData},
          self.static_init.max_accel_stddev);
    visit({"static_init.max_gyro_stddev", "rad/s, the same for the gyro", kShapesStoredData},
          self.static_init.max_gyro_stddev);
    visit({"static_init.max_gyro_norm", "rad/s, largest norm of a window's mean gyro reading",
           kShapesStoredData},
          self.static_init.max_gyro_norm);
    visit({"static_init.max_gravity_norm_error",
           "m/s^2, largest | |mean accel| - gravity | of a window", kShapesStoredData},
          self.static_init.max_gravity_norm_error);
    visit({"static_init.gravity_magnitude", "m/s^2, gravity magnitude", kShapesStoredData},
          self.static_init.gravity_magnitude);
    visit({"static_init.motion_margin_s", "s, dropped from the end of a static interval",
           kShapesStoredData},
          self.static_init.motion_margin_s);
    visit(
        {"static_init.min_static_s",
         "s, shortest static interval accepted once motion_margin_s is dropped", kShapesStoredData},
        self.static_init.min_static_s);
    visit({"static_init.lookback_s", "s, IMU readings searched before the first image",
           kShapesStoredData},
          self.static_init.lookback_s);
    visit({"static_init.max_propagation_s", "s, a static interval ending longer before is not used",
           kShapesStoredData},
          self.static_init.max_propagation_s);
    visit({"static_init.estimate_accel_bias_along_gravity",
           "estimate the accel bias along gravity (true) or leave it zero", kShapesStoredData},
          self.static_init.estimate_accel_bias_along_gravity);
    visit({"vi_init.window_size", "keyframes used (the last ones)", kShapesStoredData},
          self.vi_init.window_size);
    visit({"vi_init.min_num_frames", "fewest keyframes needed", kShapesStoredData},
          self.vi_init.min_num_frames);
    visit({"vi_init.focal_length_px", "px, converts the pixel thresholds to normalised coordinates",
           kShapesStoredData},
          self.vi_init.focal_length_px);
    visit({"vi_init.min_parallax_px", "px, mean displacement of the reference pair",
           kShapesStoredData},
          self.vi_init.min_parallax_px);
    visit({"vi_init.min_triangulation_angle_deg",
           "deg, median triangulation angle of the reference pair", kShapesStoredData},
          self.vi_init.min_triangulation_angle_deg);
    visit({"vi_init.min_pair_correspondences", "fewest correspondences of the reference pair",
           kShapesStoredData},
          self.vi_init.min_pair_correspondences);
    visit({"vi_init.essential_max_error_px",
           "px, RANSAC inlier threshold (Sampson distance) of the essential matrix",
           kShapesStoredData},
          self.vi_init.essential_max_error_px);
    visit({"vi_init.max_reprojection_error_px",
           "px, observations beyond this after the BA are dropped", kShapesStoredData},
          self.vi_init.max_reprojection_error_px);
    visit({"vi_init.min_landmark_triangulation_angle_deg",
           "deg, ray angle needed to triangulate a landmark", kShapesStoredData},
          self.vi_init.min_landmark_triangulation_angle_deg);
    visit({"vi_init.min_pnp_correspondences", "fewest landmarks for a keyframe's PnP",
           kShapesStoredData},
          self.vi_init.min_pnp_correspondences);
    visit({"vi_init.max_ba_iterations", "bundle adjustment iterations (each pass)",
           kShapesStoredData},
          self.vi_init.max_ba_iterations);
    visit({"vi_init.min_accel_stddev", "m/s^2, smallest spread of the specific force (excitation)",
           kShapesStoredData},
          self.vi_init.min_accel_stddev);
    visit({"vi_init.max_gravity_norm_error",
           "m/s^2, largest error of the linear alignment's gravity", kShapesStoredData},
          self.vi_init.max_gravity_norm_error);
    visit({"vi_init.gravity_magnitude", "m/s^2, gravity magnitude imposed by the refinement",
           kShapesStoredData},
          self.vi_init.gravity_magnitude);
    visit({"vi_init.gravity_refinement_iterations",
           "iterations of the gravity refinement on the sphere", kShapesStoredData},
          self.vi_init.gravity_refinement_iterations);
    visit({"vi_init.min_baseline_m", "m, shortest metric baseline of the reference pair",
           kShapesStoredData},
          self.vi_init.min_baseline_m);
    visit({"vi_init.max_baseline_m", "m, longest metric baseline of the reference pair",
           kShapesStoredData},
          self.vi_init.max_baseline_m);
    visit({"vi_init.seed", "seed of the RANSAC sampler", kShapesStoredData}, self.vi_init.seed);
    visit({"time_offset.estimate",
           "estimate the camera-IMU time offset; false keeps the calibration's", kShapesStoredData},
          self.time_offset.estimate);
    visit({"time_offset.max_offset_s",
           "s, candidates lie within +- this of the calibration's offset", kShapesStoredData},
          self.time_offset.max_offset_s);
    visit({"time_offset.coarse_step_s", "s, step of the coarse grid", kShapesStoredData},
          self.time_offset.coarse_step_s);
    visit({"time_offset.fine_step_s", "s, step of the fine grid", kShapesStoredData},
          self.time_offset.fine_step_s);
    visit({"time_offset.min_tracks_per_pair", "fewest corners tracked in both frames of a pair",
           kShapesStoredData},
          self.time_offset.min_tracks_per_pair);
    visit({"time_offset.estimate_readout",
           "estimate a rolling shutter's readout with the offset (when none is given)",
           kShapesStoredData},
          self.time_offset.estimate_readout);
    visit({"time_offset.max_readout_s", "s, longest rolling-shutter readout considered",
           kShapesStoredData},
          self.time_offset.max_readout_s);
    visit({"time_offset.readout_coarse_step_s", "s, step of the readout's coarse grid",
           kShapesStoredData},
          self.time_offset.readout_coarse_step_s);
    visit({"time_offset.max_frame_gap", "frames are paired with each of the next this many",
           kShapesStoredData},
          self.time_offset.max_frame_gap);
    visit({"time_offset.target_rotation_deg", "deg, gyro rotation collected before estimating",
           kShapesStoredData},
          self.time_offset.target_rotation_deg);
    visit({"time_offset.min_total_rotation_deg",
           "deg, least gyro rotation with which the estimate is trusted", kShapesStoredData},
          self.time_offset.min_total_rotation_deg);
    visit({"time_offset.max_wait_s", "s, longest wait for the target rotation", kShapesStoredData},
          self.time_offset.max_wait_s);
    visit({"time_offset.min_cost_reduction", "relative cost reduction needed to replace the offset",
           kShapesStoredData},
          self.time_offset.min_cost_reduction);
    visit({"time_offset.uncertainty_range_s",
           "s, range around the estimate searched for its standard error", kShapesStoredData},
          self.time_offset.uncertainty_range_s);
    visit({"time_offset.max_sigma_s",
           "s, largest standard error with which the estimate replaces the calibration's",
           kShapesStoredData},
          self.time_offset.max_sigma_s);
    visit({"time_offset.min_significance",
           "standard errors the estimate must lie from the calibration's to replace it",
           kShapesStoredData},
          self.time_offset.min_significance);
    visit({"imu_noise.enabled", "check the IMU noise figures; false uses them as they are",
           kShapesStoredData},
          self.imu_noise.enabled);
    visit({"imu_noise.min_ratio", "smallest ratio of a file's noise density to the measured one",
           kShapesStoredData},
          self.imu_noise.min_ratio);
    visit({"imu_noise.max_ratio", "largest ratio of a file's noise density to the measured one",
           kShapesStoredData},
          self.imu_noise.max_ratio);
    visit({"imu_noise.scale_random_walks",
           "scale each random walk as its white-noise density was changed", kShapesStoredData},
          self.imu_noise.scale_random_walks);
    visit(
        {"imu_noise.min_static_s", "s, shortest static interval to measure on", kShapesStoredData},
        self.imu_noise.min_static_s);
    visit({"imu_noise.check_in_motion",
           "raise densities below min_ratio times the high-frequency content in motion",
           kShapesStoredData},
          self.imu_noise.check_in_motion);
    visit({"imu_noise.motion_span_s", "s, motion measured from its start", kShapesStoredData},
          self.imu_noise.motion_span_s);
    visit({"imu_noise.motion_window_s", "s, window of the in-motion measurement (median over them)",
           kShapesStoredData},
          self.imu_noise.motion_window_s);
    visit({"use_static_init", "try the static start first", kShapesStoredData},
          self.use_static_init);
    VisitSigmas("static_start_sigmas", self.static_start_sigmas, visit);
    VisitSigmas("restart_sigmas", self.restart_sigmas, visit);
    visit({"gyro_rotation_prior", "feed the tracker a gyro rotation prior", kShapesStoredData},
          self.gyro_rotation_prior);
    visit({"pose_moving_start", "pose the frames of a moving start once it is initialised",
           kShapesStoredData},
          self.pose_moving_start);
    visit({"moving_start_max_imu_s",
           "s, farthest a moving start's frame is carried by the IMU from a keyframe",
           kShapesStoredData},
          self.moving_start_max_imu_s);
    visit({"rolling_shutter_readout_s",
           "s, rolling-shutter readout time of the camera (0: not given, estimated)",
           kShapesStoredData},
          self.rolling_shutter_readout_s);
    visit({"max_imu_gap_s",
           "s, longest IMU gap bridged; a longer one breaks the VIO into a new segment",
           kShapesStoredData},
          self.max_imu_gap_s);
    visit({"max_frames", "process only the first max_frames images (0: all)", kShapesStoredData},
          self.max_frames);
    visit({"show_progress", "progress bar over the frames", kRunOnly}, self.show_progress);
  }
  template <class Sigmas, class Visitor>
  static void VisitSigmas(const std::string& prefix, Sigmas& sigmas, Visitor& visit) {
    visit({prefix + ".position_m", "m, prior sigma of the position", kShapesStoredData},
          sigmas.position_m);
    visit({prefix + ".yaw_rad", "rad, prior sigma of the yaw", kShapesStoredData}, sigmas.yaw_rad);
    visit({prefix + ".roll_pitch_rad", "rad, prior sigma of roll and pitch", kShapesStoredData},
          sigmas.roll_pitch_rad);
    visit({prefix + ".velocity_mps", "m/s, prior sigma of the velocity", kShapesStoredData},
          sigmas.velocity_mps);
    visit({prefix + ".gyro_bias", "rad/s, prior sigma of the gyro bias", kShapesStoredData},
          sigmas.gyro_bias);
    visit({prefix + ".accel_bias", "m/s^2, prior sigma of the accel bias", kShapesStoredData},
          sigmas.accel_bias);
  }
};

// The estimate for one input frame.
struct VioFrameResult {
  timestamp_ns_t timestamp_ns = 0;  // the image stamp (camera clock)
  // world_from_body, velocity (m/s, world), biases; the stamp is on the IMU clock.
  ImuState state;
  VioStatus status = VioStatus::kInitializing;
  bool is_keyframe = false;
  int num_features = 0;   // tracked corners
  int num_landmarks = 0;  // triangulated landmarks seen, used by the window
  // The window's marginal covariance of world_from_body (SlidingWindowOptions
  // compute_covariance; [rotation rad, position m]); zero when the window
  // did not estimate this frame.
  Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  // Whether `state` is an estimate: false only before a moving start is
  // initialised (the state is then a placeholder at the origin).
  bool has_pose = true;
  // Trajectory segment: frames of one segment are in one consistent frame.
  // A reset starts a new segment (from its lost frame on) unless the
  // restarted window re-localised against the map of the previous one; a
  // segment joined only by the IMU's propagation across the gap is a new
  // one (its pose relative to the previous segment is as good as the IMU
  // alone over the gap).
  int segment = 0;
  // Map points of the previous segment seen while re-localising.
  int num_map_points = 0;
  // The first frame after an IMU gap longer than VioOptions::max_imu_gap_s
  // (a break: a new segment begins with it).
  bool after_imu_break = false;
};

// An IMU gap the VIO did not bridge (VioOptions::max_imu_gap_s).
struct VioImuBreak {
  timestamp_ns_t gap_start_ns = 0;  // IMU clock: the last sample before the gap
  double gap_s = 0.0;
  timestamp_ns_t frame_ns = 0;  // camera stamp of the first frame after the gap's start
};

// One failure of the estimate (status kLost) and how the VIO went on.
struct VioReset {
  timestamp_ns_t timestamp_ns = 0;  // camera stamp of the lost frame
  std::string message;              // why
  // Whether the restarted window re-localised against the previous map
  // (SlidingWindowOptions::min_relocalization_points distinct map points
  // within relocalization_window_s); false: joined by the IMU alone.
  bool relocalized = false;
  int num_map_points = 0;  // distinct map points seen while re-localising
};

struct VioSummary {
  size_t num_frames = 0;
  // Frames per status, indexed by static_cast<int>(VioStatus).
  std::array<size_t, 4> status_counts{};
  StaticInitResult static_init;    // status kNotStatic/kNotEnoughData when not a static start
  ImuNoiseCheck imu_noise;         // the calibration's IMU noise and what was used
  TimeOffsetEstimate time_offset;  // the camera-IMU time offset used (time_offset.h)
  bool visual_initialized = false;
  // Camera stamp of the first kTracking frame (-1: never).
  timestamp_ns_t first_tracking_ns = -1;
  int num_resets = 0;                   // kLost events
  std::vector<VioReset> resets;         // one per kLost event, in order
  int num_segments = 0;                 // distinct VioFrameResult::segment values
  std::vector<VioImuBreak> imu_breaks;  // IMU gaps that broke the VIO, in order
  // Stretches of consecutive kImuOnly frames, the longest (s, its first
  // frame to the first frame after it) and the camera stamp it starts at.
  size_t num_imu_only_stretches = 0;
  double longest_imu_only_s = 0.0;
  timestamp_ns_t longest_imu_only_from_ns = -1;
  int num_keyframes = 0;
  // Frames at the end that lie after the last IMU sample (on the IMU clock):
  // not processed, no pose, not in VioResult::frames.
  size_t num_frames_beyond_imu = 0;
  // Intervals between IMU samples longer than kMaxImuStepNs (samples the
  // IMU dropped; bridged by interpolated readings, imu_preintegration.h, up
  // to VioOptions::max_imu_gap_s, breaks beyond) and the longest interval, s.
  size_t num_imu_gaps = 0;
  double longest_imu_gap_s = 0.0;
  // Frames without a pose: those before a moving start was initialised
  // that VioOptions::pose_moving_start could not pose (has_pose false; left
  // out of the trajectories, kept in states.csv).
  size_t num_frames_without_pose = 0;
  // Frames of a moving start posed once it was initialised, by how:
  // an initialisation keyframe's state, PnP on its landmarks, the IMU alone.
  size_t num_moving_start_keyframes = 0;
  size_t num_moving_start_pnp = 0;
  size_t num_moving_start_imu = 0;
  double cpu_seconds = 0.0;  // process CPU time of RunVio
  double wall_seconds = 0.0;
  std::string message;  // one-paragraph outcome (static start, initialisation, failures)
};

struct VioResult {
  std::vector<VioFrameResult> frames;
  VioSummary summary;
  Rigid3d body_from_cam;

  // world_from_body / world_from_cam at the image stamps, every frame with
  // a pose (has_pose; the frames before a moving start is initialised have
  // none and are left out).
  Trajectory BodyTrajectory() const;
  Trajectory CameraTrajectory() const;
};

// Frame-by-frame processing of front-end output (what RunVio calls per
// image; tests feed it synthetic features).
class VisualInertialOdometry {
 public:
  // `imu` must outlive the object. first/last_frame_ns: camera stamps of the
  // first and last frame to come (the static start is detected in between).
  VisualInertialOdometry(const SensorRig& rig, const std::vector<ImuSample>& imu,
                         timestamp_ns_t first_frame_ns, timestamp_ns_t last_frame_ns,
                         const VioOptions& options);

  // Frames in time order; features stamped on the camera clock.
  VioFrameResult ProcessFrame(const FrameFeatures& features);

  // cam_now_from_cam_prev rotated by the gyro between two camera stamps with
  // the current gyro bias estimate (for the tracker's rotation prior);
  // identity without IMU coverage.
  Eigen::Quaterniond GyroRotationPrior(timestamp_ns_t from_ns, timestamp_ns_t to_ns) const;

  // States given, once a moving start is initialised, to frames returned
  // earlier without a pose (VioOptions::pose_moving_start): camera stamp and
  // state, each once (the call empties the list).
  std::vector<std::pair<timestamp_ns_t, ImuState>> TakeMovingStartStates();
  // Poses the moving start's frames now if that is still pending (the
  // caller's last frame was processed; see PoseMovingStart).
  void FinishMovingStart();
  // The camera stamp of the first frame returned so far whose pose or
  // segment may still change: the frames of a moving start held until it is
  // posed (TakeMovingStartStates), and the frames from a reset whose
  // re-localisation is not decided yet (VioReset::relocalized); none: every
  // frame returned is final.
  std::optional<timestamp_ns_t> FirstUnsettledFrameNs() const;

  // The summary so far (the caller sets the timings).
  const VioSummary& summary() const { return summary_; }
  VioSummary& mutable_summary() { return summary_; }

 private:
  void StartWindow(const ImuState& state, const InitialStateSigmas& sigmas,
                   const FrameFeatures& features);
  // Adds `frame` (IMU clock) to the initialisation keyframes when it is one
  // and tries the visual-inertial initialisation; on success the window is
  // started from its keyframes. `carried` (after a reset): the last good
  // state's IMU propagation, which places the new world in the old one.
  bool TryVisualInertialInitialization(const FrameFeatures& frame, const ImuState* carried);
  // ProcessFrame's steps (frame on the IMU clock, camera_ns its camera
  // stamp): a frame the initialised window estimates, with a loss or the end
  // of a re-localisation; the window started from the static state carried
  // forward by the IMU; a frame collected for the visual-inertial
  // initialisation (moving start or restart).
  void TrackInWindow(const FrameFeatures& frame, timestamp_ns_t camera_ns, VioFrameResult* result);
  void StartFromStaticState(const FrameFeatures& frame, VioFrameResult* result);
  void CollectForInitialization(const FrameFeatures& frame, timestamp_ns_t camera_ns,
                                VioFrameResult* result);
  ImuState Propagate(const ImuState& state, timestamp_ns_t to_ns) const;
  // The longest interval between IMU samples that overlaps (from_ns, to_ns)
  // (IMU clock); 0 without samples around it.
  timestamp_ns_t LongestImuIntervalNs(timestamp_ns_t from_ns, timestamp_ns_t to_ns) const;
  // A gap longer than max_imu_gap_s since the last frame: everything the
  // VIO carries is dropped (BreakAtImuGap), and true is returned.
  bool BreakAtImuGap(const FrameFeatures& frame, timestamp_ns_t camera_ns);
  // The state at to_ns (before state.timestamp_ns) from which the IMU leads
  // to `state`: the propagation run backwards.
  ImuState PropagateBack(const ImuState& state, timestamp_ns_t to_ns) const;
  // Poses the frames held while a moving start was not initialised
  // (pose_moving_start), from the initialisation's keyframe states (IMU
  // clock) and landmarks. It waits until the window has optimised them
  // with the frames after: when the first of those keyframes leaves the
  // window (or the window is lost, or the run ends), the initialisation's
  // states and landmarks are moved by the similarity that takes its
  // keyframes' positions to the window's estimates of the keyframes still
  // there (its scale is what the IMU changed the initialisation's by), and
  // those keyframes take the window's states.
  void PoseMovingStart(const std::vector<ImuState>& window_states);
  void Record(const VioFrameResult& result);

  SensorRig rig_;
  const std::vector<ImuSample>& imu_;
  VioOptions options_;
  std::unique_ptr<SlidingWindowEstimator> window_;
  VioSummary summary_;
  ImuState static_state_;
  bool static_start_ = false;
  bool have_good_state_ = false;
  ImuState last_good_state_;
  ImuState last_state_;
  std::vector<FrameFeatures> init_keyframes_;  // for the visual-inertial initialisation
  // The frames of a moving start returned without a pose (IMU clock), held
  // until it is initialised (pose_moving_start), and the states found then.
  std::deque<std::pair<timestamp_ns_t, FrameFeatures>> moving_start_frames_;  // camera stamp
  bool moving_start_pending_ = false;             // initialised, its frames not yet posed
  std::vector<ImuState> moving_start_keyframes_;  // the initialisation's
  std::unordered_map<uint64_t, Eigen::Vector3d> moving_start_points_;  // its landmarks
  std::vector<std::pair<timestamp_ns_t, ImuState>> moving_start_states_;
  // The restart after the last reset, while its re-localisation is pending.
  bool relocalization_pending_ = false;
  timestamp_ns_t restart_ns_ = 0;
  // The camera stamp of the last reset's lost frame while its
  // re-localisation is not decided.
  std::optional<timestamp_ns_t> undecided_reset_ns_;
  // IMU stamp of the last frame processed (none before the first).
  std::optional<timestamp_ns_t> last_frame_imu_ns_;
};

// cam_now_from_cam_prev: the gyro's rotation between two camera stamps
// (converted with rig.CamToImuTime) with `gyro_bias` removed; identity
// without IMU coverage.
Eigen::Quaterniond GyroRotationPrior(const SensorRig& rig, const std::vector<ImuSample>& imu,
                                     const Eigen::Vector3d& gyro_bias, timestamp_ns_t from_ns,
                                     timestamp_ns_t to_ns);

// What RunVio has done so far, reported after every frame it processes
// (for a run that consumes the poses as they come, pipeline/stream_pipeline.h).
struct VioProgress {
  // Every frame processed so far, in order (as VioResult::frames will hold
  // them, moving-start poses given as they are found).
  const std::vector<VioFrameResult>* frames = nullptr;
  // frames[0, num_settled) are final: their state, has_pose and segment no
  // longer change (VisualInertialOdometry::FirstUnsettledFrameNs).
  size_t num_settled = 0;
  // The camera-IMU time offset (and rolling-shutter readout) the frames are
  // processed with: settled before the first frame is.
  const TimeOffsetEstimate* time_offset = nullptr;
  // The IMU noise the window uses (VioSummary::imu_noise).
  const ImuNoiseCheck* imu_noise = nullptr;
  // The last report: every frame processed and settled.
  bool finished = false;
};
using VioProgressCallback = std::function<void(const VioProgress&)>;

// The VIO over a recording whose frames and IMU samples arrive as it runs
// (a recording being written, `viosfm run --follow`): RunVio one step at a
// time. Each frame is tracked and processed once the IMU reaches it (50 ms
// beyond its stamp on the IMU clock); the first frames wait for the
// camera-IMU time offset's estimate, as in RunVio, and, when the last
// frame's stamp is not known up front, until the IMU has decided the static
// start (its static interval ended by motion, or no static start: the
// window is then started from what the IMU shows, as RunVio does from the
// whole recording's IMU; the IMU noise is checked on the samples up to
// then). Given the whole sequence (last_frame_ns known, Finish called after
// adding everything) it is RunVio, result for result.
class VioRunner {
 public:
  // `rig`: the recording's. `last_frame_ns`: the last frame's camera stamp
  // when known (a whole recording), else none. Throws InputError for
  // invalid options.
  // `expected_frames`: for the progress bar (0: unknown).
  VioRunner(const SensorRig& rig, const VioOptions& options, FrameCache* frames,
            std::optional<timestamp_ns_t> last_frame_ns, VioProgressCallback on_progress = {},
            size_t expected_frames = 0);
  ~VioRunner();
  VioRunner(const VioRunner&) = delete;
  VioRunner& operator=(const VioRunner&) = delete;

  // Samples after every sample added before (InputError otherwise), then
  // whatever they allow is processed.
  void AddImu(const std::vector<ImuSample>& samples);
  // The next frame (after every frame added before: InputError otherwise),
  // then whatever the IMU allows is processed.
  void AddImage(const SequenceImage& image);
  // No more data: every frame is processed (those after the IMU's last
  // sample are counted, without a pose), the summary made. Throws
  // InputError without images or IMU.
  VioResult Finish(const std::filesystem::path& root);

  size_t num_processed() const;

 private:
  struct State;
  void Step(bool ended);
  std::unique_ptr<State> state_;
};

// Runs the VIO over a sequence: every image is read once, tracked, and
// processed. Images are read through `frames` when given (each kept there
// for a later stage, io/frame_cache.h), else from their files. With
// `on_progress`, it is called on the calling thread after every processed
// frame and once at the end. Throws InputError if the sequence has no IMU
// or the options are invalid.
VioResult RunVio(const Sequence& sequence, const VioOptions& options, FrameCache* frames = nullptr,
                 const VioProgressCallback& on_progress = {});

// Writes into `folder` (created if needed), each file atomically:
//   trajectory_body.tum, trajectory_cam.tum   TUM, every frame
//   states.csv   "#timestamp [ns],status,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz"
//   vio_summary.txt   the summary as "key: value" lines
void WriteVioResult(const std::filesystem::path& folder, const VioResult& result);

// The summary as "key: value" lines (as written to vio_summary.txt).
std::string FormatVioSummary(const VioSummary& summary);

}  // namespace viosfm
