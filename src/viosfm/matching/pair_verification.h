// One image pair through the VIO-aided verification (the steps of
// verification_driver.h: matching, step 1 under the VIO's relative pose and
// the pose corrected within its drift, the depth check, step 2 RANSAC), for
// the drivers that choose the pairs: RunVerification over a whole sequence,
// and the streamed run (pipeline/stream_pipeline.h), which verifies each
// new frame's pairs as the frame arrives. Both give a pair the same
// decision from the same features and VIO poses.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/pair_decision.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

// What the verification knows of one image: who it is, its VIO pose, and
// its features as the per-pair steps use them.
struct PairImage {
  image_t image_id = kInvalidImageId;
  std::string name;
  camera_t camera_id = kInvalidCameraId;
  timestamp_ns_t timestamp_ns = 0;
  std::optional<Rigid3d> world_from_body;                      // the VIO pose, if associated
  VioOdometer odometer;                                        // of that pose
  Eigen::Vector3d cam_angular_rate = Eigen::Vector3d::Zero();  // rad/s, for the rolling shutter
  // Features (LoadPairImageFeatures): the keypoints undistorted (x/z, y/z;
  // in undistorted pixels for guided matching), the descriptors as stored
  // (guided matching) and normalised to float (brute-force matching); null
  // where not needed.
  std::vector<Eigen::Vector2d> points_normalized;
  std::vector<Eigen::Vector2d> points_px;
  std::shared_ptr<const FeatureDescriptors> stored_descriptors;
  std::shared_ptr<const FloatDescriptors> descriptors;
};

// Both frames have a VIO pose in the same segment: the VIO's relative pose
// between them means something.
bool HasVioPrior(const PairImage& image1, const PairImage& image2);

// Fills `image`'s keypoints (compensated for the camera's rotation during a
// rolling shutter's readout of `readout_s`, 0: a global shutter) for the
// pairs' steps: normalised, and in pixels when `guided`.
void SetPairImageKeypoints(const Camera& camera, FeatureKeypoints keypoints, double readout_s,
                           bool guided, PairImage* image);

// One pair's verification and what it leaves to store.
struct PairWork {
  PairDecision decision;
  FeatureMatches matches;                   // the tentative matches (to store, for new pairs)
  std::optional<TwoViewGeometry> geometry;  // accepted: to store
  // Re-verified from stored matches (options.reverify_stored_matches): the
  // matches are not written again; had_geometry: a geometry was stored.
  bool reverified = false;
  bool had_geometry = false;
};

// Thread-seconds of a pair's steps, added up.
struct PairStepSeconds {
  double matching = 0.0;
  double vio = 0.0;
  double ransac = 0.0;
};

// The options every pair is verified with (from VerificationOptions).
struct PairVerifier {
  explicit PairVerifier(const VerificationOptions& options, const Rigid3d& body_from_cam);

  // Verifies the pair of `work` (decision.image_id1/2 and names, source,
  // resumed and the stored matches filled in by the caller: a resumed or
  // re-verified pair is not matched again) between image1 and image2,
  // whose features must be loaded. Thread-safe.
  void Verify(const PairImage& image1, const PairImage& image2, const Camera& camera1,
              const Camera& camera2, PairWork* work, PairStepSeconds* seconds) const;

  VerificationOptions options;
  Rigid3d body_from_cam;
  DescriptorMatchingOptions matching;  // single-threaded: the caller runs pairs in parallel
  GuidedMatchingOptions guided;

 private:
  // The pair's two images and cameras.
  struct PairViews {
    const PairImage& image1;
    const PairImage& image2;
    const Camera& camera1;
    const Camera& camera2;
  };
  // The VIO's relative pose and, with band_follows_drift, its covariance
  // and the epipolar band its drift allows (else T_EE).
  struct VioRelativePose {
    Rigid3d cam2_from_cam1;
    std::optional<Eigen::Matrix<double, 6, 6>> covariance;
    double drift_band_px = 0.0;
  };
  VioRelativePose RelativePoseOfVio(const PairViews& views) const;
  // The tentative matches: inside the VIO's epipolar band (guided) or by
  // brute force.
  FeatureMatches Match(const PairViews& views, const VioRelativePose& vio,
                       PairDecision* decision) const;
  // Step 1: the matches under the VIO's pose, and under that pose corrected
  // within its drift; returns which matches the depth check found
  // impossible.
  std::vector<bool> JudgeUnderVio(const PairViews& views, const VioRelativePose& vio,
                                  const FeatureMatches& matches, PairDecision* decision) const;
  // Step 2: RANSAC over `matches`, seeded by the pair.
  void JudgeByRansac(const PairViews& views, const FeatureMatches& matches,
                     PairWork* pair_work) const;
};

// Writes the pair's tentative matches (a pair matched now) and its geometry
// (accepted; an empty one for a re-verified pair now rejected) in one
// transaction, and counts a re-verified pair; a resumed pair only if it is
// now accepted without a stored geometry.
void StorePairWork(const PairWork& work, ColmapDatabase* database, VerificationSummary* summary);

// Adds the decision's outcome to the summary's counts.
void CountDecision(const PairDecision& decision, VerificationSummary* summary);

}  // namespace viosfm
