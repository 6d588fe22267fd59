#include "viosfm/sfm/imu_scale.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <memory>
#include <sstream>

#include "viosfm/geometry/lie.h"
#include "viosfm/sfm/gyro_priors.h"
#include "viosfm/util/errors.h"
#include "viosfm/vio/imu_preintegration.h"

namespace viosfm {
namespace {

struct Pair {
  size_t i = 0;
  size_t j = 0;
  int window = 0;
  std::unique_ptr<ImuPreintegration> preintegration;
};

}  // namespace

std::string ImuScaleOptions::Validate() const {
  if (!(bias_window_s > 0.0)) return "bias_window_s must be > 0";
  if (!(spacing_check_interval_s >= 0.0)) return "spacing_check_interval_s must be >= 0";
  if (!(max_spacing_disagreement > 0.0)) return "max_spacing_disagreement must be > 0";
  if (!(position_sigma_m > 0.0)) return "position_sigma_m must be > 0";
  if (!(rotation_sigma_rad >= 0.0)) return "rotation_sigma_rad must be >= 0";
  if (gravity_iterations < 1) return "gravity_iterations must be >= 1";
  if (!(max_scale_sigma > 0.0)) return "max_scale_sigma must be > 0";
  if (!(max_scale_factor > 1.0)) return "max_scale_factor must be > 1";
  if (!(vio_refuted_sigmas > 0.0)) return "vio_refuted_sigmas must be > 0";
  if (!(max_refuting_scale_sigma > 0.0)) return "max_refuting_scale_sigma must be > 0";
  if (!(max_refuting_residual_ratio > 0.0)) return "max_refuting_residual_ratio must be > 0";
  if (!(max_residual_ratio > 0.0)) return "max_residual_ratio must be > 0";
  if (!(max_factor_disagreement > 0.0)) return "max_factor_disagreement must be > 0";
  return "";
}

namespace {

// The least squares needs this many more equations than unknowns (6 per
// frame pair against 3 velocities per frame, the biases, gravity and the
// scale: 6 frames in one bias window).
constexpr int kMinRedundancy = 6;
// The a-posteriori variance factor narrows the scale's sigma only over this
// many degrees of freedom (the factor is then known within 13 %).
constexpr int kMinDofToNarrow = 30;

// One least squares over the consecutive pairs of `frames` (indices into
// `poses`, at least 4).
struct ScaleSolution {
  std::string failure;  // empty when solved
  double scale = 1.0;
  double scale_sigma = 0.0;
  double residual_ratio = 0.0;
  Eigen::Vector3d gravity_in_world = Eigen::Vector3d::Zero();
  int num_frames = 0;
  int num_pairs = 0;
};

// The normal equations of whitened rows W A x = W b, (W A)^T (W A) and
// (W A)^T W b, assembled from rows whose unknowns come in blocks of 3 columns.
class NormalEquations {
 public:
  using Blocks = std::vector<std::pair<int, Eigen::Matrix<double, 6, 3>>>;

  explicit NormalEquations(int num_unknowns) : rhs_(Eigen::VectorXd::Zero(num_unknowns)) {}

  void Add(const Blocks& blocks, const Eigen::Matrix<double, 6, 1>& b,
           const Eigen::Matrix<double, 6, 6>& whiten) {
    Blocks white;
    for (const auto& [col, block] : blocks) white.emplace_back(col, whiten * block);
    const Eigen::Matrix<double, 6, 1> wb = whiten * b;
    whitened_b2_ += wb.squaredNorm();
    for (const auto& [col_a, a] : white) {
      rhs_.segment<3>(col_a) += a.transpose() * wb;
      for (const auto& [col_b, bb] : white) {
        const Eigen::Matrix3d product = a.transpose() * bb;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            if (product(r, c) != 0.0) triplets_.emplace_back(col_a + r, col_b + c, product(r, c));
          }
        }
      }
    }
    num_rows_ += 6;
  }
  // A weak prior of `weight` on every unknown.
  void AddDiagonal(double weight) {
    for (int k = 0; k < rhs_.size(); ++k) triplets_.emplace_back(k, k, weight);
  }
  Eigen::SparseMatrix<double> Matrix() const {
    Eigen::SparseMatrix<double> matrix(rhs_.size(), rhs_.size());
    matrix.setFromTriplets(triplets_.begin(), triplets_.end());
    return matrix;
  }
  const Eigen::VectorXd& rhs() const { return rhs_; }
  double whitened_b2() const { return whitened_b2_; }
  int num_rows() const { return num_rows_; }

 private:
  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::VectorXd rhs_;
  double whitened_b2_ = 0.0;
  int num_rows_ = 0;
};

// The least squares of SolveScale over the consecutive pairs of `frames`:
// scale, gravity direction, accel biases per window and velocities per
// frame, whitened and iterated on the gravity direction.
class ScaleLeastSquares {
 public:
  ScaleLeastSquares(const std::vector<StampedPose>& poses, const std::vector<size_t>& frames,
                    const ImuNoise& noise, const ImuScaleOptions& options)
      : poses_(poses), frames_(frames), noise_(noise), options_(options) {}

  // The pairs the IMU covers, preintegrated with each window's gyro bias.
  void Preintegrate(const std::vector<ImuSample>& imu);
  ScaleSolution Solve();

 private:
  // Unknowns' columns: the scale, the gravity direction's 2-d tangent
  // correction, 3 per bias window, 3 per frame's velocity.
  static constexpr int kColScale = 0;
  static constexpr int kColGravity = 1;
  static constexpr int kColBias = 3;
  int ColVelocity() const { return kColBias + 3 * num_windows_; }
  int NumUnknowns() const { return ColVelocity() + 3 * static_cast<int>(frames_.size()); }
  int WindowOf(timestamp_ns_t t) const {
    return static_cast<int>(static_cast<double>(t - poses_[frames_.front()].timestamp_ns) * 1e-9 /
                            options_.bias_window_s);
  }
  Eigen::Matrix3d Rotation(size_t f) const {
    return poses_[frames_[f]].world_from_frame.rotation.toRotationMatrix();
  }
  Eigen::Vector3d Position(size_t f) const {
    return poses_[frames_[f]].world_from_frame.translation;
  }
  // One pair's rows [velocity (3); position (3)] under `gravity`, whitened
  // by their covariance; none when it is not positive definite.
  void AddPairRows(const Pair& pair, const Eigen::Vector3d& gravity,
                   const Eigen::Matrix<double, 3, 2>& tangent, NormalEquations* equations) const;

  const std::vector<StampedPose>& poses_;
  const std::vector<size_t>& frames_;
  const ImuNoise& noise_;
  const ImuScaleOptions& options_;
  std::vector<Pair> pairs_;
  int num_windows_ = 0;
};

void ScaleLeastSquares::Preintegrate(const std::vector<ImuSample>& imu) {
  for (size_t f = 0; f + 1 < frames_.size(); ++f) {
    Pair pair;
    pair.i = f;
    pair.j = f + 1;
    pair.window = WindowOf(poses_[frames_[f]].timestamp_ns);
    pair.preintegration = std::make_unique<ImuPreintegration>(Eigen::Vector3d::Zero(),
                                                              Eigen::Vector3d::Zero(), noise_);
    if (!pair.preintegration->IntegrateRange(imu, poses_[frames_[f]].timestamp_ns,
                                             poses_[frames_[f + 1]].timestamp_ns)) {
      continue;
    }
    pairs_.push_back(std::move(pair));
  }
  num_windows_ = WindowOf(poses_[frames_.back()].timestamp_ns) + 1;
  // Gyro bias per window from the rotations (gyro_priors.h).
  std::vector<GyroPair> gyro_pairs;
  for (const Pair& pair : pairs_) {
    gyro_pairs.push_back(
        {pair.preintegration.get(), Rotation(pair.i), Rotation(pair.j), pair.window});
  }
  const std::vector<Eigen::Vector3d> gyro_bias =
      EstimateGyroBiases(gyro_pairs, num_windows_, options_.rotation_sigma_rad, noise_);
  for (Pair& pair : pairs_) {
    pair.preintegration->Repropagate(gyro_bias[pair.window], Eigen::Vector3d::Zero());
  }
}

void ScaleLeastSquares::AddPairRows(const Pair& pair, const Eigen::Vector3d& gravity,
                                    const Eigen::Matrix<double, 3, 2>& tangent,
                                    NormalEquations* equations) const {
  const ImuPreintegration& p = *pair.preintegration;
  const double dt = p.delta_t_s();
  const Eigen::Matrix3d ri = Rotation(pair.i);
  const Eigen::Vector3d dp = ri * p.delta_p();
  const Eigen::Vector3d dv = ri * p.delta_v();
  // Residual rows [velocity (3); position (3)], unknown blocks of 3
  // columns (the scale and gravity columns padded into one 3-wide block).
  Eigen::Matrix<double, 6, 3> globals = Eigen::Matrix<double, 6, 3>::Zero();
  globals.block<3, 1>(3, 0) = Position(pair.j) - Position(pair.i);  // scale
  globals.block<3, 2>(0, 1) = -dt * tangent;
  globals.block<3, 2>(3, 1) = -0.5 * dt * dt * tangent;
  Eigen::Matrix<double, 6, 3> bias;
  bias.topRows<3>() = -ri * p.dv_dba();
  bias.bottomRows<3>() = -ri * p.dp_dba();
  Eigen::Matrix<double, 6, 3> velocity_i;
  velocity_i.topRows<3>() = -Eigen::Matrix3d::Identity();
  velocity_i.bottomRows<3>() = -dt * Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 6, 3> velocity_j = Eigen::Matrix<double, 6, 3>::Zero();
  velocity_j.topRows<3>() = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 6, 1> b;
  b.head<3>() = dv + gravity * dt;
  b.tail<3>() = dp + 0.5 * gravity * dt * dt;
  // Covariance: the preintegration's [v, p] block (rotated into the
  // world), the bias walking away from its window's value, the frames'
  // rotations (turning dv and dp) and positions.
  Eigen::Matrix<double, 6, 6> covariance;
  const Matrix9d& c = p.covariance();
  covariance.topLeftCorner<3, 3>() = ri * c.block<3, 3>(3, 3) * ri.transpose();
  covariance.topRightCorner<3, 3>() = ri * c.block<3, 3>(3, 6) * ri.transpose();
  covariance.bottomLeftCorner<3, 3>() = covariance.topRightCorner<3, 3>().transpose();
  covariance.bottomRightCorner<3, 3>() = ri * c.block<3, 3>(6, 6) * ri.transpose();
  const double walk2 = std::pow(noise_.accel_random_walk, 2) * (0.5 * options_.bias_window_s + dt);
  const Eigen::Matrix3d eye = Eigen::Matrix3d::Identity();
  covariance.topLeftCorner<3, 3>() += walk2 * dt * dt * eye;
  covariance.topRightCorner<3, 3>() += walk2 * 0.5 * dt * dt * dt * eye;
  covariance.bottomLeftCorner<3, 3>() += walk2 * 0.5 * dt * dt * dt * eye;
  covariance.bottomRightCorner<3, 3>() += walk2 * 0.25 * dt * dt * dt * dt * eye;
  const double rotation_sigma = options_.rotation_sigma_rad;
  const double rotation2 = rotation_sigma * rotation_sigma + std::pow(1e-4 * dt, 2);
  covariance.topLeftCorner<3, 3>() += rotation2 * dv.squaredNorm() * eye;
  covariance.bottomRightCorner<3, 3>() +=
      (rotation2 * dp.squaredNorm() + 2.0 * options_.position_sigma_m * options_.position_sigma_m) *
      eye;
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(covariance);
  if (llt.info() != Eigen::Success) return;
  const Eigen::Matrix<double, 6, 6> whiten =
      llt.matrixL().solve(Eigen::Matrix<double, 6, 6>::Identity());
  equations->Add({{kColScale, globals},
                  {kColBias + 3 * pair.window, bias},
                  {ColVelocity() + 3 * static_cast<int>(pair.i), velocity_i},
                  {ColVelocity() + 3 * static_cast<int>(pair.j), velocity_j}},
                 b, whiten);
}

ScaleSolution ScaleLeastSquares::Solve() {
  ScaleSolution result;
  const int num_unknowns = NumUnknowns();
  const double g_norm = kStandardGravity;
  Eigen::Vector3d gravity = GravityInWorld();
  double scale = 1.0;
  for (int iteration = 0; iteration < options_.gravity_iterations; ++iteration) {
    const Eigen::Vector3d up = -gravity.normalized();
    Eigen::Vector3d t1 = up.cross(Eigen::Vector3d::UnitX());
    if (t1.norm() < 0.1) t1 = up.cross(Eigen::Vector3d::UnitY());
    t1.normalize();
    const Eigen::Vector3d t2 = up.cross(t1);
    Eigen::Matrix<double, 3, 2> tangent;
    tangent << g_norm * t1, g_norm * t2;
    NormalEquations equations(num_unknowns);
    for (const Pair& pair : pairs_) AddPairRows(pair, gravity, tangent, &equations);
    // A weak prior on every unknown keeps unobserved ones (a window without
    // pairs) determined: 10 m/s, 1 m/s^2, 1 rad, scale 10.
    equations.AddDiagonal(1e-8);
    // Too few equations for the unknowns: the weak priors would decide, and
    // the residual, nearly zero, would claim a precise scale.
    const int num_rows = equations.num_rows();
    if (num_rows - num_unknowns < kMinRedundancy) {
      result.failure = std::to_string(num_rows) + " equations for " + std::to_string(num_unknowns) +
                       " unknowns from " + std::to_string(pairs_.size()) +
                       " frame pairs (at least " + std::to_string(kMinRedundancy) +
                       " more equations than unknowns needed)";
      return result;
    }
    const Eigen::SparseMatrix<double> normal_matrix = equations.Matrix();
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal_matrix);
    if (solver.info() != Eigen::Success) {
      result.failure = "the least squares is singular";
      return result;
    }
    const Eigen::VectorXd solution = solver.solve(equations.rhs());
    scale = solution[kColScale];
    const Eigen::Vector3d corrected = gravity + tangent * solution.segment<2>(kColGravity);
    gravity = g_norm * corrected.normalized();
    if (iteration + 1 == options_.gravity_iterations) {
      // The scale's variance: (A^T A)^-1 at (0, 0).
      Eigen::VectorXd unit = Eigen::VectorXd::Zero(num_unknowns);
      unit[kColScale] = 1.0;
      const Eigen::VectorXd column = solver.solve(unit);
      result.scale_sigma = std::sqrt(std::max(0.0, column[kColScale])) / std::abs(scale);
      // The whitened residual at the optimum, |W b|^2 - x^T A^T W^T W b,
      // gives the a-posteriori variance factor (sse / dof): the covariance
      // assumed for the equations (the preintegration's, plus the images'
      // position_sigma_m and rotation_sigma_rad, chosen on the safe side)
      // is rescaled to what the equations show. When they disagree more
      // than assumed (the trajectory's shape or rotations are worse), the
      // scale's uncertainty grows; when they agree better, it shrinks.
      // Hundreds of equations make the factor itself reliable; a shape
      // whose errors are systematic is caught by max_residual_ratio.
      const double sse = std::max(0.0, equations.whitened_b2() - solution.dot(equations.rhs()));
      const int dof = num_rows - num_unknowns;
      result.residual_ratio = std::sqrt(sse / dof);
      // Over few degrees of freedom the factor itself is uncertain (about
      // 1 / sqrt(2 dof) relative): it may widen the sigma, not narrow it.
      result.scale_sigma *=
          dof >= kMinDofToNarrow ? result.residual_ratio : std::max(1.0, result.residual_ratio);
    }
  }
  result.scale = scale;
  result.gravity_in_world = gravity;
  result.num_frames = static_cast<int>(frames_.size());
  result.num_pairs = static_cast<int>(pairs_.size());
  return result;
}

ScaleSolution SolveScale(const std::vector<StampedPose>& poses, const std::vector<size_t>& frames,
                         const std::vector<ImuSample>& imu, const ImuNoise& noise,
                         const ImuScaleOptions& options) {
  ScaleLeastSquares least_squares(poses, frames, noise, options);
  least_squares.Preintegrate(imu);
  return least_squares.Solve();
}

std::string Describe(const ScaleSolution& solution) {
  std::ostringstream message;
  message << std::fixed << std::setprecision(5) << solution.scale << " +- "
          << solution.scale_sigma * solution.scale << " from " << solution.num_pairs
          << " frame pairs (residual " << std::setprecision(2) << solution.residual_ratio
          << " times the expected)";
  return message.str();
}

}  // namespace

ImuScaleResult EstimateImuScale(const Trajectory& world_from_body,
                                const std::vector<ImuSample>& imu, const ImuNoise& noise,
                                const ImuScaleOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  ImuScaleResult result;
  const std::vector<StampedPose>& poses = world_from_body.poses;
  for (size_t k = 1; k < poses.size(); ++k) {
    VIOSFM_CHECK_LT(poses[k - 1].timestamp_ns, poses[k].timestamp_ns);
  }
  if (imu.size() < 2) {
    result.message = "no IMU samples";
    return result;
  }
  // Frames covered by the IMU; the same frames thinned to at least
  // spacing_check_interval_s apart.
  const auto check_interval_ns =
      static_cast<timestamp_ns_t>(std::llround(options.spacing_check_interval_s * 1e9));
  std::vector<size_t> frames;
  std::vector<size_t> spaced_frames;
  for (size_t k = 0; k < poses.size(); ++k) {
    if (poses[k].timestamp_ns < imu.front().timestamp_ns ||
        poses[k].timestamp_ns > imu.back().timestamp_ns) {
      continue;
    }
    frames.push_back(k);
    if (spaced_frames.empty() ||
        poses[k].timestamp_ns - poses[spaced_frames.back()].timestamp_ns >= check_interval_ns) {
      spaced_frames.push_back(k);
    }
  }
  if (frames.size() < 4) {
    result.message = "fewer than 4 frames within the IMU's time span";
    return result;
  }
  ScaleSolution solution = SolveScale(poses, frames, imu, noise, options);
  if (!solution.failure.empty()) {
    result.message = solution.failure;
    return result;
  }
  // The spacing check: over pairs too short for the motion, the frames'
  // jitter shrinks the scale (ImuScaleOptions::spacing_check_interval_s).
  // The spaced frames' scale, not shrunk, is the estimate whenever it is
  // precise enough to be used, and whenever it disagrees with the
  // consecutive frames'; otherwise the consecutive frames' stands.
  std::string spacing_note;
  if (spaced_frames.size() >= 4 && spaced_frames.size() < frames.size()) {
    const ScaleSolution spaced = SolveScale(poses, spaced_frames, imu, noise, options);
    if (spaced.failure.empty()) {
      result.spaced_scale = spaced.scale;
      result.spaced_scale_sigma = spaced.scale_sigma;
      const double difference = std::abs(spaced.scale - solution.scale);
      const double sigma =
          std::hypot(spaced.scale_sigma * spaced.scale, solution.scale_sigma * solution.scale);
      result.spacing_disagrees = difference > options.max_spacing_disagreement * sigma;
      std::ostringstream note;
      note << std::fixed << std::setprecision(5);
      if (result.spacing_disagrees || spaced.scale_sigma <= options.max_scale_sigma) {
        result.spaced_used = true;
        note << " (frames at least " << std::setprecision(2) << options.spacing_check_interval_s
             << " s apart, which the frames' jitter does not shrink; consecutive frames give "
             << std::setprecision(5) << solution.scale << " +- "
             << solution.scale_sigma * solution.scale << ", " << std::setprecision(1)
             << difference / sigma << " sigma apart" << (result.spacing_disagrees ? ": shrunk" : "")
             << ")";
        solution = spaced;
      } else {
        // Agreeing within the noise: said beside the estimate all the same,
        // so that a consecutive frames' figure far from 1 is read with it.
        note << " (frames at least " << std::setprecision(2) << options.spacing_check_interval_s
             << " s apart: " << std::setprecision(5) << spaced.scale << " +- "
             << spaced.scale_sigma * spaced.scale << ", within " << std::setprecision(1)
             << difference / sigma << " sigma)";
      }
      spacing_note = note.str();
    }
  }
  result.scale = solution.scale;
  result.scale_sigma = solution.scale_sigma;
  result.residual_ratio = solution.residual_ratio;
  result.gravity_in_world = solution.gravity_in_world;
  result.num_frames = solution.num_frames;
  result.num_pairs = solution.num_pairs;
  const double scale = result.scale;
  std::ostringstream message;
  message << "IMU scale " << Describe(solution) << spacing_note;
  if (!(scale > 1.0 / options.max_scale_factor && scale < options.max_scale_factor)) {
    message << ": outside [1/" << options.max_scale_factor << ", " << options.max_scale_factor
            << "], not used";
  } else if (!(result.residual_ratio <= options.max_residual_ratio)) {
    message << ": the trajectory's shape disagrees with the IMU more than expected, not used";
  } else if (!(result.scale_sigma <= options.max_scale_sigma)) {
    message << ": too uncertain (more than " << options.max_scale_sigma * 100
            << " %; too little motion or IMU), not used";
  } else {
    result.usable = true;
  }
  result.message = message.str();
  return result;
}

}  // namespace viosfm
