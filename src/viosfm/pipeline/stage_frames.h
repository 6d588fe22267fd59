// Stage 3 of a `viosfm run` (pipeline.h): the frames to reconstruct.
// Static start/end trimming and downsampling (frame_selection.h), then each
// selected frame's VIO pose: the VIO pose nearest in time within
// max_vio_time_difference_ns, with its segment and odometer. A frame without
// one is kept (counted, logged) and registered from the images where they
// allow. The later stages take the frames' poses from here; nothing
// associates the VIO track with the frames again. With a rolling-shutter
// readout (VioPoses::rolling_shutter_readout_s) and an IMU, each selected
// frame's camera angular rate too (scene/rolling_shutter.h), on the clock
// of the VIO's rig.
#pragma once

#include <optional>
#include <vector>

#include "viosfm/io/frame_cache.h"
#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/scene/trajectory.h"

namespace viosfm {

struct SelectedFrames {
  FrameSelection selection;  // which frames of the sequence, and why
  // The sequence with only the selected images (rig, IMU, ground truth as read).
  Sequence sequence;
  // Per selected frame: the index of its pose in VioPoses, if any.
  std::vector<std::optional<size_t>> vio_index;
  // world_from_body at the selected frames with a VIO pose (vio_body.tum).
  Trajectory vio_at_frames;
  size_t num_without_vio_pose = 0;
  // Each selected frame's camera angular rate, for the rolling-shutter
  // compensation of its keypoints (inactive: a global shutter, no IMU, or
  // PipelineOptions::compensate_rolling_shutter false).
  FrameRollingShutter rolling_shutter;
};

// The stage. Throws InputError naming the dataset when no frame is left,
// and naming the VIO (`vio_name`) when fewer than two frames have a pose.
// Releases the decoded images of the frames not selected from `frame_cache`.
SelectedFrames SelectFramesStage(const Sequence& sequence, const VioPoses& vio,
                                 const PipelineOptions& options, const std::string& vio_name,
                                 FrameCache* frame_cache);
// The stage with the frames already selected (a recording selected as it
// grew, frame_selection.h GrowingFrameSelection).
SelectedFrames SelectedFramesOf(const Sequence& sequence, const FrameSelection& selection,
                                const VioPoses& vio, const PipelineOptions& options,
                                const std::string& vio_name, FrameCache* frame_cache);

}  // namespace viosfm
