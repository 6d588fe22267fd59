// The paper's two-step VIO-aided geometric verification over a whole
// sequence (its section "VIO-Aided Geometric Verification"):
//  1. pairs: N1 temporal + N2 retrieval neighbours (or sequential /
//     exhaustive), pair_generator.h and retrieval/image_retrieval.h;
//  2. tentative matches: descriptor nearest neighbours with ratio and
//     mutual checks (descriptor_matcher.h), in parallel over pairs;
//  3. step 1, VIO prior: the pair's relative pose from the VIO trajectory
//     gives a fundamental matrix; the pair is rejected when more than
//     max_outlier_ratio of its matches lie farther than T_EE from their
//     epipolar lines (estimators/prior_verification.h);
//  4. step 2, RANSAC: essential-matrix RANSAC on the survivors; kept with at
//     least min_num_inliers inliers (estimators/two_view_geometry.h);
//  3b. beyond the paper (prior.check_depth, default on), part of step 1:
//     matches that show less parallax than any point nearer than
//     prior.max_scene_depth_m would over the metric VIO baseline are
//     impossible under the VIO pose; they count as outliers of the step-1
//     ratio (a pair that only this rejects has reason "vio_depth",
//     vio_depth_rejected set) and are left out of RANSAC (the matches table
//     keeps all tentative matches).
//
// Input: a database whose images already have features (`viosfm features`,
// features/feature_extraction.h: images are named by file name). Each
// database image is tied to its sequence image by name, and to the VIO pose
// nearest to that image's stamp within max_pose_time_difference_ns; an image
// without such a pose has no prior, and its pairs are verified by RANSAC only
// (PairDecision::has_vio_prior = false). Database images not in the sequence
// are ignored.
//
// Output: per pair, the raw matches (matches table) and, for accepted pairs
// only, the verified geometry (two_view_geometries, COLMAP's config
// CALIBRATED), so `colmap mapper` can use the database; both written in one
// transaction per pair, batch by batch, so an interrupted run keeps every
// finished pair. A re-run skips the matching of the pairs whose matches are
// stored (resume): their record says resumed; a pair with a stored geometry
// is accepted (the VIO check is recomputed from the stored matches for the
// report), one without is decided again from its stored matches (VIO check
// and RANSAC, seeded by the pair), so a resumed run records the same
// decisions, inlier counts and reasons as an uninterrupted one. With
// reverify_stored_matches the stored matches are verified again and the
// geometries replaced.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/estimators/prior_verification.h"
#include "viosfm/estimators/two_view_geometry.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/matching/descriptor_matcher.h"
#include "viosfm/matching/pair_generator.h"
#include "viosfm/retrieval/image_retrieval.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/pair_decision.h"
#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct VerificationOptions {
  // Pair generation: mode (default temporal_retrieval), N1 = 40, N2 = 30.
  // kPairList is not supported here (use a pair list with COLMAP instead).
  PairGeneratorOptions pairs;
  // Retrieval for the N2 neighbours (num_neighbors is set from pairs; the
  // vocabulary is trained on the sequence unless vocabulary_path is set).
  RetrievalOptions retrieval;
  // Descriptor matching (ratio 0.8, distance 0.7, mutual check);
  // num_threads is ignored (the driver parallelises over pairs).
  DescriptorMatchingOptions matching;
  // Step 1: the VIO-prior check. Default true. false: RANSAC only (COLMAP's
  // verification, the paper's baseline).
  bool use_vio_prior = true;
  // T_EE 20 px, outlier ratio 0.5 (the paper's), min baseline 0.01 m; the
  // depth-consistency check (beyond the paper; prior.check_depth, default
  // on) with max scene depth 20 m.
  PriorVerificationOptions prior;
  // Beyond the paper: the epipolar band follows the VIO's expected drift
  // between the two frames (DriftEpipolarBandPx): far-apart frames, such as
  // the two visits of a loop, get the band their drift allows instead of
  // the fixed T_EE, which rejects correct loop pairs once the VIO has
  // drifted a few decimetres. Default true; false: the fixed T_EE (the
  // paper).
  bool band_follows_drift = true;
  // With band_follows_drift: a pair the VIO's relative pose does not
  // explain under the fixed T_EE (step 1 would reject it) is judged again,
  // with the same T_EE, under the VIO's pose corrected by its matches within
  // the VIO's expected drift between the two frames
  // (CorrectRelativePoseWithinDrift, estimators/prior_verification.h: the
  // drift's band only bounds the search). Default true; false: each match
  // is judged alone against the band the drift allows (the VIO's pose
  // uncorrected), which lets in pairs whose matches fit no one pose near the
  // VIO's (benchmarks.md, VIO-aided verification).
  bool correct_within_drift = true;
  // The largest correction taken as the VIO's drift: its Mahalanobis
  // distance under the model's covariance (5 degrees of freedom: the
  // rotation and the translation's direction). Default 20: a VIO may drift
  // several times what the model's rates say, and the correction that would
  // join two identical floors is far beyond it while correct pairs ask for
  // much less (see docs/benchmarks.md, "VIO-aided verification").
  double max_correction_sigmas = 20.0;
  // The VIO's uncertainty (scene/vio_uncertainty.h; the pipeline sets it
  // from its own option).
  VioUncertaintyModel vio_uncertainty;
  // Standard deviations of the expected epipolar error added to the band.
  // Default 3.
  double band_sigmas = 3.0;
  // m, the depth at which the VIO's translation error (across the baseline)
  // is turned into pixels: a point this near moves most. Default 2 (indoor
  // scenes; nearer points are few and mostly seen by temporal neighbours,
  // whose drift is small).
  double band_depth_m = 2.0;
  // Match inside the band of the VIO epipolar lines instead of by brute force
  // (pairs with a prior only). Default false. With band_follows_drift the
  // band is as wide as the VIO's drift between the two frames allows
  // (DriftEpipolarBandPx, at least guided_band_px), so that the two visits
  // of a loop keep their matches, and step 1 judges them as it judges
  // brute-force matches (with the correction within the drift). With the
  // fixed band (band_follows_drift false) the matches agree with the VIO's
  // pose by construction, so step 1 rejects nothing and only RANSAC
  // decides: on the simulated two floors that accepts pairs of the
  // identical floors, which the band of the drift rejects (benchmarks.md,
  // VIO-aided verification).
  bool guided_matching = false;
  // Half width of the guided-matching band, pixels: the band of pairs whose
  // drift allows less, or of every pair with band_follows_drift false.
  // Default 20 (T_EE).
  double guided_band_px = 20.0;
  // Step 2: RANSAC (Sampson error 4 px, >= 15 inliers, confidence 0.999).
  TwoViewGeometryOptions geometry;
  // Largest gap between an image's stamp and the VIO pose used for it,
  // nanoseconds. Default 5 ms (a quarter of a 20 Hz frame period).
  timestamp_ns_t max_pose_time_difference_ns = 5'000'000;
  // Pairs matched and verified per batch (memory: the features of the
  // batch's images). Default 2000.
  int batch_size = 2000;
  // Worker threads over pairs (and retrieval); <= 0: all. Default 2.
  int num_threads = 2;
  // Seeds the RANSAC sampler (mixed with the pair id) and the vocabulary
  // training (replacing retrieval.vocabulary.seed). Default 0.
  uint64_t seed = 0;
  // Pairs whose matches are already stored: false (default) keeps them as
  // they are (resume); true reads their matches instead of matching again,
  // runs both verification steps on them and replaces the stored geometry
  // (a pair now rejected gets an empty one: no inliers). With a copy of a
  // database that holds every pair's matches, this compares verification
  // settings on identical tentative matches at a fraction of the cost.
  bool reverify_stored_matches = false;
  // Draw progress bars. Default true.
  bool show_progress = true;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
  // Every option as (name, value) text, for the report.
  std::vector<std::pair<std::string, std::string>> ToKeyValues() const;

  // The fields of the sub-structs that are options of a run are described
  // here (pairs., retrieval., matching., prior., geometry.).
  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"pairs.mode", "temporal_retrieval, sequential or exhaustive", kShapesStoredData},
          self.pairs.mode);
    visit({"pairs.num_temporal_neighbors", "N1, temporal neighbours per image", kShapesStoredData},
          self.pairs.num_temporal_neighbors);
    visit(
        {"pairs.num_retrieval_neighbors", "N2, retrieval neighbours per image", kShapesStoredData},
        self.pairs.num_retrieval_neighbors);
    visit(
        {"retrieval.vocabulary_path", "vocabulary file (content hashed); empty: trained", kRunOnly},
        self.retrieval.vocabulary_path);
    visit(
        {"retrieval.vocabulary.branching", "children per vocabulary tree node", kShapesStoredData},
        self.retrieval.vocabulary.branching);
    visit({"retrieval.vocabulary.depth", "levels of the vocabulary tree", kShapesStoredData},
          self.retrieval.vocabulary.depth);
    visit({"matching.max_ratio", "descriptor ratio test", kShapesStoredData},
          self.matching.max_ratio);
    visit({"matching.max_distance", "largest descriptor distance", kShapesStoredData},
          self.matching.max_distance);
    visit({"matching.cross_check", "keep mutual nearest neighbours only", kShapesStoredData},
          self.matching.cross_check);
    visit({"use_vio_prior", "step 1, the VIO-prior check; false: RANSAC only", kShapesStoredData},
          self.use_vio_prior);
    visit(
        {"prior.max_epipolar_error_px", "T_EE, px from the VIO's epipolar line", kShapesStoredData},
        self.prior.max_epipolar_error_px);
    visit(
        {"prior.max_outlier_ratio", "pairs with more VIO outliers are rejected", kShapesStoredData},
        self.prior.max_outlier_ratio);
    visit({"prior.min_baseline_m", "m, shorter VIO baselines skip the check", kShapesStoredData},
          self.prior.min_baseline_m);
    visit({"prior.check_depth", "the depth-consistency check", kShapesStoredData},
          self.prior.check_depth);
    visit({"prior.max_scene_depth_m", "m, depth of the farthest point of the check",
           kShapesStoredData},
          self.prior.max_scene_depth_m);
    visit({"prior.depth_tolerance_px", "px, tolerance of the depth check", kShapesStoredData},
          self.prior.depth_tolerance_px);
    visit({"prior.min_depth_parallax_px", "px, parallax from which the depth check applies",
           kShapesStoredData},
          self.prior.min_depth_parallax_px);
    visit({"band_follows_drift", "the epipolar band follows the VIO's drift", kShapesStoredData},
          self.band_follows_drift);
    visit({"correct_within_drift",
           "the VIO's relative pose corrected by the matches within its drift", kShapesStoredData},
          self.correct_within_drift);
    visit({"max_correction_sigmas", "largest correction taken as the VIO's drift, sigmas",
           kShapesStoredData},
          self.max_correction_sigmas);
    visit({"band_sigmas", "sigmas of the expected epipolar error added to the band",
           kShapesStoredData},
          self.band_sigmas);
    visit({"band_depth_m", "m, depth that turns the translation error into px", kShapesStoredData},
          self.band_depth_m);
    visit({"guided_matching", "match inside the VIO epipolar band", kShapesStoredData},
          self.guided_matching);
    visit({"reverify_stored_matches", "verify stored matches again", kShapesStoredData},
          self.reverify_stored_matches);
    visit({"guided_band_px", "px, half width of the guided-matching band", kShapesStoredData},
          self.guided_band_px);
    visit({"geometry.max_error_px", "px, RANSAC's Sampson error threshold", kShapesStoredData},
          self.geometry.max_error_px);
    visit({"geometry.min_num_inliers", "inliers for a pair to be kept", kShapesStoredData},
          self.geometry.min_num_inliers);
    visit({"geometry.confidence", "RANSAC confidence", kShapesStoredData},
          self.geometry.confidence);
    visit({"geometry.min_num_trials", "fewest RANSAC trials", kShapesStoredData},
          self.geometry.min_num_trials);
    visit({"geometry.max_num_trials", "most RANSAC trials", kShapesStoredData},
          self.geometry.max_num_trials);
    visit({"geometry.local_optimization", "LO-RANSAC", kShapesStoredData},
          self.geometry.local_optimization);
    visit({"geometry.refine_relative_pose", "refine the relative pose on the inliers",
           kShapesStoredData},
          self.geometry.refine_relative_pose);
    visit({"max_pose_time_difference_ns", "ns, largest gap between an image and its VIO pose",
           kShapesStoredData},
          self.max_pose_time_difference_ns);
    visit({"num_threads", "worker threads over pairs", kRunOnly}, self.num_threads);
    visit({"seed", "seeds RANSAC and the vocabulary training", kShapesStoredData}, self.seed);
    visit({"batch_size",
           "pairs matched and verified between two writes to the database (memory); results do not "
           "depend on it",
           kRunOnly},
          self.batch_size);
    visit({"show_progress", "progress bars", kRunOnly}, self.show_progress);
  }
};

struct VerificationResult {
  VerificationSummary summary;
  // One per generated pair, in the pair generator's (sorted) order.
  std::vector<PairDecision> decisions;
};

// Verifies the pairs of the sequence's images held in `database` (see the
// top of this file). `vio_world_from_body` is the VIO trajectory as
// world_from_body poses (the sequence's rig.body_from_cam gives the camera
// poses); empty, or options.use_vio_prior false: RANSAC only.
// `vio_segments` gives each VIO pose's segment (stage_vio.h; empty: one
// segment): a pair whose frames lie in two segments has no VIO prior (a
// relative pose across a re-initialisation means nothing) and is verified
// by RANSAC only. Throws InputError for invalid options, a database image
// without features or a camera model that cannot project.
VerificationResult RunVerification(const Sequence& sequence, const Trajectory& vio_world_from_body,
                                   ColmapDatabase* database, const VerificationOptions& options,
                                   const std::vector<int>& vio_segments = {});

// A frame's VIO pose and its place along the VIO's track.
struct FrameVioPose {
  Rigid3d world_from_body;
  VioOdometer odometer;  // ComputeVioOdometers over the VIO's track
};
// The same with the frames' VIO poses already known: frame_poses[i] is
// sequence.images[i]'s (none: RANSAC only for its pairs); nothing is
// associated by time here.
// With `rolling_shutter` active (its cam_angular_rate per image of
// `sequence`), each image's keypoints are compensated for the camera's
// rotation during the readout before they are matched and verified
// (scene/rolling_shutter.h); the database keeps them as detected.
//
// `on_verified`, if given, is called on the calling thread after each batch
// of pairs is stored, with the batch's accepted pairs (their inlier
// matches, as stored) and a stamp: every pair still to be decided has both
// its frames at or after it (the largest timestamp_ns_t after the last
// batch). A mapper running beside the verification reads them
// (sfm/verified_pair_stream.h).
using VerifiedPairsCallback =
    std::function<void(std::vector<ImagePairMatches> accepted, timestamp_ns_t pending_from_ns)>;
VerificationResult RunVerification(const Sequence& sequence,
                                   const std::vector<std::optional<FrameVioPose>>& frame_poses,
                                   ColmapDatabase* database, const VerificationOptions& options,
                                   const FrameRollingShutter& rolling_shutter = {},
                                   const VerifiedPairsCallback& on_verified = {});

// The epipolar band (pixels) of a pair whose VIO relative pose
// cam2_from_cam1 has covariance `covariance` (of [Log R_E; t_E],
// scene/vio_uncertainty.h): sqrt(T_EE^2 + (band_sigmas f (sigma_rot +
// sigma_t / band_depth_m))^2), sigma_rot the largest rotation sigma and
// sigma_t the largest translation sigma across the baseline (an error along
// it, e.g. of the scale, moves no epipolar line). T_EE =
// options.prior.max_epipolar_error_px, f in pixels.
double DriftEpipolarBandPx(const Eigen::Matrix<double, 6, 6>& covariance,
                           const Rigid3d& cam2_from_cam1, double focal_length_px,
                           const VerificationOptions& options);

// "80 of 120 pairs accepted; rejected: 30 by the VIO, 10 by RANSAC, 0 without
// matches": the console's line.
std::string FormatVerificationHeadline(const VerificationSummary& summary);
// "120 pairs of 40 images (...): 80 accepted, 30 rejected by VIO, ...; 3.2 s
// (...)": every count and time.
std::string FormatVerificationSummary(const VerificationSummary& summary);

}  // namespace viosfm
