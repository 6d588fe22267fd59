// Trajectory evaluation: association, alignment, absolute trajectory error
// (ATE) and relative pose error (RPE), with the definitions of evo
// (M. Grupp, github.com/MichaelGrupp/evo):
//  - the estimate is aligned to the reference by Umeyama on the associated
//    positions (src = estimate, dst = reference); Sim(3) scales the
//    estimate's positions;
//  - ATE translation error of pair k: |p_ref_k - p_est_aligned_k| (m);
//    ATE rotation error: the angle of R_ref_k^T R_est_aligned_k (deg);
//  - RPE of a pair of associated poses (i, j): the relative motions
//    Q = ref_i^-1 ref_j and P = est_i^-1 est_j (aligned estimate) and the
//    error E = Q^-1 P; translation |t_E| (m), rotation angle(R_E) (deg);
//  - statistics: rmse = sqrt(mean e^2), mean, median (mean of the two middle
//    values for an even count), std = population standard deviation
//    (numpy's np.std), min, max, sse = sum e^2.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "viosfm/eval/association.h"
#include "viosfm/geometry/sim3.h"
#include "viosfm/scene/trajectory.h"

namespace viosfm {

enum class AlignmentMode {
  kNone,
  kSE3,    // rotation + translation (Umeyama without scale)
  kSim3,   // rotation + translation + scale (Umeyama)
  kPosYaw  // translation + rotation about z (gravity-aligned VIO)
};
// "none", "se3", "sim3", "posyaw"; throws InputError otherwise.
AlignmentMode ParseAlignmentMode(const std::string& name);
std::string AlignmentModeName(AlignmentMode mode);

struct EvaluationOptions {
  // How estimated and reference poses are paired. Default kAuto (by index when
  // either trajectory has no stamps, else nearest stamp as evo does).
  AssociationMethod association = AssociationMethod::kAuto;
  // Largest |dt| (ns) of a stamp association. Default 10 ms (evo's 0.01 s).
  int64_t max_dt_ns = 10'000'000;
  // Added to the estimate's stamps before association (ns). Default 0.
  int64_t offset_ns = 0;
  // Alignment of the estimate to the reference. Default SE(3).
  AlignmentMode alignment = AlignmentMode::kSE3;
  // Align on the first N associated pairs only; 0 = all pairs. Default 0.
  int64_t align_first = 0;
  // RPE over a frame delta (pairs of associated poses k, k + delta); 0 = off.
  // Default 1.
  int64_t rpe_delta_frames = 1;
  // RPE over a travelled distance along the reference (m); 0 = off. Default 0.
  double rpe_delta_m = 0.0;
  // Relative tolerance on the travelled distance of a pair when
  // rpe_all_pairs is set (evo's rel_tol). Default 0.1.
  double rpe_delta_m_tolerance = 0.1;
  // true: every pair (k, k + delta) (for metres: every k with the pair whose
  // path length is nearest to delta, within the tolerance); false: evo's
  // default of consecutive, non-overlapping pairs. Default true.
  bool rpe_all_pairs = true;
  // When set, that trajectory holds camera poses (world_from_cam) and is
  // converted to body poses: world_from_body = world_from_cam * cam_from_body.
  std::optional<Rigid3d> est_body_from_cam;
  std::optional<Rigid3d> ref_body_from_cam;

  // Empty if valid; otherwise names the bad field and why.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

struct ErrorStatistics {
  size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;
  double min = 0.0;
  double max = 0.0;
  double sse = 0.0;
};
// Statistics of `errors` (all zero for an empty list).
ErrorStatistics ComputeErrorStatistics(const std::vector<double>& errors);

struct RelativePoseErrors {
  double delta = 0.0;  // in `unit`
  std::string unit;    // "frames" or "m"
  bool all_pairs = true;
  // Index pairs into EvaluationResult::pairs.
  std::vector<std::pair<size_t, size_t>> pair_indices;
  std::vector<double> translation_errors_m;
  std::vector<double> rotation_errors_deg;
  ErrorStatistics translation_m;
  ErrorStatistics rotation_deg;
};

struct EvaluationResult {
  size_t num_est_poses = 0;
  size_t num_ref_poses = 0;
  AssociationMethod association = AssociationMethod::kIndex;  // the rule used
  std::vector<PosePair> pairs;
  AlignmentMode alignment = AlignmentMode::kNone;
  size_t num_alignment_pairs = 0;
  // Maps estimate positions into the reference world frame (scale 1 unless Sim(3)).
  Sim3d ref_from_est;
  // Per associated pair, in the order of `pairs`.
  std::vector<double> translation_errors_m;
  std::vector<double> rotation_errors_deg;
  ErrorStatistics ate_translation_m;
  ErrorStatistics ate_rotation_deg;
  std::optional<RelativePoseErrors> rpe_frames;
  std::optional<RelativePoseErrors> rpe_distance;
};

// Evaluates `est` against `ref`. Throws InputError if the options are
// invalid, no pose could be associated, the association needs stamps that a
// trajectory lacks, or the alignment is degenerate (too few or collinear
// positions).
EvaluationResult EvaluateTrajectories(const Trajectory& est, const Trajectory& ref,
                                      const EvaluationOptions& options);

}  // namespace viosfm
