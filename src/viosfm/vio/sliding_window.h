// Sliding-window visual-inertial estimator (monocular camera + IMU), in the
// manner of VINS-Mono's back end.
//
// The window holds the states (world_from_body, velocity, gyro and accel
// biases) of up to window_size keyframes plus the newest frame. Each new
// frame is predicted from the newest state by IMU preintegration, joins the
// window, and the window is optimised with Ceres over
//  - IMU preintegration factors between consecutive states (imu_factor.h),
//  - reprojection factors of landmarks parameterised by their inverse depth
//    in the camera of their first observation in the window
//    (reprojection_factor.h), with a Cauchy loss,
//  - the prior left by marginalisation (marginalization.h), or at the start
//    the Gaussian prior of the initial state.
// After the optimisation, when the newest frame is a keyframe and the window
// is full, the oldest keyframe is marginalised: its state, the IMU factor to
// its successor, the landmarks anchored in it (with all their observations)
// and the previous prior become the new prior (Schur complement); the
// landmarks still observed later are re-anchored in their next observation.
// A newest frame that is not a keyframe is dropped when the next frame
// arrives (its IMU interval is integrated again from the state before it),
// so every frame gets an optimised state but only keyframes stay.
//
// Keyframes: the front end's decision, or a mean parallax (px) to the last
// keyframe of at least keyframe_parallax_px, or fewer shared tracks than
// keyframe_min_shared_tracks, or max_keyframe_interval_s elapsed.
//
// Failure detection: an implausible state (speed, biases, a non-finite
// value, a jump from the IMU prediction) resets the window (status kLost);
// fewer than min_tracked_landmarks landmarks seen by the newest frame make
// the frame kImuOnly (the window then carries the state on the IMU alone),
// and kImuOnly for longer than max_imu_only_s is kLost as well. After a
// reset, the caller starts the window again (Initialize).
//
// Frames are stamped on the IMU clock. Observations are the undistorted
// normalised coordinates of FrameFeatures.
#pragma once

#include <ceres/loss_function.h>
#include <ceres/manifold.h>

#include <Eigen/Core>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/vio/frame_features.h"
#include "viosfm/vio/imu_factor.h"
#include "viosfm/vio/imu_preintegration.h"
#include "viosfm/vio/marginalization.h"

namespace viosfm {

enum class VioStatus {
  kInitializing,  // no visual-inertial estimate yet (static start, waiting for motion/landmarks)
  kTracking,      // visual-inertial estimate with enough landmarks
  kImuOnly,       // too few landmarks: the state is carried by the IMU
  kLost,          // the estimate failed (implausible state, no landmarks for too long)
};
const char* VioStatusName(VioStatus status);

struct SlidingWindowOptions {
  // Keyframes kept in the window (besides the newest frame). Default 10.
  int window_size = 10;
  // px at kReferenceFocalLengthPx (frame_features.h), mean parallax to the
  // last keyframe that makes a keyframe. Default 10.
  double keyframe_parallax_px = 10.0;
  // Fewer tracks shared with the last keyframe make a keyframe. Default 30.
  int keyframe_min_shared_tracks = 30;
  // s, longest time between keyframes. Default 1.0.
  double max_keyframe_interval_s = 1.0;
  // px, standard deviation of a feature position. Default 1.5 (VINS-Mono).
  double pixel_sigma_px = 1.5;
  // Scale of the Cauchy loss on the whitened reprojection residual (units of
  // pixel_sigma_px). Default 1.0.
  double cauchy_loss_scale = 1.0;
  // deg, largest angle between two rays of a landmark needed to triangulate
  // it. Default 1.0.
  double min_triangulation_angle_deg = 1.0;
  // Weak texture: while the newest frame sees fewer than
  // fallback_target_landmarks triangulated landmarks, its tracks whose rays
  // make at least fallback_triangulation_angle_deg are triangulated too
  // (widest first). Defaults 0.3 deg and 30. In a richly textured scene the
  // low-parallax landmarks cost accuracy; in a weakly textured or slowly
  // moving one they are all there is (the real handheld recording, while the
  // hand barely translates).
  double fallback_triangulation_angle_deg = 0.3;
  int fallback_target_landmarks = 30;
  // m, depth range of an accepted landmark (anchor camera). Defaults 0.1, 50.
  double min_depth_m = 0.1;
  double max_depth_m = 50.0;
  // px, a landmark with an observation farther than this from its
  // reprojection after the optimisation is removed. Default 4.
  double max_reprojection_error_px = 4.0;
  // Most landmarks in one optimisation (the longest-observed first). Default 200.
  int max_landmarks = 200;
  // Ceres iterations per frame. Default 8.
  int max_num_iterations = 8;
  // Threads of the Ceres solver. Default 1.
  int num_threads = 1;
  // Fewer landmarks seen by the newest frame: kImuOnly. Default 10.
  int min_tracked_landmarks = 10;
  // s, kImuOnly for longer than this: kLost. Default 3.
  double max_imu_only_s = 3.0;
  // Plausibility limits: speed (m/s, default 10), gyro bias (rad/s, default
  // 0.3), accel bias (m/s^2, default 2), change of the newest position from
  // its IMU prediction in one optimisation (m, default 1).
  double max_speed_mps = 10.0;
  double max_gyro_bias = 0.3;
  double max_accel_bias = 2.0;
  double max_position_correction_m = 1.0;
  ImuPreintegrationOptions preintegration;
  // Re-localisation after a reset: the landmarks of the last window that
  // tracked are kept as fixed world points; the restarted window's
  // position and yaw priors are loosened to these sigmas (m, rad), and its
  // frames observing those tracks are tied to them (reprojection with the
  // Cauchy loss) for relocalization_window_s, after which the map is
  // dropped. The restart counts as re-localised when at least
  // min_relocalization_points map points are seen. Defaults 0.5 m, 0.1 rad,
  // 2 s, 15.
  double relocalization_position_sigma_m = 0.5;
  double relocalization_yaw_sigma_rad = 0.1;
  double relocalization_window_s = 2.0;
  int min_relocalization_points = 15;
  // m/s^2, the error of an IMU-only prediction assumed by the failure test:
  // after T seconds without enough landmarks, the newest position may move
  // max_position_correction_m + accel_uncertainty * T^2 / 2 from its IMU
  // prediction before the estimate counts as failed. Default 1.0 (a gravity
  // direction 3 degrees off and a bias of 0.5 m/s^2 together).
  double imu_only_accel_uncertainty = 1.0;
  // Huber loss on the whitened IMU factor residual (its norm, in standard
  // deviations; 0: plain squares), so that one interval's preintegration
  // wrong by far more than its noise (a bump, a saturated reading) weighs
  // less. It does not rescue a strong shock: with a simulated 30 m/s^2
  // shock of 0.3 s the window starts from the shocked IMU prediction and
  // rejects the landmarks that disagree, whatever this scale (0, 3 or 10
  // give the same trajectory, metres off). Default 10: normal intervals
  // (residual norm about 4 for 15 dimensions) stay quadratic.
  double imu_loss_scale = 10.0;
  // Compute the marginal covariance of the newest pose after each
  // optimisation (WindowFrameEstimate::pose_covariance). Default true.
  bool compute_covariance = true;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

// Standard deviations of the Gaussian prior of the first state.
struct InitialStateSigmas {
  double position_m = 1e-3;      // m
  double yaw_rad = 1e-3;         // rad
  double roll_pitch_rad = 0.02;  // rad
  double velocity_mps = 0.05;    // m/s
  double gyro_bias = 0.005;      // rad/s
  double accel_bias = 0.1;       // m/s^2
};

// What the estimator says about one frame.
struct WindowFrameEstimate {
  ImuState state;
  // Marginal covariance of world_from_body of this frame given everything
  // the window holds (its prior included), in the order [rotation (rad, a
  // left perturbation in the world frame), position (m)]; zero when not
  // computed. Its position and yaw parts grow as the VIO drifts.
  Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  VioStatus status = VioStatus::kInitializing;
  bool is_keyframe = false;
  int num_landmarks = 0;  // triangulated landmarks seen by this frame, used in the optimisation
  int num_window_landmarks = 0;
  // Map points of the window before a reset seen by this frame (nonzero
  // only while a restarted window re-localises).
  int num_map_points = 0;
  std::string message;  // why kLost
};

class SlidingWindowEstimator {
 public:
  // focal_length_px converts pixel thresholds to normalised coordinates.
  SlidingWindowEstimator(const Rigid3d& body_from_cam, const ImuNoise& noise,
                         double focal_length_px, const SlidingWindowOptions& options);
  ~SlidingWindowEstimator();

  // Starts the window with `state` (stamped) and its observations; clears
  // what was there.
  void Initialize(const ImuState& state, const InitialStateSigmas& sigmas,
                  const FrameFeatures& features);
  // Starts the window with the keyframes of a visual-inertial
  // initialisation: their states (stamped, in order), their observations,
  // the IMU between them, and the landmarks it triangulated (world frame,
  // by track id). The prior of `sigmas` holds the first keyframe's state.
  void InitializeWithKeyframes(const std::vector<FrameFeatures>& keyframes,
                               const std::vector<ImuState>& states,
                               const std::unordered_map<uint64_t, Eigen::Vector3d>& points_in_world,
                               const std::vector<ImuSample>& imu, const InitialStateSigmas& sigmas);
  bool initialized() const { return !frames_.empty(); }

  // Adds a frame (stamp after the newest state; `imu` ordered, covering the
  // interval from the newest state) and optimises. On kLost the window is
  // cleared (initialized() becomes false) and the state is the IMU prediction.
  WindowFrameEstimate AddFrame(const FrameFeatures& features, const std::vector<ImuSample>& imu);

  // The newest state (requires initialized()).
  ImuState NewestState() const;
  // The states of the window's frames, oldest first, as the last
  // optimisation left them (empty when not initialized()).
  std::vector<ImuState> States() const;
  // Clears the window; the landmarks of the last frame that tracked are
  // kept for the re-localisation of the next Initialize.
  void Reset();
  // Clears the window and its map: the next Initialize starts afresh.
  void Clear();
  // Whether the last restart re-localised against the map kept at the
  // reset (decided relocalization_window_s after the restart; false until then).
  bool relocalized() const { return relocalized_; }
  // Map points seen since the last restart (observations).
  int num_relocalization_observations() const { return relocalization_observations_; }

  int num_frames() const { return static_cast<int>(frames_.size()); }
  int num_landmarks() const { return static_cast<int>(landmarks_.size()); }

 private:
  struct Frame;
  struct Landmark;
  struct WindowProblem;
  struct TrackRays;
  struct TrackTriangulation;
  struct WeakLandmark;

  bool IsKeyframe(const Frame& frame, const FrameFeatures& features) const;
  void ClearWindow();
  // The robust loss of an IMU factor (null: plain squares).
  ceres::LossFunction* ImuLoss() const;
  // Counts the map points (re-localisation) the newest frame sees, drops
  // those it contradicts, and ends the re-localisation after
  // relocalization_window_s. Returns the count.
  int UpdateRelocalization(const Frame& newest);
  // Appends a frame to the window and counts its observations in the
  // landmarks (a new landmark is anchored in it).
  void AppendFrame(std::unique_ptr<Frame> frame);
  void RemoveFrame(size_t index);
  void TriangulateLandmarks();
  // TriangulateLandmarks' steps: a track's observations, its point from
  // those from `first` on, the drop of its older observations that disagree
  // (null when no newer run agrees), and the weak landmarks accepted while
  // the newest frame sees too few.
  void CollectRays(uint64_t track_id, const std::vector<Matrix3x4d>& cams_from_world,
                   TrackRays* rays) const;
  std::optional<TrackTriangulation> TriangulateRays(const TrackRays& rays,
                                                    const std::vector<Eigen::Vector3d>& centers,
                                                    size_t first) const;
  std::optional<TrackTriangulation> DropDisagreeingObservations(
      Landmark& landmark, const std::vector<Eigen::Vector3d>& centers, TrackRays* rays);
  void AcceptWeakLandmarks(const Frame& newest, int newest_seen, std::vector<WeakLandmark>* weak);
  // Landmarks used in the optimisation: triangulated, seen twice or more.
  std::vector<Landmark*> SelectLandmarks();
  // Returns the marginal covariance of the newest pose (see
  // WindowFrameEstimate) when options_.compute_covariance, else zero.
  Eigen::Matrix<double, 6, 6> Optimize(const std::vector<Landmark*>& landmarks);
  // Optimize's steps: the window's states and the landmarks' inverse depths
  // copied into one problem, its factors, the solve, the copy back, and the
  // newest pose's covariance.
  void AddStateBlocks(WindowProblem& window) const;
  void AddPriorFactor(WindowProblem& window) const;
  void AddImuFactors(WindowProblem& window);
  void AddLandmarkFactors(WindowProblem& window, const std::vector<Landmark*>& landmarks) const;
  void AddRelocalizationFactors(WindowProblem& window) const;
  // Returns whether the solution is usable.
  bool SolveWindow(WindowProblem& window, bool no_landmarks) const;
  void CopySolutionBack(const WindowProblem& window, const std::vector<Landmark*>& landmarks);
  Eigen::Matrix<double, 6, 6> NewestPoseCovariance(WindowProblem& window, int num_depths) const;
  // Drops the landmarks behind a camera, out of the depth range, or with an
  // observation farther than max_reprojection_error_px from its projection,
  // with their observations in the window (their tracks start again as new
  // landmarks from their next observation).
  void RemoveOutliers(const std::vector<Landmark*>& landmarks);
  void MarginalizeOldest(const std::vector<Landmark*>& landmarks);
  std::string CheckPlausible(const ImuState& predicted) const;
  Rigid3d WorldFromCam(const Frame& frame) const;

  Rigid3d body_from_cam_;
  ImuNoise noise_;
  double focal_length_px_;
  SlidingWindowOptions options_;
  std::shared_ptr<const ceres::Manifold> pose_manifold_;

  std::deque<std::unique_ptr<Frame>> frames_;
  std::unordered_map<uint64_t, Landmark> landmarks_;
  std::shared_ptr<LinearPrior> prior_;
  // World points of the landmarks of the last frame that tracked (by track
  // id), and the map a restarted window re-localises against.
  std::unordered_map<uint64_t, Eigen::Vector3d> map_points_;
  std::unordered_map<uint64_t, Eigen::Vector3d> relocalization_points_;
  timestamp_ns_t restart_ns_ = -1;
  int relocalization_observations_ = 0;
  std::unordered_set<uint64_t> relocalization_seen_;  // distinct map points seen
  bool relocalized_ = false;
  bool has_tracked_ = false;
  timestamp_ns_t imu_only_since_ns_ = -1;
  int next_frame_id_ = 0;
};

}  // namespace viosfm
