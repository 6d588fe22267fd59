#include "viosfm/vio/sliding_window.h"

#include <ceres/loss_function.h>
#include <ceres/ordered_groups.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "viosfm/geometry/triangulation.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/vio/reprojection_factor.h"

namespace viosfm {

const char* VioStatusName(VioStatus status) {
  switch (status) {
    case VioStatus::kInitializing: return "initializing";
    case VioStatus::kTracking: return "tracking";
    case VioStatus::kImuOnly: return "imu_only";
    case VioStatus::kLost: return "lost";
  }
  return "unknown";
}

std::string SlidingWindowOptions::Validate() const {
  if (window_size < 2) return "window_size must be >= 2";
  if (!(keyframe_parallax_px > 0)) return "keyframe_parallax_px must be > 0";
  if (keyframe_min_shared_tracks < 0) return "keyframe_min_shared_tracks must be >= 0";
  if (!(max_keyframe_interval_s > 0)) return "max_keyframe_interval_s must be > 0";
  if (!(pixel_sigma_px > 0)) return "pixel_sigma_px must be > 0";
  if (!(cauchy_loss_scale > 0)) return "cauchy_loss_scale must be > 0";
  if (!(min_triangulation_angle_deg >= 0)) return "min_triangulation_angle_deg must be >= 0";
  if (!(fallback_triangulation_angle_deg >= 0) ||
      fallback_triangulation_angle_deg > min_triangulation_angle_deg) {
    return "fallback_triangulation_angle_deg must be in [0, min_triangulation_angle_deg]";
  }
  if (fallback_target_landmarks < 0) return "fallback_target_landmarks must be >= 0";
  if (!(min_depth_m > 0) || !(max_depth_m > min_depth_m)) {
    return "min_depth_m/max_depth_m must satisfy 0 < min < max";
  }
  if (!(max_reprojection_error_px > 0)) return "max_reprojection_error_px must be > 0";
  if (max_landmarks < 1) return "max_landmarks must be >= 1";
  if (max_num_iterations < 1) return "max_num_iterations must be >= 1";
  if (num_threads < 1) return "num_threads must be >= 1";
  if (min_tracked_landmarks < 0) return "min_tracked_landmarks must be >= 0";
  if (!(max_imu_only_s > 0)) return "max_imu_only_s must be > 0";
  if (!(max_speed_mps > 0)) return "max_speed_mps must be > 0";
  if (!(max_gyro_bias > 0)) return "max_gyro_bias must be > 0";
  if (!(max_accel_bias > 0)) return "max_accel_bias must be > 0";
  if (!(max_position_correction_m > 0)) return "max_position_correction_m must be > 0";
  if (!(imu_only_accel_uncertainty >= 0)) return "imu_only_accel_uncertainty must be >= 0";
  if (!(relocalization_position_sigma_m > 0) || !(relocalization_yaw_sigma_rad > 0)) {
    return "relocalization_position_sigma_m and relocalization_yaw_sigma_rad must be > 0";
  }
  if (!(relocalization_window_s > 0)) return "relocalization_window_s must be > 0";
  if (min_relocalization_points < 1) return "min_relocalization_points must be >= 1";
  if (const std::string error = preintegration.Validate(); !error.empty()) {
    return "preintegration." + error;
  }
  return "";
}

struct SlidingWindowEstimator::Frame {
  int id = 0;
  timestamp_ns_t timestamp_ns = 0;
  ImuStateParameters parameters;
  // From the previous frame of the window to this one; null for the first.
  std::unique_ptr<ImuPreintegration> preintegration;
  bool is_keyframe = false;
  std::unordered_map<uint64_t, Eigen::Vector2d> observations;  // normalised
};

struct SlidingWindowEstimator::Landmark {
  uint64_t track_id = 0;
  // The first window frame observing it; its observation is the anchor ray.
  Frame* anchor = nullptr;
  bool triangulated = false;
  double inverse_depth = 0.0;  // 1/m, in the anchor camera
  int num_observations = 0;    // in the window
};

// A solve's copies of the window's states and of the landmarks' inverse
// depths in one array, in window and track order, with the problem over them.
struct SlidingWindowEstimator::WindowProblem {
  static constexpr size_t kStateSize = 16;  // pose 7, speed and biases 9

  explicit WindowProblem(size_t num_values) : problem(ProblemOptions()), values(num_values) {}

  static ceres::Problem::Options ProblemOptions() {
    ceres::Problem::Options options;
    options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return options;
  }
  double* PoseOf(const Frame& frame) const { return copy_of.at(frame.parameters.pose.data()); }
  double* SpeedBiasOf(const Frame& frame) const {
    return copy_of.at(frame.parameters.speed_bias.data());
  }

  ceres::Problem problem;
  std::vector<double> values;
  std::unordered_map<const double*, double*> copy_of;  // a frame's block -> its copy
  std::unique_ptr<ceres::ParameterBlockOrdering> ordering =
      std::make_unique<ceres::ParameterBlockOrdering>();
  double* inverse_depths = nullptr;  // after the states in values
};

// A track's observations in the window: the cameras' projection matrices,
// the normalised points and the frames' indices, oldest first.
struct SlidingWindowEstimator::TrackRays {
  std::vector<Matrix3x4d> poses;
  std::vector<Eigen::Vector2d> points;
  std::vector<size_t> frame_indices;
};

// A track's point from its observations from some index on, its widest ray
// angle (that first observation against the others), and whether every
// observation lies in the depth range and within max_reprojection_error_px.
struct SlidingWindowEstimator::TrackTriangulation {
  Eigen::Vector3d point;
  double angle = 0.0;
  bool consistent = true;
};

// A landmark with less parallax than min_triangulation_angle_deg, with its
// angle and inverse depth.
struct SlidingWindowEstimator::WeakLandmark {
  Landmark* landmark;
  double angle;
  double inverse_depth;
};

namespace {

ImuState StateOf(const ImuStateParameters& parameters, timestamp_ns_t timestamp_ns) {
  return parameters.ToState(timestamp_ns);
}

bool IsFinite(const ImuState& state) {
  return state.world_from_body.rotation.coeffs().allFinite() &&
         state.world_from_body.translation.allFinite() && state.velocity_in_world.allFinite() &&
         state.gyro_bias.allFinite() && state.accel_bias.allFinite();
}

// J^T J of the window's states with the inverse depths (the last num_depths
// columns of the Jacobian) eliminated by their Schur complement.
Eigen::MatrixXd StatesInformation(const ceres::CRSMatrix& jacobian, int num_states,
                                  int num_depths) {
  Eigen::MatrixXd states = Eigen::MatrixXd::Zero(num_states, num_states);
  Eigen::MatrixXd states_depths = Eigen::MatrixXd::Zero(num_states, num_depths);
  Eigen::VectorXd depths = Eigen::VectorXd::Zero(num_depths);
  // Each pair of a row's entries once: a product adds to both of its
  // symmetric cells, as the full double loop would add it to each in turn.
  for (int row = 0; row < jacobian.num_rows; ++row) {
    for (int a = jacobian.rows[row]; a < jacobian.rows[row + 1]; ++a) {
      const int column_a = jacobian.cols[a];
      for (int b = a; b < jacobian.rows[row + 1]; ++b) {
        const int column_b = jacobian.cols[b];
        const double product = jacobian.values[a] * jacobian.values[b];
        if (column_a < num_states && column_b < num_states) {
          states(column_a, column_b) += product;
          if (column_a != column_b) states(column_b, column_a) += product;
        } else if (column_a < num_states) {
          states_depths(column_a, column_b - num_states) += product;
        } else if (column_b < num_states) {
          states_depths(column_b, column_a - num_states) += product;
        } else {
          VIOSFM_CHECK_EQ(column_a, column_b) << "a residual sees two inverse depths";
          depths(column_a - num_states) += product;
        }
      }
    }
  }
  // The depths' Schur complement, states -= sum over l of s_l s_l^T / d_l,
  // as one matrix product of the scaled columns (one rank-1 update per
  // landmark took three quarters of this function's time). A depth no
  // residual sees (a zero column) constrains nothing.
  int num_seen = 0;
  for (int l = 0; l < num_depths; ++l) {
    if (!(depths(l) > 0.0)) continue;
    states_depths.col(num_seen++) = states_depths.col(l) / std::sqrt(depths(l));
  }
  const auto scaled = states_depths.leftCols(num_seen);
  states.noalias() -= scaled * scaled.transpose();
  return states;
}

// The covariance of the newest pose (the last state, rotation first) from
// the states' information matrix; zero when it is rank deficient.
Eigen::Matrix<double, 6, 6> NewestPoseCovarianceOfStates(const Eigen::MatrixXd& states) {
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  const int num_states = static_cast<int>(states.rows());
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(states);
  const Eigen::VectorXd pivots = ldlt.vectorD().cwiseAbs();
  // Rank deficient (no covariance), as ceres::Covariance's default
  // reciprocal condition number 1e-14 judges.
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || num_states == 0 ||
      !(pivots.minCoeff() > 1e-14 * pivots.maxCoeff())) {
    return covariance;
  }
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(num_states, 6);
  const int newest = num_states - 15;
  unit.block<6, 6>(newest, 0).setIdentity();
  const Eigen::Matrix<double, 6, 6> tangent = ldlt.solve(unit).block<6, 6>(newest, 0);
  // The quaternion part of the tangent is half the rotation vector.
  Eigen::Matrix<double, 6, 6> scale = Eigen::Matrix<double, 6, 6>::Identity();
  scale.topLeftCorner<3, 3>() *= 2.0;
  covariance = scale * (0.5 * (tangent + tangent.transpose())) * scale;
  return covariance;
}

}  // namespace

SlidingWindowEstimator::SlidingWindowEstimator(const Rigid3d& body_from_cam, const ImuNoise& noise,
                                               double focal_length_px,
                                               const SlidingWindowOptions& options)
    : body_from_cam_(body_from_cam),
      noise_(noise),
      focal_length_px_(focal_length_px),
      options_(options),
      pose_manifold_(CreatePoseManifold()) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid sliding window options: " + error);
  }
  VIOSFM_CHECK_GT(focal_length_px, 0.0);
}

SlidingWindowEstimator::~SlidingWindowEstimator() = default;

void SlidingWindowEstimator::ClearWindow() {
  frames_.clear();
  landmarks_.clear();
  prior_.reset();
  has_tracked_ = false;
  imu_only_since_ns_ = -1;
}

void SlidingWindowEstimator::Clear() {
  map_points_.clear();
  relocalization_points_.clear();
  relocalization_seen_.clear();
  ClearWindow();
}

void SlidingWindowEstimator::Reset() {
  if (!map_points_.empty()) relocalization_points_ = std::move(map_points_);
  map_points_.clear();
  ClearWindow();
}

ceres::LossFunction* SlidingWindowEstimator::ImuLoss() const {
  if (!(options_.imu_loss_scale > 0)) return nullptr;
  return new ceres::HuberLoss(options_.imu_loss_scale);
}

Rigid3d SlidingWindowEstimator::WorldFromCam(const Frame& frame) const {
  return StateOf(frame.parameters, frame.timestamp_ns).world_from_body * body_from_cam_;
}

ImuState SlidingWindowEstimator::NewestState() const {
  VIOSFM_CHECK(!frames_.empty());
  return StateOf(frames_.back()->parameters, frames_.back()->timestamp_ns);
}

std::vector<ImuState> SlidingWindowEstimator::States() const {
  std::vector<ImuState> states;
  states.reserve(frames_.size());
  for (const std::unique_ptr<Frame>& frame : frames_) {
    states.push_back(StateOf(frame->parameters, frame->timestamp_ns));
  }
  return states;
}

void SlidingWindowEstimator::Initialize(const ImuState& state, const InitialStateSigmas& sigmas_in,
                                        const FrameFeatures& features) {
  ClearWindow();
  InitialStateSigmas sigmas = sigmas_in;
  restart_ns_ = state.timestamp_ns;
  relocalization_observations_ = 0;
  relocalization_seen_.clear();
  relocalized_ = false;
  if (!relocalization_points_.empty()) {
    // The map of the previous window, not this prior, places the restart.
    sigmas.position_m = std::max(sigmas.position_m, options_.relocalization_position_sigma_m);
    sigmas.yaw_rad = std::max(sigmas.yaw_rad, options_.relocalization_yaw_sigma_rad);
  }
  auto frame = std::make_unique<Frame>();
  frame->id = next_frame_id_++;
  frame->timestamp_ns = state.timestamp_ns;
  frame->parameters = ImuStateParameters::FromState(state);
  frame->is_keyframe = true;
  for (const FeatureObservation& observation : features.observations) {
    frame->observations[observation.track_id] = observation.normalized;
    Landmark& landmark = landmarks_[observation.track_id];
    landmark.track_id = observation.track_id;
    landmark.anchor = frame.get();
    landmark.num_observations = 1;
  }
  // Prior in the tangent space of (pose, speed_bias): the pose tangent of
  // Ceres' quaternion manifold is half the world-frame rotation vector
  // (left perturbation), then the translation.
  Eigen::VectorXd diagonal(15);
  diagonal << 2.0 / sigmas.roll_pitch_rad, 2.0 / sigmas.roll_pitch_rad, 2.0 / sigmas.yaw_rad,
      Eigen::Vector3d::Constant(1.0 / sigmas.position_m),
      Eigen::Vector3d::Constant(1.0 / sigmas.velocity_mps),
      Eigen::Vector3d::Constant(1.0 / sigmas.gyro_bias),
      Eigen::Vector3d::Constant(1.0 / sigmas.accel_bias);
  Eigen::MatrixXd sqrt_information = diagonal.asDiagonal();
  prior_ = MakeGaussianPrior({frame->parameters.pose.data(), frame->parameters.speed_bias.data()},
                             {7, 9}, {pose_manifold_, nullptr}, sqrt_information);
  frames_.push_back(std::move(frame));
}

void SlidingWindowEstimator::InitializeWithKeyframes(
    const std::vector<FrameFeatures>& keyframes, const std::vector<ImuState>& states,
    const std::unordered_map<uint64_t, Eigen::Vector3d>& points_in_world,
    const std::vector<ImuSample>& imu, const InitialStateSigmas& sigmas) {
  VIOSFM_CHECK(!keyframes.empty() && keyframes.size() == states.size());
  Initialize(states.front(), sigmas, keyframes.front());
  for (size_t k = 1; k < keyframes.size(); ++k) {
    const ImuState previous_state = NewestState();
    auto frame = std::make_unique<Frame>();
    frame->id = next_frame_id_++;
    frame->timestamp_ns = states[k].timestamp_ns;
    frame->preintegration = std::make_unique<ImuPreintegration>(
        previous_state.gyro_bias, previous_state.accel_bias, noise_, options_.preintegration);
    if (!frame->preintegration->IntegrateRange(imu, previous_state.timestamp_ns,
                                               frame->timestamp_ns)) {
      // No IMU between two keyframes: keep what is there.
      break;
    }
    frame->parameters = ImuStateParameters::FromState(states[k]);
    frame->is_keyframe = true;
    for (const FeatureObservation& observation : keyframes[k].observations) {
      frame->observations[observation.track_id] = observation.normalized;
    }
    AppendFrame(std::move(frame));
  }
  // The restart is the newest keyframe, not the first: the re-localisation
  // lasts relocalization_window_s from now, however long the keyframes span.
  restart_ns_ = frames_.back()->timestamp_ns;
  for (auto& [track_id, landmark] : landmarks_) {
    const auto it = points_in_world.find(track_id);
    if (it == points_in_world.end()) continue;
    const double inverse_depth = InverseDepthOfPoint(
        StateOf(landmark.anchor->parameters, landmark.anchor->timestamp_ns).world_from_body,
        body_from_cam_, it->second);
    if (inverse_depth > 1.0 / options_.max_depth_m && inverse_depth < 1.0 / options_.min_depth_m) {
      landmark.inverse_depth = inverse_depth;
      landmark.triangulated = true;
    }
  }
}

bool SlidingWindowEstimator::IsKeyframe(const Frame& frame, const FrameFeatures& features) const {
  const Frame* last_keyframe = nullptr;
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if ((*it)->is_keyframe && it->get() != &frame) {
      last_keyframe = it->get();
      break;
    }
  }
  if (last_keyframe == nullptr) return true;
  if (NsToSeconds(frame.timestamp_ns - last_keyframe->timestamp_ns) >=
      options_.max_keyframe_interval_s) {
    return true;
  }
  if (features.is_keyframe) return true;
  int shared = 0;
  double parallax_sum = 0.0;
  for (const auto& [track_id, normalized] : frame.observations) {
    const auto it = last_keyframe->observations.find(track_id);
    if (it == last_keyframe->observations.end()) continue;
    ++shared;
    parallax_sum += (normalized - it->second).norm() * kReferenceFocalLengthPx;
  }
  if (shared < options_.keyframe_min_shared_tracks) return true;
  return parallax_sum / shared >= options_.keyframe_parallax_px;
}

void SlidingWindowEstimator::AppendFrame(std::unique_ptr<Frame> frame) {
  Frame* frame_pointer = frame.get();
  frames_.push_back(std::move(frame));
  for (const auto& [track_id, normalized] : frame_pointer->observations) {
    Landmark& landmark = landmarks_[track_id];
    if (landmark.anchor == nullptr) {
      landmark.track_id = track_id;
      landmark.anchor = frame_pointer;
    }
    ++landmark.num_observations;
  }
}

void SlidingWindowEstimator::RemoveFrame(size_t index) {
  VIOSFM_CHECK_LT(index, frames_.size());
  Frame* frame = frames_[index].get();
  for (const auto& [track_id, normalized] : frame->observations) {
    auto it = landmarks_.find(track_id);
    if (it == landmarks_.end()) continue;
    Landmark& landmark = it->second;
    --landmark.num_observations;
    if (landmark.anchor != frame) continue;
    // Re-anchor in the next frame that observes it.
    Frame* next_anchor = nullptr;
    for (size_t k = 0; k < frames_.size(); ++k) {
      if (k == index) continue;
      if (frames_[k]->observations.count(track_id) > 0) {
        next_anchor = frames_[k].get();
        break;
      }
    }
    if (next_anchor == nullptr) {
      landmarks_.erase(it);
      continue;
    }
    if (landmark.triangulated) {
      const Eigen::Vector3d point =
          InverseDepthPointInWorld(StateOf(frame->parameters, frame->timestamp_ns).world_from_body,
                                   body_from_cam_, normalized, landmark.inverse_depth);
      const double inverse_depth = InverseDepthOfPoint(
          StateOf(next_anchor->parameters, next_anchor->timestamp_ns).world_from_body,
          body_from_cam_, point);
      if (inverse_depth > 1.0 / options_.max_depth_m &&
          inverse_depth < 1.0 / options_.min_depth_m) {
        landmark.inverse_depth = inverse_depth;
      } else {
        landmark.triangulated = false;
      }
    }
    landmark.anchor = next_anchor;
  }
  frames_.erase(frames_.begin() + static_cast<std::ptrdiff_t>(index));
}

void SlidingWindowEstimator::TriangulateLandmarks() {
  const double min_angle = options_.min_triangulation_angle_deg * M_PI / 180.0;
  const double fallback_angle = options_.fallback_triangulation_angle_deg * M_PI / 180.0;
  std::vector<Matrix3x4d> cams_from_world;
  std::vector<Eigen::Vector3d> centers;
  cams_from_world.reserve(frames_.size());
  for (const auto& frame : frames_) {
    const Rigid3d world_from_cam = WorldFromCam(*frame);
    cams_from_world.push_back(world_from_cam.Inverse().ToMatrix());
    centers.push_back(world_from_cam.translation);
  }
  const Frame* newest = frames_.back().get();
  int newest_seen = 0;  // triangulated landmarks the newest frame observes
  for (const auto& [track_id, landmark] : landmarks_) {
    if (landmark.triangulated && newest->observations.count(track_id) > 0) ++newest_seen;
  }
  // Landmarks with less parallax than min_angle but at least fallback_angle.
  std::vector<WeakLandmark> weak;
  TrackRays rays;
  for (auto& [track_id, landmark] : landmarks_) {
    if (landmark.triangulated || landmark.num_observations < 2) continue;
    CollectRays(track_id, cams_from_world, &rays);
    if (rays.points.size() < 2) continue;
    std::optional<TrackTriangulation> triangulated = TriangulateRays(rays, centers, 0);
    if (!triangulated || triangulated->angle < std::min(min_angle, fallback_angle)) continue;
    if (!triangulated->consistent) {
      triangulated = DropDisagreeingObservations(landmark, centers, &rays);
      if (!triangulated || triangulated->angle < std::min(min_angle, fallback_angle)) continue;
    }
    const std::optional<Eigen::Vector3d> point = triangulated->point;
    const double best_angle = triangulated->angle;
    const Frame& anchor = *frames_[rays.frame_indices.front()];
    VIOSFM_CHECK(&anchor == landmark.anchor);
    const double inverse_depth = InverseDepthOfPoint(
        StateOf(anchor.parameters, anchor.timestamp_ns).world_from_body, body_from_cam_, *point);
    if (inverse_depth <= 0.0) continue;
    if (best_angle >= min_angle) {
      landmark.inverse_depth = inverse_depth;
      landmark.triangulated = true;
      if (newest->observations.count(track_id) > 0) ++newest_seen;
    } else {
      weak.push_back({&landmark, best_angle, inverse_depth});
    }
  }
  // Weak texture: while the newest frame sees fewer than
  // fallback_target_landmarks triangulated landmarks, its lower-parallax
  // tracks are triangulated too, widest angle first.
  if (!has_tracked_ || newest_seen >= options_.fallback_target_landmarks) return;
  AcceptWeakLandmarks(*newest, newest_seen, &weak);
}

void SlidingWindowEstimator::CollectRays(uint64_t track_id,
                                         const std::vector<Matrix3x4d>& cams_from_world,
                                         TrackRays* rays) const {
  rays->poses.clear();
  rays->points.clear();
  rays->frame_indices.clear();
  for (size_t k = 0; k < frames_.size(); ++k) {
    const auto it = frames_[k]->observations.find(track_id);
    if (it == frames_[k]->observations.end()) continue;
    rays->poses.push_back(cams_from_world[k]);
    rays->points.push_back(it->second);
    rays->frame_indices.push_back(k);
  }
}

std::optional<SlidingWindowEstimator::TrackTriangulation> SlidingWindowEstimator::TriangulateRays(
    const TrackRays& rays, const std::vector<Eigen::Vector3d>& centers, size_t first) const {
  const std::vector<Matrix3x4d>& poses = rays.poses;
  const std::vector<Eigen::Vector2d>& points = rays.points;
  const std::vector<size_t>& frame_indices = rays.frame_indices;
  const std::vector<Matrix3x4d> used_poses(poses.begin() + first, poses.end());
  const std::vector<Eigen::Vector2d> used_points(points.begin() + first, points.end());
  const std::optional<Eigen::Vector3d> point = TriangulateDlt(used_poses, used_points);
  if (!point || !point->allFinite()) return std::nullopt;
  TrackTriangulation result{*point};
  for (size_t k = first + 1; k < frame_indices.size(); ++k) {
    result.angle = std::max(result.angle, TriangulationAngle(centers[frame_indices[first]],
                                                             centers[frame_indices[k]], *point));
  }
  for (size_t k = first; k < poses.size() && result.consistent; ++k) {
    const Eigen::Vector3d in_cam = poses[k] * point->homogeneous();
    if (in_cam.z() < options_.min_depth_m || in_cam.z() > options_.max_depth_m) {
      result.consistent = false;
    }
    const double error_px = (in_cam.hnormalized() - points[k]).norm() * focal_length_px_;
    if (error_px > options_.max_reprojection_error_px) result.consistent = false;
  }
  return result;
}

std::optional<SlidingWindowEstimator::TrackTriangulation>
SlidingWindowEstimator::DropDisagreeingObservations(Landmark& landmark,
                                                    const std::vector<Eigen::Vector3d>& centers,
                                                    TrackRays* rays) {
  // Some observation disagrees (the track drifted, or a frame's corners
  // were off): the track goes on from the longest run of its newest
  // observations that agree, its older ones dropped, so that a stretch
  // of bad frames in the window does not hold it back until they leave.
  std::optional<TrackTriangulation> triangulated;
  size_t first = 1;
  for (; first + 1 < rays->points.size(); ++first) {
    triangulated = TriangulateRays(*rays, centers, first);
    if (triangulated && triangulated->consistent) break;
  }
  if (first + 1 >= rays->points.size()) return std::nullopt;
  for (size_t k = 0; k < first; ++k) {
    frames_[rays->frame_indices[k]]->observations.erase(landmark.track_id);
    --landmark.num_observations;
  }
  landmark.anchor = frames_[rays->frame_indices[first]].get();
  const auto dropped = static_cast<std::ptrdiff_t>(first);
  rays->poses.erase(rays->poses.begin(), rays->poses.begin() + dropped);
  rays->points.erase(rays->points.begin(), rays->points.begin() + dropped);
  rays->frame_indices.erase(rays->frame_indices.begin(), rays->frame_indices.begin() + dropped);
  return triangulated;
}

void SlidingWindowEstimator::AcceptWeakLandmarks(const Frame& newest, int newest_seen,
                                                 std::vector<WeakLandmark>* weak) {
  std::stable_sort(weak->begin(), weak->end(), [&](const WeakLandmark& a, const WeakLandmark& b) {
    const bool a_newest = newest.observations.count(a.landmark->track_id) > 0;
    const bool b_newest = newest.observations.count(b.landmark->track_id) > 0;
    if (a_newest != b_newest) return a_newest;
    if (a.angle != b.angle) return a.angle > b.angle;
    return a.landmark->track_id < b.landmark->track_id;
  });
  for (const WeakLandmark& candidate : *weak) {
    if (newest_seen >= options_.fallback_target_landmarks) break;
    if (newest.observations.count(candidate.landmark->track_id) == 0) break;
    candidate.landmark->inverse_depth = candidate.inverse_depth;
    candidate.landmark->triangulated = true;
    ++newest_seen;
  }
}

std::vector<SlidingWindowEstimator::Landmark*> SlidingWindowEstimator::SelectLandmarks() {
  std::vector<Landmark*> selected;
  for (auto& [track_id, landmark] : landmarks_) {
    if (landmark.triangulated && landmark.num_observations >= 2 &&
        relocalization_points_.count(landmark.track_id) == 0) {
      selected.push_back(&landmark);
    }
  }
  if (static_cast<int>(selected.size()) > options_.max_landmarks) {
    std::stable_sort(selected.begin(), selected.end(), [](const Landmark* a, const Landmark* b) {
      if (a->num_observations != b->num_observations) {
        return a->num_observations > b->num_observations;
      }
      return a->track_id < b->track_id;
    });
    selected.resize(options_.max_landmarks);
  }
  // A deterministic order for the problem (the map's order is not).
  std::sort(selected.begin(), selected.end(),
            [](const Landmark* a, const Landmark* b) { return a->track_id < b->track_id; });
  return selected;
}

Eigen::Matrix<double, 6, 6> SlidingWindowEstimator::Optimize(
    const std::vector<Landmark*>& landmarks) {
  // Ceres orders the parameter blocks of an ordering group by their
  // addresses, which depend on the allocation history of the whole process:
  // the same window could be solved in another order, and so give other last
  // bits, depending on what ran before. So the solve works on copies of the window's states and the
  // landmarks' inverse depths in one array, in window and track order (the
  // order of their addresses), each state block in an ordering group of its
  // own after the eliminated inverse depths; the values are copied back after.
  WindowProblem window(frames_.size() * WindowProblem::kStateSize + landmarks.size());
  AddStateBlocks(window);
  AddPriorFactor(window);
  AddImuFactors(window);
  AddLandmarkFactors(window, landmarks);
  AddRelocalizationFactors(window);
  const bool usable = SolveWindow(window, landmarks.empty());
  CopySolutionBack(window, landmarks);
  if (!options_.compute_covariance || !usable) return Eigen::Matrix<double, 6, 6>::Zero();
  return NewestPoseCovariance(window, static_cast<int>(landmarks.size()));
}

void SlidingWindowEstimator::AddStateBlocks(WindowProblem& window) const {
  ceres::Manifold* pose_manifold = const_cast<ceres::Manifold*>(pose_manifold_.get());
  int group = 1;
  for (size_t k = 0; k < frames_.size(); ++k) {
    ImuStateParameters& parameters = frames_[k]->parameters;
    double* pose = window.values.data() + k * WindowProblem::kStateSize;
    double* speed_bias = pose + parameters.pose.size();
    std::copy(parameters.pose.begin(), parameters.pose.end(), pose);
    std::copy(parameters.speed_bias.begin(), parameters.speed_bias.end(), speed_bias);
    window.copy_of[parameters.pose.data()] = pose;
    window.copy_of[parameters.speed_bias.data()] = speed_bias;
    window.problem.AddParameterBlock(pose, 7, pose_manifold);
    window.problem.AddParameterBlock(speed_bias, 9);
    window.ordering->AddElementToGroup(pose, group++);
    window.ordering->AddElementToGroup(speed_bias, group++);
  }
  window.inverse_depths = window.values.data() + frames_.size() * WindowProblem::kStateSize;
}

void SlidingWindowEstimator::AddPriorFactor(WindowProblem& window) const {
  if (prior_ == nullptr) return;
  std::vector<double*> blocks = prior_->ParameterBlocks();
  for (double*& block : blocks) {
    const auto it = window.copy_of.find(block);
    VIOSFM_CHECK(it != window.copy_of.end())
        << "the marginalisation prior acts on a block outside the window";
    block = it->second;
  }
  window.problem.AddResidualBlock(new LinearPriorFactor(prior_), nullptr, blocks);
}

void SlidingWindowEstimator::AddImuFactors(WindowProblem& window) {
  for (size_t k = 1; k < frames_.size(); ++k) {
    Frame& previous = *frames_[k - 1];
    Frame& frame = *frames_[k];
    const ImuState previous_state = StateOf(previous.parameters, previous.timestamp_ns);
    frame.preintegration->RepropagateIfNeeded(previous_state.gyro_bias, previous_state.accel_bias);
    window.problem.AddResidualBlock(ImuFactor::Create(*frame.preintegration), ImuLoss(),
                                    window.PoseOf(previous), window.SpeedBiasOf(previous),
                                    window.PoseOf(frame), window.SpeedBiasOf(frame));
  }
}

void SlidingWindowEstimator::AddLandmarkFactors(WindowProblem& window,
                                                const std::vector<Landmark*>& landmarks) const {
  for (size_t i = 0; i < landmarks.size(); ++i) {
    window.inverse_depths[i] = landmarks[i]->inverse_depth;
  }
  const double sqrt_information = focal_length_px_ / options_.pixel_sigma_px;
  for (size_t i = 0; i < landmarks.size(); ++i) {
    Landmark* landmark = landmarks[i];
    double* inverse_depth = &window.inverse_depths[i];
    const Eigen::Vector2d& anchor_observation =
        landmark->anchor->observations.at(landmark->track_id);
    window.problem.AddParameterBlock(inverse_depth, 1);
    window.ordering->AddElementToGroup(inverse_depth, 0);
    for (auto& frame : frames_) {
      if (frame.get() == landmark->anchor) continue;
      const auto it = frame->observations.find(landmark->track_id);
      if (it == frame->observations.end()) continue;
      window.problem.AddResidualBlock(
          new InverseDepthReprojectionCost(anchor_observation, it->second, body_from_cam_,
                                           sqrt_information),
          new ceres::CauchyLoss(options_.cauchy_loss_scale), window.PoseOf(*landmark->anchor),
          window.PoseOf(*frame), inverse_depth);
    }
  }
}

void SlidingWindowEstimator::AddRelocalizationFactors(WindowProblem& window) const {
  // Re-localisation: the frames' observations of the map kept at the reset.
  const double sqrt_information = focal_length_px_ / options_.pixel_sigma_px;
  for (auto& frame : frames_) {
    for (const auto& [track_id, normalized] : frame->observations) {
      const auto it = relocalization_points_.find(track_id);
      if (it == relocalization_points_.end()) continue;
      window.problem.AddResidualBlock(MapPointReprojectionFactor::Create(
                                          it->second, normalized, body_from_cam_, sqrt_information),
                                      new ceres::CauchyLoss(options_.cauchy_loss_scale),
                                      window.PoseOf(*frame));
    }
  }
}

bool SlidingWindowEstimator::SolveWindow(WindowProblem& window, bool no_landmarks) const {
  ceres::Solver::Options solver_options;
  if (no_landmarks) {
    // Only states (IMU and prior factors): no landmark block to eliminate.
    window.ordering.reset();
    solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  } else {
    // Inverse depths eliminated first (Schur complement onto the states).
    solver_options.linear_solver_type = ceres::DENSE_SCHUR;
    solver_options.linear_solver_ordering = std::move(window.ordering);
  }
  solver_options.trust_region_strategy_type = ceres::DOGLEG;
  solver_options.max_num_iterations = options_.max_num_iterations;
  solver_options.num_threads = options_.num_threads;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &window.problem, &summary);
  if (!summary.IsSolutionUsable()) {
    VIOSFM_LOG(DEBUG) << "sliding window: solver failed: " << summary.message;
  }
  return summary.IsSolutionUsable();
}

void SlidingWindowEstimator::CopySolutionBack(const WindowProblem& window,
                                              const std::vector<Landmark*>& landmarks) {
  for (auto& frame : frames_) {
    ImuStateParameters& parameters = frame->parameters;
    std::copy_n(window.PoseOf(*frame), parameters.pose.size(), parameters.pose.begin());
    std::copy_n(window.SpeedBiasOf(*frame), parameters.speed_bias.size(),
                parameters.speed_bias.begin());
  }
  for (size_t i = 0; i < landmarks.size(); ++i) {
    landmarks[i]->inverse_depth = window.inverse_depths[i];
  }
}

Eigen::Matrix<double, 6, 6> SlidingWindowEstimator::NewestPoseCovariance(WindowProblem& window,
                                                                         int num_depths) const {
  // The newest pose's marginal covariance: (J^T J)^-1 at the solution, with
  // the loss applied as in the solve, in the tangent spaces. The inverse
  // depths are eliminated in closed form (each residual sees at most one,
  // so their block of J^T J is diagonal) and the states' Schur complement is
  // inverted densely, in a fixed order: the same bits every run
  // (ceres::Covariance's sparse QR through SuiteSparse gave other last bits
  // from run to run on the same window).
  ceres::Problem::EvaluateOptions evaluate;
  for (auto& frame : frames_) {
    evaluate.parameter_blocks.push_back(window.PoseOf(*frame));
    evaluate.parameter_blocks.push_back(window.SpeedBiasOf(*frame));
  }
  for (int i = 0; i < num_depths; ++i) {
    evaluate.parameter_blocks.push_back(&window.inverse_depths[i]);
  }
  evaluate.num_threads = 1;
  ceres::CRSMatrix jacobian;
  if (!window.problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian)) {
    return Eigen::Matrix<double, 6, 6>::Zero();
  }
  const int num_states = static_cast<int>(frames_.size()) * 15;  // tangent: pose 6, speed_bias 9
  VIOSFM_CHECK_EQ(jacobian.num_cols, num_states + num_depths);
  return NewestPoseCovarianceOfStates(StatesInformation(jacobian, num_states, num_depths));
}

void SlidingWindowEstimator::RemoveOutliers(const std::vector<Landmark*>& landmarks) {
  for (Landmark* landmark : landmarks) {
    bool bad = !(landmark->inverse_depth > 1.0 / options_.max_depth_m) ||
               !(landmark->inverse_depth < 1.0 / options_.min_depth_m);
    if (!bad) {
      const Eigen::Vector3d point = InverseDepthPointInWorld(
          StateOf(landmark->anchor->parameters, 0).world_from_body, body_from_cam_,
          landmark->anchor->observations.at(landmark->track_id), landmark->inverse_depth);
      for (auto& frame : frames_) {
        const auto it = frame->observations.find(landmark->track_id);
        if (it == frame->observations.end()) continue;
        const Eigen::Vector3d in_cam = WorldFromCam(*frame).Inverse() * point;
        if (in_cam.z() <= 0.0 || (in_cam.hnormalized() - it->second).norm() * focal_length_px_ >
                                     options_.max_reprojection_error_px) {
          bad = true;
          break;
        }
      }
    }
    if (bad) {
      // The landmark and the track's observations in the window are
      // dropped; the track's next observation starts a new landmark. A
      // track that drifted is rejected again once it has parallax; a good
      // one rejected under a wrong state (a wrong time offset, a stretch on
      // the IMU alone) comes back instead of holding one of the tracker's
      // corners without ever being used.
      const uint64_t track_id = landmark->track_id;
      for (auto& frame : frames_) frame->observations.erase(track_id);
      landmarks_.erase(track_id);
    }
  }
}

void SlidingWindowEstimator::MarginalizeOldest(const std::vector<Landmark*>& landmarks) {
  VIOSFM_CHECK_GE(frames_.size(), 2u);
  Frame* oldest = frames_[0].get();
  Frame* second = frames_[1].get();
  Marginalizer marginalizer;
  for (auto& frame : frames_) {
    marginalizer.AddParameterBlock(frame->parameters.pose.data(), 7, pose_manifold_);
    marginalizer.AddParameterBlock(frame->parameters.speed_bias.data(), 9);
  }
  if (prior_ != nullptr) {
    bool touches_oldest = false;
    for (const LinearPrior::Block& block : prior_->blocks) {
      if (block.values == oldest->parameters.pose.data() ||
          block.values == oldest->parameters.speed_bias.data()) {
        touches_oldest = true;
      }
    }
    if (touches_oldest) {
      marginalizer.AddResidualBlock(new LinearPriorFactor(prior_), nullptr,
                                    prior_->ParameterBlocks());
    }
  }
  const ImuState oldest_state = StateOf(oldest->parameters, oldest->timestamp_ns);
  second->preintegration->RepropagateIfNeeded(oldest_state.gyro_bias, oldest_state.accel_bias);
  marginalizer.AddResidualBlock(
      ImuFactor::Create(*second->preintegration), ImuLoss(),
      {oldest->parameters.pose.data(), oldest->parameters.speed_bias.data(),
       second->parameters.pose.data(), second->parameters.speed_bias.data()});
  const double sqrt_information = focal_length_px_ / options_.pixel_sigma_px;
  for (Landmark* landmark : landmarks) {
    if (landmark->anchor != oldest) continue;
    const Eigen::Vector2d& anchor_observation = oldest->observations.at(landmark->track_id);
    marginalizer.AddParameterBlock(&landmark->inverse_depth, 1);
    marginalizer.MarkMarginalized(&landmark->inverse_depth);
    for (auto& frame : frames_) {
      if (frame.get() == oldest) continue;
      const auto it = frame->observations.find(landmark->track_id);
      if (it == frame->observations.end()) continue;
      marginalizer.AddResidualBlock(
          new InverseDepthReprojectionCost(anchor_observation, it->second, body_from_cam_,
                                           sqrt_information),
          new ceres::CauchyLoss(options_.cauchy_loss_scale),
          {oldest->parameters.pose.data(), frame->parameters.pose.data(),
           &landmark->inverse_depth});
    }
  }
  marginalizer.MarkMarginalized(oldest->parameters.pose.data());
  marginalizer.MarkMarginalized(oldest->parameters.speed_bias.data());
  prior_ = marginalizer.Marginalize();
  RemoveFrame(0);
}

std::string SlidingWindowEstimator::CheckPlausible(const ImuState& predicted) const {
  for (const auto& frame : frames_) {
    for (double value : frame->parameters.pose) {
      if (!std::isfinite(value)) return "non-finite pose";
    }
    for (double value : frame->parameters.speed_bias) {
      if (!std::isfinite(value)) return "non-finite velocity or bias";
    }
  }
  const ImuState newest = NewestState();
  // After T seconds carried by the IMU alone, its prediction may be off by
  // the accel uncertainty times T^2 / 2.
  double allowed_correction_m = options_.max_position_correction_m;
  if (imu_only_since_ns_ >= 0) {
    const double t = NsToSeconds(newest.timestamp_ns - imu_only_since_ns_);
    allowed_correction_m += 0.5 * options_.imu_only_accel_uncertainty * t * t;
  }
  std::ostringstream message;
  if (newest.velocity_in_world.norm() > options_.max_speed_mps) {
    message << "implausible speed " << newest.velocity_in_world.norm() << " m/s";
  } else if (newest.gyro_bias.norm() > options_.max_gyro_bias) {
    message << "implausible gyro bias " << newest.gyro_bias.norm() << " rad/s";
  } else if (newest.accel_bias.norm() > options_.max_accel_bias) {
    message << "implausible accel bias " << newest.accel_bias.norm() << " m/s^2";
  } else if ((newest.world_from_body.translation - predicted.world_from_body.translation).norm() >
             allowed_correction_m) {
    message << "position jumped "
            << (newest.world_from_body.translation - predicted.world_from_body.translation).norm()
            << " m from the IMU prediction (" << allowed_correction_m << " m allowed)";
  }
  return message.str();
}

int SlidingWindowEstimator::UpdateRelocalization(const Frame& newest) {
  if (relocalization_points_.empty()) return 0;
  // Map points the newest frame sees within the reprojection threshold;
  // those farther off are dropped (a track that jumped, or a wrong point).
  const Rigid3d cam_from_world = WorldFromCam(newest).Inverse();
  int seen = 0;
  for (const auto& [track_id, normalized] : newest.observations) {
    const auto it = relocalization_points_.find(track_id);
    if (it == relocalization_points_.end()) continue;
    const Eigen::Vector3d in_cam = cam_from_world * it->second;
    if (in_cam.z() > 0.0 && (in_cam.hnormalized() - normalized).norm() * focal_length_px_ <=
                                options_.max_reprojection_error_px) {
      ++seen;
      relocalization_seen_.insert(track_id);
    } else {
      relocalization_points_.erase(it);
    }
  }
  relocalization_observations_ += seen;
  if (NsToSeconds(newest.timestamp_ns - restart_ns_) >= options_.relocalization_window_s) {
    relocalized_ =
        static_cast<int>(relocalization_seen_.size()) >= options_.min_relocalization_points;
    relocalization_points_.clear();
    relocalization_seen_.clear();
  }
  return seen;
}

WindowFrameEstimate SlidingWindowEstimator::AddFrame(const FrameFeatures& features,
                                                     const std::vector<ImuSample>& imu) {
  VIOSFM_CHECK(initialized()) << "AddFrame before Initialize";
  WindowFrameEstimate estimate;
  // The previous newest frame stays only if it is a keyframe.
  if (frames_.size() >= 2 && !frames_.back()->is_keyframe) RemoveFrame(frames_.size() - 1);
  const Frame& previous = *frames_.back();
  VIOSFM_CHECK_GT(features.timestamp_ns, previous.timestamp_ns) << "frames must be in time order";
  const ImuState previous_state = StateOf(previous.parameters, previous.timestamp_ns);

  auto frame = std::make_unique<Frame>();
  frame->id = next_frame_id_++;
  frame->timestamp_ns = features.timestamp_ns;
  frame->preintegration = std::make_unique<ImuPreintegration>(
      previous_state.gyro_bias, previous_state.accel_bias, noise_, options_.preintegration);
  if (!frame->preintegration->IntegrateRange(imu, previous.timestamp_ns, features.timestamp_ns)) {
    // No IMU over the interval: nothing can carry the state.
    estimate.state = previous_state;
    estimate.state.timestamp_ns = features.timestamp_ns;
    estimate.status = VioStatus::kLost;
    estimate.message = "no IMU samples between the frames";
    Reset();
    return estimate;
  }
  const ImuState predicted = frame->preintegration->Predict(previous_state);
  if (!frame->preintegration->IsUsable() || !IsFinite(predicted)) {
    // Readings no IMU reports: no factor, no prediction can be made of them.
    estimate.state = previous_state;
    estimate.state.timestamp_ns = features.timestamp_ns;
    estimate.status = VioStatus::kLost;
    std::ostringstream message;
    message << "the IMU readings between " << FormatNsAsSeconds(previous.timestamp_ns, 3) << " and "
            << FormatNsAsSeconds(features.timestamp_ns, 3)
            << " s give a non-finite or degenerate preintegration (values out of any IMU's range)";
    estimate.message = message.str();
    Reset();
    return estimate;
  }
  frame->parameters = ImuStateParameters::FromState(predicted);
  for (const FeatureObservation& observation : features.observations) {
    frame->observations[observation.track_id] = observation.normalized;
  }
  frame->is_keyframe = IsKeyframe(*frame, features);
  Frame* frame_pointer = frame.get();
  AppendFrame(std::move(frame));

  TriangulateLandmarks();
  std::vector<Landmark*> selected = SelectLandmarks();
  estimate.pose_covariance = Optimize(selected);
  const std::string failure = CheckPlausible(predicted);
  if (!failure.empty()) {
    estimate.state = predicted;
    estimate.status = VioStatus::kLost;
    estimate.message = failure;
    Reset();
    return estimate;
  }
  RemoveOutliers(selected);
  selected = SelectLandmarks();
  estimate.num_map_points = UpdateRelocalization(*frame_pointer);

  estimate.state = NewestState();
  estimate.is_keyframe = frame_pointer->is_keyframe;
  estimate.num_window_landmarks = static_cast<int>(selected.size());
  for (const Landmark* landmark : selected) {
    if (frame_pointer->observations.count(landmark->track_id) > 0) ++estimate.num_landmarks;
  }
  VIOSFM_LOG(DEBUG) << "window: frame " << FormatNsAsSeconds(frame_pointer->timestamp_ns, 3)
                    << " s, " << frames_.size() << " frames, keyframe "
                    << frame_pointer->is_keyframe << ", " << frame_pointer->observations.size()
                    << " observations, " << estimate.num_window_landmarks << " landmarks used, "
                    << estimate.num_landmarks << " seen by the frame";
  if (estimate.num_landmarks >= options_.min_tracked_landmarks) {
    has_tracked_ = true;
    imu_only_since_ns_ = -1;
    estimate.status = VioStatus::kTracking;
    // The map a later restart would re-localise against.
    map_points_.clear();
    for (const Landmark* landmark : selected) {
      map_points_.emplace(
          landmark->track_id,
          InverseDepthPointInWorld(
              StateOf(landmark->anchor->parameters, 0).world_from_body, body_from_cam_,
              landmark->anchor->observations.at(landmark->track_id), landmark->inverse_depth));
    }
  } else if (!has_tracked_) {
    estimate.status = VioStatus::kInitializing;
  } else {
    if (imu_only_since_ns_ < 0) imu_only_since_ns_ = frame_pointer->timestamp_ns;
    estimate.status = VioStatus::kImuOnly;
    if (NsToSeconds(frame_pointer->timestamp_ns - imu_only_since_ns_) > options_.max_imu_only_s) {
      estimate.status = VioStatus::kLost;
      estimate.message = "too few landmarks for too long";
      Reset();
      return estimate;
    }
  }

  if (frame_pointer->is_keyframe) {
    int num_keyframes = 0;
    for (const auto& window_frame : frames_) num_keyframes += window_frame->is_keyframe ? 1 : 0;
    if (num_keyframes > options_.window_size) MarginalizeOldest(selected);
  }
  return estimate;
}

}  // namespace viosfm
