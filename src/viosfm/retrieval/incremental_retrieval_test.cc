#include "viosfm/retrieval/incremental_retrieval.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "viosfm/retrieval/synthetic_test_images.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

using testing::MakeSyntheticImages;
using testing::SmallOptions;
using testing::SyntheticImages;

std::vector<RetrievedFrame> AddAll(const SyntheticImages& images, IncrementalRetrieval* retrieval) {
  std::vector<RetrievedFrame> retrieved;
  for (size_t i = 0; i < images.image_ids.size(); ++i) {
    for (RetrievedFrame& frame : retrieval->Add(images.image_ids[i], images.descriptors[i])) {
      retrieved.push_back(std::move(frame));
    }
  }
  for (RetrievedFrame& frame : retrieval->Finish()) retrieved.push_back(std::move(frame));
  return retrieved;
}

// The 20 places are seen three times each, 20 frames apart: every frame of
// a place's second and third visit finds the earlier visits first, and
// nothing after it (the frames come in order).
TEST(IncrementalRetrieval, EachFrameFindsTheEarlierVisitsOfItsPlace) {
  const SyntheticImages images = MakeSyntheticImages(5);
  IncrementalRetrieval retrieval(SmallOptions(), /*num_training_frames=*/25,
                                 /*num_temporal_neighbors=*/3);
  // Nothing is retrieved until the vocabulary's training frames are in.
  for (size_t i = 0; i < 24; ++i) {
    EXPECT_TRUE(retrieval.Add(images.image_ids[i], images.descriptors[i]).empty());
  }
  EXPECT_FALSE(retrieval.has_vocabulary());
  const std::vector<RetrievedFrame> first =
      retrieval.Add(images.image_ids[24], images.descriptors[24]);
  ASSERT_EQ(first.size(), 25u);  // the 25 waiting frames at once, in order
  EXPECT_TRUE(retrieval.has_vocabulary());
  std::vector<RetrievedFrame> retrieved = first;
  for (size_t i = 25; i < images.image_ids.size(); ++i) {
    const std::vector<RetrievedFrame> one =
        retrieval.Add(images.image_ids[i], images.descriptors[i]);
    ASSERT_EQ(one.size(), 1u);
    retrieved.push_back(one[0]);
  }
  EXPECT_TRUE(retrieval.Finish().empty());
  ASSERT_EQ(retrieved.size(), images.image_ids.size());
  for (size_t i = 0; i < retrieved.size(); ++i) {
    EXPECT_EQ(retrieved[i].image_id, images.image_ids[i]);
    // Only frames before the temporal window.
    for (const ImageScore& score : retrieved[i].similar) {
      const size_t j = static_cast<size_t>(
          std::find(images.image_ids.begin(), images.image_ids.end(), score.image_id) -
          images.image_ids.begin());
      EXPECT_LT(j + 3, i) << "frame " << i << " retrieved frame " << j;
    }
    // The earlier visits of its place, first.
    std::set<image_t> earlier_visits;
    for (size_t j = 0; j + 3 < i; ++j) {
      if (images.place[j] == images.place[i]) earlier_visits.insert(images.image_ids[j]);
    }
    ASSERT_GE(retrieved[i].similar.size(), earlier_visits.size()) << "frame " << i;
    for (size_t k = 0; k < earlier_visits.size(); ++k) {
      EXPECT_TRUE(earlier_visits.count(retrieved[i].similar[k].image_id))
          << "frame " << i << ": rank " << k << " is not an earlier visit";
    }
    EXPECT_LE(retrieved[i].similar.size(), 5u);
  }
}

// Frames already indexed keep their scores: adding later frames changes
// nothing of an earlier frame's result, and a run on the first frames
// alone gives the same results as the longer run for them.
TEST(IncrementalRetrieval, LaterFramesDoNotChangeEarlierResults) {
  const SyntheticImages images = MakeSyntheticImages(6);
  IncrementalRetrieval all(SmallOptions(), 20, 2);
  const std::vector<RetrievedFrame> whole = AddAll(images, &all);
  SyntheticImages prefix = images;
  prefix.image_ids.resize(40);
  prefix.descriptors.resize(40);
  IncrementalRetrieval part(SmallOptions(), 20, 2);
  const std::vector<RetrievedFrame> shorter = AddAll(prefix, &part);
  ASSERT_EQ(shorter.size(), 40u);
  for (size_t i = 0; i < shorter.size(); ++i) {
    ASSERT_EQ(shorter[i].similar.size(), whole[i].similar.size()) << "frame " << i;
    for (size_t k = 0; k < shorter[i].similar.size(); ++k) {
      EXPECT_EQ(shorter[i].similar[k].image_id, whole[i].similar[k].image_id);
      EXPECT_FLOAT_EQ(shorter[i].similar[k].score, whole[i].similar[k].score);
    }
  }
}

// A recording shorter than the training frames: Finish trains on what came.
TEST(IncrementalRetrieval, FinishTrainsOnTheFramesThatCame) {
  const SyntheticImages images = MakeSyntheticImages(7);
  IncrementalRetrieval retrieval(SmallOptions(), 1000, 3);
  for (size_t i = 0; i < images.image_ids.size(); ++i) {
    EXPECT_TRUE(retrieval.Add(images.image_ids[i], images.descriptors[i]).empty());
  }
  const std::vector<RetrievedFrame> retrieved = retrieval.Finish();
  ASSERT_EQ(retrieved.size(), images.image_ids.size());
  // The last frame (third visit of its place) finds both earlier visits.
  const size_t last = images.image_ids.size() - 1;
  ASSERT_GE(retrieved[last].similar.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    const auto it = std::find(images.image_ids.begin(), images.image_ids.end(),
                              retrieved[last].similar[k].image_id);
    EXPECT_EQ(images.place[static_cast<size_t>(it - images.image_ids.begin())], images.place[last]);
  }
}

TEST(IncrementalRetrieval, DescriptorsOfAnotherLengthAreRefused) {
  const SyntheticImages images = MakeSyntheticImages(8);
  IncrementalRetrieval retrieval(SmallOptions(), 2, 0);
  retrieval.Add(images.image_ids[0], images.descriptors[0]);
  retrieval.Add(images.image_ids[1], images.descriptors[1]);
  EXPECT_THAT([&] { retrieval.Add(5, FeatureDescriptors(3, 64)); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("image 5 has 64")));
}

}  // namespace
}  // namespace viosfm
