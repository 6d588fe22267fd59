#include "viosfm/pipeline/stage_features.h"

#include <iomanip>
#include <string>
#include <unordered_map>

#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

// The keypoints' grey values (the points' colours) of the features an
// earlier run stored, sampled now from their stored keypoints while the
// VIO's decoded frames are still held: then no later stage needs a frame,
// and a resumed run's colours are a fresh run's.
void SampleStoredFeatures(const Sequence& sequence, const ColmapDatabase& database,
                          FrameCache* frame_cache, KeypointGreyValues* values) {
  std::unordered_map<std::string, image_t> image_of_name;
  for (const DatabaseImage& row : database.ReadAllImages()) {
    image_of_name.emplace(row.name, row.image_id);
  }
  for (const SequenceImage& image : sequence.images) {
    const auto it = image_of_name.find(DatabaseImageName(image));
    if (it == image_of_name.end() || values->Find(it->second) != nullptr) continue;
    values->Sample(it->second, *frame_cache->Take(image.path), database.ReadKeypoints(it->second));
  }
}

}  // namespace

FeaturesStageOutput ExtractFeaturesStage(const SelectedFrames& frames,
                                         const PipelineOptions& options, const RunFolder& folder,
                                         const RunFingerprint& fingerprint, FrameCache* frame_cache,
                                         KeypointGreyValues* values, FeaturePrefetch* prefetch) {
  // What the database's content is made from, before the database changes.
  folder.WriteRecords(fingerprint, options.ToKeyValues());
  FeaturesStageOutput output{ColmapDatabase::Open(folder.path() / "database.db"), {}};
  FeatureImageAccess access;
  access.frames = frame_cache;
  access.on_extracted = [values](image_t image_id, const GreyImage& pixels,
                                 const FeatureKeypoints& keypoints) {
    values->Sample(image_id, pixels, keypoints);
  };
  if (prefetch != nullptr) {
    access.take_extracted = [prefetch, values](image_t image_id, const SequenceImage& image,
                                               ImageFeatures* features) {
      std::vector<uint8_t> grey_values;
      if (!prefetch->Take(image.path, features, &grey_values)) return false;
      values->Set(image_id, std::move(grey_values));
      return true;
    };
  }
  output.summary = ExtractFeatures(frames.sequence, options.EffectiveSiftOptions(),
                                   &output.database, options.show_progress, access);
  SampleStoredFeatures(frames.sequence, output.database, frame_cache, values);
  VIOSFM_LOG(INFO) << "run: features of " << output.summary.num_images << " images, " << std::fixed
                   << std::setprecision(1) << output.summary.seconds << " s" << LogDetails() << ": "
                   << output.summary.ToString();
  return output;
}

}  // namespace viosfm
