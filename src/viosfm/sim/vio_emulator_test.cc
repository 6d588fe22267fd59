#include "viosfm/sim/vio_emulator.h"

#include <gtest/gtest.h>

#include "viosfm/sim/trajectory.h"

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
