// Pairs decided and stored, a handful at a time: each pair matched (or its
// stored matches taken up again), verified (pair_verification.h) in
// parallel, and its matches and geometry written; the decisions and the
// accepted pairs' inlier matches kept in the order given. The whole-sequence
// verification (verification_driver.h) and the streamed run (a frame's pairs
// as the frame arrives) decide their pairs through it.
#pragma once

#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/matching/pair_verification.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/scene/features.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

// One pair to decide: its images (features loaded, unless its matches are
// stored) and how it was proposed.
struct PairToDecide {
  const PairImage* image1 = nullptr;  // the earlier frame (image_id1 < image_id2 not required)
  const PairImage* image2 = nullptr;
  const Camera* camera1 = nullptr;
  const Camera* camera2 = nullptr;
  std::string source;
};

class PairDecider {
 public:
  PairDecider(const VerificationOptions& options, const Rigid3d& body_from_cam,
              ColmapDatabase* database);

  // Whether the pair's matches are stored: it is decided again from them,
  // and its images need no descriptors.
  bool IsStored(image_t image_id1, image_t image_id2) const;
  // Decides the pairs (in parallel over options.num_threads) and stores
  // them; returns the accepted ones' inlier matches, in the pairs' order.
  std::vector<ImagePairMatches> Decide(const std::vector<PairToDecide>& pairs);
  // The decisions so far and the summary's counts and step seconds.
  const VerificationResult& result() const { return result_; }
  VerificationResult TakeResult();

 private:
  VerificationOptions options_;
  PairVerifier verifier_;
  ColmapDatabase* database_;
  std::vector<PairStepSeconds> step_seconds_;
  VerificationResult result_;
};

}  // namespace viosfm
