// Stage 8 of a `viosfm run` (pipeline.h): each point's colour, the mean
// over its observations of the image value at the keypoint (grey images
// give grey).
#pragma once

#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sfm/batched_mapper.h"

namespace viosfm {

// input.images[i] is frames.sequence.images[i] (LoadMapperInputStage).
void ColorPointsStage(const SelectedFrames& frames, const BatchedMapperInput& input,
                      bool show_progress, Reconstruction* reconstruction);

}  // namespace viosfm
