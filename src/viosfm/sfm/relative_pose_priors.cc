#include "viosfm/sfm/relative_pose_priors.h"

#include <algorithm>
#include <limits>
#include <map>
#include <unordered_map>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// Verified matches of each pair (the largest count of a pair listed twice).
std::unordered_map<image_pair_t, int> MatchCounts(const std::vector<ImagePairMatches>& pairs) {
  std::unordered_map<image_pair_t, int> num_matches;
  for (const ImagePairMatches& pair : pairs) {
    if (pair.image_id1 == pair.image_id2) continue;
    int& count = num_matches[ImagePairToPairId(pair.image_id1, pair.image_id2)];
    count = std::max(count, static_cast<int>(pair.matches.size()));
  }
  return num_matches;
}

RelativePosePrior MakePrior(const MapperImage& image1, const MapperImage& image2, int matches) {
  RelativePosePrior prior;
  prior.image_id1 = image1.image_id;
  prior.image_id2 = image2.image_id;
  prior.cam2_from_cam1 = *image2.vio_cam_from_world * image1.vio_cam_from_world->Inverse();
  prior.cam2_from_cam1.rotation.normalize();
  prior.num_verified_matches = matches;
  return prior;
}

// The posed frames (input indices, in time order) of each VIO segment.
std::map<int, std::vector<size_t>> PosedFramesBySegment(const std::vector<MapperImage>& images) {
  std::map<int, std::vector<size_t>> frames;
  for (size_t i = 0; i < images.size(); ++i) {
    if (images[i].vio_cam_from_world) {
      frames[images[i].vio_odometer.segment].push_back(i);
    }
  }
  return frames;
}

}  // namespace

VioSample VioSampleOfImage(const MapperImage& image) {
  VIOSFM_CHECK(image.vio_cam_from_world.has_value()) << "image " << image.image_id;
  return {image.timestamp_ns, image.vio_cam_from_world->Inverse(), image.vio_odometer};
}

RelativePosePriors MakeRelativePosePriors(const BatchedMapperInput& input,
                                          const RelativePosePriorOptions& options) {
  return MakeRelativePosePriors(input.images, input.verified_pairs, options);
}

RelativePosePriors MakeRelativePosePriors(const std::vector<MapperImage>& images,
                                          const std::vector<ImagePairMatches>& verified_pairs,
                                          const RelativePosePriorOptions& options) {
  const std::unordered_map<image_pair_t, int> num_matches = MatchCounts(verified_pairs);
  const auto matches_of = [&](size_t i, size_t j) {
    const auto it = num_matches.find(ImagePairToPairId(images[i].image_id, images[j].image_id));
    return it == num_matches.end() ? 0 : it->second;
  };
  const bool covariance = options.weighting == PriorWeighting::kCovariance;
  // Both frames of a prior are of one segment, whose constant scale error
  // is the model's scale: the priors carry only its variation.
  const VioUncertaintyModel within_segment = options.vio_uncertainty.WithinSegment();
  RelativePosePriors result;
  const auto add = [&](size_t i, size_t j, int matches, bool bridging) {
    RelativePosePrior prior = MakePrior(images[i], images[j], matches);
    if (covariance) {
      prior.sqrt_information = SqrtInformationFromCovariance(RelativePoseCovariance(
          within_segment, VioSampleOfImage(images[i]), VioSampleOfImage(images[j])));
    }
    prior.rotation_only = bridging && !covariance;
    result.priors.push_back(std::move(prior));
    result.frame_indices.emplace_back(i, j);
    result.bridging.push_back(bridging);
    ++(bridging ? result.num_bridging : result.num_consecutive);
  };
  // With the covariance weighting, a stretch is poorly connected where few
  // verified matches cross it: the matches of every pair (i, j) count for
  // each cut between two consecutive frames i <= k < j (not only those of
  // the consecutive pair: keyframes seconds apart may share nothing while
  // their neighbours hold them together).
  std::vector<int64_t> crossing(images.size() + 1, 0);
  if (covariance) {
    std::unordered_map<image_t, size_t> index_of;
    for (size_t i = 0; i < images.size(); ++i) index_of[images[i].image_id] = i;
    std::vector<int64_t> difference(images.size() + 1, 0);
    for (const ImagePairMatches& pair : verified_pairs) {
      const auto it1 = index_of.find(pair.image_id1);
      const auto it2 = index_of.find(pair.image_id2);
      if (it1 == index_of.end() || it2 == index_of.end() || it1->second == it2->second) continue;
      const size_t a = std::min(it1->second, it2->second);
      const size_t b = std::max(it1->second, it2->second);
      difference[a] += static_cast<int64_t>(pair.matches.size());
      difference[b] -= static_cast<int64_t>(pair.matches.size());
    }
    int64_t running = 0;
    for (size_t k = 0; k < images.size(); ++k) crossing[k] = running += difference[k];
  }
  for (const auto& [segment, frames] : PosedFramesBySegment(images)) {
    std::vector<int> consecutive_matches;
    std::vector<int> connectivity;  // per cut between posed frames k and k + 1
    for (size_t k = 0; k + 1 < frames.size(); ++k) {
      consecutive_matches.push_back(matches_of(frames[k], frames[k + 1]));
      add(frames[k], frames[k + 1], consecutive_matches.back(), false);
      if (covariance) {
        int64_t fewest = std::numeric_limits<int64_t>::max();
        for (size_t cut = frames[k]; cut < frames[k + 1]; ++cut) {
          fewest = std::min(fewest, crossing[cut]);
        }
        connectivity.push_back(static_cast<int>(std::min<int64_t>(fewest, 1 << 30)));
      } else {
        connectivity.push_back(consecutive_matches.back());
      }
    }
    for (const int span_int : options.bridge_spans) {
      const size_t span = static_cast<size_t>(span_int);
      if (span < 2 || span >= frames.size()) continue;
      for (size_t k = 0; k + span < frames.size(); ++k) {
        const int weakest =
            *std::min_element(connectivity.begin() + k, connectivity.begin() + k + span);
        if (weakest >= options.bridge_max_matches) continue;
        const int fewest = *std::min_element(consecutive_matches.begin() + k,
                                             consecutive_matches.begin() + k + span);
        add(frames[k], frames[k + span], fewest, true);
      }
    }
  }
  return result;
}

std::vector<RelativePosePrior> MakeConsecutiveRelativePosePriors(const BatchedMapperInput& input) {
  RelativePosePriorOptions options;
  options.bridge_spans.clear();
  options.weighting = PriorWeighting::kPaper;
  return MakeRelativePosePriors(input, options).priors;
}

std::vector<RelativePosePrior> MakeBridgingRelativePosePriors(
    const BatchedMapperInput& input, const std::vector<RelativePosePrior>& consecutive,
    const std::vector<int>& spans, int max_matches) {
  VIOSFM_CHECK(consecutive.size() + 1 == input.images.size() || input.images.empty())
      << consecutive.size() << " consecutive priors for " << input.images.size() << " images";
  std::vector<RelativePosePrior> priors;
  const size_t num_images = input.images.size();
  for (const int span_int : spans) {
    const size_t span = static_cast<size_t>(span_int);
    if (span < 2 || span >= num_images) continue;
    for (size_t i = 0; i + span < num_images; ++i) {
      int fewest = std::numeric_limits<int>::max();
      for (size_t j = i; j < i + span; ++j) {
        fewest = std::min(fewest, consecutive[j].num_verified_matches);
      }
      if (fewest >= max_matches) continue;
      RelativePosePrior prior = MakePrior(input.images[i], input.images[i + span], fewest);
      prior.rotation_only = true;
      priors.push_back(prior);
    }
  }
  return priors;
}

}  // namespace viosfm
