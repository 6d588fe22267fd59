// The paper's batched incremental reconstruction (its section "Batched
// Incremental Reconstruction") with relative-pose-constrained bundle
// adjustment: images are registered k at a time in time order, each batch
// placed by the VIO, then triangulated and bundle adjusted.
//
//  1. tracks from the verified matches of all pairs (tracks.h);
//  2. batch 0 = the first k images, posed by the VIO (world = the VIO's
//     world frame: metric, gravity aligned); in batch i > 0 each image is
//     placed by its VIO relative pose to the latest registered image of its
//     VIO segment (as refined so far: for the first image of the batch the
//     last image of batch i-1, as the paper does), and, beyond the paper,
//     verified against its 2D-3D matches (frame_registration.h): re-posed
//     from the images where the VIO's prediction disagrees with them, and
//     registered from the images where there is no prediction (no VIO pose,
//     or a new VIO segment after a re-initialisation); frames that cannot be
//     registered yet are tried again after every batch;
//  3. triangulation of the tracks seen by the registered images (new points,
//     and new observations of existing points), triangulator.h;
//  4. bundle adjustment (ba/bundle_adjustment.h): Cauchy reprojection term
//     over registered images and points plus the relative-pose terms
//     (relative_pose_priors.h) between consecutive frames of a VIO segment,
//     weighted by the VIO uncertainty model's covariance times the paper's
//     connectivity factor exp(-beta c) under a Cauchy loss (or the paper's
//     w = alpha exp(-beta c) with fixed sigmas: ba.prior_weighting); the
//     first image with a VIO pose is held (gauge);
//  5. filtering (large reprojection error, small triangulation angle) and
//     re-triangulation of the tracks left without a point;
//  6. after the last batch a final global bundle adjustment, filtering and
//     re-triangulation (it replaces the last batch's own bundle adjustment);
//     frames that only then can be registered are, followed by another
//     global bundle adjustment;
//  With a rolling shutter (BatchedMapperInput::rolling_shutter_readout_s)
//  the observations are also moved by the camera's motion over their row's
//  time: at registration, with the VIO's velocity and the model's points'
//  depths, for the images' check; before every adjustment, with the
//  velocity from the model's camera centres, once for each observation.
//  7. every frame's verdict: supported by the images (frame_registration.h),
//     placed by the VIO only, or not posed (and why).
#pragma once

#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sfm/filters.h"
#include "viosfm/sfm/frame_registration.h"
#include "viosfm/sfm/gyro_priors.h"
#include "viosfm/sfm/incremental_mapper.h"
#include "viosfm/sfm/inertial_terms.h"
#include "viosfm/sfm/linear_solver_chooser.h"
#include "viosfm/sfm/mapper_input.h"
#include "viosfm/sfm/relative_pose_priors.h"
#include "viosfm/sfm/tracks.h"
#include "viosfm/sfm/triangulator.h"
#include "viosfm/sfm/verified_pair_stream.h"
#include "viosfm/util/option_fields.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"

namespace viosfm {

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
  // The final adjustment's filtering and re-triangulation change the model's
  // observations: points triangulated from the adjusted poses, observations
  // added to points, observations filtered out. Observations attached after
  // the last adjustment never moved a pose, and where the poses it started
  // from were placed by a drifting VIO, those attached before it were
  // chosen by their agreement with the VIO's poses. So while the filtering
  // and re-triangulation change more than final_ba_refine_min_change of
  // the model's observations (keypoints that gained or lost a point; one
  // filtered out near the threshold and attached again is no change: the
  // adjustment had it), the final adjustment runs again, at most
  // final_ba_max_refinements times (COLMAP's global refinements do the same:
  // 0.0005 and 5, counting what comes back as a change). Defaults 0.005 and
  // 3; 0 refinements: one final adjustment. See docs/history/benchmarks-2026.md,
  // section "What the refinement counts: keypoints that changed, at 0.5 %".
  int final_ba_max_refinements = 3;
  double final_ba_refine_min_change = 0.005;
  // The gyro's relative rotations in the final global bundle adjustment,
  // when the input has an IMU (BatchedMapperInput::imu).
  GyroPriorOptions gyro;
  // The IMU's factors in the final global bundle adjustment, when the input
  // has an IMU (in place of the gyro's priors, whose bias fit starts them).
  InertialTermOptions inertial;
  // Local window of the per-batch bundle adjustment, in batches, >= 0. 0 (the
  // paper, default): every registered image but the first is refined after
  // every batch, so the cost of the run grows quadratically with the number
  // of batches. N > 0: only the images of the last N batches are refined;
  // older images that observe the same points (and the image just before the
  // window, for its relative-pose term) are held constant and points seen
  // only by older images are left out. The final global bundle adjustment
  // refines everything either way.
  int ba_window_batches = 0;
  // With a window: each of the window's points keeps the observations of at
  // most this many held (older) images in the per-batch adjustment, the
  // latest ones; 0: all of them. They anchor the point; more of them only
  // make the problem grow with the past. Default 0.
  int ba_window_max_held_views = 0;
  // Levenberg-Marquardt iterations of each per-batch bundle adjustment, >= 1,
  // or 0 for ba.max_num_iterations; the final global bundle adjustment always
  // runs ba.max_num_iterations. Default 3. Every per-batch adjustment starts
  // from a refined reconstruction plus one batch placed by the VIO, so a few
  // iterations take it most of the way, and the final one converges: fewer
  // iterations cut the per-batch adjustments' time by more than half for the
  // same model. See docs/history/benchmarks-2026.md, section
  // "The mapper's levers: the window, the final adjustment, its tolerance".
  int batch_ba_max_num_iterations = 3;
  // The first batch's bundle adjustment runs to convergence (up to
  // ba.max_num_iterations) whatever batch_ba_max_num_iterations says.
  // Default true. That adjustment is the only one that starts from poses
  // placed by the VIO alone and points just triangulated from them: capped,
  // the points filtered after it depend on where the iterations happened to
  // stop, and with two threads' timing the later batches part ways;
  // converged, one and two threads give the same model. See
  // docs/history/benchmarks-2026.md, section "The first batch's adjustment converged".
  bool converge_first_batch_ba = true;
  // Bridging priors (beyond the paper). The paper's relative-pose terms join
  // consecutive frames only. Across a stretch of frames whose images barely
  // match, the slack each of those terms allows adds up like a random walk,
  // while a VIO's rotation error over a few seconds is far smaller than the
  // sum of its frame-to-frame noise (and its roll and pitch do not drift):
  // through a weakly textured stairwell the second floor ends up rotated
  // against the first. So for every consecutive pair with fewer than
  // `bridge_max_matches` verified matches, rotation-only relative-pose terms
  // from the VIO join the frames `bridge_spans` apart (in selected frames)
  // that straddle it, weighted w(c) with c the fewest verified matches of a
  // consecutive pair they straddle. Rotation only: a VIO's translation over
  // seconds carries its scale and position drift. Only where the images
  // give (almost) nothing: where a pair has a few dozen matches, the images
  // still hold the rotation better than the VIO. Defaults {10, 50} frames (1
  // and 5 s at 10 Hz) and 30 matches (twice the verification's minimum of
  // inliers); empty spans: off (the paper's terms only). See
  // docs/history/benchmarks-2026.md, section "Bridging priors: the stairwell of two_floors".
  // With the covariance weighting (ba.prior_weighting, the default) they
  // are full 6-DoF priors weighted by the VIO model's covariance over their
  // span, like every other prior; with the paper weighting rotation-only,
  // as before the covariance.
  std::vector<int> bridge_spans = {10, 50};
  int bridge_max_matches = 30;
  // How far the VIO's relative poses are trusted (scene/vio_uncertainty.h):
  // the priors' covariance. Default: the model's defaults (an external VIO
  // on EuRoC-class data).
  VioUncertaintyModel vio_uncertainty;
  // The final adjustment takes the VIO as a drifting world frame plus frame
  // noise (vio_drift_terms.h) in place of its consecutive relative-pose
  // priors (covariance weighting only): a chain of priors counts each
  // frame's noise twice and so trusts the VIO's pose over seconds less than
  // its own model does. Default false.
  bool vio_drift_states = false;
  // Verified registration of each frame (frame_registration.h).
  FrameRegistrationOptions registration;
  // The images-only core (incremental_mapper.h): initial pairs, frames
  // registered from the images, separate models and their merging.
  IncrementalMapperOptions incremental;
  // Worker threads (BA, triangulation); default 2.
  int num_threads = 2;
  bool show_progress = true;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }

  // The mapper stores nothing in the database: every field is run-only.
  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"batch_size", "frames registered per batch (the paper's k)", kRunOnly}, self.batch_size);
    visit({"ba_window_batches",
           "bundle adjust only the last N batches after each batch; 0: all (the paper's); the "
           "final BA refines all",
           kRunOnly},
          self.ba_window_batches);
    visit({"ba_window_max_held_views",
           "with a window, held (older) images kept per point, the latest; 0: all", kRunOnly},
          self.ba_window_max_held_views);
    visit({"batch_ba_max_num_iterations",
           "iterations of each per-batch bundle adjustment; 0: as many as the final one", kRunOnly},
          self.batch_ba_max_num_iterations);
    visit({"converge_first_batch_ba",
           "the first batch's bundle adjustment runs to convergence, uncapped", kRunOnly},
          self.converge_first_batch_ba);
    visit({"bridge_spans", "frame spans of the bridge pairs, comma-separated", kRunOnly},
          self.bridge_spans);
    visit({"bridge_max_matches",
           "a consecutive pair with fewer verified matches is poorly matched (bridged)", kRunOnly},
          self.bridge_max_matches);
    visit({"vio_drift_states",
           "final BA: the VIO as drift states and frame noise, not a chain of priors", kRunOnly},
          self.vio_drift_states);
    VisitOptionGroup({"tracks", "", kRunOnly}, self.tracks, visit);
    VisitOptionGroup({"triangulation", "", kRunOnly}, self.triangulation, visit);
    VisitOptionGroup({"ba", "", kRunOnly}, self.ba, visit);
    VisitOptionGroup({"filter", "", kRunOnly}, self.filter, visit);
    VisitOptionGroup({"registration", "", kRunOnly}, self.registration, visit);
    VisitOptionGroup({"incremental", "", kRunOnly}, self.incremental, visit);
    VisitOptionGroup({"gyro", "", kRunOnly}, self.gyro, visit);
    VisitOptionGroup({"inertial", "", kRunOnly}, self.inertial, visit);
    visit({"retriangulate", "re-triangulate tracks without a point after each filtering", kRunOnly},
          self.retriangulate);
    visit({"ba_after_each_batch", "bundle adjustment after each batch", kRunOnly},
          self.ba_after_each_batch);
    visit({"final_global_ba", "a global bundle adjustment at the end", kRunOnly},
          self.final_global_ba);
    visit({"final_ba_max_refinements",
           "final BA run again at most this many times while re-triangulation changes the model",
           kRunOnly},
          self.final_ba_max_refinements);
    visit({"final_ba_refine_min_change",
           "share of the observations filtering and re-triangulation must change to refine",
           kRunOnly},
          self.final_ba_refine_min_change);
    visit({"num_threads", "worker threads", kRunOnly}, self.num_threads);
    visit({"show_progress", "progress bars", kRunOnly}, self.show_progress);
  }
};

struct MapperBatchStatistics {
  int batch_index = 0;
  int num_images = 0;            // images in the batch
  int num_registered_total = 0;  // registered images after the batch
  int num_points_total = 0;      // points after the batch (after filtering)
  int num_ba_iterations = 0;     // iterations of the batch's bundle adjustment
  BaLinearSolver ba_linear_solver = BaLinearSolver::kAuto;  // the one it used
  // Mean over the observations in the images of the batch's adjustment
  // window (every image after a global adjustment), after the batch (BA,
  // filtering and re-triangulation), px.
  double mean_reprojection_error_px = 0.0;
  double seconds_registration = 0.0;   // the batch's frames, VIO prediction and PnP check
  double seconds_triangulation = 0.0;  // its tracks, and the pending frames retried
  double seconds_ba = 0.0;
  double seconds_filtering = 0.0;
  int num_ba_free_images = 0;   // images whose pose the batch's BA refined
  int num_ba_observations = 0;  // observations in the batch's BA (free and held images)
  double seconds_total = 0.0;   // the whole batch
};

// The verdict on one input frame.
struct MapperFrameStatus {
  image_t image_id = kInvalidImageId;
  FramePoseSource source = FramePoseSource::kNone;
  // The pose is supported by the images (frame_registration.h).
  bool supported = false;
  int num_correspondences = 0;    // 2D-3D matches when it was registered
  int num_pnp_inliers = 0;        // of the images' pose (0: PnP not run or failed)
  int num_predicted_inliers = 0;  // of the VIO's prediction
  int num_supporting_observations = 0;
  bool vio_break = false;  // the VIO jumped here (FrameRegistrationOptions::break_sigmas)
  // The model the frame is registered in: 0 the main one (the result), 1, 2,
  // ... the separate ones the images could not join to it; -1 none.
  int model = -1;
  // Why a frame is not posed (empty if it is).
  std::string reason;
};

struct BatchedMapperSummary {
  TrackStatistics tracks;
  std::vector<MapperBatchStatistics> batches;
  // The last global adjustment (after the refinements, if any).
  BundleAdjustmentSummary final_ba;
  // Times the final adjustment ran again for the model's change
  // (BatchedMapperOptions::final_ba_refine_min_change), and the share of
  // the observations the last one's filtering and re-triangulation changed.
  int num_final_ba_refinements = 0;
  double final_ba_last_change = 0.0;
  int num_images = 0;
  // Images registered in the model: every posed frame (num_supported +
  // num_vio_only below).
  int num_registered = 0;
  int num_points = 0;
  int num_observations = 0;
  double mean_track_length = 0.0;
  double mean_reprojection_error_px = 0.0;
  int num_consecutive_priors = 0;
  int num_bridging_priors = 0;   // BatchedMapperOptions::bridge_spans
  int num_gyro_priors = 0;       // in the final adjustment (BatchedMapperOptions::gyro)
  std::string gyro_message;      // MakeGyroPriors' line, empty without them
  int num_inertial_factors = 0;  // in the final adjustment (BatchedMapperOptions::inertial)
  std::string inertial_message;  // InertialTerms' line after the adjustment, empty without them
  double inertial_scale = 0.0;   // InertialTerms::scale(), 0 without them
  // The final adjustment's rolling-shutter motion compensation
  // (BatchedMapperInput::rolling_shutter_readout_s), empty without it.
  std::string rolling_shutter_message;
  // Per input frame, in input order, and the counts: posed frames are either
  // supported by the images or placed by the VIO only.
  std::vector<MapperFrameStatus> frames;
  int num_supported = 0;
  int num_vio_only = 0;
  int num_unposed = 0;
  int num_without_vio_pose = 0;  // input frames without a VIO pose
  int num_reposed = 0;           // FramePoseSource::kImagesReposed
  // Of num_reposed, the frames placed by the VIO alone at first (the gauge
  // frame, a first batch's) that the images re-posed once an adjustment had
  // given them points to check against.
  int num_reposed_after_adjustment = 0;
  int num_registered_without_vio = 0;  // FramePoseSource::kImagesWithoutVio
  int num_vio_breaks = 0;
  // Frames whose PnP pose looked like a VIO jump but whose verified matches
  // with the registered frames showed the VIO's pose (a look-alike place's
  // 2D-3D matches, FrameRegistrationOptions): their VIO pose stands.
  int num_vio_jumps_refused = 0;
  // Models: the main one and the separate ones (registered frames each,
  // the main one first), and how many models were merged into others.
  std::vector<int> frames_per_model;
  int num_models_merged = 0;
  int num_frames_in_other_models = 0;
  // No input frame had a VIO pose: the models are the images' alone (their
  // scale and frame are those of their initial pairs, unless the IMU's
  // alignment below made them metric and level).
  bool images_only = false;
  // The IMU's scale and gravity applied to a model the images alone made,
  // before its final adjustment; empty without.
  std::string imu_alignment_message;
  int num_vio_segments = 0;         // VIO segments among the input frames
  int num_vio_segments_joined = 0;  // of those, with a posed frame
  // With the pairs streamed: points joined because later pairs joined
  // their tracks, and observations taken off points because later pairs
  // split their tracks (triangulator.h MergeTrackPoints,
  // SplitPointsByTracks).
  int num_points_merged = 0;
  int num_observations_split_off = 0;
  double seconds_tracks = 0.0;
  double seconds_total = 0.0;
  std::string Headline() const;  // one short line: images, points, error, time
  std::string ToString() const;  // a few lines for the log
};

// Called after each batch but the last with the model as it stands.
using MapperBatchCallback =
    std::function<void(const Reconstruction& model, const MapperBatchStatistics& batch)>;

// The batched mapper as a class with named steps; RunBatchedMapper runs it.
// It keeps the VIO's side of the mapping (predictions, jumps, priors, the
// IMU in the global adjustments) and drives the images-only core
// (incremental_mapper.h) for what the VIO does not place.
class ImageValidator;
class VioDriftTerms;
class BatchedMapper {
 public:
  // `input` and `stream` must outlive the mapper (see RunBatchedMapper).
  BatchedMapper(const BatchedMapperInput& input, const BatchedMapperOptions& options,
                VerifiedPairStream* stream);
  ~BatchedMapper();
  Reconstruction Run(BatchedMapperSummary* summary, const MapperBatchCallback& on_batch,
                     std::vector<Reconstruction>* other_models);

 private:
  // A registered image's velocity is taken from its registered neighbours at
  // most this far apart in time (ns).
  static constexpr timestamp_ns_t kVelocityMaxGapNs = 500'000'000;

  // Input: frames joining the model, tracks, priors, a streamed batch.
  void AddNewImages();
  void BuildTracks(const std::vector<ImagePairMatches>& new_pairs);
  void BuildPriors();
  // Takes a streamed batch's frames and pairs; returns whether it is the last.
  bool TakeStreamedBatch(size_t begin, size_t* end, bool last);

  // Registration by the VIO's prediction, checked against the images.
  bool SameRun(size_t i, size_t j) const;
  std::optional<size_t> FindReference(size_t i) const;
  std::optional<Eigen::Vector3d> VioCamVelocity(size_t i) const;
  bool BeyondVioDrift(size_t i, size_t reference, const Rigid3d& images_pose,
                      const Rigid3d& vio_pose, double* position_difference,
                      double* rotation_difference) const;
  void RegisterFrame(size_t i, int model, const Rigid3d& cam_from_world, FramePoseSource source);
  bool TryRegister(size_t i);
  bool RegisterAgainstPrediction(size_t i, size_t reference, const Rigid3d& predicted,
                                 const AbsolutePoseResult& result);
  bool JumpRefuted(size_t i, const Rigid3d& predicted, const AbsolutePoseResult& result,
                   double position_difference, double rotation_difference);
  void MoveToStamp(size_t i, const Rigid3d& predicted, FrameCorrespondences* correspondences) const;
  size_t RetryPending();
  size_t RecheckVioPlaced();
  void TriangulateTracksOf(const std::vector<size_t>& frame_indices);

  // Registration from the images alone (the core), and the models.
  size_t RegisterFromImages(bool may_start_model);
  bool StartModelFromImages();
  bool StartModelFromVioSegment();
  void MergeModels();

  // Adjustment, filtering, re-triangulation.
  std::vector<RelativePosePrior> ActivePriors(bool with_bridging) const;
  BundleAdjustmentSummary Adjust(size_t window_begin, bool global);
  BaLinearSolver ChooseLinearSolver(const std::vector<image_t>& free_images, bool global);
  void CompensateRollingShutter(bool global);
  std::unique_ptr<InertialTerms> MakeInertialTerms(const GyroPriors& gyro,
                                                   const std::vector<GyroFrame>& frames);
  std::vector<GyroFrame> GyroFramesOfMainModel() const;
  void AlignMainModelToImu();
  std::unique_ptr<VioDriftTerms> MakeDriftTerms(bool global,
                                                std::vector<RelativePosePrior>* priors) const;
  void AdjustOtherModels(bool global);
  double FilterAndRetriangulateAll();
  void FilterAndRetriangulateWindow(size_t window_begin);
  std::vector<point3D_t> PointsToFilter(size_t window_begin) const;
  std::vector<image_t> WindowImages(size_t window_begin) const;

  // A batch, the final refinements, and every frame's verdict.
  void MapBatch(size_t b, size_t num_batches, const MapperBatchCallback& on_batch, bool* last);
  TriangulationStatistics RegisterBatch(size_t begin, size_t end, MapperBatchStatistics* stats);
  size_t RegisterLateFrames();
  void RefineFinalModel(bool frames_changed, double final_change, bool global);
  void JudgeFrames();

  const std::vector<image_t>& MainRegistered() const;
  bool MainModelHasGauge() const;

  const BatchedMapperInput& input_;
  const BatchedMapperOptions& options_;
  const FrameRegistrationOptions& registration_;
  VerifiedPairStream* stream_ = nullptr;
  // The frames come from the stream a batch at a time, or are all in the input.
  bool frames_streamed_ = false;
  std::unique_ptr<ImageValidator> streamed_validator_;
  std::vector<MapperImage> streamed_images_;
  const std::vector<MapperImage>* images_ = nullptr;
  const std::vector<MapperImage>& images() const { return *images_; }
  size_t num_images_ = 0;  // the frames known so far
  BatchedMapperSummary summary_;

  // Pairs and tracks (of every pair, or streamed, of those taken so far).
  std::vector<ImagePairMatches> streamed_pairs_;
  const std::vector<ImagePairMatches>* pairs_ = nullptr;
  std::optional<IncrementalTrackBuilder> track_builder_;
  IncrementalMapper core_;

  // Per frame: its VIO pose, and whether the VIO jumped just before it.
  std::vector<std::optional<Rigid3d>> vio_poses_;
  std::set<int> segments_;
  std::vector<char> is_break_;
  // The first frame with a VIO pose: placed where the VIO puts it and held
  // in every adjustment (the gauge).
  size_t gauge_index_ = std::numeric_limits<size_t>::max();
  image_t gauge_image_ = kInvalidImageId;
  // Frames not registered yet, in time order, and those registered by the
  // last registration round.
  std::vector<size_t> pending_;
  std::vector<size_t> newly_registered_;
  // The batch each pending frame arrived in.
  std::vector<size_t> batch_of_frame_;
  size_t current_batch_ = 0;

  // Relative-pose priors and the pairs of the consecutive ones.
  RelativePosePriors all_priors_;
  std::unordered_set<image_pair_t> consecutive_pairs_;

  // Points triangulated or extended since the last filtering.
  std::vector<point3D_t> changed_since_filter_;
  bool all_changed_since_filter_ = true;

  // The adjustments' state.
  BundleAdjustmentOptions ba_options_;
  LinearSolverChooser solver_chooser_;
  int num_batch_adjustments_ = 0;
  std::unordered_map<image_t, std::vector<char>> rolling_shutter_moved_;
  std::vector<float> rolling_shutter_moves_;
  // A global adjustment left the IMU's factors out: the later ones take the
  // gyro's priors at once.
  bool inertial_declined_ = false;
  // The inflation of the gyro's priors and of the IMU factors' covariance
  // the first global adjustment found; later ones keep at least that.
  double gyro_sigma_floor_ = 1.0;
  double inertial_sigma_floor_ = 1.0;
  // The main model, made by the images alone, was scaled and levelled by
  // the IMU (AlignMainModelToImu).
  bool imu_aligned_ = false;
};

// Throws InputError naming the first problem of `input`: no images, a camera
// with an invalid or duplicate id or parameters, a duplicate image id or
// name, an empty name, an unknown camera id, images not in strictly
// increasing time order, a non-finite VIO pose, a
// pair naming an unknown image, or a match indexing a keypoint that does not
// exist.
void ValidateBatchedMapperInput(const BatchedMapperInput& input);

// Runs the batched reconstruction (see the top of this file). Throws
// InputError for invalid options, images not in time order, an unknown
// camera id, or a match indexing a keypoint that does not exist.
// With a `stream` (input.verified_pairs then empty), the verified pairs come
// from it while the mapper runs: before each batch the mapper takes those
// among the batch's frames and the frames before them, waiting for the
// verification to pass the batch, and builds the tracks and the priors
// again (verified_pair_stream.h); the last batch, and so the final
// adjustment, has every pair. A stream without its frames up front brings
// the frames too (input.images then empty): the mapper takes a batch of
// them at a time, as many batches as the stream holds frames, each frame
// checked as ValidateBatchedMapperInput checks the input's; input.imu may
// then be filled by the stream's producer until it closes the stream (the
// mapper reads it only after the last batch is taken, in the final
// adjustment). Rethrows the stream's failure.
// `on_batch`, if given, is called after each batch but the last (whose
// adjustment is the final one) with the model as it stands, from the
// mapper's thread.
// The result is the main model (the one holding the VIO's first frame, or
// the largest); `other_models`, if given, receives the separate models the
// images could not join to it (each with only its own frames registered).
Reconstruction RunBatchedMapper(const BatchedMapperInput& input,
                                const BatchedMapperOptions& options,
                                BatchedMapperSummary* summary = nullptr,
                                VerifiedPairStream* stream = nullptr,
                                const MapperBatchCallback& on_batch = {},
                                std::vector<Reconstruction>* other_models = nullptr);

}  // namespace viosfm
