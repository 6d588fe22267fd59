#include "viosfm/sfm/gyro_priors.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <memory>
#include <optional>
#include <sstream>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// The median of the norm of a 3-D standard normal vector (chi with 3
// degrees of freedom).
constexpr double kMedianChi3 = 1.5382;

}  // namespace

std::string GyroPriorOptions::Validate() const {
  if (!(bias_window_s > 0.0)) return "bias_window_s must be > 0";
  if (!(frame_rotation_sigma_rad > 0.0)) return "frame_rotation_sigma_rad must be > 0";
  if (!(rotation_floor_rad >= 0.0)) return "rotation_floor_rad must be >= 0";
  if (!(max_gap_s > 0.0)) return "max_gap_s must be > 0";
  return "";
}

std::vector<Eigen::Vector3d> EstimateGyroBiases(const std::vector<GyroPair>& pairs, int num_windows,
                                                double frame_rotation_sigma_rad,
                                                const ImuNoise& noise,
                                                std::vector<double>* bias_sigma) {
  VIOSFM_CHECK(num_windows >= 1);
  std::vector<Eigen::Matrix3d> normal(num_windows, Eigen::Matrix3d::Zero());
  std::vector<Eigen::Vector3d> rhs(num_windows, Eigen::Vector3d::Zero());
  for (const GyroPair& pair : pairs) {
    VIOSFM_CHECK(pair.window >= 0 && pair.window < num_windows);
    const ImuPreintegration& p = *pair.preintegration;
    const Eigen::Matrix3d measured = pair.world_from_body_i.transpose() * pair.world_from_body_j;
    const Eigen::Vector3d error = QuaternionLog(
        Eigen::Quaterniond(p.delta_R().toRotationMatrix().transpose() * measured).normalized());
    const Eigen::Matrix3d& jacobian = p.dR_dbg();
    const double dt = p.delta_t_s();
    // Rotation noise of the preintegration and of the two frames, and the
    // bias walking within the pair.
    const double sigma2 = p.covariance().topLeftCorner<3, 3>().trace() / 3.0 +
                          2.0 * frame_rotation_sigma_rad * frame_rotation_sigma_rad + 1e-12 +
                          std::pow(noise.gyro_random_walk, 2) * dt * dt * dt / 3.0;
    normal[pair.window] += jacobian.transpose() * jacobian / sigma2;
    rhs[pair.window] += jacobian.transpose() * error / sigma2;
  }
  std::vector<Eigen::Vector3d> biases(num_windows, Eigen::Vector3d::Zero());
  std::vector<bool> solved(num_windows, false);
  for (int w = 0; w < num_windows; ++w) {
    if (!(normal[w].trace() > 0.0)) continue;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal[w]);
    if (ldlt.info() != Eigen::Success) continue;
    biases[w] = ldlt.solve(rhs[w]);
    solved[w] = true;
  }
  // The bias's uncertainty. The least squares takes the pairs' errors as
  // independent, but consecutive pairs share their frames: the frames'
  // noise telescopes, and what pins a window's mean rate is the noise of
  // its two ends over the time between them (sqrt(2) sigma / T), to which
  // the bias's walk within the window adds. A window without pairs takes
  // the nearest solved window's bias, with the walk over the distance.
  std::vector<double> covered_s(num_windows, 0.0);
  {
    std::vector<timestamp_ns_t> first(num_windows, 0);
    std::vector<timestamp_ns_t> last(num_windows, 0);
    for (const GyroPair& pair : pairs) {
      const int w = pair.window;
      if (first[w] == last[w] || pair.preintegration->start_ns() < first[w]) {
        first[w] = pair.preintegration->start_ns();
      }
      last[w] = std::max(last[w], pair.preintegration->end_ns());
    }
    for (int w = 0; w < num_windows; ++w) {
      covered_s[w] = static_cast<double>(last[w] - first[w]) * 1e-9;
    }
  }
  if (bias_sigma != nullptr) bias_sigma->assign(num_windows, 0.0);
  std::vector<Eigen::Vector3d> filled = biases;
  for (int w = 0; w < num_windows; ++w) {
    int source = w;
    if (!solved[w]) {
      int best = -1;
      for (int v = 0; v < num_windows; ++v) {
        if (solved[v] && (best < 0 || std::abs(v - w) < std::abs(best - w))) best = v;
      }
      if (best < 0) continue;  // nothing solved: zero bias, sigma 0 (no pairs either)
      source = best;
      filled[w] = biases[best];
    }
    if (bias_sigma == nullptr) continue;
    const double span = std::max(covered_s[source], 1e-3);
    const double frames2 = 2.0 * std::pow(frame_rotation_sigma_rad / span, 2);
    // The walk over a third of the window, and over the windows between.
    const double walk_s = span / 3.0 + std::abs(source - w) * span;
    (*bias_sigma)[w] = std::sqrt(frames2 + std::pow(noise.gyro_random_walk, 2) * walk_s);
  }
  return filled;
}

namespace {

// The gyro's relative-rotation prior of one pair of frames, and the
// reconstruction's whitened residual against it.
struct PairPrior {
  RelativePosePrior prior;
  double whitened_residual = 0.0;
};

// The prior of frames 1 and 2 from their pair's preintegration (its gyro
// bias already corrected, of standard error bias_sigma); none when its
// covariance is not positive definite.
std::optional<PairPrior> GyroPairPrior(const ImuPreintegration& preintegration, double bias_sigma,
                                       const GyroFrame& frame1, const GyroFrame& frame2,
                                       const Eigen::Matrix3d& body_from_cam, const ImuNoise& noise,
                                       const GyroPriorOptions& options) {
  const double dt = preintegration.delta_t_s();
  // Covariance of the body rotation's error (in body j's frame): the
  // white noise, the bias's uncertainty and its walk from the window's
  // value, and the floor.
  const Eigen::Matrix3d& jacobian = preintegration.dR_dbg();
  const double walk2 = std::pow(noise.gyro_random_walk, 2) * (0.5 * options.bias_window_s + dt);
  Eigen::Matrix3d covariance =
      preintegration.covariance().topLeftCorner<3, 3>() +
      std::pow(bias_sigma, 2) * jacobian * jacobian.transpose() +
      walk2 * dt * dt * Eigen::Matrix3d::Identity() +
      std::pow(options.rotation_floor_rad, 2) * Eigen::Matrix3d::Identity();
  // cam2_from_cam1 = cam_from_body * body_j_from_body_i * body_from_cam,
  // body_j_from_body_i = delta_R^T; the error, a left perturbation in
  // camera 2's frame, has the covariance turned into the camera's frame.
  const Eigen::Matrix3d delta_r = preintegration.delta_R().toRotationMatrix();
  const Eigen::Matrix3d cam2_from_cam1 =
      body_from_cam.transpose() * delta_r.transpose() * body_from_cam;
  covariance = body_from_cam.transpose() * covariance * body_from_cam;
  const Eigen::LLT<Eigen::Matrix3d> llt(covariance);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const Eigen::Matrix3d sqrt_information = llt.matrixL().solve(Eigen::Matrix3d::Identity());

  RelativePosePrior prior;
  prior.image_id1 = frame1.image_id;
  prior.image_id2 = frame2.image_id;
  prior.cam2_from_cam1 =
      Rigid3d(Eigen::Quaterniond(cam2_from_cam1).normalized(), Eigen::Vector3d::Zero());
  prior.rotation_only = true;
  prior.from_gyro = true;
  Eigen::Matrix<double, 6, 6> sqrt_information6 = Eigen::Matrix<double, 6, 6>::Zero();
  sqrt_information6.topLeftCorner<3, 3>() = sqrt_information;
  prior.sqrt_information = sqrt_information6;
  // The reconstruction's relative rotation against the prior.
  const Eigen::Quaterniond model_cam2_from_cam1 =
      frame2.cam_from_world.rotation * frame1.cam_from_world.rotation.conjugate();
  const Eigen::Vector3d residual = QuaternionLog(
      (model_cam2_from_cam1 * prior.cam2_from_cam1.rotation.conjugate()).normalized());
  return PairPrior{std::move(prior), (sqrt_information * residual).norm()};
}

}  // namespace

GyroPriors MakeGyroPriors(const std::vector<GyroFrame>& frames, const std::vector<ImuSample>& imu,
                          const SensorRig& rig, const GyroPriorOptions& options,
                          double min_sigma_factor) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  VIOSFM_CHECK_GE(min_sigma_factor, 1.0);
  GyroPriors result;
  for (size_t k = 1; k < frames.size(); ++k) {
    VIOSFM_CHECK_LT(frames[k - 1].timestamp_ns, frames[k].timestamp_ns);
  }
  if (frames.size() < 3 || imu.size() < 2) {
    result.message = "too few frames or IMU samples for the gyro's priors";
    return result;
  }
  const Eigen::Matrix3d body_from_cam = rig.body_from_cam.rotation.toRotationMatrix();
  const auto world_from_body = [&](const GyroFrame& frame) {
    return Eigen::Matrix3d(frame.cam_from_world.rotation.toRotationMatrix().transpose() *
                           body_from_cam.transpose());
  };
  const timestamp_ns_t t0 = rig.CamToImuTime(frames.front().timestamp_ns);
  const auto window_of = [&](timestamp_ns_t t_imu) {
    return static_cast<int>(static_cast<double>(t_imu - t0) * 1e-9 / options.bias_window_s);
  };
  const int num_windows = window_of(rig.CamToImuTime(frames.back().timestamp_ns)) + 1;
  const auto max_gap_ns = static_cast<timestamp_ns_t>(std::llround(options.max_gap_s * 1e9));

  std::vector<std::unique_ptr<ImuPreintegration>> preintegrations;
  std::vector<size_t> first_frame;  // per pair, index of frame i (j = i + 1)
  std::vector<GyroPair> pairs;
  for (size_t k = 0; k + 1 < frames.size(); ++k) {
    if (frames[k + 1].timestamp_ns - frames[k].timestamp_ns > max_gap_ns) continue;
    const timestamp_ns_t t_i = rig.CamToImuTime(frames[k].timestamp_ns);
    const timestamp_ns_t t_j = rig.CamToImuTime(frames[k + 1].timestamp_ns);
    auto preintegration = std::make_unique<ImuPreintegration>(
        Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), rig.imu_noise);
    if (!preintegration->IntegrateRange(imu, t_i, t_j)) continue;
    pairs.push_back({preintegration.get(), world_from_body(frames[k]),
                     world_from_body(frames[k + 1]), window_of(t_i)});
    first_frame.push_back(k);
    preintegrations.push_back(std::move(preintegration));
  }
  if (pairs.size() < 2) {
    result.message = "the IMU covers too few frame pairs for the gyro's priors";
    return result;
  }
  std::vector<GyroPair> supported_pairs;
  for (size_t p = 0; p < pairs.size(); ++p) {
    if (frames[first_frame[p]].supported && frames[first_frame[p] + 1].supported) {
      supported_pairs.push_back(pairs[p]);
    }
  }
  std::vector<double> bias_sigma;
  result.gyro_biases = EstimateGyroBiases(
      supported_pairs, num_windows, options.frame_rotation_sigma_rad, rig.imu_noise, &bias_sigma);

  std::vector<double> whitened;
  for (size_t p = 0; p < pairs.size(); ++p) {
    ImuPreintegration& preintegration = *preintegrations[p];
    const int window = pairs[p].window;
    preintegration.Repropagate(result.gyro_biases[window], Eigen::Vector3d::Zero());
    const std::optional<PairPrior> pair_prior =
        GyroPairPrior(preintegration, bias_sigma[window], frames[first_frame[p]],
                      frames[first_frame[p] + 1], body_from_cam, rig.imu_noise, options);
    if (!pair_prior) continue;
    whitened.push_back(pair_prior->whitened_residual);
    result.priors.push_back(pair_prior->prior);
  }
  if (!whitened.empty()) {
    std::nth_element(whitened.begin(), whitened.begin() + whitened.size() / 2, whitened.end());
    result.median_whitened_residual = whitened[whitened.size() / 2];
  }
  // Where the reconstruction's rotations and the gyro's disagree by more
  // than the covariance allows (a real rig: the camera-IMU rotation's error,
  // the clock offset's, a rolling shutter), the priors' covariance is
  // inflated by the ratio (the a-posteriori variance factor, from the median
  // so that a stretch the VIO alone held does not count); never narrowed.
  result.sigma_factor = std::max(min_sigma_factor, result.median_whitened_residual / kMedianChi3);
  for (RelativePosePrior& prior : result.priors) {
    *prior.sqrt_information /= result.sigma_factor;
  }
  std::ostringstream message;
  message << std::fixed << std::setprecision(2) << result.priors.size()
          << " gyro rotation priors, biases from " << supported_pairs.size()
          << " pairs of frames the images support in " << num_windows
          << " window(s); the reconstruction's "
          << "rotations against them: median " << result.median_whitened_residual << " sigma ("
          << kMedianChi3 << " expected)";
  if (result.sigma_factor > 1.0) {
    message << ", their sigmas multiplied by " << result.sigma_factor;
  }
  result.message = message.str();
  return result;
}

}  // namespace viosfm
