// Which image pairs to match.
//
// Modes:
//  - exhaustive: every pair;
//  - sequential: each image with the next N1 images in time (COLMAP's
//    sequential matcher with overlap N1);
//  - temporal+retrieval (the paper): for each image, its N1 temporal
//    neighbours (the N1 images nearest in time: N1/2 on each side inside the
//    sequence, more on one side at its ends) plus its N2 best retrieval
//    neighbours that are not already among those temporal neighbours;
//  - pair list: the pairs of a COLMAP-style pair-list file (io/pair_list.h).
// Every mode returns a deduplicated list of pairs, each ordered (image_id1 <
// image_id2) and the list sorted, so the output is deterministic.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "viosfm/io/pair_list.h"
#include "viosfm/matching/image_pair.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"

namespace viosfm {

enum class PairMode { kExhaustive, kSequential, kTemporalRetrieval, kPairList };

// "exhaustive", "sequential", "temporal_retrieval", "pair_list" (any case);
// throws InputError otherwise.
PairMode ParsePairMode(const std::string& name);
std::string PairModeName(PairMode mode);
// The option texts (util/option_fields.h).
inline std::string OptionText(PairMode value) {
  return PairModeName(value);
}
inline void ParseOptionText(const std::string& text, PairMode* value) {
  *value = ParsePairMode(text);
}

struct PairGeneratorOptions {
  PairMode mode = PairMode::kTemporalRetrieval;  // default: the paper's
  // N1: temporal neighbours per image (images; sequential mode: the next N1
  // images). Default 40 (the paper's, at 10 Hz input).
  int num_temporal_neighbors = 40;
  // N2: retrieval neighbours per image, beyond the temporal ones (images).
  // Default 30 (the paper's).
  int num_retrieval_neighbors = 30;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct PairGeneratorImage {
  image_t image_id = kInvalidImageId;
  timestamp_ns_t timestamp_ns = 0;
};

struct PairGeneratorInput {
  // All modes but kPairList: the images, in strictly increasing time.
  std::vector<PairGeneratorImage> images;
  // kTemporalRetrieval: retrieval[k] ranks images[k]'s visually similar
  // images, most similar first (at least N1 + N2 + 1 long to always give N2
  // after excluding the query and its temporal neighbours; ids not in
  // `images` are skipped). Empty: no retrieval neighbours.
  std::vector<std::vector<image_t>> retrieval;
  // kPairList: the list read from a file and the ids of the named images.
  ImageNamePairList pair_list;
  std::unordered_map<std::string, image_t> image_ids_by_name;
};

// Orders every pair, drops self pairs and duplicates, sorts.
std::vector<ImagePair> SortAndDeduplicatePairs(std::vector<ImagePair> pairs);

std::vector<ImagePair> ExhaustivePairs(const std::vector<PairGeneratorImage>& images);
std::vector<ImagePair> SequentialPairs(const std::vector<PairGeneratorImage>& images, int num_next);
// Indices (into `images`) of the `count` images nearest in time to images[k],
// nearest first; on equal time gaps the earlier image first.
std::vector<size_t> TemporalNeighbors(const std::vector<PairGeneratorImage>& images, size_t k,
                                      int count);
std::vector<ImagePair> TemporalRetrievalPairs(const std::vector<PairGeneratorImage>& images,
                                              const std::vector<std::vector<image_t>>& retrieval,
                                              int num_temporal_neighbors,
                                              int num_retrieval_neighbors);
// Throws InputError naming the list's file and line for a name without id.
std::vector<ImagePair> PairsFromNameList(const ImageNamePairList& list,
                                         const std::unordered_map<std::string, image_t>& ids);

// Dispatches on options.mode. Invalid options or an input that does not fit
// the mode (images not in increasing time, retrieval of the wrong size) throw
// InputError.
std::vector<ImagePair> GeneratePairs(const PairGeneratorInput& input,
                                     const PairGeneratorOptions& options);

// The pairs as names, for WriteImagePairList; throws InputError for an id
// without name.
std::vector<ImageNamePair> PairsToNames(const std::vector<ImagePair>& pairs,
                                        const std::unordered_map<image_t, std::string>& names);

}  // namespace viosfm
