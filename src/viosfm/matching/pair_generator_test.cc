#include "viosfm/matching/pair_generator.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>

#include "viosfm/io/pair_list.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// Images with ids first_id, first_id + 1, ... every `period_s` seconds.
std::vector<PairGeneratorImage> Images(int count, image_t first_id = 1, double period_s = 1.0) {
  std::vector<PairGeneratorImage> images;
  for (int k = 0; k < count; ++k) {
    images.push_back({first_id + static_cast<image_t>(k), SecondsToNs(k * period_s)});
  }
  return images;
}

std::vector<std::pair<image_t, image_t>> AsPairs(const std::vector<ImagePair>& pairs) {
  std::vector<std::pair<image_t, image_t>> out;
  for (const ImagePair& pair : pairs) out.emplace_back(pair.image_id1, pair.image_id2);
  return out;
}

using P = std::pair<image_t, image_t>;

TEST(PairGenerator, Exhaustive) {
  const std::vector<ImagePair> pairs = ExhaustivePairs(Images(6, 10));
  EXPECT_EQ(pairs.size(), 15u);
  EXPECT_EQ(AsPairs(pairs).front(), P(10, 11));
  EXPECT_EQ(AsPairs(pairs).back(), P(14, 15));
  EXPECT_TRUE(ExhaustivePairs({}).empty());
}

TEST(PairGenerator, SequentialTakesTheNextN1) {
  EXPECT_THAT(
      AsPairs(SequentialPairs(Images(5, 10), 2)),
      ElementsAre(P(10, 11), P(10, 12), P(11, 12), P(11, 13), P(12, 13), P(12, 14), P(13, 14)));
}

TEST(PairGenerator, TemporalNeighborsAreTheNearestInTime) {
  const std::vector<PairGeneratorImage> images = Images(7);
  EXPECT_THAT(TemporalNeighbors(images, 0, 2), ElementsAre(1, 2));
  EXPECT_THAT(TemporalNeighbors(images, 3, 2), ElementsAre(2, 4));  // earlier first on a tie
  EXPECT_THAT(TemporalNeighbors(images, 3, 3), ElementsAre(2, 4, 1));
  EXPECT_THAT(TemporalNeighbors(images, 6, 3), ElementsAre(5, 4, 3));
  EXPECT_THAT(TemporalNeighbors(images, 3, 100), ElementsAre(2, 4, 1, 5, 0, 6));
  // Uneven stamps: nearest by time, not by index.
  const std::vector<PairGeneratorImage> uneven = {
      {1, SecondsToNs(0.0)}, {2, SecondsToNs(0.1)}, {3, SecondsToNs(0.15)}, {4, SecondsToNs(0.4)}};
  EXPECT_THAT(TemporalNeighbors(uneven, 1, 1), ElementsAre(2));
  EXPECT_THAT(TemporalNeighbors(uneven, 2, 2), ElementsAre(1, 0));
}

TEST(PairGenerator, TemporalPlusRetrievalExactSet) {
  const std::vector<PairGeneratorImage> images = Images(6);  // ids 1..6
  // N1 = 2 temporal: 1:{2,3} 2:{1,3} 3:{2,4} 4:{3,5} 5:{4,6} 6:{5,4}.
  // N2 = 1 retrieval, skipping the query, unknown ids and temporal neighbours.
  const std::vector<std::vector<image_t>> retrieval = {
      {2, 6, 5},         // 1: 2 is temporal -> 6
      {2, 99, 3, 5, 6},  // 2: self, unknown, temporal -> 5
      {},                // 3: nothing
      {1},               // 4: 1
      {2},               // 5: 2 (again the pair 2-5)
      {1, 3}};           // 6: 1 (again 1-6); only one taken
  EXPECT_THAT(AsPairs(TemporalRetrievalPairs(images, retrieval, 2, 1)),
              ElementsAre(P(1, 2), P(1, 3), P(1, 4), P(1, 6), P(2, 3), P(2, 5), P(3, 4), P(4, 5),
                          P(4, 6), P(5, 6)));
  // N2 = 0: the temporal pairs only; no retrieval: the same.
  EXPECT_THAT(AsPairs(TemporalRetrievalPairs(images, retrieval, 2, 0)),
              ElementsAre(P(1, 2), P(1, 3), P(2, 3), P(3, 4), P(4, 5), P(4, 6), P(5, 6)));
  EXPECT_EQ(TemporalRetrievalPairs(images, {}, 2, 5),
            TemporalRetrievalPairs(images, retrieval, 2, 0));
}

TEST(PairGenerator, OutputIsOrderedSortedUniqueAndCoversEveryNeighbour) {
  Random random(3);
  const int n = 60;
  const int n1 = 6;
  const int n2 = 4;
  const std::vector<PairGeneratorImage> images = Images(n, 100, 0.1);
  std::vector<std::vector<image_t>> retrieval(n);
  for (auto& ranked : retrieval) {
    for (int r = 0; r < 15; ++r) ranked.push_back(100 + random.UniformInt(0, n - 1));
  }
  PairGeneratorInput input;
  input.images = images;
  input.retrieval = retrieval;
  PairGeneratorOptions options;
  options.num_temporal_neighbors = n1;
  options.num_retrieval_neighbors = n2;
  const std::vector<ImagePair> pairs = GeneratePairs(input, options);
  std::set<P> set;
  for (size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_LT(pairs[i].image_id1, pairs[i].image_id2);
    if (i > 0) {
      EXPECT_LT(pairs[i - 1], pairs[i]);
    }
    set.insert({pairs[i].image_id1, pairs[i].image_id2});
  }
  for (int k = 0; k < n; ++k) {
    const image_t query = images[k].image_id;
    for (const size_t t : TemporalNeighbors(images, k, n1)) {
      const image_t other = images[t].image_id;
      EXPECT_TRUE(set.contains({std::min(query, other), std::max(query, other)}));
    }
  }
  // Symmetric input order: the same list whichever way the pairs were found.
  std::vector<ImagePair> swapped;
  for (const ImagePair& pair : pairs) swapped.push_back({pair.image_id2, pair.image_id1});
  swapped.insert(swapped.end(), pairs.begin(), pairs.end());
  swapped.push_back({105, 105});
  EXPECT_EQ(SortAndDeduplicatePairs(swapped), pairs);
  // Bounded by N1 + N2 per image.
  EXPECT_LE(pairs.size(), static_cast<size_t>(n * (n1 + n2)));
  EXPECT_GE(pairs.size(), static_cast<size_t>(n * n1 / 2));
}

TEST(PairGenerator, BadInputThrows) {
  PairGeneratorInput input;
  input.images = {{1, 100}, {2, 100}};
  EXPECT_THROW(GeneratePairs(input, {}), InputError);
  input.images = Images(3);
  input.retrieval = {{2}};
  EXPECT_THROW(GeneratePairs(input, {}), InputError);
  PairGeneratorOptions options;
  options.num_temporal_neighbors = -1;
  EXPECT_THAT(options.Validate(), HasSubstr("num_temporal_neighbors"));
  EXPECT_THROW(GeneratePairs(input, options), InputError);
  EXPECT_EQ(ParsePairMode("Sequential"), PairMode::kSequential);
  EXPECT_EQ(PairModeName(ParsePairMode("temporal_retrieval")), "temporal_retrieval");
  EXPECT_THROW(ParsePairMode("spatial"), InputError);
}

TEST(PairGenerator, PairListFileRoundTrip) {
  namespace fs = std::filesystem;
  const fs::path dir = testing::MakeScratchFolder("pair_generator_list");
  std::unordered_map<image_t, std::string> names;
  std::unordered_map<std::string, image_t> ids;
  for (image_t id = 1; id <= 8; ++id) {
    names[id] = "cam0/" + std::to_string(1000 + id) + ".png";
    ids[names[id]] = id;
  }
  PairGeneratorOptions options;
  options.mode = PairMode::kSequential;
  options.num_temporal_neighbors = 3;
  PairGeneratorInput input;
  input.images = Images(8);
  const std::vector<ImagePair> pairs = GeneratePairs(input, options);
  const fs::path path = dir / "pairs.txt";
  WriteImagePairList(path, PairsToNames(pairs, names));

  PairGeneratorInput from_file;
  from_file.pair_list = ReadImagePairList(path);
  from_file.image_ids_by_name = ids;
  options.mode = PairMode::kPairList;
  EXPECT_EQ(GeneratePairs(from_file, options), pairs);

  // Unknown names are reported with the file and line.
  ImageNamePairList bad = from_file.pair_list;
  bad.pairs[2].name2 = "cam0/nope.png";
  try {
    PairsFromNameList(bad, ids);
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr(path.string() + ":3:"));
    EXPECT_THAT(error.what(), HasSubstr("cam0/nope.png"));
  }
  EXPECT_THROW(PairsToNames({{1, 42}}, names), InputError);
}

}  // namespace
}  // namespace viosfm
