// The incremental structure-from-motion core, in the shape of COLMAP's
// incremental mapper: models grown from the images alone by two-view
// initialisation, next-best-view registration (PnP), triangulation, local
// and global bundle adjustment and filtering; several models where the
// images do not connect, merged by their common points (a similarity from
// the points of the tracks both models hold) as soon as they do.
//
// All frames live in one Reconstruction; each registered frame belongs to
// one model, and a point's observations lie in the frames of one model
// (triangulation is run model by model). The batched mapper
// (batched_mapper.h) runs the paper's VIO-aided batches on top of this core:
// a frame the VIO predicts is checked against the images there, and a frame
// without a prediction is registered here.
#pragma once

#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/estimators/absolute_pose.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/geometry/sim3.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sfm/filters.h"
#include "viosfm/sfm/frame_registration.h"
#include "viosfm/sfm/tracks.h"
#include "viosfm/sfm/triangulator.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/types.h"

namespace viosfm {

struct IncrementalMapperOptions {
  // Two-view initialisation: a pair needs at least this many inliers of an
  // essential matrix (within init_max_error_px) that triangulate in front of
  // both cameras. Defaults 100 and 4 px (COLMAP's).
  int init_min_num_inliers = 100;
  double init_max_error_px = 4.0;
  // The median triangulation angle of the pair's points must reach this,
  // degrees; while no pair does, the bound is halved down to
  // init_lowest_triangulation_angle_deg. Defaults 16 and 2 (COLMAP starts at
  // 16 and relaxes it too).
  double init_min_triangulation_angle_deg = 16.0;
  double init_lowest_triangulation_angle_deg = 2.0;
  // Pairs tried for the initialisation at most: every pair of the frames
  // with the most verified matches first. Default 200.
  int init_max_pairs_tried = 200;
  // After a frame is registered from the images alone into a model the VIO
  // does not hold, the frame and its most covisible frames, at most this
  // many in all, are adjusted (the others observing their points held).
  // Default 6 (COLMAP's); 0: no local adjustment.
  int local_ba_num_images = 6;
  // Levenberg-Marquardt iterations of a local adjustment. Default 25.
  int local_ba_max_iterations = 25;
  // Two models are merged when at least this many tracks have a point in
  // both and at least merge_min_inlier_ratio of those agree with one
  // similarity: the point of one model, moved by it, reprojects into every
  // frame of the other that observes the track's point there within
  // merge_max_error_px. Defaults 30, 0.5 and 8 px.
  int merge_min_common_points = 30;
  double merge_min_inlier_ratio = 0.5;
  double merge_max_error_px = 8.0;
  // Seed of the initial pair's and the merge's RANSAC.
  uint64_t seed = 0;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"init_min_num_inliers", "inliers an initial pair needs", kRunOnly},
          self.init_min_num_inliers);
    visit({"init_min_triangulation_angle_deg",
           "deg, median triangulation angle an initial pair needs at first", kRunOnly},
          self.init_min_triangulation_angle_deg);
    visit({"init_lowest_triangulation_angle_deg", "deg, the smallest that bound is relaxed to",
           kRunOnly},
          self.init_lowest_triangulation_angle_deg);
    visit({"init_max_pairs_tried", "candidate initial pairs tried", kRunOnly},
          self.init_max_pairs_tried);
    visit({"local_ba_num_images", "frames of a local adjustment after an images-only registration",
           kRunOnly},
          self.local_ba_num_images);
    visit({"merge_min_common_points", "common points two models need to merge", kRunOnly},
          self.merge_min_common_points);
    visit({"merge_max_error_px", "px, reprojection error of a merged point", kRunOnly},
          self.merge_max_error_px);
  }
};

// A candidate initial pair, as FindInitialPair found it.
struct InitialPair {
  size_t frame1 = 0;
  size_t frame2 = 0;
  Rigid3d cam2_from_cam1;  // |t| = 1
  int num_inliers = 0;
  double median_angle_deg = 0.0;
};

// Two models merged (TryMergeModels).
struct ModelMerge {
  int into_model = -1;
  int from_model = -1;
  Sim3d into_from_from;
  int num_common_points = 0;
  int num_inliers = 0;
};

class IncrementalMapper {
 public:
  // One model: its frames in order of registration, and the frame held in
  // every adjustment (the gauge: the first frame of a model the VIO places,
  // or the first frame of its initial pair).
  struct Model {
    image_t gauge_image = kInvalidImageId;
    std::vector<image_t> registered;
    // The VIO places the model (metric, gravity-aligned); else only the
    // images do (scale and frame of its initial pair).
    bool vio_anchored = false;
  };

  IncrementalMapper(const IncrementalMapperOptions& options,
                    const TriangulationOptions& triangulation, const PointFilterOptions& filter,
                    const FrameRegistrationOptions& registration, int num_threads);

  // The frames.
  size_t AddFrame(Image image);  // unregistered; returns its index
  size_t NumFrames() const { return frame_ids_.size(); }
  image_t ImageId(size_t frame) const { return frame_ids_[frame]; }
  size_t FrameIndex(image_t image_id) const { return index_of_image_.at(image_id); }
  Reconstruction& reconstruction() { return reconstruction_; }
  const Reconstruction& reconstruction() const { return reconstruction_; }

  // The tracks (over all frames added so far) and each frame's.
  void SetTracks(std::vector<Track> tracks);
  const std::vector<Track>& tracks() const { return tracks_; }
  const std::vector<size_t>& TracksOfFrame(size_t frame) const { return tracks_of_frame_[frame]; }

  // The models.
  int NumModels() const { return static_cast<int>(models_.size()); }
  const Model& model(int m) const { return models_[m]; }
  int NewModel(bool vio_anchored);
  void SetGauge(int m, image_t image_id) { models_[m].gauge_image = image_id; }
  int ModelOf(size_t frame) const { return model_of_frame_[frame]; }
  bool IsRegistered(size_t frame) const { return model_of_frame_[frame] >= 0; }
  // Frames registered in all models.
  size_t NumRegistered() const;

  // Registers `frame` into model `m` at `cam_from_world` (normalised).
  void Register(size_t frame, int m, const Rigid3d& cam_from_world);
  // Takes `frame` out of its model with its observations.
  void Deregister(size_t frame);

  // The frame's keypoints whose tracks have a point in model `m`, and those
  // points.
  FrameCorrespondences Correspondences(size_t frame, int m) const;
  // PnP-RANSAC of the frame against `correspondences`, seeded by
  // `predicted` when given (FrameRegistrationOptions::pnp, its seed mixed
  // with the image id).
  AbsolutePoseResult EstimatePose(size_t frame, const FrameCorrespondences& correspondences,
                                  const std::optional<Rigid3d>& predicted) const;

  // The best initial pair among `candidates` (unregistered frames) from
  // their verified matches `pairs`: among the pairs of the best-connected
  // frames, those whose essential matrix has enough inliers, the one with
  // the most inliers whose points are seen under a median angle above the
  // bound (relaxed while none is).
  std::optional<InitialPair> FindInitialPair(const std::vector<size_t>& candidates,
                                             const std::vector<ImagePairMatches>& pairs) const;
  // A new model from the pair: its first frame at the origin, the second at
  // unit distance, their tracks triangulated and the two adjusted. Returns
  // the model, or -1 when too few points survive.
  int InitializeModel(const InitialPair& pair);

  // Registers candidates from the images alone into the models, the one
  // with the most correspondences first, triangulating after each and
  // adjusting locally (models the VIO does not hold), until none is left
  // that PnP can register. Returns the frames registered, in order.
  std::vector<size_t> RegisterNextFrames(const std::vector<size_t>& candidates);
  // The model (and its number of correspondences) that holds the most 2D-3D
  // matches of `frame`; -1 when none has min_num_correspondences.
  std::pair<int, int> BestModelFor(size_t frame) const;

  // Triangulates (or extends) the tracks the frames observe, each in the
  // model of its frame.
  TriangulationStatistics TriangulateFrames(const std::vector<size_t>& frames);
  // Triangulates every track in every model.
  TriangulationStatistics TriangulateAll();

  // Bundle adjustment of `free_images` of one model (all its frames when
  // they are all registered frames, else a sub-problem with the others
  // observing their points held), the model's gauge and `held_neighbour`
  // (if valid) held. max_held_views > 0: each point keeps the observations
  // of at most that many held images, the latest.
  BundleAdjustmentSummary Adjust(const std::vector<image_t>& free_images, image_t held_neighbour,
                                 image_t gauge_image, const std::vector<RelativePosePrior>& priors,
                                 const BundleAdjustmentOptions& options, int max_held_views,
                                 BundleAdjustmentTerms* terms);
  // The frame and its most covisible frames of its model (local_ba_num_images).
  BundleAdjustmentSummary AdjustLocal(size_t frame, const BundleAdjustmentOptions& options);
  // Every frame of model m, its gauge held, no priors.
  BundleAdjustmentSummary AdjustModel(int m, const BundleAdjustmentOptions& options);

  // Merges the two models with the most common points when their points
  // agree on a similarity (IncrementalMapperOptions::merge_*): the smaller
  // (or the one the VIO does not hold) moved into the other, its points
  // joined to the other's where the tracks say so, its frames' tracks
  // triangulated again. Returns what it merged, nullopt if nothing.
  std::optional<ModelMerge> TryMergeModels();

  // A copy of the reconstruction with only model m's frames registered and
  // only its points.
  Reconstruction ExtractModel(int m) const;

  const IncrementalMapperOptions& options() const { return options_; }
  const TriangulationOptions& triangulation_options() const { return triangulation_; }
  const FrameRegistrationOptions& registration_options() const { return registration_; }

 private:
  // The model holding the point of `track` (one per model) in model m, if any.
  point3D_t PointOfTrackInModel(const Track& track, int m) const;
  // The common points of models a and b: (point in a, point in b) per track.
  std::vector<std::pair<point3D_t, point3D_t>> CommonPoints(int a, int b) const;
  std::optional<Sim3d> EstimateModelSimilarity(
      int into, int from, const std::vector<std::pair<point3D_t, point3D_t>>& common,
      int* num_inliers) const;
  void MoveModel(int from, int into, const Sim3d& into_from_from);

  IncrementalMapperOptions options_;
  TriangulationOptions triangulation_;
  PointFilterOptions filter_;
  FrameRegistrationOptions registration_;
  int num_threads_ = 1;
  Reconstruction reconstruction_;
  std::vector<image_t> frame_ids_;
  std::unordered_map<image_t, size_t> index_of_image_;
  std::vector<int> model_of_frame_;
  std::vector<Model> models_;
  std::vector<Track> tracks_;
  std::vector<std::vector<size_t>> tracks_of_frame_;
};

// A model moved by `b_from_a`: its frames' poses and its points.
void TransformFrames(const Sim3d& b_from_a, const std::vector<image_t>& image_ids,
                     Reconstruction* reconstruction);

}  // namespace viosfm
