#include "viosfm/matching/pair_generator.h"

#include <algorithm>
#include <unordered_set>

#include "viosfm/matching/incremental_pair_generator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {

PairMode ParsePairMode(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "exhaustive") return PairMode::kExhaustive;
  if (lower == "sequential") return PairMode::kSequential;
  if (lower == "temporal_retrieval") return PairMode::kTemporalRetrieval;
  if (lower == "pair_list") return PairMode::kPairList;
  throw InputError("unknown pair mode '" + name +
                   "': expected exhaustive, sequential, temporal_retrieval or pair_list");
}

std::string PairModeName(PairMode mode) {
  switch (mode) {
    case PairMode::kExhaustive: return "exhaustive";
    case PairMode::kSequential: return "sequential";
    case PairMode::kTemporalRetrieval: return "temporal_retrieval";
    case PairMode::kPairList: return "pair_list";
  }
  return "unknown";
}

std::string PairGeneratorOptions::Validate() const {
  if (num_temporal_neighbors < 0) return "num_temporal_neighbors must be >= 0";
  if (num_retrieval_neighbors < 0) return "num_retrieval_neighbors must be >= 0";
  return "";
}

std::vector<ImagePair> SortAndDeduplicatePairs(std::vector<ImagePair> pairs) {
  for (ImagePair& pair : pairs) pair = ImagePair::Ordered(pair.image_id1, pair.image_id2);
  std::erase_if(pairs, [](const ImagePair& pair) { return pair.image_id1 == pair.image_id2; });
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

std::vector<ImagePair> ExhaustivePairs(const std::vector<PairGeneratorImage>& images) {
  std::vector<ImagePair> pairs;
  pairs.reserve(images.size() * (images.size() - (images.empty() ? 0 : 1)) / 2);
  for (size_t a = 0; a < images.size(); ++a) {
    for (size_t b = a + 1; b < images.size(); ++b) {
      pairs.push_back({images[a].image_id, images[b].image_id});
    }
  }
  return SortAndDeduplicatePairs(std::move(pairs));
}

std::vector<ImagePair> SequentialPairs(const std::vector<PairGeneratorImage>& images,
                                       int num_next) {
  std::vector<ImagePair> pairs;
  for (size_t a = 0; a < images.size(); ++a) {
    for (size_t b = a + 1; b < images.size() && b <= a + static_cast<size_t>(num_next); ++b) {
      pairs.push_back({images[a].image_id, images[b].image_id});
    }
  }
  return SortAndDeduplicatePairs(std::move(pairs));
}

std::vector<size_t> TemporalNeighbors(const std::vector<PairGeneratorImage>& images, size_t k,
                                      int count) {
  std::vector<size_t> neighbors;
  // Two cursors walking outwards from k; the nearer in time goes first.
  size_t left = k;   // next candidate is left - 1
  size_t right = k;  // next candidate is right + 1
  while (static_cast<int>(neighbors.size()) < count) {
    const bool has_left = left > 0;
    const bool has_right = right + 1 < images.size();
    if (!has_left && !has_right) break;
    bool take_left = has_left;
    if (has_left && has_right) {
      const timestamp_ns_t gap_left = images[k].timestamp_ns - images[left - 1].timestamp_ns;
      const timestamp_ns_t gap_right = images[right + 1].timestamp_ns - images[k].timestamp_ns;
      take_left = gap_left <= gap_right;
    }
    neighbors.push_back(take_left ? --left : ++right);
  }
  return neighbors;
}

std::vector<ImagePair> TemporalRetrievalPairs(const std::vector<PairGeneratorImage>& images,
                                              const std::vector<std::vector<image_t>>& retrieval,
                                              int num_temporal_neighbors,
                                              int num_retrieval_neighbors) {
  VIOSFM_CHECK(retrieval.empty() || retrieval.size() == images.size());
  // The frames fed to the incremental generator as a recording known up
  // front: the same pairs, frame by frame.
  PairGeneratorOptions options;
  options.mode = PairMode::kTemporalRetrieval;
  options.num_temporal_neighbors = num_temporal_neighbors;
  options.num_retrieval_neighbors = num_retrieval_neighbors;
  IncrementalPairGenerator generator(options);
  generator.SetRetrievalUsed(!retrieval.empty());
  for (const PairGeneratorImage& image : images) generator.AddFrame(image);
  for (size_t k = 0; k < retrieval.size(); ++k) generator.SetRetrieved(k, retrieval[k]);
  generator.FinishFrames();
  std::vector<ImagePair> pairs;
  size_t frame = 0;
  std::vector<ProposedPair> proposed;
  while (generator.Next(&frame, &proposed)) {
    for (const ProposedPair& pair : proposed) {
      pairs.push_back({images[pair.earlier_frame].image_id, images[frame].image_id});
    }
  }
  VIOSFM_CHECK(generator.HasFinished());
  return SortAndDeduplicatePairs(std::move(pairs));
}

std::vector<ImagePair> PairsFromNameList(const ImageNamePairList& list,
                                         const std::unordered_map<std::string, image_t>& ids) {
  std::vector<ImagePair> pairs;
  pairs.reserve(list.pairs.size());
  for (const ImageNamePair& named : list.pairs) {
    image_t found[2] = {kInvalidImageId, kInvalidImageId};
    const std::string* names[2] = {&named.name1, &named.name2};
    for (int side = 0; side < 2; ++side) {
      const auto it = ids.find(*names[side]);
      if (it == ids.end()) {
        throw InputError(list.path.string(), named.line,
                         "unknown image '" + *names[side] + "' (expected one of the " +
                             std::to_string(ids.size()) + " images of the sequence)");
      }
      found[side] = it->second;
    }
    if (found[0] == found[1]) {
      throw InputError(list.path.string(), named.line,
                       "expected two different images, got the same image twice ('" + named.name1 +
                           "', '" + named.name2 + "')");
    }
    pairs.push_back({found[0], found[1]});
  }
  return SortAndDeduplicatePairs(std::move(pairs));
}

std::vector<ImagePair> GeneratePairs(const PairGeneratorInput& input,
                                     const PairGeneratorOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("pair generator options: " + error);
  }
  if (options.mode == PairMode::kPairList) {
    return PairsFromNameList(input.pair_list, input.image_ids_by_name);
  }
  for (size_t k = 1; k < input.images.size(); ++k) {
    if (input.images[k].timestamp_ns <= input.images[k - 1].timestamp_ns) {
      throw InputError("pair generation: images must be in strictly increasing time; image " +
                       std::to_string(input.images[k].image_id) + " (position " +
                       std::to_string(k) + ") is not after image " +
                       std::to_string(input.images[k - 1].image_id));
    }
  }
  switch (options.mode) {
    case PairMode::kExhaustive: return ExhaustivePairs(input.images);
    case PairMode::kSequential:
      return SequentialPairs(input.images, options.num_temporal_neighbors);
    case PairMode::kTemporalRetrieval:
      if (!input.retrieval.empty() && input.retrieval.size() != input.images.size()) {
        throw InputError("pair generation: expected one retrieval list per image (" +
                         std::to_string(input.images.size()) + "), got " +
                         std::to_string(input.retrieval.size()));
      }
      return TemporalRetrievalPairs(input.images, input.retrieval, options.num_temporal_neighbors,
                                    options.num_retrieval_neighbors);
    case PairMode::kPairList: break;
  }
  return {};
}

std::vector<ImageNamePair> PairsToNames(const std::vector<ImagePair>& pairs,
                                        const std::unordered_map<image_t, std::string>& names) {
  std::vector<ImageNamePair> named;
  named.reserve(pairs.size());
  auto name_of = [&](image_t id) -> const std::string& {
    const auto it = names.find(id);
    if (it == names.end()) throw InputError("no image name for image id " + std::to_string(id));
    return it->second;
  };
  for (const ImagePair& pair : pairs) {
    named.push_back({name_of(pair.image_id1), name_of(pair.image_id2), 0});
  }
  return named;
}

}  // namespace viosfm
