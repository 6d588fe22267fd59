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
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/io/frame_cache.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/vio/feature_tracker.h"
#include "viosfm/vio/imu_noise_check.h"
#include "viosfm/vio/sliding_window.h"
#include "viosfm/vio/static_init.h"
#include "viosfm/vio/time_offset.h"
#include "viosfm/vio/vi_initializer.h"

namespace viosfm {

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
  // Process only the first max_frames images (0: all). Default 0.
  int max_frames = 0;
  // Progress bar over the frames (default true; drawn on a terminal only).
  bool show_progress = true;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
  // Every option as "group.name" -> value text (for a run's options.json).
  std::vector<std::pair<std::string, std::string>> ToKeyValues() const;
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
  int num_resets = 0;            // kLost events
  std::vector<VioReset> resets;  // one per kLost event, in order
  int num_segments = 0;          // distinct VioFrameResult::segment values
  int num_keyframes = 0;
  // Frames at the end that lie after the last IMU sample (on the IMU clock):
  // not processed, no pose, not in VioResult::frames.
  size_t num_frames_beyond_imu = 0;
  double cpu_seconds = 0.0;  // process CPU time of RunVio
  double wall_seconds = 0.0;
  std::string message;  // one-paragraph outcome (static start, initialisation, failures)
};

struct VioResult {
  std::vector<VioFrameResult> frames;
  VioSummary summary;
  Rigid3d body_from_cam;

  // world_from_body / world_from_cam at the image stamps, every frame.
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
  ImuState Propagate(const ImuState& state, timestamp_ns_t to_ns) const;
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
  // The restart after the last reset, while its re-localisation is pending.
  bool relocalization_pending_ = false;
  timestamp_ns_t restart_ns_ = 0;
};

// cam_now_from_cam_prev: the gyro's rotation between two camera stamps
// (converted with rig.CamToImuTime) with `gyro_bias` removed; identity
// without IMU coverage.
Eigen::Quaterniond GyroRotationPrior(const SensorRig& rig, const std::vector<ImuSample>& imu,
                                     const Eigen::Vector3d& gyro_bias, timestamp_ns_t from_ns,
                                     timestamp_ns_t to_ns);

// Runs the VIO over a sequence: every image is read once, tracked, and
// processed. Images are read through `frames` when given (each kept there
// for a later stage, io/frame_cache.h), else from their files. Throws
// InputError if the sequence has no IMU or the options are invalid.
VioResult RunVio(const Sequence& sequence, const VioOptions& options, FrameCache* frames = nullptr);

// Writes into `folder` (created if needed), each file atomically:
//   trajectory_body.tum, trajectory_cam.tum   TUM, every frame
//   states.csv   "#timestamp [ns],status,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz"
//   vio_summary.txt   the summary as "key: value" lines
void WriteVioResult(const std::filesystem::path& folder, const VioResult& result);

// The summary as "key: value" lines (as written to vio_summary.txt).
std::string FormatVioSummary(const VioSummary& summary);

}  // namespace viosfm
