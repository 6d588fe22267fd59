#include "viosfm/pipeline/stage_verification.h"

namespace viosfm {

VerificationResult VerifyPairsStage(const SelectedFrames& frames, const VioPoses& vio,
                                    const PipelineOptions& options, ColmapDatabase* database,
                                    const VerifiedPairsCallback& on_verified) {
  std::vector<std::optional<FrameVioPose>> frame_poses(frames.vio_index.size());
  for (size_t i = 0; i < frames.vio_index.size(); ++i) {
    if (const std::optional<size_t> index = frames.vio_index[i]) {
      frame_poses[i] =
          FrameVioPose{vio.world_from_body.poses[*index].world_from_frame, vio.odometers[*index]};
    }
  }
  VerificationResult result =
      RunVerification(frames.sequence, frame_poses, database,
                      options.EffectiveVerificationOptions(), frames.rolling_shutter, on_verified);
  return result;
}

}  // namespace viosfm
