#include "viosfm/matching/pair_decider.h"

#include <algorithm>

#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"

namespace viosfm {

PairDecider::PairDecider(const VerificationOptions& options, const Rigid3d& body_from_cam,
                         ColmapDatabase* database)
    : options_(options), verifier_(options, body_from_cam), database_(database) {
  VIOSFM_CHECK(database != nullptr);
  step_seconds_.assign(
      static_cast<size_t>(NumThreadsFor(1 << 20, std::max(1, options.num_threads))), {});
}

bool PairDecider::IsStored(image_t image_id1, image_t image_id2) const {
  return database_->ExistsMatches(image_id1, image_id2);
}

std::vector<ImagePairMatches> PairDecider::Decide(const std::vector<PairToDecide>& pairs) {
  std::vector<PairWork> work(pairs.size());
  for (size_t p = 0; p < pairs.size(); ++p) {
    const PairImage& image1 = *pairs[p].image1;
    const PairImage& image2 = *pairs[p].image2;
    PairWork& pair_work = work[p];
    PairDecision& decision = pair_work.decision;
    decision.image_id1 = image1.image_id;
    decision.image_id2 = image2.image_id;
    decision.name1 = image1.name;
    decision.name2 = image2.name;
    decision.source = pairs[p].source;
    decision.has_vio_prior = HasVioPrior(image1, image2);
    if (!IsStored(image1.image_id, image2.image_id)) continue;
    // Stored matches: decided again from them (reverified), or their stored
    // geometry is the decision (resumed).
    pair_work.matches = database_->ReadMatches(image1.image_id, image2.image_id);
    if (options_.reverify_stored_matches) {
      pair_work.reverified = true;
      pair_work.had_geometry = database_->ExistsTwoViewGeometry(image1.image_id, image2.image_id);
      continue;
    }
    decision.resumed = true;
    if (database_->ExistsTwoViewGeometry(image1.image_id, image2.image_id)) {
      decision.num_inliers = static_cast<int>(
          database_->ReadTwoViewGeometry(image1.image_id, image2.image_id).inlier_matches.size());
      decision.accepted = decision.num_inliers > 0;
    }
    if (!decision.accepted) decision.num_inliers = 0;
  }
  ParallelFor(static_cast<int64_t>(work.size()), options_.num_threads, [&](int64_t p, int thread) {
    verifier_.Verify(*pairs[p].image1, *pairs[p].image2, *pairs[p].camera1, *pairs[p].camera2,
                     &work[p], &step_seconds_[thread]);
  });
  std::vector<ImagePairMatches> accepted;
  VerificationSummary& summary = result_.summary;
  for (PairWork& pair_work : work) {
    const PairDecision& decision = pair_work.decision;
    if (decision.accepted) {
      ImagePairMatches pair;
      pair.image_id1 = decision.image_id1;
      pair.image_id2 = decision.image_id2;
      pair.matches = pair_work.geometry
                         ? pair_work.geometry->inlier_matches
                         : database_->ReadTwoViewGeometry(decision.image_id1, decision.image_id2)
                               .inlier_matches;
      pair.vio_contradicted = decision.vio_contradicted;
      accepted.push_back(std::move(pair));
    }
    StorePairWork(pair_work, database_, &summary);
    CountDecision(decision, &summary);
    result_.decisions.push_back(std::move(pair_work.decision));
  }
  summary.num_pairs += work.size();
  return accepted;
}

VerificationResult PairDecider::TakeResult() {
  for (const PairStepSeconds& seconds : step_seconds_) {
    result_.summary.seconds_matching += seconds.matching;
    result_.summary.seconds_vio += seconds.vio;
    result_.summary.seconds_ransac += seconds.ransac;
  }
  step_seconds_.assign(step_seconds_.size(), {});
  return std::move(result_);
}

}  // namespace viosfm
