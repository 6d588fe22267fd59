#include "viosfm/sfm/tracks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

using ::testing::ElementsAre;

MATCHER_P2(Element, image_id, point2D_idx, "") {
  return arg.image_id == static_cast<image_t>(image_id) &&
         arg.point2D_idx == static_cast<point2D_t>(point2D_idx);
}

ImagePairMatches Pair(image_t image_id1, image_t image_id2,
                      std::vector<std::pair<point2D_t, point2D_t>> matches) {
  ImagePairMatches pair;
  pair.image_id1 = image_id1;
  pair.image_id2 = image_id2;
  for (const auto& [a, b] : matches) pair.matches.push_back({a, b});
  return pair;
}

// Matches of every image pair among `images` for the scene point whose
// keypoint in image i is keypoints[i].
void AddAllPairs(const std::vector<image_t>& images, const std::vector<point2D_t>& keypoints,
                 std::vector<ImagePairMatches>* pairs) {
  for (size_t a = 0; a < images.size(); ++a) {
    for (size_t b = a + 1; b < images.size(); ++b) {
      pairs->push_back(Pair(images[a], images[b], {{keypoints[a], keypoints[b]}}));
    }
  }
}

// keypoint[j][i]: the keypoint index of scene point j in image i, a random
// permutation of the points in each image.
std::vector<std::vector<point2D_t>> RandomKeypoints(int num_points, int num_images,
                                                    Random* random) {
  std::vector<std::vector<point2D_t>> keypoint(num_points, std::vector<point2D_t>(num_images));
  for (int i = 0; i < num_images; ++i) {
    std::vector<point2D_t> indices(num_points);
    for (int j = 0; j < num_points; ++j) indices[j] = static_cast<point2D_t>(j);
    std::shuffle(indices.begin(), indices.end(), random->engine());
    for (int j = 0; j < num_points; ++j) keypoint[j][i] = indices[j];
  }
  return keypoint;
}

TEST(TracksTest, BuildsExactTracksSortedWithHistogram) {
  const std::vector<ImagePairMatches> pairs = {
      Pair(2, 3, {{0, 5}, {1, 6}}),
      Pair(1, 2, {{1, 1}, {0, 0}}),
      Pair(3, 1, {{5, 0}}),  // reversed orientation
      Pair(5, 4, {{3, 3}}),
  };
  const TrackBuildResult result = BuildTracks(pairs);
  ASSERT_EQ(result.tracks.size(), 3u);
  EXPECT_THAT(result.tracks[0].elements, ElementsAre(Element(1, 0), Element(2, 0), Element(3, 5)));
  EXPECT_THAT(result.tracks[1].elements, ElementsAre(Element(1, 1), Element(2, 1), Element(3, 6)));
  EXPECT_THAT(result.tracks[2].elements, ElementsAre(Element(4, 3), Element(5, 3)));
  const TrackStatistics& stats = result.statistics;
  EXPECT_EQ(stats.num_pairs, 4u);
  EXPECT_EQ(stats.num_input_matches, 6u);
  EXPECT_EQ(stats.num_unique_matches, 6u);
  EXPECT_EQ(stats.num_components, 3u);
  EXPECT_EQ(stats.num_inconsistent_components, 0u);
  EXPECT_EQ(stats.num_tracks, 3u);
  EXPECT_EQ(stats.num_observations, 8u);
  EXPECT_THAT(stats.length_histogram, ElementsAre(0, 0, 1, 2));
  EXPECT_FALSE(stats.Summary().empty());
}

TEST(TracksTest, MinTrackLengthDropsShortTracks) {
  const std::vector<ImagePairMatches> pairs = {Pair(1, 2, {{0, 0}}), Pair(2, 3, {{0, 0}}),
                                               Pair(4, 5, {{7, 7}})};
  TrackBuilderOptions options;
  options.min_track_length = 3;
  const TrackBuildResult result = BuildTracks(pairs, options);
  ASSERT_EQ(result.tracks.size(), 1u);
  EXPECT_THAT(result.tracks[0].elements, ElementsAre(Element(1, 0), Element(2, 0), Element(3, 0)));
  EXPECT_EQ(result.statistics.num_dropped_short, 1u);
}

TEST(TracksTest, DuplicatesAndSelfMatchesAreIgnored) {
  const std::vector<ImagePairMatches> pairs = {Pair(1, 2, {{0, 0}, {0, 0}}), Pair(2, 1, {{0, 0}}),
                                               Pair(3, 3, {{0, 1}})};
  const TrackBuildResult result = BuildTracks(pairs);
  ASSERT_EQ(result.tracks.size(), 1u);
  EXPECT_THAT(result.tracks[0].elements, ElementsAre(Element(1, 0), Element(2, 0)));
  EXPECT_EQ(result.statistics.num_input_matches, 4u);
  EXPECT_EQ(result.statistics.num_unique_matches, 1u);
  EXPECT_EQ(result.statistics.num_self_matches, 1u);
}

// Two scene points A (keypoint 10 in images 1..5) and B (keypoint 20), each
// matched in all pairs, and one wrong match A in image 1 <-> B in image 2
// that joins them into one component holding two keypoints of each image.
std::vector<ImagePairMatches> BridgedTracks() {
  std::vector<ImagePairMatches> pairs;
  AddAllPairs({1, 2, 3, 4, 5}, {10, 10, 10, 10, 10}, &pairs);
  AddAllPairs({1, 2, 3, 4, 5}, {20, 20, 20, 20, 20}, &pairs);
  pairs.push_back(Pair(1, 2, {{10, 20}}));
  return pairs;
}

TEST(TracksTest, SplitRefusesTheUnsupportedBridgingMatch) {
  const TrackBuildResult result = BuildTracks(BridgedTracks());
  ASSERT_EQ(result.tracks.size(), 2u);
  EXPECT_THAT(result.tracks[0].elements, ElementsAre(Element(1, 10), Element(2, 10), Element(3, 10),
                                                     Element(4, 10), Element(5, 10)));
  EXPECT_THAT(result.tracks[1].elements, ElementsAre(Element(1, 20), Element(2, 20), Element(3, 20),
                                                     Element(4, 20), Element(5, 20)));
  const TrackStatistics& stats = result.statistics;
  EXPECT_EQ(stats.num_components, 1u);
  EXPECT_EQ(stats.num_inconsistent_components, 1u);
  EXPECT_EQ(stats.num_refused_matches, 1u);
  EXPECT_EQ(stats.num_split_pieces, 2u);
  EXPECT_EQ(stats.num_dropped_inconsistent, 0u);
  EXPECT_THAT(stats.length_histogram, ElementsAre(0, 0, 0, 0, 0, 2));
}

TEST(TracksTest, DropPolicyDiscardsInconsistentComponents) {
  std::vector<ImagePairMatches> pairs = BridgedTracks();
  pairs.push_back(Pair(7, 8, {{1, 1}}));  // an unrelated consistent track
  TrackBuilderOptions options;
  options.conflict_policy = TrackConflictPolicy::kDrop;
  const TrackBuildResult result = BuildTracks(pairs, options);
  ASSERT_EQ(result.tracks.size(), 1u);
  EXPECT_THAT(result.tracks[0].elements, ElementsAre(Element(7, 1), Element(8, 1)));
  EXPECT_EQ(result.statistics.num_dropped_inconsistent, 1u);
  EXPECT_EQ(result.statistics.num_refused_matches, 0u);
}

TEST(TracksTest, NonUniqueMatchInAPairIsSplitOff) {
  // Keypoint 0 of image 1 is matched to keypoints 0 and 1 of image 2; image 3
  // confirms 0 <-> 0.
  const std::vector<ImagePairMatches> pairs = {Pair(1, 2, {{0, 0}, {0, 1}}), Pair(1, 3, {{0, 0}}),
                                               Pair(2, 3, {{0, 0}})};
  const TrackBuildResult result = BuildTracks(pairs);
  ASSERT_EQ(result.tracks.size(), 1u);
  EXPECT_THAT(result.tracks[0].elements, ElementsAre(Element(1, 0), Element(2, 0), Element(3, 0)));
  EXPECT_EQ(result.statistics.num_refused_matches, 1u);
  EXPECT_EQ(result.statistics.num_split_pieces, 2u);
  EXPECT_EQ(result.statistics.num_dropped_short, 1u);  // keypoint 1 of image 2 alone
}

// The pairs of images (counted from 0, ids from 1) at most `max_gap`
// apart, in order, each with the matches `fill(a, b, &pair)` gives.
template <class Fill>
std::vector<ImagePairMatches> PairsWithin(int num_images, int max_gap, Fill&& fill) {
  std::vector<ImagePairMatches> pairs;
  for (image_t a = 0; a < static_cast<image_t>(num_images); ++a) {
    for (image_t b = a + 1; b < static_cast<image_t>(num_images) && b <= a + max_gap; ++b) {
      ImagePairMatches pair{a + 1, b + 1, {}};
      fill(a, b, &pair);
      pairs.push_back(std::move(pair));
    }
  }
  return pairs;
}

// A match between two random keypoints of [0, num_points).
FeatureMatch RandomMatch(int num_points, Random* random) {
  return {static_cast<point2D_t>(random->UniformInt(0, num_points - 1)),
          static_cast<point2D_t>(random->UniformInt(0, num_points - 1))};
}

void ExpectSameTracks(const std::vector<Track>& a, const std::vector<Track>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].elements, b[i].elements) << "track " << i;
}

TEST(TracksTest, OutputDoesNotDependOnPairOrderOrOrientation) {
  // 60 scene points in 8 images (random keypoint indices), matched in every
  // pair of images at most 3 apart, plus 25 random wrong matches.
  Random random(7);
  constexpr int kNumImages = 8;
  constexpr int kNumPoints = 60;
  const std::vector<std::vector<point2D_t>> keypoint =
      RandomKeypoints(kNumPoints, kNumImages, &random);
  int num_wrong = 0;
  const std::vector<ImagePairMatches> pairs =
      PairsWithin(kNumImages, 3, [&](image_t a, image_t b, ImagePairMatches* pair) {
        for (int j = 0; j < kNumPoints; ++j) {
          pair->matches.push_back({keypoint[j][a], keypoint[j][b]});
        }
        for (int k = 0; k < 3 && num_wrong < 25; ++k, ++num_wrong) {
          pair->matches.push_back(RandomMatch(kNumPoints, &random));
        }
      });
  const TrackBuildResult reference = BuildTracks(pairs);
  EXPECT_GT(reference.statistics.num_inconsistent_components, 0u);
  for (const Track& track : reference.tracks) {
    std::set<image_t> images;
    for (const TrackElement& element : track.elements) {
      EXPECT_TRUE(images.insert(element.image_id).second) << "two keypoints of one image";
    }
  }

  for (int trial = 0; trial < 5; ++trial) {
    std::vector<ImagePairMatches> shuffled = pairs;
    std::shuffle(shuffled.begin(), shuffled.end(), random.engine());
    for (ImagePairMatches& pair : shuffled) {
      std::shuffle(pair.matches.begin(), pair.matches.end(), random.engine());
      if (random.Uniform() < 0.5) {
        std::swap(pair.image_id1, pair.image_id2);
        for (FeatureMatch& match : pair.matches) std::swap(match.point2D_idx1, match.point2D_idx2);
      }
    }
    const TrackBuildResult result = BuildTracks(shuffled);
    ExpectSameTracks(result.tracks, reference.tracks);
    EXPECT_EQ(result.statistics.num_refused_matches, reference.statistics.num_refused_matches);
    EXPECT_EQ(result.statistics.length_histogram, reference.statistics.length_histogram);
  }
}

// Every figure of a track build, compared.
void ExpectSameStatistics(const TrackStatistics& a, const TrackStatistics& b) {
  EXPECT_EQ(a.num_pairs, b.num_pairs);
  EXPECT_EQ(a.num_input_matches, b.num_input_matches);
  EXPECT_EQ(a.num_unique_matches, b.num_unique_matches);
  EXPECT_EQ(a.num_self_matches, b.num_self_matches);
  EXPECT_EQ(a.num_components, b.num_components);
  EXPECT_EQ(a.num_inconsistent_components, b.num_inconsistent_components);
  EXPECT_EQ(a.num_refused_matches, b.num_refused_matches);
  EXPECT_EQ(a.num_split_pieces, b.num_split_pieces);
  EXPECT_EQ(a.num_dropped_inconsistent, b.num_dropped_inconsistent);
  EXPECT_EQ(a.num_dropped_short, b.num_dropped_short);
  EXPECT_EQ(a.num_tracks, b.num_tracks);
  EXPECT_EQ(a.num_observations, b.num_observations);
  EXPECT_EQ(a.length_histogram, b.length_histogram);
}

// The incremental builder, given the pairs a few at a time in a random
// order (with wrong matches that split components, a pair given twice and
// a self-match), gives after every addition what BuildTracks gives of every
// pair added so far, with either conflict policy and a minimum length.
TEST(TracksTest, IncrementalBuildIsTheBuildOfEveryPairSoFar) {
  Random random(11);
  constexpr int kNumImages = 30;
  constexpr int kNumPoints = 80;
  const std::vector<std::vector<point2D_t>> keypoint =
      RandomKeypoints(kNumPoints, kNumImages, &random);
  std::vector<ImagePairMatches> pairs =
      PairsWithin(kNumImages, 4, [&](image_t a, image_t b, ImagePairMatches* pair) {
        for (int j = 0; j < kNumPoints; ++j) {
          // Each point seen in a stretch of images; wrong matches now and then.
          if ((j + a) % 9 == 0) continue;
          pair->matches.push_back({keypoint[j][a], keypoint[j][b]});
        }
        if (a % 6 == 0 && b == a + 2) pair->matches.push_back(RandomMatch(kNumPoints, &random));
      });
  pairs.push_back(pairs[5]);              // a pair given twice
  pairs.push_back(Pair(3, 3, {{1, 2}}));  // a self-match
  std::shuffle(pairs.begin(), pairs.end(), random.engine());
  std::vector<std::pair<image_t, size_t>> num_keypoints;
  for (image_t i = 1; i <= kNumImages; ++i) num_keypoints.emplace_back(i, kNumPoints);

  for (const TrackConflictPolicy policy :
       {TrackConflictPolicy::kSplit, TrackConflictPolicy::kDrop}) {
    TrackBuilderOptions options;
    options.conflict_policy = policy;
    options.min_track_length = 3;
    IncrementalTrackBuilder builder(num_keypoints, options);
    std::vector<ImagePairMatches> so_far;
    for (size_t begin = 0; begin < pairs.size();) {
      const size_t end =
          std::min(pairs.size(), begin + 1 + static_cast<size_t>(random.UniformInt(0, 9)));
      const std::vector<ImagePairMatches> handful(pairs.begin() + static_cast<ptrdiff_t>(begin),
                                                  pairs.begin() + static_cast<ptrdiff_t>(end));
      builder.AddPairs(handful);
      so_far.insert(so_far.end(), handful.begin(), handful.end());
      const TrackBuildResult reference = BuildTracks(so_far, options);
      const TrackBuildResult result = builder.Result();
      ExpectSameTracks(result.tracks, reference.tracks);
      ExpectSameStatistics(result.statistics, reference.statistics);
      begin = end;
    }
    const TrackBuildResult whole = BuildTracks(pairs, options);
    EXPECT_GT(whole.statistics.num_inconsistent_components, 0u);
    EXPECT_GT(whole.statistics.num_tracks, 0u);
  }
}

TEST(TracksTest, IncrementalBuildRefusesBadPairs) {
  IncrementalTrackBuilder builder({{1, 10}, {2, 5}});
  EXPECT_THROW(builder.AddPairs({Pair(1, 7, {{0, 0}})}), InputError);
  EXPECT_THROW(builder.AddPairs({Pair(1, 2, {{9, 5}})}), InputError);
}

TEST(TracksTest, OptionsValidate) {
  TrackBuilderOptions options;
  EXPECT_TRUE(options.Check());
  options.min_track_length = 1;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("min_track_length"));
  EXPECT_THROW(BuildTracks({}, options), InternalError);
}

}  // namespace
}  // namespace viosfm
