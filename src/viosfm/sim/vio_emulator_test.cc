#include "viosfm/sim/vio_emulator.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "viosfm/sim/trajectory.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

Trajectory GroundTruth(double duration_s) {
  WalkOptions walk;
  walk.duration_s = duration_s;
  walk.seed = 11;
  const BodyTrajectory body = GenerateWalk(walk);
  std::vector<timestamp_ns_t> stamps;
  for (timestamp_ns_t t = body.start_ns(); t <= body.end_ns(); t += 50'000'000) stamps.push_back(t);
  return body.Sample(stamps);
}

double FinalPositionError(const Trajectory& a, const Trajectory& b) {
  return (a.poses.back().world_from_frame.translation - b.poses.back().world_from_frame.translation)
      .norm();
}

TEST(VioEmulator, ZeroDriftReproducesGroundTruth) {
  const Trajectory gt = GroundTruth(20.0);
  const Trajectory vio = EmulateVioDrift(gt, VioDriftOptions().Scaled(0.0));
  ASSERT_EQ(vio.size(), gt.size());
  for (size_t k = 0; k < gt.size(); ++k) {
    EXPECT_EQ(vio.poses[k].timestamp_ns, gt.poses[k].timestamp_ns);
    EXPECT_LT((vio.poses[k].world_from_frame.translation - gt.poses[k].world_from_frame.translation)
                  .norm(),
              1e-9);
    EXPECT_LT(vio.poses[k].world_from_frame.rotation.angularDistance(
                  gt.poses[k].world_from_frame.rotation),
              1e-9);
  }
}

TEST(VioEmulator, ScaleErrorStretchesDisplacements) {
  const Trajectory gt = GroundTruth(20.0);
  VioDriftOptions options = VioDriftOptions().Scaled(0.0);
  options.scale_error = 0.05;
  const Trajectory vio = EmulateVioDrift(gt, options);
  const Eigen::Vector3d gt_span =
      gt.poses.back().world_from_frame.translation - gt.poses.front().world_from_frame.translation;
  const Eigen::Vector3d vio_span = vio.poses.back().world_from_frame.translation -
                                   vio.poses.front().world_from_frame.translation;
  EXPECT_LT((vio_span - 1.05 * gt_span).norm(), 1e-9);
}

TEST(VioEmulator, DriftGrowsWithTheDriftLevelAndIsSeeded) {
  const Trajectory gt = GroundTruth(60.0);
  double previous = 0.0;
  for (double factor : {1.0, 4.0, 16.0}) {
    double sum = 0.0;
    for (uint64_t seed = 0; seed < 20; ++seed) {
      VioDriftOptions options = VioDriftOptions().Scaled(factor);
      options.seed = seed;
      sum += FinalPositionError(EmulateVioDrift(gt, options), gt);
    }
    EXPECT_GT(sum / 20, 2.0 * previous) << "factor " << factor;
    previous = sum / 20;
  }
  VioDriftOptions options;
  const Trajectory a = EmulateVioDrift(gt, options);
  const Trajectory b = EmulateVioDrift(gt, options);
  EXPECT_EQ(FinalPositionError(a, b), 0.0);
  // Roll and pitch do not drift: gravity direction in the body frame is kept to jitter level.
  for (size_t k = 0; k < gt.size(); k += 50) {
    const Eigen::Vector3d up_gt =
        gt.poses[k].world_from_frame.rotation.inverse() * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d up_vio =
        a.poses[k].world_from_frame.rotation.inverse() * Eigen::Vector3d::UnitZ();
    EXPECT_LT(std::acos(std::min(1.0, up_gt.dot(up_vio))), 6 * options.rotation_jitter_rad);
  }
}

}  // namespace
}  // namespace viosfm

namespace viosfm {
namespace {

// r = [Log(R_E); t_E] of the VIO's cam2_from_cam1 against the true one
// (ba/cost_functions.h's RelativePoseError), poses world_from_cam.
Eigen::Matrix<double, 6, 1> RelativePoseResidual(const Rigid3d& true1, const Rigid3d& true2,
                                                 const Rigid3d& vio1, const Rigid3d& vio2) {
  const Rigid3d p12 = true2.Inverse() * true1;
  const Rigid3d p12_hat = vio2.Inverse() * vio1;
  const Rigid3d error = p12 * p12_hat.Inverse();
  const Eigen::AngleAxisd angle_axis(error.rotation);
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = angle_axis.angle() * angle_axis.axis();
  r.tail<3>() = error.translation;
  return r;
}

VioSample FrameAt(const Trajectory& trajectory, const std::vector<VioOdometer>& odometers,
                  size_t k) {
  return {trajectory.poses[k].timestamp_ns, trajectory.poses[k].world_from_frame, odometers[k]};
}

// The covariance of scene/vio_uncertainty.h against a Monte-Carlo of the
// realistic emulator drawn from the same rates (the scale error drawn per
// run with the model's scale_sigma), for frame pairs 0.05 s to 20 s apart.
TEST(RealisticVioEmulator, CovarianceMatchesMonteCarlo) {
  const Trajectory gt = GroundTruth(30.0);
  const std::vector<VioOdometer> odometers = ComputeVioOdometers(gt, {});
  const VioUncertaintyModel model;
  struct Span {
    size_t first, second;
    double tolerance;  // relative, on each standard deviation
  };
  // 20 Hz: 0.05 s, 1 s, 5 s and 20 s apart. The longest, over a curving
  // walk, tests the straight-path approximation of the yaw's lever arm.
  const std::vector<Span> spans = {
      {100, 101, 0.08}, {100, 120, 0.08}, {200, 300, 0.1}, {100, 500, 0.2}};
  const int num_runs = 1200;
  std::vector<Eigen::Matrix<double, 6, 6>> sums(spans.size(), Eigen::Matrix<double, 6, 6>::Zero());
  Random scale_random(5);
  for (int run = 0; run < num_runs; ++run) {
    RealisticVioOptions options;
    options.model = model;
    options.scale_error = scale_random.Normal(0.0, model.scale_sigma);
    options.seed = 1000 + run;
    const EmulatedVio vio = EmulateRealisticVio(gt, options);
    ASSERT_EQ(vio.world_from_frame.size(), gt.size());
    for (size_t s = 0; s < spans.size(); ++s) {
      const Eigen::Matrix<double, 6, 1> r = RelativePoseResidual(
          gt.poses[spans[s].first].world_from_frame, gt.poses[spans[s].second].world_from_frame,
          vio.world_from_frame.poses[spans[s].first].world_from_frame,
          vio.world_from_frame.poses[spans[s].second].world_from_frame);
      sums[s] += r * r.transpose();
    }
  }
  for (size_t s = 0; s < spans.size(); ++s) {
    const Eigen::Matrix<double, 6, 6> sampled = sums[s] / num_runs;
    const Eigen::Matrix<double, 6, 6> predicted = RelativePoseCovariance(
        model, FrameAt(gt, odometers, spans[s].first), FrameAt(gt, odometers, spans[s].second));
    for (int i = 0; i < 6; ++i) {
      const double ratio = std::sqrt(sampled(i, i) / predicted(i, i));
      EXPECT_NEAR(ratio, 1.0, spans[s].tolerance)
          << "span " << spans[s].first << "-" << spans[s].second << ", component " << i
          << ": Monte-Carlo sigma " << std::sqrt(sampled(i, i)) << ", model "
          << std::sqrt(predicted(i, i));
    }
    // The whole covariance: the Monte-Carlo samples' mean Mahalanobis
    // distance under the model is the dimension (6) when the model is right.
    const Eigen::Matrix<double, 6, 6> information = predicted.inverse();
    const double mean_mahalanobis = (information * sampled).trace();
    EXPECT_NEAR(mean_mahalanobis, 6.0, 6.0 * 2 * spans[s].tolerance)
        << "span " << spans[s].first << "-" << spans[s].second;
  }
}

TEST(RealisticVioEmulator, ReinitialisationStartsANewSegmentInANewWorldFrame) {
  const Trajectory gt = GroundTruth(30.0);
  RealisticVioOptions options;
  options.reinit_times_s = {10.0, 20.0};
  options.reinit_gap_s = 1.0;
  const EmulatedVio vio = EmulateRealisticVio(gt, options);
  ASSERT_EQ(vio.segments.size(), vio.world_from_frame.size());
  // 2 s without poses (20 Hz).
  EXPECT_EQ(vio.world_from_frame.size(), gt.size() - 40);
  EXPECT_EQ(vio.segments.front(), 0);
  EXPECT_EQ(vio.segments.back(), 2);
  size_t first_of_segment_1 = 0;
  while (vio.segments[first_of_segment_1] == 0) ++first_of_segment_1;
  const StampedPose& restart = vio.world_from_frame.poses[first_of_segment_1];
  EXPECT_EQ(restart.timestamp_ns - vio.world_from_frame.poses[first_of_segment_1 - 1].timestamp_ns,
            1'050'000'000);
  // The new world frame's origin is the body (up to the frame noise), its
  // yaw that of the body.
  EXPECT_LT(restart.world_from_frame.translation.norm(), 0.02);
  const Eigen::Vector3d forward = restart.world_from_frame.rotation * Eigen::Vector3d::UnitX();
  EXPECT_LT(std::abs(std::atan2(forward.y(), forward.x())), 0.01);
  // Same segments from the time gaps.
  EXPECT_EQ(SegmentsFromTimeGaps(vio.world_from_frame, 500'000'000), vio.segments);

  // Without a gap the jump is invisible in the stamps.
  options.reinit_gap_s = 0.0;
  const EmulatedVio jumping = EmulateRealisticVio(gt, options);
  EXPECT_EQ(jumping.world_from_frame.size(), gt.size());
  EXPECT_EQ(jumping.segments.back(), 2);
  EXPECT_EQ(SegmentsFromTimeGaps(jumping.world_from_frame, 500'000'000).back(), 0);
}

}  // namespace
}  // namespace viosfm

namespace viosfm {
namespace {

// Keyframes 0.3 to 4 s apart, the realistic VIO emulated on a 20 Hz grid
// through them: a pose at each keyframe, the grid never coarser than asked,
// the exact model reproducing the keyframes, and the default model's drift
// over the run as large as the same VIO emulated on the dense ground truth
// gives (the walks do not depend on how finely the path is sampled).
TEST(RealisticVioEmulator, OnAGridThroughSparseKeyframes) {
  const Trajectory dense = GroundTruth(60.0);
  Trajectory keyframes;
  const std::vector<double> gaps = {0.3, 4.0, 1.2, 0.55, 2.5, 3.95};
  size_t k = 0;
  for (size_t g = 0; k < dense.size(); ++g) {
    keyframes.poses.push_back(dense.poses[k]);
    k += static_cast<size_t>(std::lround(gaps[g % gaps.size()] / 0.05));
  }
  ASSERT_GT(keyframes.size(), 20u);

  RealisticVioOptions exact = RealisticVioOptions().Scaled(0.0);
  const EmulatedVio on_grid = EmulateRealisticVioOnGrid(keyframes, exact, 20.0);
  size_t matched = 0;
  for (size_t i = 1; i < on_grid.world_from_frame.size(); ++i) {
    EXPECT_LE(on_grid.world_from_frame.poses[i].timestamp_ns -
                  on_grid.world_from_frame.poses[i - 1].timestamp_ns,
              50'000'000);
  }
  for (const StampedPose& keyframe : keyframes.poses) {
    for (const StampedPose& pose : on_grid.world_from_frame.poses) {
      if (pose.timestamp_ns != keyframe.timestamp_ns) continue;
      ++matched;
      EXPECT_LT((pose.world_from_frame.translation - keyframe.world_from_frame.translation).norm(),
                1e-6);
      EXPECT_LT(pose.world_from_frame.rotation.angularDistance(keyframe.world_from_frame.rotation),
                1e-6);
    }
  }
  EXPECT_EQ(matched, keyframes.size());

  // The default model: RMS end drift over 200 seeds on both grids, within
  // the Monte-Carlo's spread (about 4 % on the ratio).
  double grid_sq = 0.0, dense_sq = 0.0;
  const int seeds = 200;
  for (int seed = 0; seed < seeds; ++seed) {
    RealisticVioOptions options;
    options.scale_error = 0.0;
    options.seed = 100 + seed;
    const EmulatedVio a = EmulateRealisticVioOnGrid(keyframes, options, 20.0);
    const EmulatedVio b = EmulateRealisticVioOnGrid(keyframes, options, 100.0);
    const Eigen::Vector3d end = keyframes.poses.back().world_from_frame.translation;
    for (const StampedPose& pose : a.world_from_frame.poses) {
      if (pose.timestamp_ns == keyframes.poses.back().timestamp_ns) {
        grid_sq += (pose.world_from_frame.translation - end).squaredNorm();
      }
    }
    for (const StampedPose& pose : b.world_from_frame.poses) {
      if (pose.timestamp_ns == keyframes.poses.back().timestamp_ns) {
        dense_sq += (pose.world_from_frame.translation - end).squaredNorm();
      }
    }
  }
  const double grid_rms = std::sqrt(grid_sq / seeds), dense_rms = std::sqrt(dense_sq / seeds);
  EXPECT_GT(dense_rms, 0.02);
  EXPECT_NEAR(grid_rms / dense_rms, 1.0, 0.15) << grid_rms << " against " << dense_rms;

  // Seeded.
  RealisticVioOptions seeded;
  seeded.seed = 7;
  const EmulatedVio first = EmulateRealisticVioOnGrid(keyframes, seeded, 20.0);
  const EmulatedVio second = EmulateRealisticVioOnGrid(keyframes, seeded, 20.0);
  ASSERT_EQ(first.world_from_frame.size(), second.world_from_frame.size());
  EXPECT_EQ(first.world_from_frame.poses.back().world_from_frame.translation,
            second.world_from_frame.poses.back().world_from_frame.translation);
}

}  // namespace
}  // namespace viosfm
