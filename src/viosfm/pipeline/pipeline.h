// The end-to-end VIO-aided reconstruction of one sequence (`viosfm run`),
// the paper's pipeline (its Fig. "overview"): VIO poses, frame selection,
// features, two-step VIO-aided verification, batched incremental mapping with
// relative-pose-constrained bundle adjustment, then evaluation and outputs.
//
// Stages (each a file of its own; timed, reported in summary.json "stages"):
//  1. read_dataset   stage_dataset.h: EuRoC ASL folder (mav0/), an image
//                    folder or a ROS 1 bag;
//  2. vio            stage_vio.h: the VIO trajectory (world_from_body) of the
//                    sequence, from PipelineOptions::vio_source if set, else
//                    from the file vio_trajectory, else from viosfm's own VIO
//                    (vio/odometry.h) on the images and IMU, split into
//                    segments at re-initialisations;
//  3. select_frames  stage_frames.h: static start/end trimming and
//                    downsampling to target_rate_hz (frame_selection.h); a
//                    frame without a VIO pose within
//                    max_vio_time_difference_ns is kept without one (counted
//                    and logged) and registered from the images where they
//                    allow;
//  4. features       stage_features.h: SIFT into OUT/database.db (resumable);
//  5. verification   stage_verification.h: pairs, matching, VIO check and
//                    RANSAC (resumable);
//  6. load_matches   stage_mapping.h: the inlier matches of the accepted pairs;
//  7. mapper         stage_mapping.h: sfm/batched_mapper.h, then the IMU's
//                    metric scale (metric_scale.h) when the dataset has an IMU;
//  8. colors         stage_colors.h: each point's colour, the mean over its
//                    observations of the image value at the keypoint;
//  9. evaluation     stage_evaluation.h: with ground truth only, the Sim(3)
//                    ATE of the estimated body trajectory and of the input VIO
//                    on the same frames;
// 10. write_outputs  stage_outputs.h: the files below.
//
// Each image is decoded once per run (io/frame_cache.h; summary.json
// "images" counts the decodes).
//
// Output folder (every file written atomically; summary.json last, so a
// folder holding summary.json is complete):
//   OUT/options.json                 every option, name -> value text
//   OUT/database.db                  COLMAP database (features, matches, geometries)
//   OUT/verification/pairs.csv, verification.json
//   OUT/model/                       COLMAP binary model (cameras, images, points3D .bin)
//   OUT/model_txt/                   the same as COLMAP text
//   OUT/points.ply                   coloured points
//   OUT/trajectory_cam.tum           estimated world_from_cam of the registered frames
//   OUT/trajectory_body.tum          estimated world_from_body of the registered frames
//   OUT/vio_body.tum                 the input VIO world_from_body of the selected frames
//   OUT/groundtruth_body.tum         ground truth at the selected frames (if present)
//   OUT/eval.json, OUT/eval_vio.json eval/report.h JSON (if ground truth)
//   OUT/summary.json                 see pipeline_summary.h
//
//   OUT/fingerprint.json             what the stored features and matches were
//                                    made from (run_fingerprint.h)
//
// The folder (run_folder.h) owns the lock, the resume check and the order
// of the records. Resume: a re-run on the same folder reuses the stored
// features and pair verifications when its fingerprint (run_fingerprint.h: the dataset's
// files, images and calibration, the VIO's input and poses, every option
// that shapes the stored data) equals the stored one; otherwise it is an
// InputError naming each changed key with its old and new value, before
// anything in the folder changes. `overwrite` removes what viosfm wrote in
// the folder first (its manifest, run_folder.h) and starts afresh. Mapper options do not
// count: a re-run with other ones reuses the features and matches.
//
// Crash safety: a run killed at any point (SIGKILL included) and run again
// with the same options ends as an uninterrupted run would, byte for byte
// with --threads 1 (with more threads, Ceres' parallel sums make the bundle
// adjustment differ slightly run to run, see docs/design.md, "Repeatability
// of a run"): the database keeps every committed image's
// features and every verified pair (SQLite, WAL; one transaction per image
// and per pair), a pair stored as rejected is decided again from its stored
// matches, and every other output is recomputed. summary.json is removed
// when the folder starts to change and written last, atomically: a folder
// without it is incomplete (`viosfm report` and `viosfm export` refuse it).
// Leftovers of interrupted atomic writes are removed at the start, and the
// folder is locked (util/file_util.h FolderLock) while a run writes into it.
#pragma once

#include "viosfm/pipeline/pipeline_options.h"
#include "viosfm/pipeline/pipeline_summary.h"

namespace viosfm {

// Runs the pipeline (see the top of this file). Throws InputError for invalid
// options, unreadable or empty input, a VIO trajectory that does not overlap
// the images in time, a sequence without moving frames, a stored database
// made from other inputs or options (see Resume above), or an output folder
// another run is writing into.
PipelineSummary RunPipeline(const PipelineOptions& options);

}  // namespace viosfm
