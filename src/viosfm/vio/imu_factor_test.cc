#include "viosfm/vio/imu_factor.h"

#include <ceres/gradient_checker.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include <iostream>
#include <memory>

#include "viosfm/geometry/lie.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

BodyTrajectory MakeWalk(uint64_t seed) {
  WalkOptions options;
  options.duration_s = 5.0;
  options.static_start_s = 0.0;
  options.speed_mps = 1.0;
  options.seed = seed;
  return GenerateWalk(options);
}

SynthesizedImu NoiseFreeImu(const BodyTrajectory& trajectory, double rate_hz,
                            const Eigen::Vector3d& bg, const Eigen::Vector3d& ba) {
  ImuSynthesisOptions options;
  options.add_noise = false;
  options.noise.rate_hz = rate_hz;
  options.initial_gyro_bias = bg;
  options.initial_accel_bias = ba;
  return SynthesizeImu(trajectory, trajectory.start_ns(), trajectory.end_ns(), options);
}

ImuState TrueState(const BodyTrajectory& trajectory, timestamp_ns_t t, const Eigen::Vector3d& bg,
                   const Eigen::Vector3d& ba) {
  ImuState state;
  state.timestamp_ns = t;
  state.world_from_body = trajectory.WorldFromBody(t);
  state.velocity_in_world = trajectory.VelocityInWorld(t);
  state.gyro_bias = bg;
  state.accel_bias = ba;
  return state;
}

const Eigen::Vector3d kGyroBias(0.004, -0.003, 0.002);
const Eigen::Vector3d kAccelBias(0.05, -0.03, 0.04);

TEST(ImuFactor, StateParametersRoundTrip) {
  ImuState state;
  state.world_from_body =
      Rigid3d(So3Exp(Eigen::Vector3d(0.3, -0.2, 1.0)), Eigen::Vector3d(1, 2, 3));
  state.velocity_in_world = Eigen::Vector3d(0.1, 0.2, 0.3);
  state.gyro_bias = Eigen::Vector3d(0.01, 0.02, 0.03);
  state.accel_bias = Eigen::Vector3d(-0.1, -0.2, -0.3);
  const ImuState back = ImuStateParameters::FromState(state).ToState(42);
  EXPECT_EQ(back.timestamp_ns, 42);
  EXPECT_LT(back.world_from_body.rotation.angularDistance(state.world_from_body.rotation), 1e-15);
  EXPECT_EQ(back.world_from_body.translation, state.world_from_body.translation);
  EXPECT_EQ(back.velocity_in_world, state.velocity_in_world);
  EXPECT_EQ(back.gyro_bias, state.gyro_bias);
  EXPECT_EQ(back.accel_bias, state.accel_bias);
}

TEST(ImuFactor, ResidualZeroAtGroundTruth) {
  const BodyTrajectory trajectory = MakeWalk(11);
  const timestamp_ns_t t_i = trajectory.start_ns() + SecondsToNs(1.0);
  const timestamp_ns_t t_j = t_i + SecondsToNs(1.0);
  const ImuState truth_i = TrueState(trajectory, t_i, kGyroBias, kAccelBias);
  const ImuState truth_j = TrueState(trajectory, t_j, kGyroBias, kAccelBias);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();

  // 200 Hz, linearised at the true biases: the residual is the midpoint
  // integration error.
  {
    ImuPreintegration preintegration(kGyroBias, kAccelBias, ImuNoise());
    ASSERT_TRUE(preintegration.IntegrateRange(
        NoiseFreeImu(trajectory, 200.0, kGyroBias, kAccelBias).samples, t_i, t_j));
    const Eigen::Matrix<double, 15, 1> r = ImuResidual(preintegration, truth_i, truth_j);
    std::cout << "200 Hz, 1 s: |residual| rotation " << r.head<3>().norm() << " rad, velocity "
              << r.segment<3>(3).norm() << " m/s, position " << r.segment<3>(6).norm() << " m\n";
    EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-4);
    // At the predicted state the residual vanishes to rounding.
    const ImuState predicted = preintegration.Predict(truth_i);
    EXPECT_LT(ImuResidual(preintegration, truth_i, predicted).cwiseAbs().maxCoeff(), 1e-9);
  }
  // 5 kHz: the integration error is (200/5000)^2 smaller.
  {
    ImuPreintegration preintegration(kGyroBias, kAccelBias, ImuNoise());
    ASSERT_TRUE(preintegration.IntegrateRange(
        NoiseFreeImu(trajectory, 5000.0, kGyroBias, kAccelBias).samples, t_i, t_j));
    const Eigen::Matrix<double, 15, 1> r = ImuResidual(preintegration, truth_i, truth_j);
    std::cout << "5 kHz, 1 s: max |residual component| " << r.cwiseAbs().maxCoeff() << "\n";
    EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-6);
    // The weighted residual (what Ceres sees) is also small.
    const ImuStateParameters i = ImuStateParameters::FromState(truth_i);
    const ImuStateParameters j = ImuStateParameters::FromState(truth_j);
    std::unique_ptr<ceres::CostFunction> cost(ImuFactor::Create(preintegration));
    const double* parameters[] = {i.pose.data(), i.speed_bias.data(), j.pose.data(),
                                  j.speed_bias.data()};
    Eigen::Matrix<double, 15, 1> weighted;
    ASSERT_TRUE(cost->Evaluate(parameters, weighted.data(), nullptr));
    std::cout << "5 kHz, 1 s: max |weighted residual| " << weighted.cwiseAbs().maxCoeff() << "\n";
    EXPECT_LT(weighted.cwiseAbs().maxCoeff(), 1e-3);
  }
  // Linearised at zero bias, the factor corrects to the true biases to first
  // order: what is left is second order in the bias change.
  {
    ImuPreintegration preintegration(zero, zero, ImuNoise());
    ASSERT_TRUE(preintegration.IntegrateRange(
        NoiseFreeImu(trajectory, 5000.0, kGyroBias, kAccelBias).samples, t_i, t_j));
    const Eigen::Matrix<double, 15, 1> r = ImuResidual(preintegration, truth_i, truth_j);
    std::cout << "5 kHz, 1 s, linearised at zero bias: max |residual component| "
              << r.cwiseAbs().maxCoeff() << "\n";
    EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-4);
  }
}

TEST(ImuFactor, JacobiansMatchNumericDifferentiation) {
  const BodyTrajectory trajectory = MakeWalk(12);
  const timestamp_ns_t t_i = trajectory.start_ns() + SecondsToNs(0.8);
  const timestamp_ns_t t_j = t_i + SecondsToNs(0.5);
  ImuPreintegration preintegration(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
  ASSERT_TRUE(preintegration.IntegrateRange(
      NoiseFreeImu(trajectory, 200.0, kGyroBias, kAccelBias).samples, t_i, t_j));
  std::unique_ptr<ceres::CostFunction> cost(ImuFactor::Create(preintegration));
  std::unique_ptr<ceres::Manifold> pose_manifold(CreatePoseManifold());
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), nullptr,
                                                         pose_manifold.get(), nullptr};
  ceres::NumericDiffOptions numeric_options;
  ceres::GradientChecker checker(cost.get(), &manifolds, numeric_options);

  Random random(5);
  auto perturbed = [&](const ImuState& truth) {
    ImuState state = truth;
    state.world_from_body.rotation =
        state.world_from_body.rotation *
        So3Exp(Eigen::Vector3d(random.Normal(0, 0.05), random.Normal(0, 0.05),
                               random.Normal(0, 0.05)));
    state.world_from_body.translation += Eigen::Vector3d::Constant(random.Normal(0, 0.1));
    state.velocity_in_world += Eigen::Vector3d(random.Normal(0, 0.1), random.Normal(0, 0.1), 0.0);
    state.gyro_bias += Eigen::Vector3d(random.Normal(0, 0.003), 0.0, random.Normal(0, 0.003));
    state.accel_bias += Eigen::Vector3d(0.0, random.Normal(0, 0.03), random.Normal(0, 0.03));
    return state;
  };
  for (int trial = 0; trial < 3; ++trial) {
    const ImuStateParameters i =
        ImuStateParameters::FromState(perturbed(TrueState(trajectory, t_i, kGyroBias, kAccelBias)));
    const ImuStateParameters j =
        ImuStateParameters::FromState(perturbed(TrueState(trajectory, t_j, kGyroBias, kAccelBias)));
    const double* parameters[] = {i.pose.data(), i.speed_bias.data(), j.pose.data(),
                                  j.speed_bias.data()};
    ceres::GradientChecker::ProbeResults results;
    const bool ok = checker.Probe(parameters, 1e-6, &results);
    std::cout << "trial " << trial << ": max relative Jacobian error "
              << results.maximum_relative_error << "\n";
    EXPECT_TRUE(ok) << results.error_log;
    EXPECT_LT(results.maximum_relative_error, 1e-6);
  }
}

// Four keyframes 0.5 s apart; the first is fixed at the truth, the other
// three start perturbed. IMU factors alone bring them back.
TEST(ImuFactor, OptimisationRecoversPerturbedStates) {
  const BodyTrajectory trajectory = MakeWalk(13);
  const SynthesizedImu imu = NoiseFreeImu(trajectory, 200.0, kGyroBias, kAccelBias);
  const int kKeyframes = 4;
  std::vector<ImuState> truth;
  for (int k = 0; k < kKeyframes; ++k) {
    truth.push_back(TrueState(trajectory, trajectory.start_ns() + SecondsToNs(0.5 + 0.5 * k),
                              kGyroBias, kAccelBias));
  }
  // Preintegrated at zero bias; re-propagated after the first solve.
  std::vector<ImuPreintegration> preintegrations;
  for (int k = 0; k + 1 < kKeyframes; ++k) {
    preintegrations.emplace_back(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise());
    ASSERT_TRUE(preintegrations.back().IntegrateRange(imu.samples, truth[k].timestamp_ns,
                                                      truth[k + 1].timestamp_ns));
  }
  std::vector<ImuStateParameters> states;
  Random random(9);
  for (int k = 0; k < kKeyframes; ++k) {
    ImuState start = truth[k];
    if (k > 0) {
      start.world_from_body.rotation =
          start.world_from_body.rotation * So3Exp(Eigen::Vector3d(0.05, -0.04, 0.06));
      start.world_from_body.translation += Eigen::Vector3d(0.3, -0.2, 0.25);
      start.velocity_in_world += Eigen::Vector3d(-0.2, 0.3, 0.1);
      start.gyro_bias.setZero();
      start.accel_bias.setZero();
    }
    states.push_back(ImuStateParameters::FromState(start));
  }

  auto solve = [&]() {
    ceres::Problem problem;
    for (int k = 0; k < kKeyframes; ++k) {
      problem.AddParameterBlock(states[k].pose.data(), 7, CreatePoseManifold());
      problem.AddParameterBlock(states[k].speed_bias.data(), 9);
    }
    for (int k = 0; k + 1 < kKeyframes; ++k) {
      problem.AddResidualBlock(ImuFactor::Create(preintegrations[k]), nullptr,
                               states[k].pose.data(), states[k].speed_bias.data(),
                               states[k + 1].pose.data(), states[k + 1].speed_bias.data());
    }
    problem.SetParameterBlockConstant(states[0].pose.data());
    problem.SetParameterBlockConstant(states[0].speed_bias.data());
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = 50;
    options.function_tolerance = 1e-14;
    options.gradient_tolerance = 1e-14;
    options.parameter_tolerance = 1e-14;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    return summary;
  };
  const ceres::Solver::Summary first = solve();
  EXPECT_TRUE(first.IsSolutionUsable()) << first.BriefReport();
  // Re-linearise at the estimated biases (the bias change here is below the
  // automatic threshold, so force it).
  int repropagated = 0;
  for (int k = 0; k + 1 < kKeyframes; ++k) {
    const ImuState state = states[k].ToState();
    repropagated += preintegrations[k].RepropagateIfNeeded(state.gyro_bias, state.accel_bias);
    preintegrations[k].Repropagate(state.gyro_bias, state.accel_bias);
  }
  const ceres::Solver::Summary second = solve();
  EXPECT_TRUE(second.IsSolutionUsable()) << second.BriefReport();
  std::cout << "first solve: " << first.BriefReport() << "\nre-propagated " << repropagated
            << " intervals; second solve: " << second.BriefReport() << "\n";

  for (int k = 1; k < kKeyframes; ++k) {
    const ImuState estimate = states[k].ToState();
    const double rotation_error =
        So3Log(truth[k].world_from_body.rotation.conjugate() * estimate.world_from_body.rotation)
            .norm();
    const double position_error =
        (truth[k].world_from_body.translation - estimate.world_from_body.translation).norm();
    const double velocity_error = (truth[k].velocity_in_world - estimate.velocity_in_world).norm();
    const double gyro_bias_error = (estimate.gyro_bias - kGyroBias).norm();
    const double accel_bias_error = (estimate.accel_bias - kAccelBias).norm();
    std::cout << "keyframe " << k << ": rotation " << rotation_error << " rad, position "
              << position_error << " m, velocity " << velocity_error << " m/s, gyro bias "
              << gyro_bias_error << " rad/s, accel bias " << accel_bias_error << " m/s^2\n";
    EXPECT_LT(rotation_error, 1e-4);
    EXPECT_LT(position_error, 1e-3);
    EXPECT_LT(velocity_error, 1e-3);
    EXPECT_LT(gyro_bias_error, 1e-6);
    EXPECT_LT(accel_bias_error, 1e-5);
  }
}

}  // namespace
}  // namespace viosfm
