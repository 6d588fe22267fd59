#include "viosfm/matching/incremental_pair_generator.h"

#include <algorithm>
#include <unordered_set>

#include "viosfm/util/errors.h"

namespace viosfm {

IncrementalPairGenerator::IncrementalPairGenerator(const PairGeneratorOptions& options)
    : options_(options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("pair generator options: " + error);
  }
  if (options.mode == PairMode::kPairList) {
    throw InputError("pairs from a list are not decided frame by frame");
  }
}

size_t IncrementalPairGenerator::AddFrame(const PairGeneratorImage& image) {
  VIOSFM_CHECK(!frames_finished_) << "a frame after the last";
  if (!images_.empty()) {
    VIOSFM_CHECK_GT(image.timestamp_ns, images_.back().timestamp_ns)
        << "frames must come in increasing time";
  }
  frame_of_image_[image.image_id] = images_.size();
  images_.push_back(image);
  retrieved_.emplace_back();
  temporal_.emplace_back();
  retrieval_neighbors_.emplace_back();
  later_retrieval_partners_.emplace_back();
  return images_.size() - 1;
}

void IncrementalPairGenerator::SetRetrieved(size_t k, std::vector<image_t> ranked) {
  VIOSFM_CHECK_LT(k, images_.size());
  retrieved_[k] = std::move(ranked);
}

bool IncrementalPairGenerator::HasFinished() const {
  return frames_finished_ && next_ >= images_.size();
}

bool IncrementalPairGenerator::Decidable(size_t d) const {
  if (d >= images_.size()) return false;
  if (options_.mode != PairMode::kTemporalRetrieval) return true;
  // Its temporal neighbours lie among the N1 frames on either side.
  const size_t n1 = static_cast<size_t>(options_.num_temporal_neighbors);
  if (!frames_finished_ && images_.size() <= d + n1) return false;
  const bool retrieval = retrieval_used_ && options_.num_retrieval_neighbors > 0;
  return !retrieval || retrieved_[d].has_value();
}

const std::vector<size_t>& IncrementalPairGenerator::RetrievalNeighborsOf(size_t k) {
  if (retrieval_neighbors_[k]) return *retrieval_neighbors_[k];
  std::vector<size_t>& neighbors = retrieval_neighbors_[k].emplace();
  if (!retrieval_used_ || options_.num_retrieval_neighbors == 0 || !retrieved_[k]) {
    return neighbors;
  }
  std::unordered_set<size_t> taken(temporal_[k].begin(), temporal_[k].end());
  taken.insert(k);
  for (const image_t candidate : *retrieved_[k]) {
    if (static_cast<int>(neighbors.size()) >= options_.num_retrieval_neighbors) break;
    const auto it = frame_of_image_.find(candidate);
    if (it == frame_of_image_.end() || !taken.insert(it->second).second) continue;
    neighbors.push_back(it->second);
  }
  return neighbors;
}

bool IncrementalPairGenerator::Next(size_t* frame, std::vector<ProposedPair>* pairs) {
  const size_t d = next_;
  if (!Decidable(d)) return false;
  pairs->clear();
  *frame = d;
  if (options_.mode == PairMode::kExhaustive) {
    for (size_t i = 0; i < d; ++i) pairs->push_back({i, "exhaustive"});
  } else if (options_.mode == PairMode::kSequential) {
    const size_t n1 = static_cast<size_t>(options_.num_temporal_neighbors);
    for (size_t i = d > n1 ? d - n1 : 0; i < d; ++i) pairs->push_back({i, "sequential"});
  } else {
    temporal_[d] = TemporalNeighbors(images_, d, options_.num_temporal_neighbors);
    std::vector<std::pair<size_t, const char*>> partners;
    std::unordered_set<size_t> taken;
    for (const size_t i : temporal_[d]) {
      if (i < d && taken.insert(i).second) partners.emplace_back(i, "temporal");
    }
    // Frames before it whose temporal neighbours include it.
    const size_t n1 = static_cast<size_t>(options_.num_temporal_neighbors);
    for (size_t i = d > n1 ? d - n1 : 0; i < d; ++i) {
      const std::vector<size_t>& of_i = temporal_[i];
      if (std::find(of_i.begin(), of_i.end(), d) != of_i.end() && taken.insert(i).second) {
        partners.emplace_back(i, "temporal");
      }
    }
    for (const size_t i : RetrievalNeighborsOf(d)) {
      if (i < d) {
        if (taken.insert(i).second) partners.emplace_back(i, "retrieval");
      } else {
        later_retrieval_partners_[i].push_back(d);
      }
    }
    // Frames before it that retrieved it.
    for (const size_t i : later_retrieval_partners_[d]) {
      if (taken.insert(i).second) partners.emplace_back(i, "retrieval");
    }
    std::sort(partners.begin(), partners.end());
    for (const auto& [i, source] : partners) pairs->push_back({i, source});
  }
  ++next_;
  return true;
}

}  // namespace viosfm
