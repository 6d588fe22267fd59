#include "viosfm/matching/pair_verification.h"

#include <algorithm>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// SplitMix64 finaliser: an independent seed per pair.
uint64_t MixSeed64(uint64_t seed, uint64_t index) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace

bool HasVioPrior(const PairImage& image1, const PairImage& image2) {
  return image1.world_from_body && image2.world_from_body &&
         image1.odometer.segment == image2.odometer.segment;
}

void SetPairImageKeypoints(const Camera& camera, FeatureKeypoints keypoints, double readout_s,
                           bool guided, PairImage* image) {
  CompensateRollingShutterRotation(camera, readout_s, image->cam_angular_rate, &keypoints);
  image->points_normalized = UndistortKeypoints(camera, keypoints);
  image->points_px.clear();
  if (guided) {
    const Eigen::Matrix3d K = CalibrationMatrix(camera);
    image->points_px.reserve(image->points_normalized.size());
    for (const Eigen::Vector2d& x : image->points_normalized) {
      image->points_px.push_back((K * x.homogeneous()).hnormalized());
    }
  }
}

PairVerifier::PairVerifier(const VerificationOptions& verification_options,
                           const Rigid3d& body_from_cam_in)
    : options(verification_options), body_from_cam(body_from_cam_in) {
  matching = options.matching;
  matching.num_threads = 1;
  guided.matching = matching;
  guided.max_epipolar_distance_px = options.guided_band_px;
}

void PairVerifier::Verify(const PairImage& image1, const PairImage& image2, const Camera& camera1,
                          const Camera& camera2, PairWork* pair_work,
                          PairStepSeconds* seconds) const {
  PairDecision& decision = pair_work->decision;
  const PairViews views{image1, image2, camera1, camera2};
  Timer timer;
  VioRelativePose vio;
  vio.drift_band_px = options.prior.max_epipolar_error_px;
  if (decision.has_vio_prior) {
    vio = RelativePoseOfVio(views);
    seconds->vio += timer.ElapsedSeconds();
  }
  if (!decision.resumed && !pair_work->reverified) {
    timer.Start();
    pair_work->matches = Match(views, vio, &decision);
    seconds->matching += timer.ElapsedSeconds();
  }
  const FeatureMatches& matches = pair_work->matches;
  decision.num_matches = static_cast<int>(matches.size());
  std::vector<bool> depth_inconsistent;  // per match (with the depth check)
  if (decision.has_vio_prior && !matches.empty()) {
    timer.Start();
    depth_inconsistent = JudgeUnderVio(views, vio, matches, &decision);
    seconds->vio += timer.ElapsedSeconds();
  }
  // Across a gap in the VIO's poses its relative pose may be a
  // re-initialisation's jump: RANSAC alone judges what step 1 rejected.
  decision.spans_vio_gap = decision.has_vio_prior && image1.odometer.gap != image2.odometer.gap;
  const bool against_vio = decision.spans_vio_gap && decision.vio_rejected;
  if (against_vio) {
    decision.vio_rejected = false;
    decision.vio_contradicted = true;
    depth_inconsistent.clear();
  }
  if (decision.resumed && decision.accepted) {
    // The stored geometry is the decision.
    decision.vio_rejected = false;
    decision.reason = decision.vio_contradicted ? kPairAcceptedAgainstVio : kPairAccepted;
    return;
  }
  // A stored pair without a geometry was rejected: decided again below
  // from its stored matches (the same steps with the same seed, so the
  // same decision, inlier count and reason as when it was stored).
  if (matches.empty()) {
    decision.reason = kPairNoMatches;
    return;
  }
  if (decision.vio_rejected) {
    decision.reason = decision.vio_depth_rejected ? kPairVioDepth : kPairVioOutlierRatio;
    return;
  }

  // Beyond the paper: the depth-inconsistent matches (impossible under
  // the VIO pose) do not enter RANSAC.
  FeatureMatches consistent;
  const bool depth_checked = decision.has_vio_prior && decision.vio_depth_applied && !against_vio;
  if (depth_checked) {
    for (size_t m = 0; m < matches.size(); ++m) {
      if (!depth_inconsistent[m]) consistent.push_back(matches[m]);
    }
  }
  timer.Start();
  JudgeByRansac(views, depth_checked ? consistent : matches, pair_work);
  seconds->ransac += timer.ElapsedSeconds();
}

PairVerifier::VioRelativePose PairVerifier::RelativePoseOfVio(const PairViews& views) const {
  const PairImage& image1 = views.image1;
  const PairImage& image2 = views.image2;
  VioRelativePose vio;
  vio.drift_band_px = options.prior.max_epipolar_error_px;
  vio.cam2_from_cam1 = RelativePoseFromVio(*image1.world_from_body, *image2.world_from_body,
                                           body_from_cam, body_from_cam);
  if (options.band_follows_drift) {
    const VioSample frame1{image1.timestamp_ns, *image1.world_from_body * body_from_cam,
                           image1.odometer};
    const VioSample frame2{image2.timestamp_ns, *image2.world_from_body * body_from_cam,
                           image2.odometer};
    vio.covariance = RelativePoseCovariance(options.vio_uncertainty, frame1, frame2);
    vio.drift_band_px = DriftEpipolarBandPx(
        *vio.covariance, vio.cam2_from_cam1,
        0.5 * (MeanFocalLength(views.camera1) + MeanFocalLength(views.camera2)), options);
  }
  return vio;
}

FeatureMatches PairVerifier::Match(const PairViews& views, const VioRelativePose& vio,
                                   PairDecision* decision) const {
  if (!options.guided_matching || !decision->has_vio_prior) {
    return MatchDescriptors(*views.image1.descriptors, *views.image2.descriptors, matching);
  }
  const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(
      vio.cam2_from_cam1, CalibrationMatrix(views.camera1), CalibrationMatrix(views.camera2));
  // The band the VIO's drift allows, so that the two visits of a loop keep
  // their matches; step 1 then judges them under the fixed T_EE, and under
  // the corrected pose.
  GuidedMatchingOptions pair_guided = guided;
  pair_guided.max_epipolar_distance_px =
      std::max(options.guided_band_px, options.band_follows_drift ? vio.drift_band_px : 0.0);
  decision->guided_band_px = pair_guided.max_epipolar_distance_px;
  return MatchDescriptorsGuided(*views.image1.stored_descriptors, *views.image2.stored_descriptors,
                                views.image1.points_px, views.image2.points_px, fundamental,
                                pair_guided);
}

std::vector<bool> PairVerifier::JudgeUnderVio(const PairViews& views, const VioRelativePose& vio,
                                              const FeatureMatches& matches,
                                              PairDecision* decision) const {
  const std::vector<Eigen::Vector2d>& points1 = views.image1.points_normalized;
  const std::vector<Eigen::Vector2d>& points2 = views.image2.points_normalized;
  PriorVerificationOptions prior = options.prior;
  if (vio.covariance && !options.correct_within_drift) {
    prior.max_epipolar_error_px = vio.drift_band_px;
  }
  decision->vio_band_px = prior.max_epipolar_error_px;
  PriorVerificationResult check = VerifyPairWithPrior(
      views.camera1, views.camera2, vio.cam2_from_cam1, points1, points2, matches, prior);
  // A pair the VIO's pose does not explain: judged again under the pose its
  // matches show, if that is within the VIO's drift.
  if (vio.covariance && options.correct_within_drift && !check.accepted && !check.rotation_only) {
    const DriftCorrection correction = CorrectRelativePoseWithinDrift(
        views.camera1, views.camera2, vio.cam2_from_cam1, *vio.covariance, points1, points2,
        matches, vio.drift_band_px, options.max_correction_sigmas, prior);
    decision->vio_correction_sigmas = correction.mahalanobis;
    if (correction.corrected) {
      decision->vio_corrected = true;
      check = VerifyPairWithPrior(views.camera1, views.camera2, correction.cam2_from_cam1, points1,
                                  points2, matches, prior);
    }
  }
  decision->vio_outlier_ratio = check.outlier_ratio;
  decision->vio_rotation_only = check.rotation_only;
  decision->vio_depth_applied = check.depth_applied;
  decision->vio_depth_inconsistent_ratio = check.depth_inconsistent_ratio;
  decision->vio_depth_rejected = check.depth_rejected;
  decision->vio_rejected = !check.accepted;
  return std::move(check.depth_inconsistent);
}

void PairVerifier::JudgeByRansac(const PairViews& views, const FeatureMatches& matches,
                                 PairWork* pair_work) const {
  PairDecision& decision = pair_work->decision;
  TwoViewGeometryOptions geometry = options.geometry;
  geometry.seed =
      MixSeed64(options.seed, ImagePairToPairId(decision.image_id1, decision.image_id2));
  const TwoViewGeometryResult estimate = EstimateCalibratedTwoViewGeometry(
      views.image1.points_normalized, views.image2.points_normalized, matches, views.camera1,
      views.camera2, geometry);
  decision.num_inliers = estimate.num_inliers();
  decision.accepted = estimate.accepted();
  decision.reason = !decision.accepted          ? kPairTooFewInliers
                    : decision.vio_contradicted ? kPairAcceptedAgainstVio
                                                : kPairAccepted;
  if (decision.accepted) pair_work->geometry = estimate.ToTwoViewGeometry();
}

void StorePairWork(const PairWork& pair_work, ColmapDatabase* database,
                   VerificationSummary* summary) {
  const PairDecision& decision = pair_work.decision;
  // A resumed pair is written again only if it is now accepted without
  // a stored geometry (it cannot be with the options it was stored with,
  // which the caller keeps; the database then holds what the decision says).
  if (decision.resumed && !pair_work.geometry) return;
  ColmapDatabase::Transaction transaction(*database);
  if (!pair_work.reverified && !decision.resumed) {
    database->WriteMatches(decision.image_id1, decision.image_id2, pair_work.matches);
  }
  if (pair_work.geometry) {
    database->WriteTwoViewGeometry(decision.image_id1, decision.image_id2, *pair_work.geometry);
  } else if (pair_work.had_geometry) {
    // Now rejected: no inliers (as COLMAP records a failed pair).
    database->WriteTwoViewGeometry(decision.image_id1, decision.image_id2, TwoViewGeometry());
  }
  if (pair_work.reverified) ++summary->num_reverified;
  transaction.Commit();
}

void CountDecision(const PairDecision& decision, VerificationSummary* summary) {
  if (!decision.has_vio_prior) ++summary->num_pairs_without_prior;
  if (decision.resumed) ++summary->num_resumed;
  if (decision.accepted) {
    ++summary->num_accepted;
    if (decision.vio_corrected) ++summary->num_accepted_corrected;
  } else if (decision.reason == kPairNoMatches) {
    ++summary->num_no_matches;
  } else if (decision.vio_rejected) {
    ++summary->num_vio_rejected;
    if (decision.vio_depth_rejected) ++summary->num_vio_depth_rejected;
  } else {
    ++summary->num_ransac_rejected;
  }
}

}  // namespace viosfm
