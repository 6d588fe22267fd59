// Stages 6 and 7 of a `viosfm run` (pipeline.h): the mapper's input from
// the database (the selected frames' keypoints and VIO camera poses, the
// inlier matches of the accepted pairs), the batched incremental mapping
// with relative-pose-constrained bundle adjustment (sfm/batched_mapper.h),
// then the IMU's metric scale (metric_scale.h) when the dataset has an IMU.
#pragma once

#include "viosfm/io/colmap_database.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/pipeline_summary.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/sfm/batched_mapper.h"

namespace viosfm {

// The mapper's input without its pairs: the frames' keypoints (compensated
// for a rolling shutter's rotation) and VIO camera poses, the cameras, the
// IMU and the rig; input.images[i] is frames.sequence.images[i].
BatchedMapperInput LoadMapperImages(const SelectedFrames& frames, const VioPoses& vio,
                                    ColmapDatabase* database);

// The mapper's input with the inlier matches of the accepted pairs.
BatchedMapperInput LoadMapperInputStage(const SelectedFrames& frames, const VioPoses& vio,
                                        const VerificationResult& verification,
                                        ColmapDatabase* database);

// Maps, applies the metric scale, and fills summary's mapper, metric_scale,
// frame counts and model figures (logging every frame left without a pose
// and why). With a `stream` the pairs come from it (input.verified_pairs
// empty; sfm/batched_mapper.h).
Reconstruction MapStage(const BatchedMapperInput& input, const Sequence& sequence,
                        const VioPoses& vio, const PipelineOptions& options,
                        PipelineSummary* summary, VerifiedPairStream* stream = nullptr);

// MapStage after the mapper (summary->mapper holds its summary): the
// metric scale and the summary's frame counts and model figures.
void FinishMapping(const Sequence& sequence, const VioPoses& vio, const PipelineOptions& options,
                   PipelineSummary* summary, Reconstruction* reconstruction);

}  // namespace viosfm
