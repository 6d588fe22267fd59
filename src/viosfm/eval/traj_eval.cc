#include "viosfm/eval/traj_eval.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "viosfm/geometry/alignment.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

std::vector<timestamp_ns_t> Stamps(const Trajectory& trajectory) {
  std::vector<timestamp_ns_t> stamps(trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) stamps[i] = trajectory.poses[i].timestamp_ns;
  return stamps;
}

std::vector<PosePair> Associate(const Trajectory& est, const Trajectory& ref,
                                const EvaluationOptions& options, AssociationMethod* used) {
  AssociationMethod method = options.association;
  const bool stamped = est.has_timestamps && ref.has_timestamps;
  if (method == AssociationMethod::kAuto) {
    method = stamped ? AssociationMethod::kNearest : AssociationMethod::kIndex;
  }
  *used = method;
  if (method != AssociationMethod::kIndex && !stamped) {
    throw InputError("association '" + AssociationMethodName(method) +
                     "' needs timestamps, but the " +
                     (est.has_timestamps ? "reference" : "estimate") +
                     " has none (KITTI format): use --associate index");
  }
  switch (method) {
    case AssociationMethod::kIndex: return AssociateByIndex(est.size(), ref.size());
    case AssociationMethod::kNearest:
      return AssociateNearest(Stamps(est), Stamps(ref), options.max_dt_ns, options.offset_ns);
    case AssociationMethod::kGreedy:
      return AssociateGreedy(Stamps(est), Stamps(ref), options.max_dt_ns, options.offset_ns);
    case AssociationMethod::kAuto: break;
  }
  VIOSFM_CHECK(false) << "unhandled association method";
  return {};
}

Sim3d Align(const std::vector<Eigen::Vector3d>& est_positions,
            const std::vector<Eigen::Vector3d>& ref_positions, AlignmentMode mode) {
  std::optional<Sim3d> ref_from_est;
  switch (mode) {
    case AlignmentMode::kNone: return Sim3d();
    case AlignmentMode::kSE3:
      ref_from_est = AlignPointsUmeyama(est_positions, ref_positions, /*with_scale=*/false);
      break;
    case AlignmentMode::kSim3:
      ref_from_est = AlignPointsUmeyama(est_positions, ref_positions, /*with_scale=*/true);
      break;
    case AlignmentMode::kPosYaw:
      ref_from_est = AlignPointsPositionYaw(est_positions, ref_positions);
      break;
  }
  if (!ref_from_est) {
    throw InputError("cannot compute the " + AlignmentModeName(mode) + " alignment from " +
                     std::to_string(est_positions.size()) +
                     " associated positions: expected at least 3 (2 for posyaw) that are not "
                     "collinear");
  }
  return *ref_from_est;
}

std::vector<std::pair<size_t, size_t>> FramePairs(size_t count, size_t delta, bool all_pairs) {
  std::vector<std::pair<size_t, size_t>> pairs;
  if (all_pairs) {
    for (size_t i = 0; i + delta < count; ++i) pairs.emplace_back(i, i + delta);
  } else {
    for (size_t i = 0; i + delta < count; i += delta) pairs.emplace_back(i, i + delta);
  }
  return pairs;
}

std::vector<std::pair<size_t, size_t>> DistancePairs(const std::vector<Eigen::Vector3d>& positions,
                                                     double delta, double tolerance,
                                                     bool all_pairs) {
  std::vector<std::pair<size_t, size_t>> pairs;
  if (positions.empty()) return pairs;
  if (all_pairs) {
    // path[k]: distance travelled from pose 0 to pose k.
    std::vector<double> path(positions.size(), 0.0);
    for (size_t k = 1; k < positions.size(); ++k) {
      path[k] = path[k - 1] + (positions[k] - positions[k - 1]).norm();
    }
    for (size_t i = 0; i + 1 < positions.size(); ++i) {
      const double target = path[i] + delta;
      const auto it =
          std::lower_bound(path.begin() + static_cast<std::ptrdiff_t>(i) + 1, path.end(), target);
      size_t best = positions.size();
      double best_residual = 0.0;
      const size_t k = static_cast<size_t>(it - path.begin());
      for (size_t candidate : {k - 1, k}) {
        if (candidate <= i || candidate >= positions.size()) continue;
        const double residual = std::abs(path[candidate] - target);
        if (best == positions.size() || residual < best_residual) {
          best = candidate;
          best_residual = residual;
        }
      }
      if (best != positions.size() && best_residual <= delta * tolerance) {
        pairs.emplace_back(i, best);
      }
    }
  } else {
    // evo's filter_pairs_by_path: a pose is kept each time the distance
    // travelled since the last kept one reaches delta; consecutive kept poses
    // form the pairs.
    std::vector<size_t> kept;
    double travelled = 0.0;
    for (size_t k = 0; k < positions.size(); ++k) {
      if (k > 0) travelled += (positions[k] - positions[k - 1]).norm();
      if (travelled >= delta) {
        kept.push_back(k);
        travelled = 0.0;
      }
    }
    for (size_t i = 1; i < kept.size(); ++i) pairs.emplace_back(kept[i - 1], kept[i]);
  }
  return pairs;
}

RelativePoseErrors ComputeRelativeErrors(const std::vector<Rigid3d>& est_aligned,
                                         const std::vector<Rigid3d>& ref,
                                         std::vector<std::pair<size_t, size_t>> pair_indices,
                                         double delta, std::string unit, bool all_pairs) {
  RelativePoseErrors result;
  result.delta = delta;
  result.unit = std::move(unit);
  result.all_pairs = all_pairs;
  result.pair_indices = std::move(pair_indices);
  for (const auto& [i, j] : result.pair_indices) {
    const Rigid3d ref_motion = ref[i].Inverse() * ref[j];
    const Rigid3d est_motion = est_aligned[i].Inverse() * est_aligned[j];
    const Rigid3d error = ref_motion.Inverse() * est_motion;
    result.translation_errors_m.push_back(error.translation.norm());
    result.rotation_errors_deg.push_back(RotationAngleDeg(error.rotation));
  }
  result.translation_m = ComputeErrorStatistics(result.translation_errors_m);
  result.rotation_deg = ComputeErrorStatistics(result.rotation_errors_deg);
  return result;
}

}  // namespace

AlignmentMode ParseAlignmentMode(const std::string& name) {
  const std::string lower = ToLower(Trim(name));
  if (lower == "none") return AlignmentMode::kNone;
  if (lower == "se3") return AlignmentMode::kSE3;
  if (lower == "sim3") return AlignmentMode::kSim3;
  if (lower == "posyaw") return AlignmentMode::kPosYaw;
  throw InputError("unknown alignment '" + name + "': expected none, se3, sim3 or posyaw");
}

std::string AlignmentModeName(AlignmentMode mode) {
  switch (mode) {
    case AlignmentMode::kNone: return "none";
    case AlignmentMode::kSE3: return "se3";
    case AlignmentMode::kSim3: return "sim3";
    case AlignmentMode::kPosYaw: return "posyaw";
  }
  return "unknown";
}

std::string EvaluationOptions::Validate() const {
  if (max_dt_ns < 0) return "max_dt_ns must be >= 0, got " + std::to_string(max_dt_ns);
  if (align_first < 0) return "align_first must be >= 0, got " + std::to_string(align_first);
  if (rpe_delta_frames < 0) {
    return "rpe_delta_frames must be >= 0, got " + std::to_string(rpe_delta_frames);
  }
  if (!(rpe_delta_m >= 0.0) || !std::isfinite(rpe_delta_m)) {
    return "rpe_delta_m must be finite and >= 0, got " + std::to_string(rpe_delta_m);
  }
  if (!(rpe_delta_m_tolerance >= 0.0) || !std::isfinite(rpe_delta_m_tolerance)) {
    return "rpe_delta_m_tolerance must be finite and >= 0, got " +
           std::to_string(rpe_delta_m_tolerance);
  }
  return "";
}

ErrorStatistics ComputeErrorStatistics(const std::vector<double>& errors) {
  ErrorStatistics stats;
  stats.count = errors.size();
  if (errors.empty()) return stats;
  const double n = static_cast<double>(errors.size());
  double sum = 0.0;
  for (double e : errors) {
    sum += e;
    stats.sse += e * e;
  }
  stats.mean = sum / n;
  stats.rmse = std::sqrt(stats.sse / n);
  double squared_deviation = 0.0;
  for (double e : errors) squared_deviation += (e - stats.mean) * (e - stats.mean);
  stats.std = std::sqrt(squared_deviation / n);
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  stats.min = sorted.front();
  stats.max = sorted.back();
  const size_t middle = sorted.size() / 2;
  stats.median =
      sorted.size() % 2 == 1 ? sorted[middle] : 0.5 * (sorted[middle - 1] + sorted[middle]);
  return stats;
}

EvaluationResult EvaluateTrajectories(const Trajectory& est_input, const Trajectory& ref_input,
                                      const EvaluationOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid evaluation options: " + error);
  }
  if (est_input.empty()) throw InputError("the estimated trajectory has no poses");
  if (ref_input.empty()) throw InputError("the reference trajectory has no poses");
  const Trajectory est = options.est_body_from_cam
                             ? CameraToBodyTrajectory(est_input, *options.est_body_from_cam)
                             : est_input;
  const Trajectory ref = options.ref_body_from_cam
                             ? CameraToBodyTrajectory(ref_input, *options.ref_body_from_cam)
                             : ref_input;

  EvaluationResult result;
  result.num_est_poses = est.size();
  result.num_ref_poses = ref.size();
  result.pairs = Associate(est, ref, options, &result.association);
  if (result.pairs.empty()) {
    throw InputError("no estimated pose could be associated with a reference pose (association " +
                     AssociationMethodName(result.association) + ", max dt " +
                     FormatNsAsSeconds(options.max_dt_ns) + " s, offset " +
                     FormatNsAsSeconds(options.offset_ns) + " s)");
  }

  const size_t n = result.pairs.size();
  std::vector<Rigid3d> est_poses(n);
  std::vector<Rigid3d> ref_poses(n);
  std::vector<Eigen::Vector3d> est_positions(n);
  std::vector<Eigen::Vector3d> ref_positions(n);
  for (size_t k = 0; k < n; ++k) {
    est_poses[k] = est.poses[result.pairs[k].est_index].world_from_frame;
    ref_poses[k] = ref.poses[result.pairs[k].ref_index].world_from_frame;
    est_positions[k] = est_poses[k].translation;
    ref_positions[k] = ref_poses[k].translation;
  }

  result.alignment = options.alignment;
  result.num_alignment_pairs =
      options.align_first > 0 ? std::min(n, static_cast<size_t>(options.align_first)) : n;
  const std::vector<Eigen::Vector3d> est_for_alignment(
      est_positions.begin(), est_positions.begin() + result.num_alignment_pairs);
  const std::vector<Eigen::Vector3d> ref_for_alignment(
      ref_positions.begin(), ref_positions.begin() + result.num_alignment_pairs);
  result.ref_from_est = Align(est_for_alignment, ref_for_alignment, options.alignment);

  std::vector<Rigid3d> est_aligned(n);
  result.translation_errors_m.resize(n);
  result.rotation_errors_deg.resize(n);
  for (size_t k = 0; k < n; ++k) {
    est_aligned[k] = result.ref_from_est.TransformPose(est_poses[k]);
    result.translation_errors_m[k] = (ref_positions[k] - est_aligned[k].translation).norm();
    result.rotation_errors_deg[k] =
        RotationAngleDeg(ref_poses[k].rotation.inverse() * est_aligned[k].rotation);
  }
  result.ate_translation_m = ComputeErrorStatistics(result.translation_errors_m);
  result.ate_rotation_deg = ComputeErrorStatistics(result.rotation_errors_deg);

  if (options.rpe_delta_frames > 0) {
    result.rpe_frames = ComputeRelativeErrors(
        est_aligned, ref_poses,
        FramePairs(n, static_cast<size_t>(options.rpe_delta_frames), options.rpe_all_pairs),
        static_cast<double>(options.rpe_delta_frames), "frames", options.rpe_all_pairs);
  }
  if (options.rpe_delta_m > 0.0) {
    result.rpe_distance =
        ComputeRelativeErrors(est_aligned, ref_poses,
                              DistancePairs(ref_positions, options.rpe_delta_m,
                                            options.rpe_delta_m_tolerance, options.rpe_all_pairs),
                              options.rpe_delta_m, "m", options.rpe_all_pairs);
  }
  return result;
}

}  // namespace viosfm
