#include "viosfm/vio/vi_initializer.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include "viosfm/estimators/essential_matrix.h"
#include "viosfm/estimators/ransac.h"
#include "viosfm/estimators/two_view_geometry.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/triangulation.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/vio/static_init.h"

namespace viosfm {

std::string ViInitOptions::Validate() const {
  if (window_size < 4) return "window_size must be >= 4";
  if (min_num_frames < 4) return "min_num_frames must be >= 4 (the alignment needs them)";
  if (min_num_frames > window_size) return "min_num_frames must be <= window_size";
  if (!(focal_length_px > 0.0)) return "focal_length_px must be > 0";
  if (!(min_parallax_px >= 0.0)) return "min_parallax_px must be >= 0";
  if (!(min_triangulation_angle_deg > 0.0)) return "min_triangulation_angle_deg must be > 0";
  if (min_pair_correspondences < 8) return "min_pair_correspondences must be >= 8";
  if (!(essential_max_error_px > 0.0)) return "essential_max_error_px must be > 0";
  if (!(max_reprojection_error_px > 0.0)) return "max_reprojection_error_px must be > 0";
  if (!(min_landmark_triangulation_angle_deg > 0.0)) {
    return "min_landmark_triangulation_angle_deg must be > 0";
  }
  if (min_pnp_correspondences < 4) return "min_pnp_correspondences must be >= 4";
  if (max_ba_iterations < 1) return "max_ba_iterations must be >= 1";
  if (!(min_accel_stddev >= 0.0)) return "min_accel_stddev must be >= 0";
  if (!(max_gravity_norm_error > 0.0)) return "max_gravity_norm_error must be > 0";
  if (!(gravity_magnitude > 0.0)) return "gravity_magnitude must be > 0";
  if (gravity_refinement_iterations < 1) return "gravity_refinement_iterations must be >= 1";
  if (!(min_baseline_m > 0.0)) return "min_baseline_m must be > 0";
  if (!(max_baseline_m > min_baseline_m)) return "max_baseline_m must be > min_baseline_m";
  return "";
}

namespace {

constexpr double kDegToRad = M_PI / 180.0;

// Reprojection error (pixels at `focal`) of a point in the visual frame V
// seen by a camera with pose cam_from_V = (q, t).
struct ReprojectionCost {
  ReprojectionCost(const Eigen::Vector2d& observed, double focal)
      : observed(observed), focal(focal) {}

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* point, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(rotation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(translation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> x(point);
    const Eigen::Matrix<T, 3, 1> in_cam = q * x + t;
    if (in_cam.z() < T(1e-6)) return false;
    residuals[0] = T(focal) * (in_cam.x() / in_cam.z() - T(observed.x()));
    residuals[1] = T(focal) * (in_cam.y() / in_cam.z() - T(observed.y()));
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector2d& observed, double focal) {
    return new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 4, 3, 3>(
        new ReprojectionCost(observed, focal));
  }

  Eigen::Vector2d observed;
  double focal;
};

// Camera pose as Ceres parameter blocks: cam_from_V.
struct PoseBlock {
  std::array<double, 4> q{0, 0, 0, 1};  // x y z w
  std::array<double, 3> t{0, 0, 0};
  bool registered = false;

  Rigid3d ToRigid() const {
    return Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(),
                   Eigen::Vector3d(t[0], t[1], t[2]));
  }
  void FromRigid(const Rigid3d& cam_from_v) {
    q = {cam_from_v.rotation.x(), cam_from_v.rotation.y(), cam_from_v.rotation.z(),
         cam_from_v.rotation.w()};
    t = {cam_from_v.translation.x(), cam_from_v.translation.y(), cam_from_v.translation.z()};
    registered = true;
  }
};

struct Observation {
  int frame = 0;
  Eigen::Vector2d normalized;
};

// The up-to-scale visual reconstruction of the window.
class WindowSfm {
 public:
  WindowSfm(const std::vector<const FrameFeatures*>& frames, const ViInitOptions& options)
      : options_(options), num_frames_(static_cast<int>(frames.size())) {
    for (int k = 0; k < num_frames_; ++k) {
      for (const FeatureObservation& observation : frames[k]->observations) {
        tracks_[observation.track_id].push_back({k, observation.normalized});
      }
    }
    poses_.resize(num_frames_);
  }

  // Runs the reconstruction; on failure, false and *message says why.
  bool Run(ViInitResult* result, std::string* message) {
    if (!InitializeReferencePair(result, message)) return false;
    const int last = num_frames_ - 1;
    TriangulateAll();
    for (int k = reference_ + 1; k < last; ++k) {
      if (!Register(k, poses_[k - 1].ToRigid(), message)) return false;
      TriangulateAll();
    }
    for (int k = reference_ - 1; k >= 0; --k) {
      if (!Register(k, poses_[k + 1].ToRigid(), message)) return false;
      TriangulateAll();
    }
    BundleAdjust();
    RemoveOutliers();
    TriangulateAll();
    BundleAdjust();
    RemoveOutliers();
    result->reprojection_rms_px = ReprojectionRms();
    if (points_.size() < static_cast<size_t>(options_.min_pair_correspondences)) {
      *message =
          "too few landmarks after bundle adjustment (" + std::to_string(points_.size()) + ")";
      return false;
    }
    return true;
  }

  Rigid3d CamFromV(int k) const { return poses_[k].ToRigid(); }
  std::map<uint64_t, Eigen::Vector3d> Points() const {
    std::map<uint64_t, Eigen::Vector3d> points;
    for (const auto& [id, p] : points_) points[id] = Eigen::Vector3d(p[0], p[1], p[2]);
    return points;
  }

 private:
  bool InitializeReferencePair(ViInitResult* result, std::string* message) {
    const int last = num_frames_ - 1;
    const double focal = options_.focal_length_px;
    double best_angle_deg = 0.0;
    for (int l = 0; l < last; ++l) {
      std::vector<Eigen::Vector2d> x1;
      std::vector<Eigen::Vector2d> x2;
      double parallax_sum = 0.0;
      for (const auto& [id, observations] : tracks_) {
        const Observation* a = Find(observations, l);
        const Observation* b = Find(observations, last);
        if (a == nullptr || b == nullptr) continue;
        x1.push_back(a->normalized);
        x2.push_back(b->normalized);
        parallax_sum += (a->normalized - b->normalized).norm() * focal;
      }
      if (x1.size() < static_cast<size_t>(options_.min_pair_correspondences)) continue;
      const double parallax_px = parallax_sum / static_cast<double>(x1.size());
      if (parallax_px < options_.min_parallax_px) continue;

      RansacOptions ransac_options;
      ransac_options.max_error = options_.essential_max_error_px / focal;
      ransac_options.seed = options_.seed;
      ransac_options.max_num_trials = 1000;
      const Ransac<EssentialMatrixFivePointEstimator, EssentialMatrixLocalEstimator> ransac(
          ransac_options);
      const auto report = ransac.Estimate(x1, x2);
      if (!report.success ||
          report.num_inliers < static_cast<size_t>(options_.min_pair_correspondences)) {
        continue;
      }
      std::vector<Eigen::Vector2d> in1;
      std::vector<Eigen::Vector2d> in2;
      for (size_t i = 0; i < x1.size(); ++i) {
        if (report.inlier_mask[i]) {
          in1.push_back(x1[i]);
          in2.push_back(x2[i]);
        }
      }
      int num_in_front = 0;
      Rigid3d cam2_from_cam1 = RelativePoseFromEssential(report.model, in1, in2, &num_in_front);
      cam2_from_cam1 = RefineRelativePose(cam2_from_cam1, in1, in2);
      // Median triangulation angle of the inliers in front of both cameras
      // (points that fail count as zero parallax).
      const Rigid3d identity;
      std::vector<double> angles;
      for (size_t i = 0; i < in1.size(); ++i) {
        const auto point = TriangulateMidpoint(identity, cam2_from_cam1, in1[i], in2[i]);
        if (!point || !HasPositiveDepth(identity, *point) ||
            !HasPositiveDepth(cam2_from_cam1, *point)) {
          angles.push_back(0.0);
          continue;
        }
        angles.push_back(
            TriangulationAngle(Eigen::Vector3d::Zero(), ProjectionCenter(cam2_from_cam1), *point));
      }
      std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
      const double median_deg = angles[angles.size() / 2] / kDegToRad;
      best_angle_deg = std::max(best_angle_deg, median_deg);
      if (median_deg < options_.min_triangulation_angle_deg) continue;

      reference_ = l;
      result->reference_frame = l;
      result->median_parallax_deg = median_deg;
      poses_[l].FromRigid(Rigid3d());
      poses_[last].FromRigid(cam2_from_cam1);
      return true;
    }
    std::ostringstream stream;
    stream << "not enough parallax: no keyframe has " << options_.min_pair_correspondences
           << " correspondences, " << options_.min_parallax_px
           << " px mean parallax and a median triangulation angle of "
           << options_.min_triangulation_angle_deg << " deg with the last keyframe (best angle "
           << best_angle_deg << " deg)";
    *message = stream.str();
    return false;
  }

  static const Observation* Find(const std::vector<Observation>& observations, int frame) {
    for (const Observation& observation : observations) {
      if (observation.frame == frame) return &observation;
    }
    return nullptr;
  }

  double PixelError(int frame, const Eigen::Vector3d& point,
                    const Eigen::Vector2d& observed) const {
    const Eigen::Vector3d in_cam = poses_[frame].ToRigid() * point;
    if (in_cam.z() <= 1e-9) return std::numeric_limits<double>::infinity();
    return (in_cam.hnormalized() - observed).norm() * options_.focal_length_px;
  }

  // Triangulates every track seen by two or more registered frames that has
  // no point yet. Observations that disagree with the DLT point are excluded
  // and the point triangulated again from the rest (once).
  void TriangulateAll() {
    for (const auto& [id, observations] : tracks_) {
      if (points_.count(id) != 0) continue;
      std::vector<int> frames;
      std::vector<Eigen::Vector2d> xs;
      for (const Observation& observation : observations) {
        if (!poses_[observation.frame].registered) continue;
        if (excluded_.count({id, observation.frame}) != 0) continue;
        frames.push_back(observation.frame);
        xs.push_back(observation.normalized);
      }
      for (int attempt = 0; attempt < 2 && frames.size() >= 2; ++attempt) {
        const auto point = TriangulateFrom(frames, xs);
        if (!point) break;
        std::vector<int> inlier_frames;
        std::vector<Eigen::Vector2d> inlier_xs;
        for (size_t i = 0; i < frames.size(); ++i) {
          if (PixelError(frames[i], *point, xs[i]) <= options_.max_reprojection_error_px) {
            inlier_frames.push_back(frames[i]);
            inlier_xs.push_back(xs[i]);
          }
        }
        if (inlier_frames.size() == frames.size()) {
          if (MaxTriangulationAngle(frames, *point) >=
              options_.min_landmark_triangulation_angle_deg * kDegToRad) {
            points_[id] = {point->x(), point->y(), point->z()};
            for (const Observation& observation : observations) {
              if (poses_[observation.frame].registered &&
                  std::find(frames.begin(), frames.end(), observation.frame) == frames.end()) {
                excluded_.insert({id, observation.frame});
              }
            }
          }
          break;
        }
        if (attempt == 1 || inlier_frames.size() < 2) break;
        // Retry without the outliers only when they are a minority.
        if (2 * inlier_frames.size() <= frames.size()) break;
        frames = std::move(inlier_frames);
        xs = std::move(inlier_xs);
      }
    }
  }

  std::optional<Eigen::Vector3d> TriangulateFrom(const std::vector<int>& frames,
                                                 const std::vector<Eigen::Vector2d>& xs) const {
    std::vector<Matrix3x4d> cams;
    for (const int frame : frames) cams.push_back(poses_[frame].ToRigid().ToMatrix());
    return TriangulateDlt(cams, xs);
  }

  double MaxTriangulationAngle(const std::vector<int>& frames, const Eigen::Vector3d& point) const {
    double max_angle = 0.0;
    for (size_t i = 0; i < frames.size(); ++i) {
      const Eigen::Vector3d center_i = ProjectionCenter(poses_[frames[i]].ToRigid());
      for (size_t j = i + 1; j < frames.size(); ++j) {
        max_angle = std::max(
            max_angle,
            TriangulationAngle(center_i, ProjectionCenter(poses_[frames[j]].ToRigid()), point));
      }
    }
    return max_angle;
  }

  ceres::Solver::Options SolverOptions() const {
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_SCHUR;
    solver_options.num_threads = 1;
    solver_options.max_num_iterations = options_.max_ba_iterations;
    solver_options.logging_type = ceres::SILENT;
    solver_options.minimizer_progress_to_stdout = false;
    return solver_options;
  }

  // PnP of frame k from the triangulated points, starting at `initial`.
  bool Register(int k, const Rigid3d& initial, std::string* message) {
    PoseBlock pose;
    pose.FromRigid(initial);
    ceres::Problem problem;
    int num_correspondences = 0;
    for (auto& [id, point] : points_) {
      const Observation* observation = Find(tracks_.at(id), k);
      if (observation == nullptr) continue;
      problem.AddResidualBlock(
          ReprojectionCost::Create(observation->normalized, options_.focal_length_px),
          new ceres::HuberLoss(1.0), pose.q.data(), pose.t.data(), point.data());
      problem.SetParameterBlockConstant(point.data());
      ++num_correspondences;
    }
    if (num_correspondences < options_.min_pnp_correspondences) {
      *message = "keyframe " + std::to_string(k) + " sees only " +
                 std::to_string(num_correspondences) + " landmarks (PnP needs " +
                 std::to_string(options_.min_pnp_correspondences) + ")";
      return false;
    }
    problem.SetManifold(pose.q.data(), new ceres::EigenQuaternionManifold());
    ceres::Solver::Summary summary;
    ceres::Solver::Options solver_options = SolverOptions();
    solver_options.linear_solver_type = ceres::DENSE_QR;
    ceres::Solve(solver_options, &problem, &summary);
    poses_[k] = pose;
    int num_inliers = 0;
    for (const auto& [id, point] : points_) {
      const Observation* observation = Find(tracks_.at(id), k);
      if (observation == nullptr) continue;
      if (PixelError(k, Eigen::Vector3d(point[0], point[1], point[2]), observation->normalized) <=
          options_.max_reprojection_error_px) {
        ++num_inliers;
      }
    }
    if (num_inliers < options_.min_pnp_correspondences) {
      poses_[k].registered = false;
      *message = "PnP of keyframe " + std::to_string(k) + " failed (" +
                 std::to_string(num_inliers) + " inliers of " +
                 std::to_string(num_correspondences) + ")";
      return false;
    }
    return true;
  }

  // Bundle adjustment over all poses and points; the reference camera is
  // fixed and the last camera's translation (the reference baseline) keeps
  // unit norm, which fixes the gauge.
  void BundleAdjust() {
    ceres::Problem problem;
    for (auto& [id, point] : points_) {
      for (const Observation& observation : tracks_.at(id)) {
        if (excluded_.count({id, observation.frame}) != 0) continue;
        PoseBlock& pose = poses_[observation.frame];
        problem.AddResidualBlock(
            ReprojectionCost::Create(observation.normalized, options_.focal_length_px),
            new ceres::HuberLoss(1.0), pose.q.data(), pose.t.data(), point.data());
      }
    }
    const int last = num_frames_ - 1;
    for (int k = 0; k < num_frames_; ++k) {
      PoseBlock& pose = poses_[k];
      if (!problem.HasParameterBlock(pose.q.data())) continue;
      problem.SetManifold(pose.q.data(), new ceres::EigenQuaternionManifold());
      if (k == reference_) {
        problem.SetParameterBlockConstant(pose.q.data());
        problem.SetParameterBlockConstant(pose.t.data());
      } else if (k == last) {
        problem.SetManifold(pose.t.data(), new ceres::SphereManifold<3>());
      }
    }
    ceres::Solver::Summary summary;
    ceres::Solve(SolverOptions(), &problem, &summary);
  }

  // Drops observations with a large reprojection error, then points seen by
  // fewer than two frames or with a non-positive depth.
  void RemoveOutliers() {
    for (auto it = points_.begin(); it != points_.end();) {
      const Eigen::Vector3d point(it->second[0], it->second[1], it->second[2]);
      int num_kept = 0;
      for (const Observation& observation : tracks_.at(it->first)) {
        if (!poses_[observation.frame].registered) continue;
        if (excluded_.count({it->first, observation.frame}) != 0) continue;
        if (PixelError(observation.frame, point, observation.normalized) >
            options_.max_reprojection_error_px) {
          excluded_.insert({it->first, observation.frame});
        } else {
          ++num_kept;
        }
      }
      if (num_kept < 2) {
        it = points_.erase(it);
      } else {
        ++it;
      }
    }
  }

  double ReprojectionRms() const {
    double sum = 0.0;
    int count = 0;
    for (const auto& [id, p] : points_) {
      for (const Observation& observation : tracks_.at(id)) {
        if (excluded_.count({id, observation.frame}) != 0) continue;
        const double error = PixelError(observation.frame, Eigen::Vector3d(p[0], p[1], p[2]),
                                        observation.normalized);
        sum += error * error;
        ++count;
      }
    }
    return count > 0 ? std::sqrt(sum / count) : 0.0;
  }

  const ViInitOptions& options_;
  int num_frames_ = 0;
  int reference_ = -1;
  // Ordered maps and sets: the iteration order, hence the result, is fixed.
  std::map<uint64_t, std::vector<Observation>> tracks_;
  std::map<uint64_t, std::array<double, 3>> points_;
  std::set<std::pair<uint64_t, int>> excluded_;
  std::vector<PoseBlock> poses_;
};

// Linear alignment (see the header): solves for velocities (in V), gravity
// (in V) and scale. With `gravity_direction` set, |g| is fixed and only a
// 2-DoF tangent correction is solved; *gravity receives the new gravity.
struct AlignmentInput {
  std::vector<Eigen::Vector3d> centers;      // c_k, up to scale, in V
  std::vector<Eigen::Matrix3d> v_from_cam;   // R_V_ck
  std::vector<Eigen::Matrix3d> v_from_body;  // R_V_bk
  const std::vector<ImuPreintegration>* preintegrations = nullptr;
  Eigen::Vector3d cam_from_body_translation;  // t_cb
};

struct AlignmentSolution {
  std::vector<Eigen::Vector3d> velocities;
  Eigen::Vector3d gravity;
  double scale = 0.0;
  double rms = 0.0;
};

AlignmentSolution SolveAlignment(const AlignmentInput& input,
                                 const std::optional<Eigen::Vector3d>& fixed_gravity) {
  const int n = static_cast<int>(input.centers.size());
  const int num_gravity = fixed_gravity ? 2 : 3;
  const int num_unknowns = 3 * n + num_gravity + 1;
  const int gravity_col = 3 * n;
  const int scale_col = 3 * n + num_gravity;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(6 * (n - 1), num_unknowns);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(6 * (n - 1));
  Eigen::Vector3d g0 = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, Eigen::Dynamic> gravity_basis(3, num_gravity);
  if (fixed_gravity) {
    g0 = *fixed_gravity;
    const Eigen::Vector3d direction = g0.normalized();
    const Eigen::Vector3d helper =
        std::abs(direction.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d b1 = direction.cross(helper).normalized();
    const Eigen::Vector3d b2 = direction.cross(b1);
    gravity_basis.col(0) = b1;
    gravity_basis.col(1) = b2;
  } else {
    gravity_basis = Eigen::Matrix3d::Identity();
  }
  const Eigen::Vector3d& t_cb = input.cam_from_body_translation;
  for (int k = 0; k + 1 < n; ++k) {
    const ImuPreintegration& pre = (*input.preintegrations)[k];
    const double dt = pre.delta_t_s();
    const int row = 6 * k;
    // Position rows.
    a.block<3, 1>(row, scale_col) = input.centers[k + 1] - input.centers[k];
    a.block<3, 3>(row, 3 * k) = -dt * Eigen::Matrix3d::Identity();
    a.block(row, gravity_col, 3, num_gravity) = -0.5 * dt * dt * gravity_basis;
    b.segment<3>(row) = input.v_from_body[k] * pre.delta_p() -
                        (input.v_from_cam[k + 1] - input.v_from_cam[k]) * t_cb + 0.5 * dt * dt * g0;
    // Velocity rows.
    a.block<3, 3>(row + 3, 3 * (k + 1)) = Eigen::Matrix3d::Identity();
    a.block<3, 3>(row + 3, 3 * k) = -Eigen::Matrix3d::Identity();
    a.block(row + 3, gravity_col, 3, num_gravity) = -dt * gravity_basis;
    b.segment<3>(row + 3) = input.v_from_body[k] * pre.delta_v() + dt * g0;
  }
  // Column equilibration for conditioning (positions are small next to g).
  Eigen::VectorXd column_scale(num_unknowns);
  for (int c = 0; c < num_unknowns; ++c) {
    const double norm = a.col(c).norm();
    column_scale[c] = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  const Eigen::MatrixXd scaled = a * column_scale.asDiagonal();
  const Eigen::VectorXd y = scaled.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd x = column_scale.asDiagonal() * y;

  AlignmentSolution solution;
  solution.velocities.resize(n);
  for (int k = 0; k < n; ++k) solution.velocities[k] = x.segment<3>(3 * k);
  solution.gravity = g0 + gravity_basis * x.segment(gravity_col, num_gravity);
  solution.scale = x[scale_col];
  solution.rms = std::sqrt((a * x - b).squaredNorm() / static_cast<double>(b.size()));
  return solution;
}

ViInitResult Fail(ViInitResult result, const std::string& message) {
  result.success = false;
  result.message = message;
  result.states.clear();
  result.points_in_world.clear();
  VIOSFM_LOG(DEBUG) << "Visual-inertial initialisation failed: " << message;
  return result;
}

// The initialisation's steps over a window of time-ordered keyframes. A step
// that can fail on good input returns why (empty: it succeeded).
class ViInitializer {
 public:
  ViInitializer(std::vector<const FrameFeatures*> window, const Rigid3d& body_from_cam,
                const ViInitOptions& options)
      : window_(std::move(window)),
        n_(static_cast<int>(window_.size())),
        cam_from_body_(body_from_cam.Inverse()),
        options_(options),
        sfm_(window_, options) {}
  ViInitializer(const ViInitializer&) = delete;
  ViInitializer& operator=(const ViInitializer&) = delete;

  ViInitResult Run(const std::vector<ImuSample>& imu, const ImuNoise& noise) {
    // IMU between consecutive keyframes (checked first: it is cheap).
    if (const std::string message = Preintegrate(imu, noise); !message.empty()) {
      return Fail(result_, message);
    }
    // 1. Vision-only SfM up to scale.
    if (std::string message; !sfm_.Run(&result_, &message)) return Fail(result_, message);
    SetUpAlignment();
    EstimateGyroBias();
    if (const std::string message = CheckExcitation(); !message.empty()) {
      return Fail(result_, message);
    }
    if (const std::string message = AlignLinearly(); !message.empty()) {
      return Fail(result_, message);
    }
    if (const std::string message = RefineGravity(); !message.empty()) {
      return Fail(result_, message);
    }
    SetGravityAlignedStates();
    Report();
    return result_;
  }

 private:
  std::string Preintegrate(const std::vector<ImuSample>& imu, const ImuNoise& noise) {
    preintegrations_.reserve(n_ - 1);
    for (int k = 0; k + 1 < n_; ++k) {
      preintegrations_.emplace_back(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), noise);
      if (!preintegrations_.back().IntegrateRange(imu, window_[k]->timestamp_ns,
                                                  window_[k + 1]->timestamp_ns)) {
        return "the IMU samples do not cover keyframes " + std::to_string(k) + " to " +
               std::to_string(k + 1);
      }
    }
    return "";
  }

  // The reconstruction's camera centres and rotations in its frame V.
  void SetUpAlignment() {
    input_.preintegrations = &preintegrations_;
    input_.cam_from_body_translation = cam_from_body_.translation;
    for (int k = 0; k < n_; ++k) {
      const Rigid3d v_from_cam = sfm_.CamFromV(k).Inverse();
      input_.centers.push_back(v_from_cam.translation);
      input_.v_from_cam.push_back(v_from_cam.rotation.toRotationMatrix());
      input_.v_from_body.push_back(
          (v_from_cam.rotation * cam_from_body_.rotation).toRotationMatrix());
    }
  }

  // 2. Gyro bias: Exp(dR_dbg (bg - bg0)) = dR^T * R_bk^T R_bk+1, least squares.
  void EstimateGyroBias() {
    Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
    for (int iteration = 0; iteration < 2; ++iteration) {
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      for (int k = 0; k + 1 < n_; ++k) {
        const ImuPreintegration& pre = preintegrations_[k];
        const Eigen::Quaterniond visual(input_.v_from_body[k].transpose() *
                                        input_.v_from_body[k + 1]);
        const Eigen::Vector3d residual = So3Log(pre.delta_R().inverse() * visual);
        normal += pre.dR_dbg().transpose() * pre.dR_dbg();
        rhs += pre.dR_dbg().transpose() * residual;
      }
      gyro_bias += normal.ldlt().solve(rhs);
      for (ImuPreintegration& pre : preintegrations_) {
        pre.Repropagate(gyro_bias, Eigen::Vector3d::Zero());
      }
    }
    result_.gyro_bias = gyro_bias;
  }

  // Excitation: spread of the mean specific force between keyframes, in V.
  std::string CheckExcitation() {
    std::vector<Eigen::Vector3d> forces;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int k = 0; k + 1 < n_; ++k) {
      forces.push_back(input_.v_from_body[k] * preintegrations_[k].delta_v() /
                       preintegrations_[k].delta_t_s());
      mean += forces.back();
    }
    mean /= static_cast<double>(forces.size());
    double sum = 0.0;
    for (const Eigen::Vector3d& force : forces) sum += (force - mean).squaredNorm();
    result_.accel_stddev = std::sqrt(sum / static_cast<double>(forces.size()));
    if (!(result_.accel_stddev < options_.min_accel_stddev)) return "";
    std::ostringstream stream;
    stream << "not enough IMU excitation: acceleration stddev " << result_.accel_stddev
           << " m/s^2 < " << options_.min_accel_stddev << " (scale unobservable)";
    return stream.str();
  }

  // 3. Linear alignment.
  std::string AlignLinearly() {
    solution_ = SolveAlignment(input_, std::nullopt);
    result_.gravity_norm_linear = solution_.gravity.norm();
    std::ostringstream stream;
    if (!(solution_.scale > 0.0)) {
      stream << "negative scale from the linear alignment (" << solution_.scale << ")";
    } else if (std::abs(result_.gravity_norm_linear - options_.gravity_magnitude) >
               options_.max_gravity_norm_error) {
      stream << "gravity norm of the linear alignment " << result_.gravity_norm_linear
             << " m/s^2 is far from " << options_.gravity_magnitude;
    }
    return stream.str();
  }

  // 4. Gravity refinement with |g| fixed.
  std::string RefineGravity() {
    Eigen::Vector3d gravity = solution_.gravity.normalized() * options_.gravity_magnitude;
    for (int iteration = 0; iteration < options_.gravity_refinement_iterations; ++iteration) {
      solution_ = SolveAlignment(input_, gravity);
      gravity = solution_.gravity.normalized() * options_.gravity_magnitude;
    }
    solution_.gravity = gravity;
    result_.alignment_rms = solution_.rms;
    result_.scale = solution_.scale;
    const double baseline = solution_.scale * input_.centers.back().norm();
    const bool plausible = solution_.scale > 0.0 && !(baseline < options_.min_baseline_m) &&
                           !(baseline > options_.max_baseline_m);
    if (plausible) return "";
    std::ostringstream stream;
    stream << "implausible scale " << solution_.scale << " (reference baseline " << baseline
           << " m, allowed [" << options_.min_baseline_m << ", " << options_.max_baseline_m << "])";
    return stream.str();
  }

  // 5. Gravity-aligned world: z up, origin and zero yaw at the first body.
  void SetGravityAlignedStates() {
    double roll = 0.0;
    double pitch = 0.0;
    const Eigen::Quaterniond tilt = GravityAlignedRotation(-solution_.gravity, &roll, &pitch);
    const Eigen::Vector3d x_axis = tilt * input_.v_from_body[0].col(0);
    const double yaw = std::atan2(x_axis.y(), x_axis.x());
    const Eigen::Quaterniond world_from_v =
        (Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()) * tilt).normalized();
    std::vector<Eigen::Vector3d> body_positions(n_);
    for (int k = 0; k < n_; ++k) {
      body_positions[k] =
          solution_.scale * input_.centers[k] + input_.v_from_cam[k] * cam_from_body_.translation;
    }
    const Eigen::Vector3d origin = body_positions[0];
    result_.states.resize(n_);
    for (int k = 0; k < n_; ++k) {
      ImuState& state = result_.states[k];
      state.timestamp_ns = window_[k]->timestamp_ns;
      state.world_from_body =
          Rigid3d((world_from_v * Eigen::Quaterniond(input_.v_from_body[k])).normalized(),
                  world_from_v * (body_positions[k] - origin));
      state.velocity_in_world = world_from_v * solution_.velocities[k];
      state.gyro_bias = result_.gyro_bias;
      state.accel_bias.setZero();
    }
    for (const auto& [id, point] : sfm_.Points()) {
      result_.points_in_world[id] = world_from_v * (solution_.scale * point - origin);
    }
    result_.gravity_in_world = Eigen::Vector3d(0.0, 0.0, -options_.gravity_magnitude);
    result_.accel_bias.setZero();
    result_.success = true;
  }

  void Report() {
    std::ostringstream stream;
    stream << "initialised from " << n_ << " keyframes (reference " << result_.reference_frame
           << ", parallax " << result_.median_parallax_deg << " deg), "
           << result_.points_in_world.size() << " landmarks, reprojection RMS "
           << result_.reprojection_rms_px << " px, scale " << result_.scale << ", |g| linear "
           << result_.gravity_norm_linear << " m/s^2, accel std " << result_.accel_stddev
           << " m/s^2, gyro bias " << result_.gyro_bias.transpose() << " rad/s";
    result_.message = stream.str();
    VIOSFM_LOG(INFO) << "Visual-inertial initialisation: " << result_.message;
  }

  const std::vector<const FrameFeatures*> window_;
  const int n_;
  const Rigid3d cam_from_body_;
  const ViInitOptions& options_;
  WindowSfm sfm_;
  ViInitResult result_;
  std::vector<ImuPreintegration> preintegrations_;
  AlignmentInput input_;
  AlignmentSolution solution_;
};

}  // namespace

ViInitResult InitializeVisualInertial(const std::vector<FrameFeatures>& frames,
                                      const std::vector<ImuSample>& imu,
                                      const Rigid3d& body_from_cam, const ImuNoise& noise,
                                      const ViInitOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  const int first = std::max(0, static_cast<int>(frames.size()) - options.window_size);
  std::vector<const FrameFeatures*> window;
  for (size_t i = first; i < frames.size(); ++i) window.push_back(&frames[i]);
  const int n = static_cast<int>(window.size());
  if (n < options.min_num_frames) {
    return Fail(ViInitResult(), "too few keyframes (" + std::to_string(n) + ", need " +
                                    std::to_string(options.min_num_frames) + ")");
  }
  for (int k = 0; k + 1 < n; ++k) {
    VIOSFM_CHECK_LT(window[k]->timestamp_ns, window[k + 1]->timestamp_ns)
        << "keyframes must be time ordered";
  }
  return ViInitializer(std::move(window), body_from_cam, options).Run(imu, noise);
}

}  // namespace viosfm
