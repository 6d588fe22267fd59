// The paper's batched incremental reconstruction (its section "Batched
// Incremental Reconstruction") with relative-pose-constrained bundle
// adjustment: images are registered k at a time in time order, each batch
// placed by the VIO, then triangulated and bundle adjusted.
//
//  1. tracks from the verified matches of all pairs (tracks.h);
//  2. batch 0 = the first k images, posed by the VIO (world = the VIO's
//     world frame: metric, gravity aligned); batch i > 0 is placed by the VIO
//     relative pose between its first image and the last image of batch i-1
//     (as refined so far), and each image inside it by its VIO relative pose
//     to the batch's first image;
//  3. triangulation of the tracks seen by the registered images (new points,
//     and new observations of existing points), triangulator.h;
//  4. bundle adjustment (ba/bundle_adjustment.h): Cauchy reprojection term
//     over registered images and points plus the relative-pose term between
//     consecutive frames, w = alpha exp(-beta c) with c the verified matches
//     of the two frames; the first image's pose is held (gauge);
//  5. filtering (large reprojection error, small triangulation angle) and
//     re-triangulation of the tracks left without a point;
//  6. after the last batch a final global bundle adjustment, filtering and
//     re-triangulation.
#pragma once

#include <string>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sfm/filters.h"
#include "viosfm/sfm/tracks.h"
#include "viosfm/sfm/triangulator.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"

namespace viosfm {

// One input frame.
struct MapperImage {
  image_t image_id = kInvalidImageId;
  camera_t camera_id = kInvalidCameraId;
  std::string name;  // as in the database (relative path)
  timestamp_ns_t timestamp_ns = 0;
  // Keypoints in raw (distorted) pixels, viosfm's convention.
  FeatureKeypoints keypoints;
  // The VIO pose of this frame's camera, in the VIO's world frame.
  Rigid3d vio_cam_from_world;
};

struct BatchedMapperInput {
  std::vector<Camera> cameras;
  // Frames in strictly increasing time order.
  std::vector<MapperImage> images;
  // Inlier matches of every accepted pair (point2D_idx index the images'
  // keypoints).
  std::vector<ImagePairMatches> verified_pairs;
};

struct BatchedMapperOptions {
  // Frames per batch, >= 1 (the paper's k = 50). Default 50.
  int batch_size = 50;
  TrackBuilderOptions tracks;
  TriangulationOptions triangulation;
  // Reprojection (Cauchy) + relative-pose terms; ba.use_relative_pose_priors
  // = false is the paper's "w/o RPC" ablation.
  BundleAdjustmentOptions ba;
  PointFilterOptions filter;
  // Re-triangulate tracks without a point after each filtering. Default true.
  bool retriangulate = true;
  // Bundle adjust after every batch (the paper) or only at the end. Default true.
  bool ba_after_each_batch = true;
  // Final global bundle adjustment after the last batch. Default true.
  bool final_global_ba = true;
  // Worker threads (BA, triangulation); default 2.
  int num_threads = 2;
  bool show_progress = true;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct MapperBatchStatistics {
  int batch_index = 0;
  int num_images = 0;                       // images in the batch
  int num_registered_total = 0;             // registered images after the batch
  int num_points_total = 0;                 // points after the batch (after filtering)
  double mean_reprojection_error_px = 0.0;  // after the batch's BA
  double seconds_triangulation = 0.0;
  double seconds_ba = 0.0;
  double seconds_filtering = 0.0;
};

struct BatchedMapperSummary {
  TrackStatistics tracks;
  std::vector<MapperBatchStatistics> batches;
  BundleAdjustmentSummary final_ba;
  int num_images = 0;
  int num_registered = 0;
  int num_points = 0;
  int num_observations = 0;
  double mean_track_length = 0.0;
  double mean_reprojection_error_px = 0.0;
  double seconds_tracks = 0.0;
  double seconds_total = 0.0;
  std::string ToString() const;  // a few lines for the log
};

// Runs the batched reconstruction (see the top of this file). Throws
// InputError for invalid options, images not in time order, an unknown
// camera id, or a match indexing a keypoint that does not exist.
Reconstruction RunBatchedMapper(const BatchedMapperInput& input,
                                const BatchedMapperOptions& options,
                                BatchedMapperSummary* summary = nullptr);

}  // namespace viosfm
