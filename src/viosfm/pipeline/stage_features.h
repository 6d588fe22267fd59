// Stage 4 of a `viosfm run` (pipeline.h): SIFT features of the selected
// frames into OUT/database.db. Resumable: an image whose features the
// database holds is not extracted again (the run folder's fingerprint,
// written just before, says what they were made from).
#pragma once

#include "viosfm/features/feature_extraction.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/pipeline/feature_prefetch.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/pipeline/stage_colors.h"
#include "viosfm/pipeline/stage_frames.h"

namespace viosfm {

struct FeaturesStageOutput {
  ColmapDatabase database;  // OUT/database.db, open
  FeatureExtractionSummary summary;
};

// Writes fingerprint.json and options.json, opens the database and
// extracts the features it lacks, taking the images from `frame_cache` and
// sampling each keypoint's grey value into `values` (stage_colors.h);
// features extracted beside the VIO are taken from `prefetch` when given.
FeaturesStageOutput ExtractFeaturesStage(const SelectedFrames& frames,
                                         const PipelineOptions& options, const RunFolder& folder,
                                         const RunFingerprint& fingerprint, FrameCache* frame_cache,
                                         KeypointGreyValues* values,
                                         FeaturePrefetch* prefetch = nullptr);

}  // namespace viosfm
