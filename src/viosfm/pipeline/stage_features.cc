#include "viosfm/pipeline/stage_features.h"

#include <iomanip>

#include "viosfm/util/logging.h"

namespace viosfm {

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
  VIOSFM_LOG(INFO) << "run: features of " << output.summary.num_images << " images, " << std::fixed
                   << std::setprecision(1) << output.summary.seconds << " s" << LogDetails() << ": "
                   << output.summary.ToString();
  return output;
}

}  // namespace viosfm
