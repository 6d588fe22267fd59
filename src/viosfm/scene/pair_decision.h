// The verification record of one image pair (matching/verification_driver.h
// fills it, io/verification_report.h writes it): which pair, where it came
// from, how many tentative matches it had, what the VIO-prior check and the
// RANSAC check said, and the final decision.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/util/types.h"

namespace viosfm {

struct PairDecision {
  image_t image_id1 = kInvalidImageId;  // image_id1 < image_id2 (COLMAP's order)
  image_t image_id2 = kInvalidImageId;
  std::string name1;  // database image names
  std::string name2;
  // How the pair was proposed: "temporal", "retrieval", "sequential",
  // "exhaustive" or "pair_list".
  std::string source;
  int num_matches = 0;  // tentative (descriptor) matches
  // Both images have a VIO pose, so the VIO-prior check ran.
  bool has_vio_prior = false;
  // The epipolar band of the EE test, pixels (T_EE; with the wide band,
  // wider where the VIO's drift between the frames allows:
  // matching/verification_driver.h); NaN when the check did not run.
  double vio_band_px = std::numeric_limits<double>::quiet_NaN();
  // With guided matching: the half width of the band around the VIO's
  // epipolar lines the pair was matched in, pixels (wider than
  // guided_band_px where the VIO's drift between the frames allows); NaN
  // when the pair was matched by brute force or not matched again.
  double guided_band_px = std::numeric_limits<double>::quiet_NaN();
  // With the correction within the drift (matching/verification_driver.h):
  // the Mahalanobis distance of the correction the matches asked for (NaN
  // when none was sought: the VIO's pose explained the pair, or no
  // correction was possible), and whether it was within the drift, so that
  // the pair was judged under the corrected pose.
  double vio_correction_sigmas = std::numeric_limits<double>::quiet_NaN();
  bool vio_corrected = false;
  // Outliers / matches under the VIO relative pose (the paper's EE test);
  // NaN when the check did not run.
  double vio_outlier_ratio = std::numeric_limits<double>::quiet_NaN();
  // The VIO baseline was below the minimum: transfer errors were used.
  bool vio_rotation_only = false;
  // The depth-consistency check (estimators/prior_verification.h, beyond the
  // paper) had enough scored matches to apply; its depth-inconsistent ratio
  // (NaN when not applied), and whether it rejected the pair.
  bool vio_depth_applied = false;
  double vio_depth_inconsistent_ratio = std::numeric_limits<double>::quiet_NaN();
  bool vio_depth_rejected = false;
  // Step 1 rejected the pair (the EE test, or the depth check: then
  // vio_depth_rejected too).
  bool vio_rejected = false;
  // The pair's frames lie on two sides of a gap in the VIO's poses
  // (VioOdometer::gap), where the VIO may have re-initialised: a pair step 1
  // rejects is then judged by RANSAC alone and, accepted, is evidence that
  // the VIO jumped there (vio_contradicted; sfm/vio_gaps.h decides).
  bool spans_vio_gap = false;
  bool vio_contradicted = false;
  int num_inliers = 0;    // RANSAC inliers (0 if RANSAC did not run)
  bool accepted = false;  // the pair's geometry is stored
  // The matches were already in the database: the pair was not matched or
  // verified again (accepted and num_inliers come from the stored geometry).
  bool resumed = false;
  // "accepted", "accepted_against_vio" (vio_contradicted), "no_matches",
  // "vio_outlier_ratio", "vio_depth", "too_few_inliers".
  std::string reason;
};

// Reasons, as written in PairDecision::reason.
inline constexpr const char* kPairAccepted = "accepted";
inline constexpr const char* kPairAcceptedAgainstVio = "accepted_against_vio";
inline constexpr const char* kPairNoMatches = "no_matches";
inline constexpr const char* kPairVioOutlierRatio = "vio_outlier_ratio";
inline constexpr const char* kPairVioDepth = "vio_depth";
inline constexpr const char* kPairTooFewInliers = "too_few_inliers";

// What a verification run did, over all pairs.
struct VerificationSummary {
  size_t num_images = 0;               // images verified (in the database and the sequence)
  size_t num_images_with_prior = 0;    // images with a VIO pose
  size_t num_pairs = 0;                // pairs generated
  size_t num_pairs_without_prior = 0;  // pairs checked by RANSAC only (an image without pose)
  size_t num_resumed = 0;              // pairs whose matches were already stored
  size_t num_reverified = 0;           // stored matches verified again (reverify_stored_matches)
  size_t num_no_matches = 0;           // rejected: no tentative match
  size_t num_vio_rejected = 0;         // rejected by step 1 (VIO prior; EE or depth)
  size_t num_vio_depth_rejected = 0;   // of those, by the depth check
  // Accepted pairs judged under the VIO's relative pose corrected by their
  // matches within the VIO's drift (PairDecision::vio_corrected).
  size_t num_accepted_corrected = 0;
  size_t num_ransac_rejected = 0;  // rejected by step 2 (too few RANSAC inliers)
  size_t num_accepted = 0;         // accepted (geometry stored)
  // Wall-clock seconds of the whole run and of its sequential parts.
  double seconds_total = 0.0;
  double seconds_pair_generation = 0.0;  // retrieval and pair generation
  double seconds_loading = 0.0;          // reading and undistorting features
  double seconds_deciding = 0.0;         // matching, verifying, storing
  // Thread-seconds (summed over worker threads) of the per-pair steps.
  double seconds_matching = 0.0;
  double seconds_vio = 0.0;
  double seconds_ransac = 0.0;
  // The database the run wrote (empty if unknown).
  std::string database_path;
  // The options used, as (name, value) text, written next to the results.
  std::vector<std::pair<std::string, std::string>> options;
};

// A verification run judged against ground truth (sim/pair_truth.h): a
// candidate pair is correct when its two views see the same surface; an
// accepted pair is wrong when most of its inliers disagree with the true
// geometry.
struct VerificationTruthSummary {
  std::string name;                   // the run (report folder)
  size_t num_candidates = 0;          // pairs generated
  size_t num_correct_candidates = 0;  // of those, correct
  size_t num_accepted = 0;
  size_t num_accepted_correct = 0;  // correct, inliers agree
  size_t num_accepted_wrong = 0;    // inliers disagree
  // Accepted, inliers agree, but the overlap is below the correct threshold.
  size_t num_accepted_other = 0;
  // Pairs the first (baseline) run accepted as correct, and how many of them
  // this run accepted too; their ratio (NaN when the baseline has none).
  size_t num_baseline_correct = 0;
  size_t num_baseline_correct_kept = 0;
  double recall_vs_baseline = std::numeric_limits<double>::quiet_NaN();
  // The accepted wrong pairs (name1, name2).
  std::vector<std::pair<std::string, std::string>> wrong_pairs;
};

}  // namespace viosfm
