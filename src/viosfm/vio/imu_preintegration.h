// IMU preintegration on the SO(3) manifold (Forster, Carlone, Dellaert,
// Scaramuzza, "On-Manifold Preintegration for Real-Time Visual-Inertial
// Odometry", TRO 2017), with midpoint integration, first-order bias
// Jacobians, covariance propagation and re-propagation on a large bias change.
//
// Conventions:
//  - The body frame is the IMU frame. A state is world_from_body (R, p), the
//    velocity v of the body origin in the world frame and the gyro / accel
//    biases bg, ba (measurement = truth + bias + noise).
//  - The world is z up; gravity is g = (0, 0, -kStandardGravity).
//  - The preintegrated deltas between stamps i and j, computed with the
//    linearisation biases (bg0, ba0), relate the states by
//      R_j = R_i * dR
//      v_j = v_i + g * dt + R_i * dv
//      p_j = p_i + v_i * dt + 0.5 * g * dt^2 + R_i * dp
//  - Error states follow Forster: a right perturbation of the rotation
//    (dR_true = dR * Exp(delta_phi)), additive for velocity and position.
//    The covariance and the Jacobians are ordered [phi (3), v (3), p (3)], and
//    the bias Jacobians as d(delta)/d(bg) and d(delta)/d(ba).
//  - Midpoint integration of one step between samples a and b (dt = tb - ta):
//      w   = (w_a + w_b) / 2 - bg
//      R'  = R * Exp(w * dt)
//      acc = (R * (a_a - ba) + R' * (a_b - ba)) / 2
//      p'  = p + v * dt + acc * dt^2 / 2,   v' = v + acc * dt
//    The bias Jacobians are the exact linearisation of this discrete scheme.
//  - Noise: the white noise of one step is modelled as independent with the
//    continuous-time density (covariance density^2 / dt on the mean rate and
//    the mean specific force of the step), which gives the continuous-time
//    growth density^2 * T regardless of the step length.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

inline Eigen::Vector3d GravityInWorld() {
  return Eigen::Vector3d(0.0, 0.0, -kStandardGravity);
}

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Matrix15d = Eigen::Matrix<double, 15, 15>;
using Matrix96d = Eigen::Matrix<double, 9, 6>;

// The navigation state of the body at one stamp.
struct ImuState {
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d world_from_body;
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();  // m/s
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();          // rad/s
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();         // m/s^2
};

struct ImuPreintegrationOptions {
  // Re-propagate (RepropagateIfNeeded) when a bias moves further than this
  // from the linearisation bias. rad/s, default 0.01.
  double gyro_bias_repropagation_threshold = 0.01;
  // m/s^2, default 0.1.
  double accel_bias_repropagation_threshold = 0.1;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

// The preintegrated deltas, possibly corrected for a bias change.
struct PreintegratedDeltas {
  Eigen::Quaterniond delta_R = Eigen::Quaterniond::Identity();
  Eigen::Vector3d delta_v = Eigen::Vector3d::Zero();
  Eigen::Vector3d delta_p = Eigen::Vector3d::Zero();
};

// ns, the longest interval between IMU samples integrated as one step
// (IntegrateRange; 25 ms: the real RealSense recording's longest is 19.9 ms
// at 200 Hz), and the step of the readings interpolated across a longer gap.
constexpr timestamp_ns_t kMaxImuStepNs = 25'000'000;
constexpr timestamp_ns_t kImuBridgeStepNs = 5'000'000;
// The white noise of an interpolated reading, in standard deviations of a
// measured one: what the motion did during the gap is not known. On the
// real recording with two 0.5 s gaps, 1 and 10 lost track after the first
// gap (178 and 84 frames on the IMU alone, a reset), 30 and 100 tracked
// every frame as without the gaps; a hand's angular rate changes by about
// 0.5 rad/s in half a second, 250 times the gyro's noise in one 5 ms
// reading, its acceleration by 1 to 2 m/s^2, 10 to 20 times the
// accelerometer's.
constexpr double kImuBridgeNoiseScale = 30.0;

class ImuPreintegration {
 public:
  ImuPreintegration(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias,
                    const ImuNoise& noise, const ImuPreintegrationOptions& options = {});

  // One midpoint step between two samples (b strictly after a). Consecutive
  // calls normally chain (the next a is this b), but need not.
  void Integrate(const ImuSample& a, const ImuSample& b);

  // Integrates [t_from, t_to] from samples ordered by strictly increasing
  // stamp; the readings at t_from and t_to are interpolated linearly between
  // the neighbouring samples. A gap between samples longer than
  // kMaxImuStepNs (samples a real IMU dropped) is bridged by readings
  // interpolated linearly every kImuBridgeStepNs, their noise
  // kImuBridgeNoiseScale times a measured reading's, and a range within one
  // interval between samples is integrated in two halves: one step's
  // covariance is singular (its velocity and position noise both come from
  // one reading), which failed every adjustment holding it. Returns false
  // (and integrates nothing) when the samples do not cover [t_from, t_to] or
  // t_to <= t_from.
  [[nodiscard]] bool IntegrateRange(const std::vector<ImuSample>& samples, timestamp_ns_t t_from,
                                    timestamp_ns_t t_to);

  // Integrates again all steps so far with new linearisation biases.
  void Repropagate(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias);
  // Repropagates when either bias differs from the linearisation bias by more
  // than the options' thresholds; returns whether it did.
  bool RepropagateIfNeeded(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias);

  // Deltas at the linearisation biases.
  const Eigen::Quaterniond& delta_R() const { return deltas_.delta_R; }
  const Eigen::Vector3d& delta_v() const { return deltas_.delta_v; }
  const Eigen::Vector3d& delta_p() const { return deltas_.delta_p; }
  // Integrated time, seconds, and its ends (0 before the first step).
  double delta_t_s() const { return delta_t_s_; }
  timestamp_ns_t start_ns() const { return start_ns_; }
  timestamp_ns_t end_ns() const { return end_ns_; }
  int num_steps() const { return static_cast<int>(steps_.size()); }

  const Eigen::Vector3d& linearization_gyro_bias() const { return gyro_bias_; }
  const Eigen::Vector3d& linearization_accel_bias() const { return accel_bias_; }
  const ImuNoise& noise() const { return noise_; }

  // Covariance of [delta_phi, delta_v, delta_p] (rad, m/s, m) from the white
  // measurement noise; biases are fixed over the interval.
  const Matrix9d& covariance() const { return covariance_; }
  // 15x15 covariance of the IMU factor residual [phi, v, p, bg walk, ba walk]:
  // the 9x9 block above and, for the bias changes over the interval, the
  // random walks: walk^2 * dt * I.
  Matrix15d FullCovariance() const;
  // Square-root information: the lower-triangular L^-1 with L L^T =
  // FullCovariance() (Cholesky), so that |L^-1 r|^2 = r^T covariance^-1 r.
  // Requires IsUsable().
  Matrix15d SqrtInformation() const;
  // Whether the deltas, their bias Jacobians and the covariance are finite
  // and the covariance positive definite: false when readings far outside
  // what an IMU reports (or non-finite ones) were integrated, which no
  // factor or prediction may use.
  bool IsUsable() const;

  // Jacobians of the deltas w.r.t. the biases at the linearisation point.
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }

  // First-order bias update of the deltas:
  //   dR(bg) = dR * Exp(dR_dbg * (bg - bg0)),  dv(bg, ba) = dv + dv_dbg (bg - bg0) + dv_dba (ba -
  //   ba0)
  // and likewise for dp.
  PreintegratedDeltas Corrected(const Eigen::Vector3d& gyro_bias,
                                const Eigen::Vector3d& accel_bias) const;

  // The state at end_ns() predicted from `state_i` (at start_ns()) with its
  // biases (bias-corrected deltas); the biases are carried over unchanged.
  ImuState Predict(const ImuState& state_i,
                   const Eigen::Vector3d& gravity_in_world = GravityInWorld()) const;

 private:
  void Reset();
  void Step(const ImuSample& a, const ImuSample& b, double noise_scale = 1.0);
  // Integrate with the step's white noise scaled (readings bridging a gap).
  void IntegrateScaled(const ImuSample& a, const ImuSample& b, double noise_scale);

  ImuNoise noise_;
  ImuPreintegrationOptions options_;
  Eigen::Vector3d gyro_bias_;
  Eigen::Vector3d accel_bias_;

  PreintegratedDeltas deltas_;
  double delta_t_s_ = 0.0;
  timestamp_ns_t start_ns_ = 0;
  timestamp_ns_t end_ns_ = 0;
  Matrix9d covariance_ = Matrix9d::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dba_ = Eigen::Matrix3d::Zero();
  // Every integrated step (a, b), for re-propagation.
  struct StepSamples {
    ImuSample a;
    ImuSample b;
    double noise_scale = 1.0;  // of the white noise's standard deviation
  };
  std::vector<StepSamples> steps_;
};

// The reading at t, interpolated linearly between two samples with
// before.timestamp_ns <= t <= after.timestamp_ns.
ImuSample InterpolateImu(const ImuSample& before, const ImuSample& after, timestamp_ns_t t);

}  // namespace viosfm
