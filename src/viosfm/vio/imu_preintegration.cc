#include "viosfm/vio/imu_preintegration.h"

#include <algorithm>
#include <cmath>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"

namespace viosfm {

std::string ImuPreintegrationOptions::Validate() const {
  if (!(gyro_bias_repropagation_threshold > 0)) {
    return "gyro_bias_repropagation_threshold must be > 0";
  }
  if (!(accel_bias_repropagation_threshold > 0)) {
    return "accel_bias_repropagation_threshold must be > 0";
  }
  return "";
}

ImuSample InterpolateImu(const ImuSample& before, const ImuSample& after, timestamp_ns_t t) {
  VIOSFM_CHECK_LE(before.timestamp_ns, t);
  VIOSFM_CHECK_LE(t, after.timestamp_ns);
  ImuSample sample;
  sample.timestamp_ns = t;
  if (after.timestamp_ns == before.timestamp_ns) {
    sample.gyro = before.gyro;
    sample.accel = before.accel;
    return sample;
  }
  const double s = static_cast<double>(t - before.timestamp_ns) /
                   static_cast<double>(after.timestamp_ns - before.timestamp_ns);
  sample.gyro = (1.0 - s) * before.gyro + s * after.gyro;
  sample.accel = (1.0 - s) * before.accel + s * after.accel;
  return sample;
}

ImuPreintegration::ImuPreintegration(const Eigen::Vector3d& gyro_bias,
                                     const Eigen::Vector3d& accel_bias, const ImuNoise& noise,
                                     const ImuPreintegrationOptions& options)
    : noise_(noise), options_(options), gyro_bias_(gyro_bias), accel_bias_(accel_bias) {
  VIOSFM_CHECK(noise_.Check()) << noise_.Validate();
  VIOSFM_CHECK(options_.Check()) << options_.Validate();
}

void ImuPreintegration::Reset() {
  deltas_ = PreintegratedDeltas();
  delta_t_s_ = 0.0;
  start_ns_ = 0;
  end_ns_ = 0;
  covariance_.setZero();
  dR_dbg_.setZero();
  dv_dbg_.setZero();
  dv_dba_.setZero();
  dp_dbg_.setZero();
  dp_dba_.setZero();
}

void ImuPreintegration::Integrate(const ImuSample& a, const ImuSample& b) {
  IntegrateScaled(a, b, 1.0);
}

void ImuPreintegration::IntegrateScaled(const ImuSample& a, const ImuSample& b,
                                        double noise_scale) {
  Step(a, b, noise_scale);
  steps_.push_back({a, b, noise_scale});
}

void ImuPreintegration::Step(const ImuSample& a, const ImuSample& b, double noise_scale) {
  VIOSFM_CHECK_LT(a.timestamp_ns, b.timestamp_ns);
  const double dt = NsToSeconds(b.timestamp_ns - a.timestamp_ns);
  const double dt2 = dt * dt;
  if (delta_t_s_ == 0.0) start_ns_ = a.timestamp_ns;

  // Nominal midpoint step.
  const Eigen::Vector3d rate = 0.5 * (a.gyro + b.gyro) - gyro_bias_;
  const Eigen::Vector3d phi = rate * dt;
  const Eigen::Quaterniond step_rotation = So3Exp(phi);
  const Eigen::Matrix3d step_R = step_rotation.toRotationMatrix();
  const Eigen::Matrix3d R = deltas_.delta_R.toRotationMatrix();
  const Eigen::Matrix3d R_next = R * step_R;
  const Eigen::Vector3d force_a = a.accel - accel_bias_;
  const Eigen::Vector3d force_b = b.accel - accel_bias_;
  const Eigen::Vector3d acc = 0.5 * (R * force_a + R_next * force_b);

  // Linearisation of the step: error state x = [phi, v, p], inputs the
  // mean rate perturbation (d_rate) and the specific force perturbation
  // (d_force, common to both samples).
  const Eigen::Matrix3d Jr = So3RightJacobian(phi);
  const Eigen::Matrix3d M_phi =
      -0.5 * (R * Hat(force_a) + R_next * Hat(force_b) * step_R.transpose());
  const Eigen::Matrix3d M_rate = -0.5 * R_next * Hat(force_b) * Jr * dt;
  const Eigen::Matrix3d M_force = 0.5 * (R + R_next);

  Matrix9d A = Matrix9d::Identity();
  A.block<3, 3>(0, 0) = step_R.transpose();
  A.block<3, 3>(3, 0) = M_phi * dt;
  A.block<3, 3>(6, 0) = 0.5 * M_phi * dt2;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt;
  Eigen::Matrix<double, 9, 3> B_rate;
  B_rate.block<3, 3>(0, 0) = Jr * dt;
  B_rate.block<3, 3>(3, 0) = M_rate * dt;
  B_rate.block<3, 3>(6, 0) = 0.5 * M_rate * dt2;
  Eigen::Matrix<double, 9, 3> B_force;
  B_force.block<3, 3>(0, 0).setZero();
  B_force.block<3, 3>(3, 0) = M_force * dt;
  B_force.block<3, 3>(6, 0) = 0.5 * M_force * dt2;

  // Covariance: white noise with covariance density^2 / dt on the step's
  // mean rate and mean specific force.
  const double scale2 = noise_scale * noise_scale;
  const double rate_var = scale2 * noise_.gyro_noise_density * noise_.gyro_noise_density / dt;
  const double force_var = scale2 * noise_.accel_noise_density * noise_.accel_noise_density / dt;
  covariance_ = A * covariance_ * A.transpose() + rate_var * B_rate * B_rate.transpose() +
                force_var * B_force * B_force.transpose();

  // Bias Jacobians: d_rate = -d_bg, d_force = -d_ba.
  Matrix96d J;
  J.block<3, 3>(0, 0) = dR_dbg_;
  J.block<3, 3>(0, 3).setZero();
  J.block<3, 3>(3, 0) = dv_dbg_;
  J.block<3, 3>(3, 3) = dv_dba_;
  J.block<3, 3>(6, 0) = dp_dbg_;
  J.block<3, 3>(6, 3) = dp_dba_;
  Matrix96d J_next = A * J;
  J_next.block<9, 3>(0, 0) -= B_rate;
  J_next.block<9, 3>(0, 3) -= B_force;
  dR_dbg_ = J_next.block<3, 3>(0, 0);
  dv_dbg_ = J_next.block<3, 3>(3, 0);
  dv_dba_ = J_next.block<3, 3>(3, 3);
  dp_dbg_ = J_next.block<3, 3>(6, 0);
  dp_dba_ = J_next.block<3, 3>(6, 3);

  // Deltas.
  deltas_.delta_p += deltas_.delta_v * dt + 0.5 * acc * dt2;
  deltas_.delta_v += acc * dt;
  deltas_.delta_R = (deltas_.delta_R * step_rotation).normalized();
  delta_t_s_ += dt;
  end_ns_ = b.timestamp_ns;
}

bool ImuPreintegration::IntegrateRange(const std::vector<ImuSample>& samples, timestamp_ns_t t_from,
                                       timestamp_ns_t t_to) {
  if (t_to <= t_from || samples.size() < 2) return false;
  if (samples.front().timestamp_ns > t_from || samples.back().timestamp_ns < t_to) return false;
  // First sample strictly after t_from (exists since t_to > t_from).
  auto it =
      std::upper_bound(samples.begin(), samples.end(), t_from,
                       [](timestamp_ns_t t, const ImuSample& s) { return t < s.timestamp_ns; });
  VIOSFM_CHECK(it != samples.begin() && it != samples.end());
  // One interval in at least min_parts steps, none longer than kMaxImuStepNs.
  const auto integrate_bridged = [this](const ImuSample& a, const ImuSample& b, int min_parts) {
    const timestamp_ns_t span = b.timestamp_ns - a.timestamp_ns;
    int parts = min_parts;
    if (span > kMaxImuStepNs) {
      parts = std::max(parts, static_cast<int>((span + kImuBridgeStepNs - 1) / kImuBridgeStepNs));
    }
    // Readings interpolated across a gap are far less certain than measured ones.
    const double noise_scale = span > kMaxImuStepNs ? kImuBridgeNoiseScale : 1.0;
    ImuSample from = a;
    for (int k = 1; k <= parts; ++k) {
      const ImuSample to = k == parts ? b : InterpolateImu(a, b, a.timestamp_ns + span * k / parts);
      IntegrateScaled(from, to, noise_scale);
      from = to;
    }
  };
  const bool within_one_interval = it->timestamp_ns >= t_to;
  ImuSample previous = InterpolateImu(*(it - 1), *it, t_from);
  for (; it->timestamp_ns < t_to; ++it) {
    VIOSFM_CHECK_LT(previous.timestamp_ns, it->timestamp_ns) << "IMU stamps must increase";
    integrate_bridged(previous, *it, 1);
    previous = *it;
    VIOSFM_CHECK(it + 1 != samples.end());
  }
  // Now it->timestamp_ns >= t_to > previous.timestamp_ns.
  integrate_bridged(previous, InterpolateImu(previous, *it, t_to), within_one_interval ? 2 : 1);
  return true;
}

void ImuPreintegration::Repropagate(const Eigen::Vector3d& gyro_bias,
                                    const Eigen::Vector3d& accel_bias) {
  gyro_bias_ = gyro_bias;
  accel_bias_ = accel_bias;
  Reset();
  for (const StepSamples& step : steps_) Step(step.a, step.b, step.noise_scale);
}

bool ImuPreintegration::RepropagateIfNeeded(const Eigen::Vector3d& gyro_bias,
                                            const Eigen::Vector3d& accel_bias) {
  if ((gyro_bias - gyro_bias_).norm() <= options_.gyro_bias_repropagation_threshold &&
      (accel_bias - accel_bias_).norm() <= options_.accel_bias_repropagation_threshold) {
    return false;
  }
  Repropagate(gyro_bias, accel_bias);
  return true;
}

Matrix15d ImuPreintegration::FullCovariance() const {
  Matrix15d covariance = Matrix15d::Zero();
  covariance.block<9, 9>(0, 0) = covariance_;
  covariance.block<3, 3>(9, 9) =
      Eigen::Matrix3d::Identity() * noise_.gyro_random_walk * noise_.gyro_random_walk * delta_t_s_;
  covariance.block<3, 3>(12, 12) = Eigen::Matrix3d::Identity() * noise_.accel_random_walk *
                                   noise_.accel_random_walk * delta_t_s_;
  return covariance;
}

bool ImuPreintegration::IsUsable() const {
  if (!deltas_.delta_R.coeffs().allFinite() || !deltas_.delta_v.allFinite() ||
      !deltas_.delta_p.allFinite() || !covariance_.allFinite() || !dR_dbg_.allFinite() ||
      !dv_dbg_.allFinite() || !dv_dba_.allFinite() || !dp_dbg_.allFinite() ||
      !dp_dba_.allFinite() || !std::isfinite(delta_t_s_)) {
    return false;
  }
  const Eigen::LLT<Matrix15d> llt(FullCovariance());
  return llt.info() == Eigen::Success && llt.matrixL().toDenseMatrix().allFinite();
}

Matrix15d ImuPreintegration::SqrtInformation() const {
  const Matrix15d covariance = FullCovariance();
  const Eigen::LLT<Matrix15d> llt(covariance);
  VIOSFM_CHECK(llt.info() == Eigen::Success)
      << "IMU preintegration covariance is not positive definite (zero noise densities or "
         "random walks, or nothing integrated?)";
  return llt.matrixL().solve(Matrix15d::Identity());
}

PreintegratedDeltas ImuPreintegration::Corrected(const Eigen::Vector3d& gyro_bias,
                                                 const Eigen::Vector3d& accel_bias) const {
  const Eigen::Vector3d dbg = gyro_bias - gyro_bias_;
  const Eigen::Vector3d dba = accel_bias - accel_bias_;
  PreintegratedDeltas corrected;
  corrected.delta_R = (deltas_.delta_R * So3Exp(dR_dbg_ * dbg)).normalized();
  corrected.delta_v = deltas_.delta_v + dv_dbg_ * dbg + dv_dba_ * dba;
  corrected.delta_p = deltas_.delta_p + dp_dbg_ * dbg + dp_dba_ * dba;
  return corrected;
}

ImuState ImuPreintegration::Predict(const ImuState& state_i,
                                    const Eigen::Vector3d& gravity_in_world) const {
  const PreintegratedDeltas deltas = Corrected(state_i.gyro_bias, state_i.accel_bias);
  const double dt = delta_t_s_;
  const Eigen::Quaterniond& R_i = state_i.world_from_body.rotation;
  const Eigen::Vector3d& p_i = state_i.world_from_body.translation;
  const Eigen::Vector3d& v_i = state_i.velocity_in_world;
  ImuState state_j = state_i;
  state_j.timestamp_ns = end_ns_;
  state_j.world_from_body.rotation = (R_i * deltas.delta_R).normalized();
  state_j.world_from_body.translation =
      p_i + v_i * dt + 0.5 * gravity_in_world * dt * dt + R_i * deltas.delta_p;
  state_j.velocity_in_world = v_i + gravity_in_world * dt + R_i * deltas.delta_v;
  return state_j;
}

}  // namespace viosfm
