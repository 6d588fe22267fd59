#include "viosfm/vio/odometry.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <iomanip>
#include <optional>
#include <sstream>
#include <unordered_map>

#include "viosfm/estimators/absolute_pose.h"
#include "viosfm/geometry/alignment.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/io/vio_states_io.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"
#include "viosfm/vio/imu_noise_check.h"
#include "viosfm/vio/rolling_shutter.h"
#include "viosfm/vio/time_offset.h"

namespace viosfm {

namespace {

// m/s per second of IMU-only propagation added to the velocity prior of a
// window started after a static interval: an accel bias or gravity error of
// 0.3 m/s^2, the size a consumer IMU's bias reaches (BMI055: 70 mg offset).
constexpr double kCarriedVelocitySigmaPerSecond = 0.3;

}  // namespace

std::string OptionText(ContrastEqualization equalization) {
  switch (equalization) {
    case ContrastEqualization::kNever: return "never";
    case ContrastEqualization::kAlways: return "always";
    default: break;
  }
  return "when_dark";
}

void ParseOptionText(const std::string& text, ContrastEqualization* equalization) {
  for (const ContrastEqualization value :
       {ContrastEqualization::kNever, ContrastEqualization::kAlways,
        ContrastEqualization::kWhenDark}) {
    if (text == OptionText(value)) {
      *equalization = value;
      return;
    }
  }
  throw InputError("expected never, always or when_dark");
}

std::vector<std::pair<std::string, std::string>> VioOptions::ToKeyValues() const {
  return OptionsToKeyValues(*this);
}

std::string VioOptions::Validate() const {
  if (const std::string error = tracker.Validate(); !error.empty()) return "tracker." + error;
  if (const std::string error = window.Validate(); !error.empty()) return "window." + error;
  if (const std::string error = static_init.Validate(); !error.empty()) {
    return "static_init." + error;
  }
  if (const std::string error = vi_init.Validate(); !error.empty()) return "vi_init." + error;
  if (const std::string error = time_offset.Validate(); !error.empty()) {
    return "time_offset." + error;
  }
  if (const std::string error = imu_noise.Validate(); !error.empty()) return "imu_noise." + error;
  if (!(rolling_shutter_readout_s >= 0.0 && rolling_shutter_readout_s < 1.0)) {
    return "rolling_shutter_readout_s must be in [0, 1) s";
  }
  for (const InitialStateSigmas* sigmas : {&static_start_sigmas, &restart_sigmas}) {
    if (!(sigmas->position_m > 0) || !(sigmas->yaw_rad > 0) || !(sigmas->roll_pitch_rad > 0) ||
        !(sigmas->velocity_mps > 0) || !(sigmas->gyro_bias > 0) || !(sigmas->accel_bias > 0)) {
      return sigmas == &static_start_sigmas ? "static_start_sigmas must all be > 0"
                                            : "restart_sigmas must all be > 0";
    }
  }
  if (!(max_imu_gap_s >= NsToSeconds(kMaxImuStepNs))) {
    return "max_imu_gap_s must be at least the bridged step of the preintegration";
  }
  if (max_frames < 0) return "max_frames must be >= 0";
  return "";
}

Trajectory VioResult::BodyTrajectory() const {
  Trajectory trajectory;
  trajectory.poses.reserve(frames.size());
  for (const VioFrameResult& frame : frames) {
    if (!frame.has_pose) continue;  // before a moving start is initialised
    trajectory.poses.push_back({frame.timestamp_ns, frame.state.world_from_body});
  }
  return trajectory;
}

Trajectory VioResult::CameraTrajectory() const {
  return BodyToCameraTrajectory(BodyTrajectory(), body_from_cam);
}

namespace {

// Keyframe test for the initialisation buffer: the window's parallax and
// shared-track criteria against the last buffered keyframe.
bool IsNewKeyframe(const FrameFeatures& last, const FrameFeatures& frame,
                   const SlidingWindowOptions& options) {
  std::unordered_map<uint64_t, Eigen::Vector2d> previous;
  for (const FeatureObservation& observation : last.observations) {
    previous.emplace(observation.track_id, observation.normalized);
  }
  int shared = 0;
  double parallax_sum = 0.0;
  for (const FeatureObservation& observation : frame.observations) {
    const auto it = previous.find(observation.track_id);
    if (it == previous.end()) continue;
    ++shared;
    parallax_sum += (observation.normalized - it->second).norm() * kReferenceFocalLengthPx;
  }
  if (shared < options.keyframe_min_shared_tracks) return true;
  return parallax_sum / shared >= options.keyframe_parallax_px;
}

}  // namespace

VisualInertialOdometry::VisualInertialOdometry(const SensorRig& rig,
                                               const std::vector<ImuSample>& imu,
                                               timestamp_ns_t first_frame_ns,
                                               timestamp_ns_t last_frame_ns,
                                               const VioOptions& options)
    : rig_(rig), imu_(imu), options_(options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid VIO options: " + error);
  }
  summary_.static_init.status = StaticInitStatus::kNotEnoughData;
  if (options_.use_static_init) {
    const timestamp_ns_t first_image = rig_.CamToImuTime(first_frame_ns);
    timestamp_ns_t from = first_image;
    if (!imu_.empty()) {
      from = std::max(imu_.front().timestamp_ns,
                      first_image - SecondsToNs(options_.static_init.lookback_s));
    }
    summary_.static_init = DetectStaticStart(
        imu_, std::min(from, first_image), rig_.CamToImuTime(last_frame_ns), options_.static_init);
    StaticInitResult& init = summary_.static_init;
    if (init.is_static() &&
        first_image - init.end_ns > SecondsToNs(options_.static_init.max_propagation_s)) {
      init.status = StaticInitStatus::kNotStatic;
      init.message = "the static interval ends " + FormatNsAsSeconds(first_image - init.end_ns, 2) +
                     " s before the first image (more than static_init.max_propagation_s)";
    }
    static_start_ = init.is_static();
  }
  // The IMU noise the window uses (imu_noise_check.h): measured on the
  // static interval, which may lie before the first image.
  summary_.imu_noise = CheckImuNoise(
      rig_.imu_noise, imu_, summary_.static_init.is_static() ? &summary_.static_init : nullptr,
      options_.imu_noise, rig_.CamToImuTime(first_frame_ns), rig_.CamToImuTime(last_frame_ns));
  rig_.imu_noise = summary_.imu_noise.used;
  if (summary_.imu_noise.changes.empty()) {
    VIOSFM_LOG(INFO) << "vio: IMU noise of the calibration kept" << LogDetails() << " ("
                     << summary_.imu_noise.message << ")";
  } else {
    VIOSFM_LOG(WARNING) << "vio: IMU noise of the calibration replaced ("
                        << summary_.imu_noise.changes.size() << " figures; summary.json: warnings)"
                        << LogDetails() << ": " << summary_.imu_noise.message;
  }
  window_ = std::make_unique<SlidingWindowEstimator>(rig_.body_from_cam, rig_.imu_noise,
                                                     MeanFocalLength(rig_.camera), options_.window);
  if (static_start_) {
    const StaticInitResult& init = summary_.static_init;
    static_state_.world_from_body = init.world_from_body;
    static_state_.world_from_body.translation.setZero();
    static_state_.gyro_bias = init.gyro_bias;
    static_state_.accel_bias = init.accel_bias;
    static_state_.timestamp_ns = init.end_ns;
    last_good_state_ = static_state_;
    have_good_state_ = true;
    VIOSFM_LOG(INFO) << "vio: static start over " << NsToSeconds(init.end_ns - init.start_ns)
                     << " s" << LogDetails() << " (ending "
                     << FormatNsAsSeconds(init.end_ns - rig_.CamToImuTime(first_frame_ns), 2)
                     << " s from the first image): roll " << init.roll_rad * 180.0 / M_PI
                     << " deg, pitch " << init.pitch_rad * 180.0 / M_PI << " deg, gyro bias "
                     << init.gyro_bias.transpose();
  } else {
    VIOSFM_LOG(INFO) << "vio: no static start (" << summary_.static_init.message
                     << "); visual-inertial initialisation";
  }
}

timestamp_ns_t VisualInertialOdometry::LongestImuIntervalNs(timestamp_ns_t from_ns,
                                                            timestamp_ns_t to_ns) const {
  if (imu_.size() < 2 || to_ns <= from_ns) return 0;
  auto first = std::upper_bound(
      imu_.begin(), imu_.end(), from_ns,
      [](timestamp_ns_t t, const ImuSample& sample) { return t < sample.timestamp_ns; });
  if (first != imu_.begin()) --first;
  auto last = std::lower_bound(
      imu_.begin(), imu_.end(), to_ns,
      [](const ImuSample& sample, timestamp_ns_t t) { return sample.timestamp_ns < t; });
  if (last == imu_.end()) --last;
  timestamp_ns_t longest = 0;
  for (auto it = first; it < last; ++it) {
    longest = std::max(longest, (it + 1)->timestamp_ns - it->timestamp_ns);
  }
  return longest;
}

bool VisualInertialOdometry::BreakAtImuGap(const FrameFeatures& frame, timestamp_ns_t camera_ns) {
  std::optional<timestamp_ns_t> from_ns = last_frame_imu_ns_;
  if (have_good_state_) {
    from_ns =
        from_ns ? std::min(*from_ns, last_good_state_.timestamp_ns) : last_good_state_.timestamp_ns;
  }
  if (!from_ns || *from_ns >= frame.timestamp_ns) return false;
  const timestamp_ns_t max_gap_ns = SecondsToNs(options_.max_imu_gap_s);
  if (LongestImuIntervalNs(*from_ns, frame.timestamp_ns) <= max_gap_ns) return false;
  // The gap's first sample: the start of the first too long interval.
  auto it = std::upper_bound(
      imu_.begin(), imu_.end(), *from_ns,
      [](timestamp_ns_t t, const ImuSample& sample) { return t < sample.timestamp_ns; });
  if (it != imu_.begin()) --it;
  while (it + 1 < imu_.end() && (it + 1)->timestamp_ns - it->timestamp_ns <= max_gap_ns) ++it;
  const timestamp_ns_t gap_start_ns = it->timestamp_ns;
  const double gap_s =
      it + 1 < imu_.end() ? NsToSeconds((it + 1)->timestamp_ns - gap_start_ns) : 0.0;
  // A frame in the gap broke the VIO already: the frames up to its end are
  // part of the same break.
  const bool new_gap =
      summary_.imu_breaks.empty() || summary_.imu_breaks.back().gap_start_ns != gap_start_ns;
  if (new_gap) {
    summary_.imu_breaks.push_back({gap_start_ns, gap_s, camera_ns});
    VIOSFM_LOG(WARNING) << "vio: the IMU has no sample for "
                        << FormatNsAsSeconds(SecondsToNs(gap_s), 3) << " s after "
                        << FormatNsAsSeconds(gap_start_ns, 3) << " s (more than max_imu_gap_s "
                        << options_.max_imu_gap_s
                        << " s): the VIO breaks there and starts a new segment, "
                           "initialised again after the gap";
  }
  if (moving_start_pending_) {
    PoseMovingStart(window_->initialized() ? window_->States() : std::vector<ImuState>());
  }
  if (undecided_reset_ns_) {
    // A restart cut off by the gap before its re-localisation was decided.
    summary_.resets.back().relocalized = false;
    undecided_reset_ns_.reset();
  }
  window_->Clear();
  have_good_state_ = false;
  static_start_ = false;
  init_keyframes_.clear();
  moving_start_frames_.clear();
  relocalization_pending_ = false;
  return new_gap;
}

ImuState VisualInertialOdometry::Propagate(const ImuState& state, timestamp_ns_t to_ns) const {
  if (to_ns <= state.timestamp_ns) return state;
  ImuPreintegration preintegration(state.gyro_bias, state.accel_bias, rig_.imu_noise);
  if (!preintegration.IntegrateRange(imu_, state.timestamp_ns, to_ns) ||
      !preintegration.IsUsable()) {
    ImuState held = state;
    held.timestamp_ns = to_ns;
    return held;
  }
  ImuState predicted = preintegration.Predict(state);
  predicted.timestamp_ns = to_ns;
  return predicted;
}

// s, the longest a moving start's frames wait for its initialisation to
// pose them (VioOptions::pose_moving_start): the 15 s start of the real
// recording initialised 3.8 s in, and its first 2.5 s of corners were gone
// by then.
constexpr double kMovingStartHoldS = 10.0;

ImuState VisualInertialOdometry::PropagateBack(const ImuState& state, timestamp_ns_t to_ns) const {
  if (to_ns >= state.timestamp_ns) return state;
  ImuPreintegration preintegration(state.gyro_bias, state.accel_bias, rig_.imu_noise);
  ImuState earlier = state;
  earlier.timestamp_ns = to_ns;
  if (!preintegration.IntegrateRange(imu_, to_ns, state.timestamp_ns) ||
      !preintegration.IsUsable()) {
    return earlier;
  }
  // Predict's equations (imu_preintegration.h) solved for the earlier state:
  // R_j = R_i dR, v_j = v_i + g dt + R_i dv, p_j = p_i + v_i dt + g dt^2 / 2 + R_i dp.
  const double dt = NsToSeconds(state.timestamp_ns - to_ns);
  const Eigen::Vector3d gravity = GravityInWorld();
  const Eigen::Quaterniond rotation =
      (state.world_from_body.rotation * preintegration.delta_R().conjugate()).normalized();
  earlier.world_from_body.rotation = rotation;
  earlier.velocity_in_world =
      state.velocity_in_world - gravity * dt - rotation * preintegration.delta_v();
  earlier.world_from_body.translation = state.world_from_body.translation -
                                        earlier.velocity_in_world * dt - 0.5 * gravity * dt * dt -
                                        rotation * preintegration.delta_p();
  return earlier;
}

std::optional<timestamp_ns_t> VisualInertialOdometry::FirstUnsettledFrameNs() const {
  std::optional<timestamp_ns_t> first = undecided_reset_ns_;
  if (!moving_start_frames_.empty()) {
    const timestamp_ns_t held_ns = moving_start_frames_.front().first;
    first = first ? std::min(*first, held_ns) : held_ns;
  }
  return first;
}

void VisualInertialOdometry::FinishMovingStart() {
  if (!moving_start_pending_) return;
  PoseMovingStart(window_->initialized() ? window_->States() : std::vector<ImuState>());
}

void VisualInertialOdometry::PoseMovingStart(const std::vector<ImuState>& window_states) {
  moving_start_pending_ = false;
  std::vector<ImuState> keyframe_states = std::move(moving_start_keyframes_);
  std::unordered_map<uint64_t, Eigen::Vector3d> points_in_world = std::move(moving_start_points_);
  // The initialisation's keyframes the window still holds, and its estimates of them.
  std::vector<Eigen::Vector3d> initial_positions;
  std::vector<Eigen::Vector3d> window_positions;
  std::unordered_map<timestamp_ns_t, const ImuState*> window_by_stamp;
  for (const ImuState& state : window_states) window_by_stamp.emplace(state.timestamp_ns, &state);
  for (const ImuState& state : keyframe_states) {
    const auto found = window_by_stamp.find(state.timestamp_ns);
    if (found == window_by_stamp.end()) continue;
    initial_positions.push_back(state.world_from_body.translation);
    window_positions.push_back(found->second->world_from_body.translation);
  }
  if (initial_positions.size() >= 3) {
    if (const std::optional<Sim3d> window_from_initial =
            AlignPointsUmeyama(initial_positions, window_positions, /*with_scale=*/true)) {
      const Sim3d& t = *window_from_initial;
      for (ImuState& state : keyframe_states) {
        const auto found = window_by_stamp.find(state.timestamp_ns);
        if (found != window_by_stamp.end()) {
          state = *found->second;
          continue;
        }
        state.world_from_body.rotation = (t.rotation * state.world_from_body.rotation).normalized();
        state.world_from_body.translation = t * state.world_from_body.translation;
        state.velocity_in_world = t.scale * (t.rotation * state.velocity_in_world);
      }
      for (auto& [track_id, point] : points_in_world) point = t * point;
    }
  }
  const double focal_length_px = MeanFocalLength(rig_.camera);
  const Rigid3d cam_from_body = rig_.body_from_cam.Inverse();
  const AbsolutePoseOptions pnp_options;  // 8 px, 15 inliers
  std::vector<Eigen::Vector2d> points_normalized;
  std::vector<Eigen::Vector3d> points;
  for (const auto& [camera_ns, frame] : moving_start_frames_) {
    // The keyframe nearest in time.
    const ImuState* nearest = nullptr;
    timestamp_ns_t nearest_gap_ns = 0;
    for (const ImuState& keyframe : keyframe_states) {
      const timestamp_ns_t gap_ns = std::abs(frame.timestamp_ns - keyframe.timestamp_ns);
      if (nearest == nullptr || gap_ns < nearest_gap_ns) {
        nearest = &keyframe;
        nearest_gap_ns = gap_ns;
      }
    }
    if (nearest == nullptr) break;
    ImuState state = *nearest;
    if (nearest_gap_ns == 0) {
      ++summary_.num_moving_start_keyframes;
    } else {
      state = frame.timestamp_ns > nearest->timestamp_ns
                  ? Propagate(*nearest, frame.timestamp_ns)
                  : PropagateBack(*nearest, frame.timestamp_ns);
      points_normalized.clear();
      points.clear();
      for (const FeatureObservation& observation : frame.observations) {
        const auto point = points_in_world.find(observation.track_id);
        if (point == points_in_world.end()) continue;
        points_normalized.push_back(observation.normalized);
        points.push_back(point->second);
      }
      AbsolutePoseResult pnp;
      if (static_cast<int>(points.size()) >= pnp_options.min_num_inliers) {
        pnp = EstimateAbsolutePose(points_normalized, points, focal_length_px, pnp_options,
                                   cam_from_body * state.world_from_body.Inverse());
      }
      if (pnp.success) {
        state.world_from_body = pnp.cam_from_world.Inverse() * cam_from_body;
        ++summary_.num_moving_start_pnp;
      } else if (NsToSeconds(nearest_gap_ns) <= options_.moving_start_max_imu_s) {
        ++summary_.num_moving_start_imu;
      } else {
        continue;
      }
    }
    state.timestamp_ns = frame.timestamp_ns;
    moving_start_states_.emplace_back(camera_ns, state);
  }
  moving_start_frames_.clear();
}

std::vector<std::pair<timestamp_ns_t, ImuState>> VisualInertialOdometry::TakeMovingStartStates() {
  std::vector<std::pair<timestamp_ns_t, ImuState>> states;
  states.swap(moving_start_states_);
  return states;
}

Eigen::Quaterniond GyroRotationPrior(const SensorRig& rig, const std::vector<ImuSample>& imu,
                                     const Eigen::Vector3d& gyro_bias, timestamp_ns_t from_ns,
                                     timestamp_ns_t to_ns) {
  ImuPreintegration preintegration(gyro_bias, Eigen::Vector3d::Zero(), rig.imu_noise);
  if (!preintegration.IntegrateRange(imu, rig.CamToImuTime(from_ns), rig.CamToImuTime(to_ns))) {
    return Eigen::Quaterniond::Identity();
  }
  // x_cam_now = R_bc^T * R_body_now_from_body_prev * R_bc * x_cam_prev.
  const Eigen::Quaterniond& body_from_cam = rig.body_from_cam.rotation;
  return (body_from_cam.conjugate() * preintegration.delta_R().conjugate() * body_from_cam)
      .normalized();
}

Eigen::Quaterniond VisualInertialOdometry::GyroRotationPrior(timestamp_ns_t from_ns,
                                                             timestamp_ns_t to_ns) const {
  return viosfm::GyroRotationPrior(rig_, imu_, last_state_.gyro_bias, from_ns, to_ns);
}

void VisualInertialOdometry::StartWindow(const ImuState& state, const InitialStateSigmas& sigmas,
                                         const FrameFeatures& features) {
  window_->Initialize(state, sigmas, features);
}

void VisualInertialOdometry::Record(const VioFrameResult& result) {
  ++summary_.num_frames;
  ++summary_.status_counts[static_cast<int>(result.status)];
  if (result.is_keyframe) ++summary_.num_keyframes;
  if (result.status == VioStatus::kTracking && summary_.first_tracking_ns < 0) {
    summary_.first_tracking_ns = result.timestamp_ns;
    summary_.visual_initialized = true;
  }
  if (result.status == VioStatus::kLost) ++summary_.num_resets;
  last_state_ = result.state;
  if (result.status == VioStatus::kTracking ||
      (result.status == VioStatus::kInitializing && static_start_)) {
    last_good_state_ = result.state;
    have_good_state_ = true;
  }
}

bool VisualInertialOdometry::TryVisualInertialInitialization(const FrameFeatures& frame,
                                                             const ImuState* carried) {
  // A frame before the IMU's first sample cannot be initialised from: kept
  // among the keyframes, it would fail every attempt until it left them.
  if (imu_.empty() || frame.timestamp_ns <= imu_.front().timestamp_ns) return false;
  if (!(frame.is_keyframe || init_keyframes_.empty() ||
        IsNewKeyframe(init_keyframes_.back(), frame, options_.window))) {
    return false;
  }
  init_keyframes_.push_back(frame);
  if (static_cast<int>(init_keyframes_.size()) > options_.vi_init.window_size) {
    init_keyframes_.erase(init_keyframes_.begin());
  }
  if (static_cast<int>(init_keyframes_.size()) < options_.vi_init.min_num_frames) return false;
  const ViInitResult init = InitializeVisualInertial(init_keyframes_, imu_, rig_.body_from_cam,
                                                     rig_.imu_noise, options_.vi_init);
  if (!init.success || init.states.empty()) return false;
  // Readings out of any IMU's range can leave the alignment non-finite.
  const auto finite = [](const ImuState& state) {
    return state.world_from_body.rotation.coeffs().allFinite() &&
           state.world_from_body.translation.allFinite() && state.velocity_in_world.allFinite() &&
           state.gyro_bias.allFinite() && state.accel_bias.allFinite();
  };
  if (!std::all_of(init.states.begin(), init.states.end(), finite) ||
      !std::all_of(init.points_in_world.begin(), init.points_in_world.end(),
                   [](const auto& point) { return point.second.allFinite(); })) {
    VIOSFM_LOG(WARNING) << "vio: the visual-inertial initialisation at "
                        << FormatNsAsSeconds(frame.timestamp_ns - rig_.cam_time_offset_ns, 3)
                        << " s gave non-finite states (IMU readings out of any IMU's range?): "
                           "not used";
    init_keyframes_.clear();
    return false;
  }
  VIOSFM_LOG(INFO) << "vio: visual-inertial initialisation at "
                   << FormatNsAsSeconds(frame.timestamp_ns - rig_.cam_time_offset_ns, 3)
                   << " s: " << init.message;
  const size_t used = init.states.size();
  std::vector<FrameFeatures> used_keyframes(init_keyframes_.end() - used, init_keyframes_.end());
  std::vector<ImuState> states = init.states;
  std::unordered_map<uint64_t, Eigen::Vector3d> points = init.points_in_world;
  for (size_t k = 0; k < used; ++k) states[k].timestamp_ns = used_keyframes[k].timestamp_ns;
  if (carried != nullptr && have_good_state_) {
    // A restart: the initialisation's world (gravity-aligned, origin and yaw
    // at its first keyframe) is placed in the VIO's world so that its first
    // keyframe lands where the IMU carries the last good state.
    const ImuState at_first = Propagate(last_good_state_, states.front().timestamp_ns);
    const Eigen::Matrix3d delta =
        at_first.world_from_body.rotation.toRotationMatrix() *
        states.front().world_from_body.rotation.toRotationMatrix().transpose();
    const double yaw = std::atan2(delta(1, 0) - delta(0, 1), delta(0, 0) + delta(1, 1));
    const Eigen::Quaterniond rotation(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
    const Eigen::Vector3d translation = at_first.world_from_body.translation -
                                        rotation * states.front().world_from_body.translation;
    for (ImuState& state : states) {
      state.world_from_body.rotation = (rotation * state.world_from_body.rotation).normalized();
      state.world_from_body.translation =
          rotation * state.world_from_body.translation + translation;
      state.velocity_in_world = rotation * state.velocity_in_world;
    }
    for (auto& [track_id, point] : points) point = rotation * point + translation;
  }
  if (carried == nullptr && summary_.resets.empty() && options_.pose_moving_start) {
    moving_start_pending_ = true;
    moving_start_keyframes_ = states;
    moving_start_points_ = points;
  }
  window_->InitializeWithKeyframes(used_keyframes, states, points, imu_, options_.restart_sigmas);
  init_keyframes_.clear();
  return true;
}

VioFrameResult VisualInertialOdometry::ProcessFrame(const FrameFeatures& features) {
  VioFrameResult result;
  result.timestamp_ns = features.timestamp_ns;
  result.num_features = static_cast<int>(features.observations.size());
  FrameFeatures frame = features;
  frame.timestamp_ns = rig_.CamToImuTime(features.timestamp_ns);
  result.after_imu_break = BreakAtImuGap(frame, features.timestamp_ns);
  last_frame_imu_ns_ = frame.timestamp_ns;

  if (window_->initialized()) {
    TrackInWindow(frame, features.timestamp_ns, &result);
    Record(result);
    return result;
  }

  result.status = VioStatus::kInitializing;
  if (static_start_ && frame.timestamp_ns <= summary_.static_init.end_ns) {
    // Standing still: hold the static state.
    result.state = static_state_;
    result.state.timestamp_ns = frame.timestamp_ns;
  } else if (have_good_state_ && static_start_ && summary_.num_resets == 0) {
    StartFromStaticState(frame, &result);
  } else {
    CollectForInitialization(frame, features.timestamp_ns, &result);
  }
  Record(result);
  return result;
}

void VisualInertialOdometry::TrackInWindow(const FrameFeatures& frame, timestamp_ns_t camera_ns,
                                           VioFrameResult* result) {
  const WindowFrameEstimate estimate = window_->AddFrame(frame, imu_);
  if (moving_start_pending_) {
    // Posed once the first of the initialisation's keyframes has left the
    // window (the others then carry the window's estimates), or now if
    // the window was lost.
    const std::vector<ImuState> window_states = window_->States();
    const bool first_left =
        window_states.empty() ||
        std::none_of(window_states.begin(), window_states.end(), [&](const ImuState& state) {
          return state.timestamp_ns == moving_start_keyframes_.front().timestamp_ns;
        });
    if (first_left) PoseMovingStart(window_states);
  }
  result->state = estimate.state;
  result->status = estimate.status;
  result->is_keyframe = estimate.is_keyframe;
  result->num_landmarks = estimate.num_landmarks;
  result->pose_covariance = estimate.pose_covariance;
  result->num_map_points = estimate.num_map_points;
  if (estimate.status == VioStatus::kLost) {
    VIOSFM_LOG(WARNING) << "vio: lost at " << FormatNsAsSeconds(camera_ns, 3)
                        << " s: " << estimate.message;
    VioReset reset;
    reset.timestamp_ns = camera_ns;
    reset.message = estimate.message;
    summary_.resets.push_back(reset);
    relocalization_pending_ = false;
    undecided_reset_ns_ = camera_ns;
    init_keyframes_.clear();
  } else if (relocalization_pending_ && NsToSeconds(frame.timestamp_ns - restart_ns_) >=
                                            options_.window.relocalization_window_s) {
    relocalization_pending_ = false;
    undecided_reset_ns_.reset();
    VioReset& reset = summary_.resets.back();
    reset.relocalized = window_->relocalized();
    reset.num_map_points = window_->num_relocalization_observations();
    VIOSFM_LOG(INFO) << "vio: the restart after the reset at "
                     << FormatNsAsSeconds(reset.timestamp_ns, 3) << " s "
                     << (reset.relocalized ? "re-localised against the previous map"
                                           : "did not re-localise (joined by the IMU alone)")
                     << " (" << reset.num_map_points << " map point observations)";
  }
}

void VisualInertialOdometry::StartFromStaticState(const FrameFeatures& frame,
                                                  VioFrameResult* result) {
  // The static start ended: the window starts from the static state
  // carried forward by the IMU.
  ImuState start = Propagate(last_good_state_, frame.timestamp_ns);
  if (!start.velocity_in_world.allFinite() ||
      start.velocity_in_world.norm() > options_.window.max_speed_mps) {
    start = last_good_state_;
    start.timestamp_ns = frame.timestamp_ns;
    start.velocity_in_world.setZero();
  }
  // Carried by the IMU alone from the end of the static interval: the
  // velocity is known less well the longer that took.
  InitialStateSigmas sigmas = options_.static_start_sigmas;
  const double carried_s = NsToSeconds(frame.timestamp_ns - last_good_state_.timestamp_ns);
  sigmas.velocity_mps = std::hypot(sigmas.velocity_mps, kCarriedVelocitySigmaPerSecond * carried_s);
  StartWindow(start, sigmas, frame);
  result->state = start;
}

void VisualInertialOdometry::CollectForInitialization(const FrameFeatures& frame,
                                                      timestamp_ns_t camera_ns,
                                                      VioFrameResult* result) {
  // A moving start, or a restart after kLost: keyframes are collected until
  // the visual-inertial initialisation succeeds on them (a restart thus
  // takes its velocity and gravity from the images and the IMU together,
  // not from an IMU propagation across the failure, which may be what
  // failed). Meanwhile a restart's frames are carried by the IMU from the
  // last good state (status kImuOnly); a moving start's have no pose.
  result->state.timestamp_ns = frame.timestamp_ns;
  result->has_pose = false;
  std::optional<ImuState> carried;
  if (have_good_state_) {
    carried = Propagate(last_good_state_, frame.timestamp_ns);
    if (carried->velocity_in_world.allFinite() &&
        carried->velocity_in_world.norm() <= options_.window.max_speed_mps) {
      result->state = *carried;
      result->status = VioStatus::kImuOnly;
      result->has_pose = true;
    } else {
      carried.reset();
    }
  }
  if (TryVisualInertialInitialization(frame, carried ? &*carried : nullptr)) {
    result->state = window_->NewestState();
    result->status = VioStatus::kInitializing;
    result->has_pose = true;
    if (!summary_.resets.empty()) {
      relocalization_pending_ = true;
      restart_ns_ = frame.timestamp_ns;
    }
  } else if (!result->has_pose && summary_.resets.empty() && options_.pose_moving_start) {
    moving_start_frames_.emplace_back(camera_ns, frame);
    // Held for kMovingStartHoldS at most: older frames' corners have left
    // the view by the time an initialisation succeeds, and a recording
    // that never initialises must not hold every frame.
    while (frame.timestamp_ns - moving_start_frames_.front().second.timestamp_ns >
           SecondsToNs(kMovingStartHoldS)) {
      moving_start_frames_.pop_front();
    }
  }
}

// IMU a frame waits for beyond its stamp (IMU clock) before it is tracked:
// the gyro's rotation prior, the rolling-shutter rates and the
// preintegration up to it need the samples around it.
constexpr timestamp_ns_t kImuLeadNs = 50'000'000;

struct VioRunner::State {
  SensorRig rig;
  VioOptions options;
  FrameCache* frames = nullptr;
  std::optional<timestamp_ns_t> last_frame_ns;
  VioProgressCallback on_progress;
  double cpu_start = 0.0;
  Timer timer;

  std::vector<ImuSample> imu;
  std::vector<SequenceImage> images;
  size_t num_frames_limit = std::numeric_limits<size_t>::max();  // options.max_frames
  size_t next = 0;                                               // the next image to track

  VioResult result;
  FeatureTracker tracker;
  std::unique_ptr<ProgressBar> progress;
  // The previous frame's observations as tracked, for the rolling-shutter
  // correction's image velocities.
  std::optional<FrameFeatures> previous_tracked;
  // The readout the observations are corrected with: the one given, or the
  // one estimated with the time offset (the startup frames then stay as
  // tracked until the estimate, and are corrected after it).
  double readout_s = 0.0;
  bool estimate_readout = false;
  // The camera-IMU time offset, from the first frames that rotate enough
  // (they are tracked with the calibration's offset for the gyro prior and
  // kept until the estimate is made), and the frames tracked before the
  // window starts.
  std::vector<FrameFeatures> startup;
  bool time_offset_done = false;
  double rotation_deg = 0.0;
  TimeOffsetEstimate time_offset;
  std::unique_ptr<VisualInertialOdometry> vio;
  size_t num_beyond_imu = 0;
  // Segments: a reset that did not re-localise starts a new one at its lost
  // frame. Given to the frames as they settle (their reset decided).
  int segment = 0;
  size_t next_reset = 0;
  size_t num_settled = 0;

  State(const SensorRig& rig_in, const VioOptions& options_in, FrameCache* frames_in,
        std::optional<timestamp_ns_t> last_in, VioProgressCallback callback)
      : rig(rig_in),
        options(options_in),
        frames(frames_in),
        last_frame_ns(last_in),
        on_progress(std::move(callback)),
        tracker(rig_in.camera, options_in.tracker) {
    readout_s = options.rolling_shutter_readout_s;
    estimate_readout =
        options.time_offset.estimate && options.time_offset.estimate_readout && readout_s == 0.0;
    time_offset.offset_ns = time_offset.calibration_offset_ns = rig.cam_time_offset_ns;
    time_offset.message = "the calibration's camera-IMU time offset (not estimated)";
    time_offset_done = !options.time_offset.estimate;
    if (options.max_frames > 0) num_frames_limit = static_cast<size_t>(options.max_frames);
  }

  FrameFeatures ReadAndTrack(size_t k, const std::optional<Eigen::Quaterniond>& prior) {
    const SequenceImage& image = images[k];
    FrameFeatures features =
        frames != nullptr
            ? tracker.Track(image.timestamp_ns, *frames->Read(image.path, /*keep=*/true), prior)
            : tracker.Track(image.timestamp_ns, ReadGreyImage(image.path), prior);
    if (readout_s > 0.0) {
      FrameFeatures tracked = features;
      CorrectRollingShutter(previous_tracked ? &*previous_tracked : nullptr, readout_s,
                            static_cast<int>(rig.camera.height),
                            CamAngularRate(rig, imu, image.timestamp_ns), &features);
      previous_tracked = std::move(tracked);
    }
    progress->Update();
    return features;
  }

  void Settle(size_t until) {
    const std::vector<VioReset>& resets = vio->summary().resets;
    for (; num_settled < until; ++num_settled) {
      VioFrameResult& frame = result.frames[num_settled];
      if (frame.status == VioStatus::kLost && next_reset < resets.size()) {
        if (!resets[next_reset].relocalized) ++segment;
        ++next_reset;
      }
      if (frame.after_imu_break) ++segment;
      frame.segment = segment;
    }
  }

  // States found for earlier frames once a moving start is initialised;
  // then what has settled is reported.
  void PoseMovingStart() {
    for (const auto& [camera_ns, state] : vio->TakeMovingStartStates()) {
      for (auto frame = result.frames.rbegin(); frame != result.frames.rend(); ++frame) {
        if (frame->timestamp_ns != camera_ns) continue;
        frame->state = state;
        frame->has_pose = true;
        break;
      }
    }
    const std::optional<timestamp_ns_t> unsettled_ns = vio->FirstUnsettledFrameNs();
    size_t until = num_settled;
    while (until < result.frames.size() &&
           (!unsettled_ns || result.frames[until].timestamp_ns < *unsettled_ns)) {
      ++until;
    }
    Settle(until);
    if (on_progress) {
      on_progress({&result.frames, num_settled, &time_offset, &vio->summary().imu_noise, false});
    }
  }

  void Process(const FrameFeatures& features) {
    result.frames.push_back(vio->ProcessFrame(features));
    PoseMovingStart();
  }

  // The IMU reaches frame k (or the data has ended).
  bool ImuReaches(size_t k, bool ended) const {
    return ended || (!imu.empty() && imu.back().timestamp_ns >=
                                         rig.CamToImuTime(images[k].timestamp_ns) + kImuLeadNs);
  }

  // Whether the window may start: the last frame is known (the whole
  // recording), the data has ended, or the IMU has decided the static start
  // (see VioRunner).
  bool StaticStartDecided(bool ended) const {
    if (last_frame_ns || ended || !options.use_static_init) return true;
    if (imu.empty() || images.empty()) return false;
    const StaticInitOptions& static_init = options.static_init;
    const timestamp_ns_t first_image = rig.CamToImuTime(images.front().timestamp_ns);
    const timestamp_ns_t from =
        std::max(imu.front().timestamp_ns, first_image - SecondsToNs(static_init.lookback_s));
    const timestamp_ns_t to = imu.back().timestamp_ns;
    const StaticInitResult detected =
        DetectStaticStart(imu, std::min(from, first_image), to, static_init);
    if (detected.status == StaticInitStatus::kNotEnoughData) return false;
    if (detected.status == StaticInitStatus::kNotStatic) return true;
    // Ended by motion, not by the data: the data go on well past it.
    return detected.end_ns + SecondsToNs(2.0 * static_init.window_s + static_init.motion_margin_s) <
           to;
  }

  void EstimateTheTimeOffset() {
    time_offset = EstimateTimeOffset(startup, imu, rig.body_from_cam, rig.cam_time_offset_ns,
                                     MeanFocalLength(rig.camera), options.time_offset,
                                     estimate_readout ? static_cast<int>(rig.camera.height) : 0);
    time_offset_done = true;
    VIOSFM_LOG(INFO) << "vio: " << TimeOffsetHeadline(time_offset) << LogDetails() << " ("
                     << time_offset.message << ")";
    rig.cam_time_offset_ns = time_offset.offset_ns;
    if (time_offset.readout_estimated) {
      // The startup frames, tracked uncorrected, corrected now (at the
      // estimated offset), and the frames after them as they come.
      readout_s = time_offset.readout_s;
      if (!startup.empty()) previous_tracked = startup.back();
      for (size_t i = startup.size(); i-- > 0;) {
        CorrectRollingShutter(i > 0 ? &startup[i - 1] : nullptr, readout_s,
                              static_cast<int>(rig.camera.height),
                              CamAngularRate(rig, imu, startup[i].timestamp_ns), &startup[i]);
      }
    }
  }

  void StartWindow(bool ended) {
    time_offset.readout_s = readout_s;
    const timestamp_ns_t last_ns = last_frame_ns ? *last_frame_ns : images.back().timestamp_ns;
    vio = std::make_unique<VisualInertialOdometry>(rig, imu, images.front().timestamp_ns, last_ns,
                                                   options);
    // Frames the IMU does not reach (after the time offset) cannot be
    // propagated to; at the end they are counted and reported.
    const timestamp_ns_t last_imu_ns = imu.back().timestamp_ns;
    for (const FrameFeatures& features : startup) {
      if (ended && rig.CamToImuTime(features.timestamp_ns) > last_imu_ns) {
        ++num_beyond_imu;
        continue;
      }
      Process(features);
    }
    startup.clear();
  }
};

VioRunner::VioRunner(const SensorRig& rig, const VioOptions& options, FrameCache* frames,
                     std::optional<timestamp_ns_t> last_frame_ns, VioProgressCallback on_progress,
                     size_t expected_frames) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid VIO options: " + error);
  }
  state_ = std::make_unique<State>(rig, options, frames, last_frame_ns, std::move(on_progress));
  State& s = *state_;
  s.cpu_start = ProcessCpuSeconds();
  s.result.body_from_cam = rig.body_from_cam;
  s.result.frames.reserve(expected_frames);
  s.progress = std::make_unique<ProgressBar>(
      "vio", static_cast<int64_t>(expected_frames),
      options.show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
}

VioRunner::~VioRunner() = default;

size_t VioRunner::num_processed() const {
  return state_->result.frames.size();
}

void VioRunner::AddImu(const std::vector<ImuSample>& samples) {
  State& s = *state_;
  for (const ImuSample& sample : samples) {
    if (!s.imu.empty() && sample.timestamp_ns <= s.imu.back().timestamp_ns) {
      throw InputError("vio: IMU sample at " + FormatNsAsSeconds(sample.timestamp_ns) +
                       " s does not follow the last one, at " +
                       FormatNsAsSeconds(s.imu.back().timestamp_ns) + " s");
    }
    s.imu.push_back(sample);
  }
  Step(/*ended=*/false);
}

void VioRunner::AddImage(const SequenceImage& image) {
  State& s = *state_;
  if (!s.images.empty() && image.timestamp_ns <= s.images.back().timestamp_ns) {
    throw InputError(image.path.string(), 0,
                     "vio: frame at " + FormatNsAsSeconds(image.timestamp_ns) +
                         " s does not follow the last one, at " +
                         FormatNsAsSeconds(s.images.back().timestamp_ns) + " s");
  }
  s.images.push_back(image);
  Step(/*ended=*/false);
}

void VioRunner::Step(bool ended) {
  State& s = *state_;
  const size_t num_frames = std::min(s.images.size(), s.num_frames_limit);
  // The frames before the window starts: the time offset's startup, then
  // (a recording that is still being made) until the static start is
  // decided.
  while (s.vio == nullptr) {
    if (s.time_offset_done && !s.images.empty() && s.imu.size() >= 1 &&
        s.StaticStartDecided(ended)) {
      s.StartWindow(ended);
      break;
    }
    if (s.next >= num_frames || !s.ImuReaches(s.next, ended)) return;
    const size_t k = s.next++;
    std::optional<Eigen::Quaterniond> prior;
    if (s.options.gyro_rotation_prior && k > 0) {
      prior = GyroRotationPrior(s.rig, s.imu, Eigen::Vector3d::Zero(), s.images[k - 1].timestamp_ns,
                                s.images[k].timestamp_ns);
    }
    s.startup.push_back(s.ReadAndTrack(k, prior));
    if (s.time_offset_done) continue;
    if (s.startup.size() >= 2) {
      s.rotation_deg += GyroRotationSumDeg({s.startup[s.startup.size() - 2], s.startup.back()},
                                           s.imu, s.rig.cam_time_offset_ns);
    }
    if (s.rotation_deg < s.options.time_offset.target_rotation_deg &&
        NsToSeconds(s.startup.back().timestamp_ns - s.startup.front().timestamp_ns) <
            s.options.time_offset.max_wait_s) {
      continue;
    }
    s.EstimateTheTimeOffset();
  }
  const timestamp_ns_t last_imu_ns = s.imu.back().timestamp_ns;
  for (; s.next < num_frames; ++s.next) {
    const size_t k = s.next;
    if (ended && s.rig.CamToImuTime(s.images[k].timestamp_ns) > last_imu_ns) {
      s.num_beyond_imu += num_frames - k;
      s.next = num_frames;
      break;
    }
    if (!s.ImuReaches(k, ended)) return;
    std::optional<Eigen::Quaterniond> prior;
    if (s.options.gyro_rotation_prior && k > 0) {
      prior = s.vio->GyroRotationPrior(s.images[k - 1].timestamp_ns, s.images[k].timestamp_ns);
    }
    s.Process(s.ReadAndTrack(k, prior));
  }
}

namespace {

// Intervals between IMU samples longer than kMaxImuStepNs: all of them, and
// those the preintegration bridges (at most max_gap_ns).
struct ImuGaps {
  size_t num_gaps = 0;
  size_t num_bridged = 0;
  timestamp_ns_t longest_ns = 0;  // the longest interval between samples, gap or not
  timestamp_ns_t longest_bridged_ns = 0;
};

ImuGaps FindImuGaps(const std::vector<ImuSample>& imu, timestamp_ns_t max_gap_ns) {
  ImuGaps gaps;
  for (size_t i = 1; i < imu.size(); ++i) {
    const timestamp_ns_t gap_ns = imu[i].timestamp_ns - imu[i - 1].timestamp_ns;
    if (gap_ns > kMaxImuStepNs) ++gaps.num_gaps;
    if (gap_ns > kMaxImuStepNs && gap_ns <= max_gap_ns) {
      ++gaps.num_bridged;
      gaps.longest_bridged_ns = std::max(gaps.longest_bridged_ns, gap_ns);
    }
    gaps.longest_ns = std::max(gaps.longest_ns, gap_ns);
  }
  return gaps;
}

// Stretches on the IMU alone: from a stretch's first frame to the frame
// after it (to its last when it runs to the end).
void CountImuOnlyStretches(const std::vector<VioFrameResult>& frames, VioSummary* summary) {
  for (size_t k = 0; k < frames.size();) {
    if (frames[k].status != VioStatus::kImuOnly) {
      ++k;
      continue;
    }
    size_t end = k;
    while (end < frames.size() && frames[end].status == VioStatus::kImuOnly) ++end;
    ++summary->num_imu_only_stretches;
    const timestamp_ns_t until_ns = frames[std::min(end, frames.size() - 1)].timestamp_ns;
    const double length_s = NsToSeconds(until_ns - frames[k].timestamp_ns);
    if (summary->longest_imu_only_from_ns < 0 || length_s > summary->longest_imu_only_s) {
      summary->longest_imu_only_s = length_s;
      summary->longest_imu_only_from_ns = frames[k].timestamp_ns;
    }
    k = end;
  }
}

// Says how many frames ran on the IMU alone or were lost, when any did.
void WarnImuOnlyFrames(const VioSummary& summary, timestamp_ns_t first_image_ns) {
  const size_t num_imu_only = summary.status_counts[static_cast<int>(VioStatus::kImuOnly)];
  const size_t num_lost = summary.status_counts[static_cast<int>(VioStatus::kLost)];
  if (num_imu_only == 0 && num_lost == 0) return;
  VIOSFM_LOG(WARNING) << "vio: " << num_imu_only << " of " << summary.num_frames << " frames ("
                      << std::fixed << std::setprecision(0)
                      << 100.0 * static_cast<double>(num_imu_only) /
                             static_cast<double>(std::max<size_t>(1, summary.num_frames))
                      << " %) ran on the IMU alone, in " << summary.num_imu_only_stretches
                      << " stretch(es), the longest " << std::setprecision(2)
                      << summary.longest_imu_only_s << " s from "
                      << (summary.longest_imu_only_from_ns >= 0
                              ? FormatNsAsSeconds(summary.longest_imu_only_from_ns - first_image_ns,
                                                  2)
                              : std::string("-"))
                      << " s after the first image; " << num_lost << " frame(s) lost ("
                      << summary.num_resets << " reset(s)): their poses are the IMU's"
                      << std::defaultfloat;
}

// The run in a sentence: the start, the initialisation, the moving start's
// frames, the frames on the IMU alone, resets and IMU breaks.
std::string SummaryMessage(const VioSummary& summary, const SensorRig& rig,
                           timestamp_ns_t first_image_ns, timestamp_ns_t last_image_ns) {
  const size_t num_imu_only = summary.status_counts[static_cast<int>(VioStatus::kImuOnly)];
  std::ostringstream message;
  if (summary.static_init.is_static()) {
    message << "static start detected (" << std::fixed << std::setprecision(2)
            << NsToSeconds(summary.static_init.end_ns - summary.static_init.start_ns) << " s); ";
  } else {
    message << "no static start; ";
  }
  if (summary.visual_initialized) {
    message << "visual-inertial tracking from "
            << FormatNsAsSeconds(summary.first_tracking_ns - first_image_ns, 2)
            << " s after the first image";
  } else if (summary.static_init.is_static() &&
             rig.CamToImuTime(last_image_ns) <= summary.static_init.end_ns) {
    message << "not enough motion to initialise the visual part (the platform stays static)";
  } else {
    message << "the visual part was never initialised (not enough motion or landmarks)";
  }
  const size_t moving_start_posed = summary.num_moving_start_keyframes +
                                    summary.num_moving_start_pnp + summary.num_moving_start_imu;
  if (moving_start_posed > 0 || summary.num_frames_without_pose > 0) {
    message << "; the moving start's frames before it: " << moving_start_posed
            << " posed once initialised (" << summary.num_moving_start_keyframes << " keyframes, "
            << summary.num_moving_start_pnp << " by PnP on its landmarks, "
            << summary.num_moving_start_imu << " by the IMU), " << summary.num_frames_without_pose
            << " without a pose";
  }
  if (num_imu_only > 0) {
    message << "; " << num_imu_only << " frames on the IMU alone ("
            << summary.num_imu_only_stretches << " stretches, the longest " << std::fixed
            << std::setprecision(2) << summary.longest_imu_only_s << " s)";
  }
  if (summary.num_resets > 0) message << "; " << summary.num_resets << " resets after failures";
  if (!summary.imu_breaks.empty()) {
    message << "; " << summary.imu_breaks.size()
            << " IMU gap(s) longer than max_imu_gap_s broke the VIO into segments";
  }
  return message.str();
}

}  // namespace

VioResult VioRunner::Finish(const std::filesystem::path& root) {
  State& s = *state_;
  if (s.imu.empty())
    throw InputError(root.string(), 0, "VIO needs an IMU stream (mav0/imu0/data.csv)");
  if (s.images.empty()) throw InputError(root.string(), 0, "no images");
  Step(/*ended=*/true);
  if (s.vio == nullptr) {
    // Every frame in the startup: the offset from what they show.
    if (!s.time_offset_done) s.EstimateTheTimeOffset();
    s.StartWindow(/*ended=*/true);
  }
  VisualInertialOdometry& vio = *s.vio;
  VioResult& result = s.result;
  const std::vector<ImuSample>& imu = s.imu;
  const size_t num_frames = std::min(s.images.size(), s.num_frames_limit);
  // Samples the IMU dropped: said once; bridged in the preintegration up
  // to max_imu_gap_s, breaks beyond (said as they were met).
  const ImuGaps gaps = FindImuGaps(imu, SecondsToNs(s.options.max_imu_gap_s));
  if (gaps.num_bridged > 0) {
    VIOSFM_LOG(WARNING) << "vio: the IMU stream has " << gaps.num_bridged
                        << " gap(s) between samples longer than " << NsToSeconds(kMaxImuStepNs)
                        << " s and at most max_imu_gap_s " << s.options.max_imu_gap_s
                        << " s (the longest " << FormatNsAsSeconds(gaps.longest_bridged_ns, 3)
                        << " s): bridged by readings interpolated linearly";
  }
  vio.FinishMovingStart();
  s.PoseMovingStart();
  s.Settle(result.frames.size());
  s.progress->Finish();
  result.summary = vio.summary();
  VioSummary& summary = result.summary;
  summary.time_offset = s.time_offset;
  summary.num_frames_beyond_imu = s.num_beyond_imu;
  const timestamp_ns_t last_imu_ns = imu.back().timestamp_ns;
  if (s.num_beyond_imu > 0) {
    VIOSFM_LOG(WARNING) << "vio: the last " << s.num_beyond_imu
                        << " frame(s) lie after the last IMU sample ("
                        << FormatNsAsSeconds(last_imu_ns, 3)
                        << " s on the IMU clock, camera-IMU offset "
                        << NsToSeconds(s.rig.cam_time_offset_ns) * 1e3 << " ms): no pose for them";
  }
  summary.num_segments = s.segment + 1;
  summary.num_imu_gaps = gaps.num_gaps;
  summary.longest_imu_gap_s = NsToSeconds(gaps.longest_ns);
  summary.num_frames_without_pose = static_cast<size_t>(
      std::count_if(result.frames.begin(), result.frames.end(),
                    [](const VioFrameResult& frame) { return !frame.has_pose; }));
  CountImuOnlyStretches(result.frames, &summary);
  summary.cpu_seconds = ProcessCpuSeconds() - s.cpu_start;
  summary.wall_seconds = s.timer.ElapsedSeconds();

  const SequenceImage& first_image = s.images.front();
  WarnImuOnlyFrames(summary, first_image.timestamp_ns);
  summary.message = SummaryMessage(summary, s.rig, first_image.timestamp_ns,
                                   s.images[num_frames - 1].timestamp_ns);
  VIOSFM_LOG(INFO) << "vio: " << summary.num_frames << " frames (tracking "
                   << summary.status_counts[1] << ", initializing " << summary.status_counts[0]
                   << ", imu_only " << summary.status_counts[2] << ", lost "
                   << summary.status_counts[3] << "), " << summary.num_keyframes
                   << " keyframes, CPU " << std::fixed << std::setprecision(1)
                   << summary.cpu_seconds << " s" << LogDetails() << ": " << summary.message;
  if (s.on_progress) {
    s.on_progress(
        {&result.frames, result.frames.size(), &summary.time_offset, &summary.imu_noise, true});
  }
  return std::move(result);
}

VioResult RunVio(const Sequence& sequence, const VioOptions& options, FrameCache* frames,
                 const VioProgressCallback& on_progress) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid VIO options: " + error);
  }
  if (!sequence.has_imu()) {
    throw InputError(sequence.root.string(), 0, "VIO needs an IMU stream (mav0/imu0/data.csv)");
  }
  if (sequence.images.empty()) throw InputError(sequence.root.string(), 0, "no images");
  size_t num_frames = sequence.images.size();
  if (options.max_frames > 0) num_frames = std::min(num_frames, size_t(options.max_frames));
  VioRunner runner(sequence.rig, options, frames, sequence.images[num_frames - 1].timestamp_ns,
                   on_progress, num_frames);
  runner.AddImu(sequence.imu);
  for (size_t k = 0; k < num_frames; ++k) runner.AddImage(sequence.images[k]);
  return runner.Finish(sequence.root);
}

std::string FormatVioSummary(const VioSummary& summary) {
  std::ostringstream out;
  out << std::setprecision(10);
  out << "num_frames: " << summary.num_frames << "\n";
  for (int k = 0; k < 4; ++k) {
    out << "frames_" << VioStatusName(static_cast<VioStatus>(k)) << ": " << summary.status_counts[k]
        << "\n";
  }
  out << "num_keyframes: " << summary.num_keyframes << "\n";
  out << "num_frames_beyond_imu: " << summary.num_frames_beyond_imu << "\n";
  out << "imu_gaps: " << summary.num_imu_gaps << "  # intervals between IMU samples longer than "
      << NsToSeconds(kMaxImuStepNs) << " s; the longest " << summary.longest_imu_gap_s << " s\n";
  out << "imu_breaks: " << summary.imu_breaks.size()
      << "  # gaps longer than max_imu_gap_s: the VIO broke into a new segment\n";
  for (const VioImuBreak& imu_break : summary.imu_breaks) {
    out << "imu_break: {gap_start_ns: " << imu_break.gap_start_ns << ", gap_s: " << imu_break.gap_s
        << ", first_frame_ns: " << imu_break.frame_ns << "}\n";
  }
  out << "imu_only_stretches: " << summary.num_imu_only_stretches << "\n";
  out << "longest_imu_only_s: " << summary.longest_imu_only_s << "  # from camera stamp "
      << summary.longest_imu_only_from_ns << "\n";
  out << "num_frames_without_pose: " << summary.num_frames_without_pose
      << "  # before a moving start was initialised, not posed then\n";
  out << "moving_start_posed: [" << summary.num_moving_start_keyframes << ", "
      << summary.num_moving_start_pnp << ", " << summary.num_moving_start_imu
      << "]  # frames of a moving start posed once initialised: keyframes, PnP, IMU\n";
  out << "static_start: " << (summary.static_init.is_static() ? "true" : "false") << "\n";
  out << "static_init_status: " << StaticInitStatusName(summary.static_init.status) << "\n";
  if (summary.static_init.is_static()) {
    const StaticInitResult& init = summary.static_init;
    out << "static_interval_ns: [" << init.start_ns << ", " << init.end_ns << "]\n";
    out << "gravity_in_body: [" << init.gravity_in_body.x() << ", " << init.gravity_in_body.y()
        << ", " << init.gravity_in_body.z() << "]\n";
    out << "gyro_bias: [" << init.gyro_bias.x() << ", " << init.gyro_bias.y() << ", "
        << init.gyro_bias.z() << "]\n";
    out << "accel_bias: [" << init.accel_bias.x() << ", " << init.accel_bias.y() << ", "
        << init.accel_bias.z() << "]\n";
  }
  out << "time_offset_ns: " << summary.time_offset.offset_ns << "\n";
  out << "time_offset_estimated: " << (summary.time_offset.estimated ? "true" : "false") << "\n";
  out << "time_offset_sigma_s: " << summary.time_offset.sigma_s
      << "  # standard error the images and the gyro give (0: not computed)\n";
  out << "time_offset_determined: " << (summary.time_offset.sigma_bounded ? "true" : "false")
      << "  # false: undetermined within +-time_offset_sigma_s\n";
  out << "time_offset_message: \"" << summary.time_offset.message << "\"\n";
  out << "rolling_shutter_readout_s: " << summary.time_offset.readout_s
      << "  # 0: a global shutter\n";
  out << "rolling_shutter_readout_estimated: "
      << (summary.time_offset.readout_estimated ? "true" : "false") << "\n";
  const ImuNoise& used = summary.imu_noise.used;
  out << "imu_noise_used: [" << used.gyro_noise_density << ", " << used.gyro_random_walk << ", "
      << used.accel_noise_density << ", " << used.accel_random_walk
      << "]  # gyro density, gyro walk, accel density, accel walk\n";
  out << "imu_noise_message: \"" << summary.imu_noise.message << "\"\n";
  out << "visual_initialized: " << (summary.visual_initialized ? "true" : "false") << "\n";
  out << "first_tracking_ns: " << summary.first_tracking_ns << "\n";
  out << "num_resets: " << summary.num_resets << "\n";
  out << "num_segments: " << summary.num_segments << "\n";
  for (const VioReset& reset : summary.resets) {
    out << "reset: {timestamp_ns: " << reset.timestamp_ns
        << ", relocalized: " << (reset.relocalized ? "true" : "false")
        << ", map_point_observations: " << reset.num_map_points << ", message: \"" << reset.message
        << "\"}\n";
  }
  out << "cpu_seconds: " << summary.cpu_seconds << "\n";
  out << "wall_seconds: " << summary.wall_seconds << "\n";
  out << "message: \"" << summary.message << "\"\n";
  return out.str();
}

void WriteVioResult(const std::filesystem::path& folder, const VioResult& result) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) throw InputError(folder.string(), 0, "cannot create the output folder");
  WriteTumTrajectory(folder / "trajectory_body.tum", result.BodyTrajectory());
  WriteTumTrajectory(folder / "trajectory_cam.tum", result.CameraTrajectory());
  std::vector<VioStateRecord> records;
  records.reserve(result.frames.size());
  for (const VioFrameResult& frame : result.frames) {
    VioStateRecord record;
    record.timestamp_ns = frame.timestamp_ns;
    record.status = VioStatusName(frame.status);
    record.world_from_body = frame.state.world_from_body;
    record.velocity_in_world = frame.state.velocity_in_world;
    record.gyro_bias = frame.state.gyro_bias;
    record.accel_bias = frame.state.accel_bias;
    for (int i = 0; i < 6; ++i) {
      record.pose_sigma[i] = std::sqrt(std::max(0.0, frame.pose_covariance(i, i)));
    }
    record.segment = frame.segment;
    record.has_pose = frame.has_pose;
    records.push_back(std::move(record));
  }
  WriteVioStatesCsv(folder / "states.csv", records);
  WriteFileAtomically(folder / "vio_summary.txt",
                      [&](std::ostream& out) { out << FormatVioSummary(result.summary); });
}

}  // namespace viosfm
