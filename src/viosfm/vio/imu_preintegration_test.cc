#include "viosfm/vio/imu_preintegration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "viosfm/geometry/lie.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/trajectory.h"

namespace viosfm {
namespace {

BodyTrajectory MakeWalk(uint64_t seed) {
  WalkOptions options;
  options.duration_s = 6.0;
  options.static_start_s = 0.0;
  options.speed_mps = 1.0;
  options.seed = seed;
  return GenerateWalk(options);
}

ImuSynthesisOptions NoiseFree(const Eigen::Vector3d& bg, const Eigen::Vector3d& ba) {
  ImuSynthesisOptions options;
  options.add_noise = false;
  options.initial_gyro_bias = bg;
  options.initial_accel_bias = ba;
  return options;
}

// Relative motion the preintegrated deltas must equal (no bias, no noise).
struct TrueDeltas {
  Eigen::Quaterniond delta_R;
  Eigen::Vector3d delta_v;
  Eigen::Vector3d delta_p;
};

TrueDeltas ComputeTrueDeltas(const BodyTrajectory& trajectory, timestamp_ns_t t_i,
                             timestamp_ns_t t_j) {
  const Rigid3d pose_i = trajectory.WorldFromBody(t_i);
  const Rigid3d pose_j = trajectory.WorldFromBody(t_j);
  const Eigen::Vector3d v_i = trajectory.VelocityInWorld(t_i);
  const Eigen::Vector3d v_j = trajectory.VelocityInWorld(t_j);
  const Eigen::Vector3d g = GravityInWorld();
  const double dt = NsToSeconds(t_j - t_i);
  const Eigen::Quaterniond R_i_inv = pose_i.rotation.conjugate();
  TrueDeltas truth;
  truth.delta_R = R_i_inv * pose_j.rotation;
  truth.delta_v = R_i_inv * (v_j - v_i - g * dt);
  truth.delta_p =
      R_i_inv * (pose_j.translation - pose_i.translation - v_i * dt - 0.5 * g * dt * dt);
  return truth;
}

// At rest the simulator's accelerometer reads -g in the body frame and the
// preintegration's gravity vector cancels it: a static second predicts no motion.
TEST(ImuPreintegration, StaticImuPredictsNoMotion) {
  WalkOptions walk;
  walk.duration_s = 3.0;
  walk.static_start_s = 2.5;
  const BodyTrajectory trajectory = GenerateWalk(walk);
  ImuSynthesisOptions options;
  options.add_noise = false;
  const SynthesizedImu imu = SynthesizeImu(trajectory, trajectory.start_ns(),
                                           trajectory.start_ns() + SecondsToNs(2.0), options);
  ImuPreintegration preintegration(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  ASSERT_TRUE(preintegration.IntegrateRange(imu.samples, trajectory.start_ns(),
                                            trajectory.start_ns() + SecondsToNs(1.0)));
  const Eigen::Vector3d g = GravityInWorld();
  const Eigen::Matrix3d R =
      trajectory.WorldFromBody(trajectory.start_ns()).rotation.toRotationMatrix();
  // delta_v = R^T (v_j - v_i - g dt) = -R^T g dt for a body at rest.
  EXPECT_LT((preintegration.delta_v() + R.transpose() * g * 1.0).norm(), 1e-9);
  EXPECT_LT(So3Log(preintegration.delta_R()).norm(), 1e-12);
}

TEST(ImuPreintegration, NoiseFreeReproducesGroundTruthMotion) {
  const BodyTrajectory trajectory = MakeWalk(3);
  const Eigen::Vector3d bg(0.01, -0.02, 0.015);
  const Eigen::Vector3d ba(0.1, -0.05, 0.08);
  const timestamp_ns_t start = trajectory.start_ns();
  const SynthesizedImu imu =
      SynthesizeImu(trajectory, start, start + SecondsToNs(5.0), NoiseFree(bg, ba));
  // Stamps off the 200 Hz grid: the ends are interpolated.
  const timestamp_ns_t t_i = start + SecondsToNs(1.2345678);
  const timestamp_ns_t t_j = t_i + SecondsToNs(1.0);
  ImuPreintegration preintegration(bg, ba, ImuNoise());
  ASSERT_TRUE(preintegration.IntegrateRange(imu.samples, t_i, t_j));
  EXPECT_NEAR(preintegration.delta_t_s(), 1.0, 1e-12);
  EXPECT_EQ(preintegration.start_ns(), t_i);
  EXPECT_EQ(preintegration.end_ns(), t_j);
  EXPECT_EQ(preintegration.num_steps(), 201);

  const TrueDeltas truth = ComputeTrueDeltas(trajectory, t_i, t_j);
  const double rotation_error = So3Log(truth.delta_R.conjugate() * preintegration.delta_R()).norm();
  const double velocity_error = (truth.delta_v - preintegration.delta_v()).norm();
  const double position_error = (truth.delta_p - preintegration.delta_p()).norm();
  std::cout << "1 s of noise-free 200 Hz IMU: rotation error " << rotation_error << " rad (of "
            << So3Log(truth.delta_R).norm() << "), velocity error " << velocity_error << " m/s (of "
            << truth.delta_v.norm() << "), position error " << position_error << " m (of "
            << truth.delta_p.norm() << ")\n";
  EXPECT_LT(rotation_error, 1e-4);
  EXPECT_LT(velocity_error, 1e-3);
  EXPECT_LT(position_error, 1e-3);
  // The motion is not trivial.
  EXPECT_GT(So3Log(truth.delta_R).norm(), 0.05);
  EXPECT_GT(truth.delta_v.norm(), 5.0);

  // Predict() gives the true state at t_j.
  ImuState state_i;
  state_i.timestamp_ns = t_i;
  state_i.world_from_body = trajectory.WorldFromBody(t_i);
  state_i.velocity_in_world = trajectory.VelocityInWorld(t_i);
  state_i.gyro_bias = bg;
  state_i.accel_bias = ba;
  const ImuState state_j = preintegration.Predict(state_i);
  EXPECT_EQ(state_j.timestamp_ns, t_j);
  EXPECT_LT((state_j.world_from_body.translation - trajectory.PositionInWorld(t_j)).norm(), 1e-3);
  EXPECT_LT((state_j.velocity_in_world - trajectory.VelocityInWorld(t_j)).norm(), 1e-3);
  EXPECT_LT(
      So3Log(state_j.world_from_body.rotation.conjugate() * trajectory.WorldFromBody(t_j).rotation)
          .norm(),
      1e-4);
}

TEST(ImuPreintegration, IntegrateRangeNeedsCoverage) {
  const BodyTrajectory trajectory = MakeWalk(4);
  const timestamp_ns_t start = trajectory.start_ns();
  const SynthesizedImu imu =
      SynthesizeImu(trajectory, start, start + SecondsToNs(1.0),
                    NoiseFree(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
  ImuPreintegration preintegration(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  EXPECT_FALSE(preintegration.IntegrateRange(imu.samples, start - 1, start + SecondsToNs(0.5)));
  EXPECT_FALSE(preintegration.IntegrateRange(imu.samples, start, start + SecondsToNs(1.5)));
  EXPECT_FALSE(preintegration.IntegrateRange(imu.samples, start + 10, start + 10));
  EXPECT_EQ(preintegration.num_steps(), 0);
  // Ends on samples: no interpolated step of zero length.
  ASSERT_TRUE(preintegration.IntegrateRange(imu.samples, start, start + SecondsToNs(0.5)));
  EXPECT_EQ(preintegration.num_steps(), 100);
}

// Samples a real IMU dropped: a range across a 0.2 s gap is bridged by
// readings interpolated every 5 ms, and a range within one interval between
// samples is integrated in two halves, so that the covariance is positive
// definite (one step's is singular: its velocity and position noise come
// from one reading; the VIO failed on such a recording with an internal
// error). Ranges over the 200 Hz samples themselves keep their steps.
TEST(ImuPreintegration, GapsAndShortRangesGiveAPositiveDefiniteCovariance) {
  const BodyTrajectory trajectory = MakeWalk(4);
  const timestamp_ns_t start = trajectory.start_ns();
  const SynthesizedImu imu =
      SynthesizeImu(trajectory, start, start + SecondsToNs(1.0),
                    NoiseFree(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
  std::vector<ImuSample> with_gap;
  const timestamp_ns_t gap_from = start + SecondsToNs(0.4);
  const timestamp_ns_t gap_to = start + SecondsToNs(0.6);
  for (const ImuSample& sample : imu.samples) {
    if (sample.timestamp_ns <= gap_from || sample.timestamp_ns >= gap_to) {
      with_gap.push_back(sample);
    }
  }
  // A frame pair inside the gap (0.45 to 0.5 s): one interval, 0.05 s of it.
  ImuPreintegration inside(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  ASSERT_TRUE(inside.IntegrateRange(with_gap, start + SecondsToNs(0.45), start + SecondsToNs(0.5)));
  EXPECT_EQ(inside.num_steps(), 10);  // 50 ms in steps of at most 5 ms
  EXPECT_TRUE(inside.SqrtInformation().allFinite());
  // Across the gap (0.3 to 0.7 s): 20 samples' steps each side, 40 bridging.
  ImuPreintegration across(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  ASSERT_TRUE(across.IntegrateRange(with_gap, start + SecondsToNs(0.3), start + SecondsToNs(0.7)));
  EXPECT_EQ(across.num_steps(), 80);
  EXPECT_TRUE(across.SqrtInformation().allFinite());
  // The interpolated readings count 30 times a measured one's noise: the
  // position across the gap is known far less well than with the samples.
  ImuPreintegration measured(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  ASSERT_TRUE(
      measured.IntegrateRange(imu.samples, start + SecondsToNs(0.3), start + SecondsToNs(0.7)));
  EXPECT_EQ(measured.num_steps(), 80);
  const double bridged_position_var = across.covariance().block(6, 6, 3, 3).trace();
  const double measured_position_var = measured.covariance().block(6, 6, 3, 3).trace();
  EXPECT_GT(bridged_position_var, 100.0 * measured_position_var);
  // Within one 5 ms interval of the 200 Hz samples: two halves.
  ImuPreintegration short_range(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  ASSERT_TRUE(short_range.IntegrateRange(imu.samples, start + SecondsToNs(0.1) + 1'000'000,
                                         start + SecondsToNs(0.1) + 3'000'000));
  EXPECT_EQ(short_range.num_steps(), 2);
  EXPECT_TRUE(short_range.SqrtInformation().allFinite());
}

// Central finite differences of re-integration with perturbed biases.
TEST(ImuPreintegration, BiasJacobiansMatchFiniteDifferences) {
  const BodyTrajectory trajectory = MakeWalk(5);
  const timestamp_ns_t start = trajectory.start_ns();
  const Eigen::Vector3d bg(0.003, -0.004, 0.002);
  const Eigen::Vector3d ba(0.05, 0.02, -0.04);
  const SynthesizedImu imu =
      SynthesizeImu(trajectory, start, start + SecondsToNs(3.0), NoiseFree(bg, ba));
  const timestamp_ns_t t_i = start + SecondsToNs(0.7);
  const timestamp_ns_t t_j = t_i + SecondsToNs(1.0);
  auto integrate = [&](const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias) {
    ImuPreintegration p(gyro_bias, accel_bias, ImuNoise());
    VIOSFM_CHECK(p.IntegrateRange(imu.samples, t_i, t_j));
    return p;
  };
  const ImuPreintegration nominal = integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  Matrix96d numeric;
  const double h = 1e-5;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix<double, 6, 1> delta = Eigen::Matrix<double, 6, 1>::Zero();
    delta[k] = h;
    const ImuPreintegration plus = integrate(delta.head<3>(), delta.tail<3>());
    const ImuPreintegration minus = integrate(-delta.head<3>(), -delta.tail<3>());
    numeric.block<3, 1>(0, k) = (So3Log(nominal.delta_R().conjugate() * plus.delta_R()) -
                                 So3Log(nominal.delta_R().conjugate() * minus.delta_R())) /
                                (2 * h);
    numeric.block<3, 1>(3, k) = (plus.delta_v() - minus.delta_v()) / (2 * h);
    numeric.block<3, 1>(6, k) = (plus.delta_p() - minus.delta_p()) / (2 * h);
  }
  struct Block {
    const char* name;
    Eigen::Matrix3d analytic;
    Eigen::Matrix3d numeric;
  };
  const Block blocks[] = {
      {"dR/dbg", nominal.dR_dbg(), numeric.block<3, 3>(0, 0)},
      {"dv/dbg", nominal.dv_dbg(), numeric.block<3, 3>(3, 0)},
      {"dv/dba", nominal.dv_dba(), numeric.block<3, 3>(3, 3)},
      {"dp/dbg", nominal.dp_dbg(), numeric.block<3, 3>(6, 0)},
      {"dp/dba", nominal.dp_dba(), numeric.block<3, 3>(6, 3)},
  };
  for (const Block& block : blocks) {
    const double relative = (block.analytic - block.numeric).norm() / block.numeric.norm();
    std::cout << block.name << ": relative difference to finite differences " << relative
              << " (norm " << block.numeric.norm() << ")\n";
    EXPECT_LT(relative, 1e-3) << block.name << "\nanalytic\n"
                              << block.analytic << "\nnumeric\n"
                              << block.numeric;
  }
  // The rotation does not depend on the accel bias.
  EXPECT_LT((numeric.block<3, 3>(0, 3).norm()), 1e-9);
}

TEST(ImuPreintegration, CorrectedMatchesRepropagation) {
  const BodyTrajectory trajectory = MakeWalk(6);
  const timestamp_ns_t start = trajectory.start_ns();
  const SynthesizedImu imu =
      SynthesizeImu(trajectory, start, start + SecondsToNs(2.0),
                    NoiseFree(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
  ImuPreintegration preintegration(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  ASSERT_TRUE(preintegration.IntegrateRange(imu.samples, start + SecondsToNs(0.5),
                                            start + SecondsToNs(1.5)));
  const Eigen::Vector3d bg(0.004, -0.003, 0.005);
  const Eigen::Vector3d ba(0.03, 0.05, -0.02);
  const PreintegratedDeltas corrected = preintegration.Corrected(bg, ba);
  const PreintegratedDeltas nominal =
      preintegration.Corrected(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  // Small change: no re-propagation.
  EXPECT_FALSE(preintegration.RepropagateIfNeeded(bg, ba));
  EXPECT_EQ(preintegration.linearization_gyro_bias(), Eigen::Vector3d::Zero());
  preintegration.Repropagate(bg, ba);
  EXPECT_EQ(preintegration.linearization_gyro_bias(), bg);
  const double rotation_error =
      So3Log(corrected.delta_R.conjugate() * preintegration.delta_R()).norm();
  const double velocity_error = (corrected.delta_v - preintegration.delta_v()).norm();
  const double position_error = (corrected.delta_p - preintegration.delta_p()).norm();
  std::cout << "first-order bias correction vs re-propagation (|dbg| " << bg.norm()
            << " rad/s, |dba| " << ba.norm() << " m/s^2): " << rotation_error << " rad, "
            << velocity_error << " m/s, " << position_error << " m\n";
  // The first-order update leaves a second-order error: a small fraction of
  // the bias effect itself.
  const double rotation_change =
      So3Log(nominal.delta_R.conjugate() * preintegration.delta_R()).norm();
  const double velocity_change = (nominal.delta_v - preintegration.delta_v()).norm();
  const double position_change = (nominal.delta_p - preintegration.delta_p()).norm();
  std::cout << "  bias effect: " << rotation_change << " rad, " << velocity_change << " m/s, "
            << position_change << " m\n";
  EXPECT_LT(rotation_error, 0.01 * rotation_change);
  EXPECT_LT(velocity_error, 0.01 * velocity_change);
  EXPECT_LT(position_error, 0.01 * position_change);
  // Corrected() at the linearisation bias is the identity.
  const PreintegratedDeltas same = preintegration.Corrected(bg, ba);
  EXPECT_LT((same.delta_v - preintegration.delta_v()).norm(), 1e-15);
  // A large change re-propagates.
  EXPECT_TRUE(preintegration.RepropagateIfNeeded(bg + Eigen::Vector3d(0.02, 0, 0), ba));
  EXPECT_TRUE(preintegration.RepropagateIfNeeded(bg, ba + Eigen::Vector3d(0, 0.2, 0)));
  EXPECT_EQ(preintegration.linearization_accel_bias(), ba + Eigen::Vector3d(0, 0.2, 0));
}

// Sample covariance of the preintegration error over noisy IMU realisations
// against the propagated covariance.
TEST(ImuPreintegration, CovarianceMatchesMonteCarlo) {
  const BodyTrajectory trajectory = MakeWalk(7);
  const timestamp_ns_t start = trajectory.start_ns();
  const timestamp_ns_t t_i = start + SecondsToNs(1.0);
  const timestamp_ns_t t_j = t_i + SecondsToNs(1.0);
  ImuNoise noise;  // EuRoC densities, no bias walk (the biases are fixed in the interval)
  noise.gyro_random_walk = 0.0;
  noise.accel_random_walk = 0.0;
  const Eigen::Vector3d bg(0.002, 0.001, -0.003);
  const Eigen::Vector3d ba(0.02, -0.01, 0.03);

  ImuSynthesisOptions exact = NoiseFree(bg, ba);
  exact.noise = noise;
  const SynthesizedImu imu = SynthesizeImu(trajectory, t_i, t_j, exact);
  ImuPreintegration reference(bg, ba, noise);
  ASSERT_TRUE(reference.IntegrateRange(imu.samples, t_i, t_j));

  const int kRuns = 500;
  Matrix9d sample_covariance = Matrix9d::Zero();
  for (int run = 0; run < kRuns; ++run) {
    ImuSynthesisOptions noisy = exact;
    noisy.add_noise = true;
    noisy.seed = 1000 + run;
    const SynthesizedImu noisy_imu = SynthesizeImu(trajectory, t_i, t_j, noisy);
    ImuPreintegration preintegration(bg, ba, noise);
    ASSERT_TRUE(preintegration.IntegrateRange(noisy_imu.samples, t_i, t_j));
    Vector9d error;
    error.head<3>() = So3Log(reference.delta_R().conjugate() * preintegration.delta_R());
    error.segment<3>(3) = preintegration.delta_v() - reference.delta_v();
    error.tail<3>() = preintegration.delta_p() - reference.delta_p();
    sample_covariance += error * error.transpose();
  }
  sample_covariance /= kRuns;
  const Matrix9d& propagated = reference.covariance();
  for (int k = 0; k < 9; ++k) {
    const double ratio = sample_covariance(k, k) / propagated(k, k);
    std::cout << "covariance diagonal " << k << ": Monte-Carlo " << sample_covariance(k, k)
              << ", propagated " << propagated(k, k) << ", ratio " << ratio << "\n";
    EXPECT_NEAR(ratio, 1.0, 0.2) << "diagonal entry " << k;
  }
  // Continuous-time check: the rotation variance grows as density^2 * T.
  EXPECT_NEAR(propagated(0, 0), noise.gyro_noise_density * noise.gyro_noise_density * 1.0,
              0.05 * noise.gyro_noise_density * noise.gyro_noise_density);

  // The full covariance adds the bias random walks; its square-root
  // information whitens it.
  ImuPreintegration with_walk(bg, ba, ImuNoise());
  ASSERT_TRUE(with_walk.IntegrateRange(imu.samples, t_i, t_j));
  const Matrix15d full = with_walk.FullCovariance();
  EXPECT_NEAR(full(9, 9), std::pow(ImuNoise().gyro_random_walk, 2) * 1.0, 1e-18);
  EXPECT_NEAR(full(14, 14), std::pow(ImuNoise().accel_random_walk, 2) * 1.0, 1e-15);
  const Matrix15d sqrt_information = with_walk.SqrtInformation();
  EXPECT_LT((sqrt_information * full * sqrt_information.transpose() - Matrix15d::Identity())
                .cwiseAbs()
                .maxCoeff(),
            1e-6);
}

}  // namespace
}  // namespace viosfm
