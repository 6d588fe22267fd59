// Stage 5 of a `viosfm run` (pipeline.h): candidate pairs (N1 temporal + N2
// retrieval), matching, the VIO-aided check and RANSAC
// (matching/verification_driver.h), on the selected frames with the VIO
// poses stage 3 gave them. Resumable: a pair the database holds as verified
// is not matched again.
#pragma once

#include "viosfm/io/colmap_database.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/pipeline/stage_vio.h"

namespace viosfm {

// `on_verified`: RunVerification's (matching/verification_driver.h).
VerificationResult VerifyPairsStage(const SelectedFrames& frames, const VioPoses& vio,
                                    const PipelineOptions& options, ColmapDatabase* database,
                                    const VerifiedPairsCallback& on_verified = {});

}  // namespace viosfm
