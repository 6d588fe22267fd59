// Synthetic descriptor "images" with a known answer, for the retrieval
// tests (header-only; not part of the library's API).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "viosfm/retrieval/image_retrieval.h"
#include "viosfm/scene/features.h"
#include "viosfm/util/random.h"
#include "viosfm/util/types.h"

namespace viosfm::testing {

// Synthetic "images": bags of descriptors drawn around 300 prototype
// descriptors ("true words"). Each of 20 places uses its own 40 prototypes;
// each place is seen by 3 near-duplicate images, which draw 85% of their
// descriptors from the place's prototypes and 15% from any prototype, each
// with uniform noise of +-4 per value. Input order interleaves the places,
// so that duplicates are 20 positions apart; image id = 1000 + 3 * index.
struct SyntheticImages {
  static constexpr int kPlaces = 20;
  static constexpr int kCopies = 3;
  std::vector<image_t> image_ids;
  std::vector<FeatureDescriptors> descriptors;
  std::vector<int> place;  // per image
};

inline SyntheticImages MakeSyntheticImages(uint64_t seed) {
  constexpr int kPrototypes = 300;
  constexpr int kWordsPerPlace = 40;
  constexpr int kDescriptorsPerImage = 120;
  Random random(seed);
  FeatureDescriptors prototypes(kPrototypes, 128);
  for (int p = 0; p < kPrototypes; ++p) {
    for (int d = 0; d < 128; ++d)
      prototypes(p, d) = static_cast<uint8_t>(random.UniformInt(0, 120));
  }
  std::vector<std::vector<int>> place_words(SyntheticImages::kPlaces);
  for (auto& words : place_words) {
    for (int w = 0; w < kWordsPerPlace; ++w)
      words.push_back(static_cast<int>(random.UniformInt(0, kPrototypes - 1)));
  }
  SyntheticImages images;
  for (int index = 0; index < SyntheticImages::kPlaces * SyntheticImages::kCopies; ++index) {
    const int place = index % SyntheticImages::kPlaces;
    FeatureDescriptors descriptors(kDescriptorsPerImage, 128);
    for (int i = 0; i < kDescriptorsPerImage; ++i) {
      const int prototype = random.Uniform() < 0.85
                                ? place_words[place][random.UniformInt(0, kWordsPerPlace - 1)]
                                : static_cast<int>(random.UniformInt(0, kPrototypes - 1));
      for (int d = 0; d < 128; ++d) {
        descriptors(i, d) =
            static_cast<uint8_t>(prototypes(prototype, d) + random.UniformInt(0, 8));
      }
    }
    images.image_ids.push_back(1000 + 3 * index);
    images.descriptors.push_back(std::move(descriptors));
    images.place.push_back(place);
  }
  return images;
}

inline RetrievalOptions SmallOptions() {
  RetrievalOptions options;
  options.num_neighbors = 5;
  options.vocabulary.branching = 8;
  options.vocabulary.depth = 3;
  options.vocabulary.max_training_descriptors = 4000;
  options.vocabulary.seed = 1;
  options.num_threads = 2;
  return options;
}

}  // namespace viosfm::testing
