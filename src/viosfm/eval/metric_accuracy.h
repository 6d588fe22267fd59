// Metric accuracy of a trajectory against the ground truth: the ATE after
// each of the three alignments, and the scale.
//
//  - Sim(3) (rotation, translation and scale): the shape alone, what a
//    purely visual reconstruction can be judged on;
//  - SE(3) (rotation and translation): the shape and the metric scale;
//  - position + yaw (4 DoF, scale 1): also the gravity direction, what a
//    visual-inertial estimate in a gravity-aligned world should get right;
//  - the scale of the estimate: 1 / s of the Sim(3) alignment's scale s
//    (which multiplies the estimate onto the reference), so that 1.02 means
//    the estimate's lengths are 2 % too long; scale_error = that - 1.
#pragma once

#include <string>

#include "viosfm/eval/traj_eval.h"

namespace viosfm {

struct MetricAccuracy {
  size_t num_poses = 0;  // associated poses
  ErrorStatistics ate_sim3_m;
  ErrorStatistics ate_se3_m;
  ErrorStatistics ate_posyaw_m;
  double sim3_scale = 1.0;  // the Sim(3) alignment's scale s (reference from estimate)
  double scale = 1.0;       // the estimate's scale, 1 / sim3_scale
  double scale_error() const { return scale - 1.0; }
};

// Evaluates `estimate` against `reference` (world_from_body, nearest-stamp
// association within options.max_dt_ns) with the three alignments. Throws
// InputError as EvaluateTrajectories does (no association, degenerate
// alignment). options.alignment is ignored.
MetricAccuracy EvaluateMetricAccuracy(const Trajectory& estimate, const Trajectory& reference,
                                      const EvaluationOptions& options = {});

// "Sim(3) 0.0123 m, SE(3) 0.0150 m, pos+yaw 0.0151 m, scale 1.0021 (+0.21 %)"
std::string FormatMetricAccuracy(const MetricAccuracy& accuracy);

}  // namespace viosfm
