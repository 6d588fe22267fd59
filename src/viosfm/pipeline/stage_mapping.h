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
#include "viosfm/sfm/vio_gaps.h"

namespace viosfm {

// The mapper's input without its pairs, each frame through the ingest step
// (frame_ingest.h) from its stored features: the frames' keypoints (compensated
// for a rolling shutter's rotation) and VIO camera poses, the cameras, the
// IMU and the rig; input.images[i] is frames.sequence.images[i].
BatchedMapperInput LoadMapperImages(const SelectedFrames& frames, const VioPoses& vio,
                                    ColmapDatabase* database);

// The mapper's input with the inlier matches of the accepted pairs, the
// gaps in the VIO's poses judged by them (sfm/vio_gaps.h; `gaps`, if given,
// receives the decisions).
BatchedMapperInput LoadMapperInputStage(const SelectedFrames& frames, const VioPoses& vio,
                                        const VerificationResult& verification,
                                        ColmapDatabase* database, VioGapSummary* gaps = nullptr);

// Maps, applies the metric scale, and fills summary's mapper, metric_scale,
// frame counts and model figures (logging every frame left without a pose
// and why). With a `stream` the pairs come from it (input.verified_pairs
// empty; sfm/batched_mapper.h).
// The models the images could not join to the main one go to
// `other_models` when given.
Reconstruction MapStage(const BatchedMapperInput& input, const Sequence& sequence,
                        const VioPoses& vio, const PipelineOptions& options,
                        PipelineSummary* summary, VerifiedPairStream* stream = nullptr,
                        std::vector<Reconstruction>* other_models = nullptr);

// The mapper's options in a run: the run's (EffectiveMapperOptions), with
// the camera's focal length, distortion and principal point refined where
// it was guessed.
BatchedMapperOptions MapperOptionsOfRun(const Sequence& sequence, const PipelineOptions& options);

// MapStage after the mapper (summary->mapper holds its summary): the
// metric scale and the summary's frame counts and model figures.
void FinishMapping(const Sequence& sequence, const VioPoses& vio, const PipelineOptions& options,
                   PipelineSummary* summary, Reconstruction* reconstruction);

}  // namespace viosfm
