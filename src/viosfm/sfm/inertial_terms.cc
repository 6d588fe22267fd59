#include "viosfm/sfm/inertial_terms.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <sstream>

#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/pose_parameters.h"
#include "viosfm/util/errors.h"
#include "viosfm/vio/imu_factor.h"

namespace viosfm {
namespace {

// The median of the norm of a 9-D standard normal vector (the square root
// of the chi-square median with 9 degrees of freedom, 8.343).
constexpr double kMedianChi9 = 2.8884;
// The same with 3 degrees of freedom.
constexpr double kMedianChi3 = 1.5382;

// The IMU factor on a frame pair's camera poses (cam_from_world blocks), the
// model's scale and the levelling tilt; see the top of inertial_terms.h.
class InertialCost {
 public:
  InertialCost(const ImuPreintegration& preintegration, const Rigid3d& cam_from_body, double weight)
      : factor_(preintegration), cam_from_body_(cam_from_body), weight_(weight) {}

  // Blocks: the two frames' poses (cam_from_world) and velocities, the
  // biases of the first frame's window (both frames take them: the factor's
  // bias rows are zero, the walk between windows is BiasWalkCost's), the
  // scale and the tilt. Residuals: ImuFactor's first 9 (rotation, velocity,
  // position).
  template <typename T>
  bool operator()(const T* cam_from_world_i, const T* velocity_i, const T* cam_from_world_j,
                  const T* velocity_j, const T* biases, const T* scale, const T* tilt,
                  T* residuals) const {
    T pose_i[7];
    T pose_j[7];
    WorldFromBody(cam_from_world_i, scale, tilt, pose_i);
    WorldFromBody(cam_from_world_j, scale, tilt, pose_j);
    T speed_bias_i[9];
    T speed_bias_j[9];
    for (int d = 0; d < 3; ++d) {
      speed_bias_i[d] = velocity_i[d];
      speed_bias_j[d] = velocity_j[d];
    }
    for (int d = 0; d < 6; ++d) speed_bias_i[3 + d] = speed_bias_j[3 + d] = biases[d];
    T full[ImuFactor::kNumResiduals];
    if (!factor_(pose_i, speed_bias_i, pose_j, speed_bias_j, full)) return false;
    for (int k = 0; k < kNumResiduals; ++k) residuals[k] = T(weight_) * full[k];
    return true;
  }

  static constexpr int kNumResiduals = 9;

  static ceres::CostFunction* Create(const ImuPreintegration& preintegration,
                                     const Rigid3d& cam_from_body, double weight) {
    return new ceres::AutoDiffCostFunction<InertialCost, kNumResiduals, 7, 3, 7, 3, 6, 1, 2>(
        new InertialCost(preintegration, cam_from_body, weight));
  }

 private:
  // world'_from_body = [R_tilt R_wb, s R_tilt p_wb] with world_from_body =
  // cam_from_world^-1 * cam_from_body, as [qx, qy, qz, qw, p] (ImuFactor).
  template <typename T>
  void WorldFromBody(const T* cam_from_world, const T* scale, const T* tilt, T* pose) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> q_cw(cam_from_world[3], cam_from_world[0], cam_from_world[1],
                                    cam_from_world[2]);
    const Vector3T t_cw(cam_from_world[4], cam_from_world[5], cam_from_world[6]);
    const Eigen::Quaternion<T> q_wc = q_cw.conjugate();
    const Vector3T p_wc = -(q_wc * t_cw);
    const Eigen::Quaternion<T> q_cb = cam_from_body_.rotation.cast<T>();
    const Vector3T t_cb = cam_from_body_.translation.cast<T>();
    const Eigen::Quaternion<T> q_tilt = QuaternionExp(Vector3T(tilt[0], tilt[1], T(0)));
    const Eigen::Quaternion<T> q_wb = q_tilt * (q_wc * q_cb);
    const Vector3T p_wb = scale[0] * (q_tilt * Vector3T(q_wc * t_cb + p_wc));
    pose[0] = q_wb.x();
    pose[1] = q_wb.y();
    pose[2] = q_wb.z();
    pose[3] = q_wb.w();
    pose[4] = p_wb.x();
    pose[5] = p_wb.y();
    pose[6] = p_wb.z();
  }

  ImuFactor factor_;
  Rigid3d cam_from_body_;
  double weight_;
};

// The biases' random walk between two consecutive windows' biases (gyro,
// accelerometer), whitened by its standard deviation over `seconds`.
class BiasWalkCost {
 public:
  BiasWalkCost(const ImuNoise& noise, double seconds)
      : gyro_sigma_(noise.gyro_random_walk * std::sqrt(seconds)),
        accel_sigma_(noise.accel_random_walk * std::sqrt(seconds)) {}

  template <typename T>
  bool operator()(const T* biases_a, const T* biases_b, T* residuals) const {
    for (int d = 0; d < 3; ++d) {
      residuals[d] = (biases_b[d] - biases_a[d]) / T(gyro_sigma_);
      residuals[3 + d] = (biases_b[3 + d] - biases_a[3 + d]) / T(accel_sigma_);
    }
    return true;
  }

  static ceres::CostFunction* Create(const ImuNoise& noise, double seconds) {
    return new ceres::AutoDiffCostFunction<BiasWalkCost, 6, 6, 6>(new BiasWalkCost(noise, seconds));
  }

 private:
  double gyro_sigma_;
  double accel_sigma_;
};

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace

struct InertialTerms::Factor {
  size_t i = 0;  // frame indices, j = the next frame with a factor
  size_t j = 0;
  ImuPreintegration preintegration;
};

std::string InertialTermOptions::Validate() const {
  if (!(max_gap_s > 0.0)) return "max_gap_s must be > 0";
  if (!(bias_window_s >= 0.0)) return "bias_window_s must be >= 0";
  if (!(max_sigma_factor >= 1.0)) return "max_sigma_factor must be >= 1";
  if (!(max_scale_change > 0.0)) return "max_scale_change must be > 0";
  return "";
}

InertialTerms::InertialTerms(const std::vector<InertialFrame>& frames,
                             const std::vector<ImuSample>& imu, const SensorRig& rig,
                             const Eigen::Vector3d& initial_gyro_bias,
                             const InertialTermOptions& options)
    : frames_(frames), rig_(rig), options_(options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  for (size_t k = 1; k < frames_.size(); ++k) {
    VIOSFM_CHECK_LT(frames_[k - 1].timestamp_ns, frames_[k].timestamp_ns);
  }
  velocity_.assign(frames_.size(), {});
  window_.assign(frames_.size(), 0);
  used_.assign(frames_.size(), false);
  if (!frames_.empty()) {
    // Only the windows that hold a frame get biases (a window shorter than
    // the frames' interval is a pair per frame, not one per window number);
    // bias_window_s = 0: a pair per frame, each window starting at its frame.
    const timestamp_ns_t t0 = frames_.front().timestamp_ns;
    const bool per_frame = options.bias_window_s == 0.0;
    int64_t previous_number = -1;
    for (size_t k = 0; k < frames_.size(); ++k) {
      const double t = static_cast<double>(frames_[k].timestamp_ns - t0) * 1e-9;
      const auto number =
          per_frame ? static_cast<int64_t>(k) : static_cast<int64_t>(t / options.bias_window_s);
      if (number != previous_number) {
        window_start_s_.push_back(per_frame ? t
                                            : static_cast<double>(number) * options.bias_window_s);
      }
      previous_number = number;
      window_[k] = static_cast<int>(window_start_s_.size()) - 1;
    }
    biases_.assign(window_start_s_.size(), {});
  }
  const auto max_gap_ns = static_cast<timestamp_ns_t>(std::llround(options.max_gap_s * 1e9));
  for (size_t k = 0; k + 1 < frames_.size(); ++k) {
    if (frames_[k + 1].timestamp_ns - frames_[k].timestamp_ns > max_gap_ns) continue;
    auto factor = std::make_unique<Factor>(Factor{
        k, k + 1, ImuPreintegration(initial_gyro_bias, Eigen::Vector3d::Zero(), rig.imu_noise)});
    if (imu.size() < 2 ||
        !factor->preintegration.IntegrateRange(imu, rig.CamToImuTime(frames_[k].timestamp_ns),
                                               rig.CamToImuTime(frames_[k + 1].timestamp_ns))) {
      continue;
    }
    used_[k] = used_[k + 1] = true;
    factors_.push_back(std::move(factor));
  }
  // Start: the velocity from the neighbouring frames' body positions, the
  // gyro bias given, no accelerometer bias.
  const Rigid3d cam_from_body = rig.cam_from_body();
  std::vector<Eigen::Vector3d> positions(frames_.size());
  for (size_t k = 0; k < frames_.size(); ++k) {
    positions[k] = (frames_[k].cam_from_world.Inverse() * cam_from_body).translation;
  }
  for (size_t k = 0; k < frames_.size(); ++k) {
    const size_t a = k > 0 ? k - 1 : k;
    const size_t b = k + 1 < frames_.size() ? k + 1 : k;
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    if (b > a) {
      velocity = (positions[b] - positions[a]) /
                 (static_cast<double>(frames_[b].timestamp_ns - frames_[a].timestamp_ns) * 1e-9);
    }
    for (int d = 0; d < 3; ++d) velocity_[k][d] = velocity[d];
  }
  for (std::array<double, 6>& biases : biases_) {
    for (int d = 0; d < 3; ++d) {
      biases[d] = initial_gyro_bias[d];
      biases[3 + d] = 0.0;
    }
  }
}

InertialTerms::~InertialTerms() = default;

double InertialTerms::tilt_rad() const {
  return std::hypot(tilt_[0], tilt_[1]);
}

bool InertialTerms::Initialise(int num_threads, double min_sigma_factor) {
  VIOSFM_CHECK_GE(min_sigma_factor, 1.0);
  if (factors_.size() < 2) {
    refusal_ = "the IMU covers too few frame pairs for its factors";
    return false;
  }
  std::vector<PoseParameters> poses(frames_.size());
  for (size_t k = 0; k < frames_.size(); ++k)
    poses[k] = ToPoseParameters(frames_[k].cam_from_world);
  const Rigid3d cam_from_body = rig_.cam_from_body();
  // Twice: the preintegration is linearised again at the first solution's
  // biases (a bias far from the start makes its first-order correction
  // poor).
  for (int round = 0; round < 2; ++round) {
    ceres::Problem problem;
    for (const std::unique_ptr<Factor>& factor : factors_) {
      problem.AddResidualBlock(InertialCost::Create(factor->preintegration, cam_from_body, 1.0),
                               nullptr, poses[factor->i].data(), velocity_[factor->i].data(),
                               poses[factor->j].data(), velocity_[factor->j].data(),
                               biases_[window_[factor->i]].data(), scale_.data(), tilt_.data());
    }
    AddBiasWalks(&problem, [&](int w) { return biases_[w].data(); });
    for (size_t k = 0; k < frames_.size(); ++k) {
      if (used_[k]) problem.SetParameterBlockConstant(poses[k].data());
    }
    // The scale and the tilt stay at the model's (the VIO's, within a few
    // per cent and a few tenths of a degree): with the poses held, their
    // jitter between consecutive frames looks like accelerations the IMU
    // did not sense, and a free scale would shrink to fit them.
    problem.SetParameterBlockConstant(scale_.data());
    problem.SetParameterBlockConstant(tilt_.data());
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver_options.max_num_iterations = 50;
    solver_options.num_threads = std::max(1, num_threads);
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    for (const std::unique_ptr<Factor>& factor : factors_) {
      const std::array<double, 6>& biases = biases_[window_[factor->i]];
      factor->preintegration.Repropagate(Eigen::Vector3d(biases[0], biases[1], biases[2]),
                                         Eigen::Vector3d(biases[3], biases[4], biases[5]));
    }
  }
  std::vector<Rigid3d> cam_from_world(frames_.size());
  for (size_t k = 0; k < frames_.size(); ++k) cam_from_world[k] = frames_[k].cam_from_world;
  median_whitened_residual_ = MedianWhitenedResidual(cam_from_world);
  // The inflation from the rotations alone: the model's rotations are
  // better than the gyro's over a frame pair, so where they disagree beyond
  // the covariance the rig is to blame (its timing, rolling shutter,
  // camera-IMU rotation), and the rest of the factor shares that; the
  // positions' disagreement is the held poses' own jitter, which the
  // adjustment removes.
  median_whitened_rotation_residual_ = MedianWhitenedRotationResidual(cam_from_world);
  sigma_factor_ = std::max(min_sigma_factor, median_whitened_rotation_residual_ / kMedianChi3);
  if (sigma_factor_ > options_.max_sigma_factor) {
    std::ostringstream refusal;
    refusal << std::fixed << std::setprecision(2)
            << "the model's rotations disagree with the gyro's by "
            << median_whitened_rotation_residual_ << " sigma (median; " << kMedianChi3
            << " expected), more than max_sigma_factor " << options_.max_sigma_factor
            << " times: the rig is further from the IMU model than its factors can take";
    refusal_ = refusal.str();
    return false;
  }
  initialised_ = true;
  return true;
}

double InertialTerms::MedianWhitenedResidual(const std::vector<Rigid3d>& cam_from_world) const {
  VIOSFM_CHECK_EQ(cam_from_world.size(), frames_.size());
  const Rigid3d cam_from_body = rig_.cam_from_body();
  std::vector<double> norms;
  for (const std::unique_ptr<Factor>& factor : factors_) {
    const InertialCost cost(factor->preintegration, cam_from_body, 1.0);
    const PoseParameters pose_i = ToPoseParameters(cam_from_world[factor->i]);
    const PoseParameters pose_j = ToPoseParameters(cam_from_world[factor->j]);
    Eigen::Matrix<double, InertialCost::kNumResiduals, 1> residual =
        Eigen::Matrix<double, InertialCost::kNumResiduals, 1>::Zero();
    cost(pose_i.data(), velocity_[factor->i].data(), pose_j.data(), velocity_[factor->j].data(),
         biases_[window_[factor->i]].data(), scale_.data(), tilt_.data(), residual.data());
    norms.push_back(residual.norm());
  }
  return Median(std::move(norms));
}

double InertialTerms::MedianWhitenedRotationResidual(
    const std::vector<Rigid3d>& cam_from_world) const {
  const Eigen::Quaterniond body_from_cam = rig_.body_from_cam.rotation;
  std::vector<double> norms;
  for (const std::unique_ptr<Factor>& factor : factors_) {
    const ImuPreintegration& preintegration = factor->preintegration;
    const std::array<double, 6>& biases = biases_[window_[factor->i]];
    const PreintegratedDeltas deltas =
        preintegration.Corrected(Eigen::Vector3d(biases[0], biases[1], biases[2]),
                                 Eigen::Vector3d(biases[3], biases[4], biases[5]));
    // body_i_from_body_j = body_from_cam * cam_i_from_world * world_from_cam_j * cam_from_body.
    const Eigen::Quaterniond body_i_from_body_j =
        body_from_cam * cam_from_world[factor->i].rotation *
        cam_from_world[factor->j].rotation.conjugate() * body_from_cam.conjugate();
    const Eigen::Vector3d residual = QuaternionLog(
        Eigen::Quaterniond(deltas.delta_R.conjugate() * body_i_from_body_j).normalized());
    const Eigen::LLT<Eigen::Matrix3d> llt(preintegration.covariance().topLeftCorner<3, 3>());
    if (llt.info() != Eigen::Success) continue;
    norms.push_back(llt.matrixL().solve(residual).norm());
  }
  return Median(std::move(norms));
}

double InertialTerms::MedianWhitenedResidual(const Reconstruction& reconstruction) const {
  std::vector<Rigid3d> cam_from_world(frames_.size());
  for (size_t k = 0; k < frames_.size(); ++k) {
    cam_from_world[k] = reconstruction.GetImage(frames_[k].image_id).cam_from_world;
  }
  return MedianWhitenedResidual(cam_from_world);
}

template <typename Visit>
void InertialTerms::ForEachParameterArray(Visit&& visit) {
  for (size_t k = 0; k < velocity_.size(); ++k) {
    visit(velocity_[k].data(), velocity_[k].size(), VelocityOffset(k));
  }
  for (size_t w = 0; w < biases_.size(); ++w) {
    visit(biases_[w].data(), biases_[w].size(), BiasesOffset(static_cast<int>(w)));
  }
  visit(scale_.data(), scale_.size(), ScaleOffset());
  visit(tilt_.data(), tilt_.size(), TiltOffset());
}

size_t InertialTerms::NumParameters() const {
  return TiltOffset() + tilt_.size();
}

std::vector<double*> InertialTerms::AddTo(ceres::Problem* problem,
                                          const std::function<double*(image_t)>& pose_block,
                                          double* storage) {
  std::vector<double*> blocks;
  if (!initialised_) return blocks;
  ForEachParameterArray([&](const double* own, size_t size, size_t offset) {
    std::copy_n(own, size, storage + offset);
  });
  const auto velocity = [&](size_t k) { return storage + VelocityOffset(k); };
  const auto biases = [&](int w) { return storage + BiasesOffset(w); };
  double* const scale = storage + ScaleOffset();
  double* const tilt = storage + TiltOffset();

  const Rigid3d cam_from_body = rig_.cam_from_body();
  std::vector<bool> velocity_added(frames_.size(), false);
  std::vector<bool> biases_added(biases_.size(), false);
  for (const std::unique_ptr<Factor>& factor : factors_) {
    double* pose_i = pose_block(frames_[factor->i].image_id);
    double* pose_j = pose_block(frames_[factor->j].image_id);
    if (pose_i == nullptr || pose_j == nullptr) continue;
    const int window = window_[factor->i];
    problem->AddResidualBlock(
        InertialCost::Create(factor->preintegration, cam_from_body, 1.0 / sigma_factor_), nullptr,
        pose_i, velocity(factor->i), pose_j, velocity(factor->j), biases(window), scale, tilt);
    for (const size_t k : {factor->i, factor->j}) {
      if (!velocity_added[k]) blocks.push_back(velocity(k));
      velocity_added[k] = true;
    }
    if (!biases_added[window]) blocks.push_back(biases(window));
    biases_added[window] = true;
  }
  if (!blocks.empty()) {
    AddBiasWalks(problem, biases);
    blocks.push_back(scale);
    blocks.push_back(tilt);
  }
  return blocks;
}

void InertialTerms::TakeSolution(const double* storage) {
  if (!initialised_) return;
  ForEachParameterArray(
      [&](double* own, size_t size, size_t offset) { std::copy_n(storage + offset, size, own); });
}

void InertialTerms::AddBiasWalks(ceres::Problem* problem,
                                 const std::function<double*(int)>& biases) const {
  int previous = -1;
  for (int w = 0; w < static_cast<int>(biases_.size()); ++w) {
    if (!problem->HasParameterBlock(biases(w))) continue;
    if (previous >= 0) {
      problem->AddResidualBlock(
          BiasWalkCost::Create(rig_.imu_noise, window_start_s_[w] - window_start_s_[previous]),
          nullptr, biases(previous), biases(w));
    }
    previous = w;
  }
}

Eigen::Vector3d InertialTerms::velocity(size_t k) const {
  return Eigen::Vector3d(velocity_[k][0], velocity_[k][1], velocity_[k][2]);
}

int InertialTerms::BiasWindowOfFrame(size_t k) const {
  std::vector<bool> starts_factor(biases_.size(), false);
  for (const std::unique_ptr<Factor>& factor : factors_) starts_factor[window_[factor->i]] = true;
  int window = window_[k];
  while (window > 0 && !starts_factor[window]) --window;
  return window;
}

Eigen::Vector3d InertialTerms::gyro_bias(size_t k) const {
  const std::array<double, 6>& biases = biases_[BiasWindowOfFrame(k)];
  return Eigen::Vector3d(biases[0], biases[1], biases[2]);
}

Eigen::Vector3d InertialTerms::accel_bias(size_t k) const {
  const std::array<double, 6>& biases = biases_[BiasWindowOfFrame(k)];
  return Eigen::Vector3d(biases[3], biases[4], biases[5]);
}

std::string InertialTerms::Message() const {
  if (!refusal_.empty()) return "no IMU factors: " + refusal_;
  std::ostringstream message;
  message << std::fixed << std::setprecision(2) << factors_.size()
          << " IMU factors between consecutive frames; the model's metric scale "
          << std::setprecision(5) << scale_[0] << ", its tilt " << std::setprecision(3)
          << tilt_rad() * 180.0 / M_PI << " degrees; the poses against the IMU: median "
          << std::setprecision(2) << median_whitened_residual_ << " sigma (" << kMedianChi9
          << " expected)";
  message << ", their rotations " << median_whitened_rotation_residual_ << " sigma (" << kMedianChi3
          << " expected)";
  if (sigma_factor_ > 1.0) message << ", the factors' sigmas multiplied by " << sigma_factor_;
  return message.str();
}

}  // namespace viosfm
