#include "viosfm/retrieval/image_retrieval.h"

#include <algorithm>
#include <unordered_set>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {

std::string RetrievalOptions::Validate() const {
  if (num_neighbors < 1) return "num_neighbors must be >= 1";
  const std::string problem = vocabulary.Validate();
  if (!problem.empty()) return "vocabulary." + problem;
  return "";
}

std::vector<std::vector<ImageScore>> RetrieveSimilarImageScores(
    const std::vector<image_t>& image_ids, const DescriptorLoader& load,
    const std::vector<std::vector<image_t>>& exclude, const RetrievalOptions& options,
    const VocabularyTree* vocabulary) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  VIOSFM_CHECK(exclude.empty() || exclude.size() == image_ids.size())
      << exclude.size() << " exclusion lists for " << image_ids.size() << " images";
  if (image_ids.empty()) return {};
  Timer timer;

  VocabularyTree owned;
  std::string source = "given";
  if (vocabulary == nullptr) {
    if (!options.vocabulary_path.empty()) {
      owned = VocabularyTree::Load(options.vocabulary_path);
      source = "loaded from " + options.vocabulary_path;
    } else {
      VocabularyTreeOptions training = options.vocabulary;
      training.num_threads = options.num_threads;
      owned = TrainVocabularyTree(image_ids.size(), load, training);
      source = "trained on the images";
    }
    vocabulary = &owned;
  }
  VIOSFM_CHECK(!vocabulary->empty()) << "empty vocabulary tree";

  InvertedIndex index(vocabulary->num_words());
  {
    ProgressBar progress("Indexing images", static_cast<int64_t>(image_ids.size()));
    for (size_t i = 0; i < image_ids.size(); ++i) {
      const FeatureDescriptors descriptors = load(i);
      if (descriptors.rows() > 0 && descriptors.cols() != vocabulary->descriptor_dim()) {
        throw InputError(options.vocabulary_path, 0,
                         "the vocabulary has descriptors of " +
                             std::to_string(vocabulary->descriptor_dim()) + " values, image " +
                             std::to_string(image_ids[i]) + " has " +
                             std::to_string(descriptors.cols()));
      }
      std::vector<int32_t> words;
      if (descriptors.rows() > 0) words = vocabulary->Quantize(descriptors, options.num_threads);
      index.AddImage(image_ids[i], words);
      progress.Update();
    }
  }
  index.Finalize();

  std::vector<std::vector<ImageScore>> results(image_ids.size());
  {
    ProgressBar progress("Retrieving similar images", static_cast<int64_t>(image_ids.size()));
    ParallelForChunks(static_cast<int64_t>(image_ids.size()), options.num_threads, 8,
                      [&](int64_t begin, int64_t end) {
                        for (int64_t i = begin; i < end; ++i) {
                          std::unordered_set<image_t> excluded;
                          if (!exclude.empty())
                            excluded.insert(exclude[i].begin(), exclude[i].end());
                          results[i] = index.Query(image_ids[i], options.num_neighbors, excluded);
                          progress.Update();
                        }
                      });
  }
  int64_t num_retrieved = 0;
  for (const std::vector<ImageScore>& result : results) num_retrieved += result.size();
  VIOSFM_LOG(INFO) << "Retrieval: " << image_ids.size() << " images, vocabulary of "
                   << vocabulary->num_words() << " words (" << source << "), " << num_retrieved
                   << " retrieved neighbours, " << timer.ElapsedSeconds() << " s" << LogDetails()
                   << " (up to " << options.num_neighbors << " per image)";
  return results;
}

std::vector<std::vector<image_t>> RetrieveSimilarImages(
    const std::vector<image_t>& image_ids, const DescriptorLoader& load,
    const std::vector<std::vector<image_t>>& exclude, const RetrievalOptions& options,
    const VocabularyTree* vocabulary) {
  const std::vector<std::vector<ImageScore>> scores =
      RetrieveSimilarImageScores(image_ids, load, exclude, options, vocabulary);
  std::vector<std::vector<image_t>> ids(scores.size());
  for (size_t i = 0; i < scores.size(); ++i) {
    for (const ImageScore& score : scores[i]) ids[i].push_back(score.image_id);
  }
  return ids;
}

std::vector<std::vector<image_t>> RetrieveSimilarImages(
    const std::vector<image_t>& image_ids, const std::vector<FeatureDescriptors>& descriptors,
    const std::vector<std::vector<image_t>>& exclude, const RetrievalOptions& options,
    const VocabularyTree* vocabulary) {
  VIOSFM_CHECK_EQ(image_ids.size(), descriptors.size());
  return RetrieveSimilarImages(
      image_ids, [&descriptors](size_t index) { return descriptors[index]; }, exclude, options,
      vocabulary);
}

std::vector<std::vector<image_t>> TemporalNeighborExclusion(const std::vector<image_t>& image_ids,
                                                            int window) {
  const int64_t n = static_cast<int64_t>(image_ids.size());
  std::vector<std::vector<image_t>> exclude(n);
  for (int64_t i = 0; i < n; ++i) {
    for (int64_t j = std::max<int64_t>(0, i - window); j <= std::min(n - 1, i + window); ++j) {
      if (j != i) exclude[i].push_back(image_ids[j]);
    }
  }
  return exclude;
}

}  // namespace viosfm
