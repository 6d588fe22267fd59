#include "viosfm/eval/metric_accuracy.h"

#include <iomanip>
#include <sstream>

namespace viosfm {

MetricAccuracy EvaluateMetricAccuracy(const Trajectory& estimate, const Trajectory& reference,
                                      const EvaluationOptions& options) {
  EvaluationOptions eval_options = options;
  eval_options.rpe_delta_frames = 0;
  eval_options.rpe_delta_m = 0.0;
  MetricAccuracy accuracy;
  eval_options.alignment = AlignmentMode::kSim3;
  const EvaluationResult sim3 = EvaluateTrajectories(estimate, reference, eval_options);
  accuracy.num_poses = sim3.pairs.size();
  accuracy.ate_sim3_m = sim3.ate_translation_m;
  accuracy.sim3_scale = sim3.ref_from_est.scale;
  accuracy.scale = 1.0 / sim3.ref_from_est.scale;
  eval_options.alignment = AlignmentMode::kSE3;
  accuracy.ate_se3_m = EvaluateTrajectories(estimate, reference, eval_options).ate_translation_m;
  eval_options.alignment = AlignmentMode::kPosYaw;
  accuracy.ate_posyaw_m = EvaluateTrajectories(estimate, reference, eval_options).ate_translation_m;
  return accuracy;
}

std::string FormatMetricAccuracy(const MetricAccuracy& accuracy) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(4) << "Sim(3) " << accuracy.ate_sim3_m.rmse << " m, SE(3) "
      << accuracy.ate_se3_m.rmse << " m, pos+yaw " << accuracy.ate_posyaw_m.rmse << " m, scale "
      << accuracy.scale << " (" << std::showpos << std::setprecision(2)
      << 100.0 * accuracy.scale_error() << " %)";
  return out.str();
}

}  // namespace viosfm
