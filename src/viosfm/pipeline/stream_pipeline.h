// A `viosfm run` as one stream (PipelineOptions::stream, `viosfm run
// --stream`): the stages of pipeline.h overlap instead of running one after
// the other, so that both cores stay busy and the model is ready soon after
// the recording's last frame.
//
// Threads:
//  - the VIO: viosfm's own VIO over every image (vio/odometry.h), reporting
//    each frame once its pose is settled (a moving start's held frames and a
//    reset's frames wait for their decision); with a VIO file, a reader that
//    decodes the selected frames;
//  - the features: SIFT on each selected frame right after the VIO decoded
//    it (feature_prefetch.h, below the VIO's priority);
//  - this thread, the verification: each selected frame in time order takes
//    its VIO pose (as SelectFramesStage associates it), its features
//    (written to the database) and its retrieval among the frames before
//    it (retrieval/incremental_retrieval.h: the vocabulary trained on the
//    first stream_vocabulary_frames frames); once the frames after it fix
//    its temporal neighbours (N1: the frames nearest in time, as the pair
//    generator chooses them), its pairs with the frames before it (temporal,
//    and its N2 retrieved ones beyond those) are matched and verified as a
//    batch run verifies a pair (matching/pair_verification.h) and handed to
//    the mapper;
//  - the mapper (sfm/batched_mapper.h), taking the frames and their pairs a
//    batch at a time (sfm/verified_pair_stream.h); the final adjustment
//    once the last frame's pairs are in.
// Then, as in pipeline.h: the metric scale, the colours, the evaluation and
// the outputs; the same files, the same summary.json (its "stages":
// read_dataset, stream, colors, evaluation, write_outputs; "stream": each
// thread's time and the seconds from the last frame to the model).
//
// What differs from the run of pipeline.h on the same data: the retrieval
// pairs (each frame's similar frames are among the frames before it, and the
// vocabulary is trained on the first frames), and the pairs each batch of
// the mapper sees (those among its frames and the frames before it). The
// temporal pairs, each pair's decision, the frame selection and the VIO are
// the same.
//
// A streamed run starts afresh: it does not resume a folder's stored data
// (InputError without --overwrite). Its fingerprint.json says the VIO poses
// are pending until the VIO ends, so a run killed midway is refused by any
// later run until --overwrite.
#pragma once

#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/pipeline_summary.h"

namespace viosfm {

// Throws InputError as RunPipeline does, and for a folder with stored data
// (see above) or a frame selection that needs the own VIO's trajectory.
PipelineSummary RunStreamPipeline(const PipelineOptions& options);

}  // namespace viosfm
