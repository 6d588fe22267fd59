#include "viosfm/sfm/batched_mapper.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "viosfm/scene/reprojection.h"
#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sfm/linear_solver_chooser.h"
#include "viosfm/sfm/vio_drift_terms.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

constexpr char kInputLabel[] = "batched mapper input";

std::string DescribeImage(const MapperImage& image) {
  std::ostringstream out;
  out << "image " << image.image_id << " (" << image.name << ")";
  return out.str();
}

bool IsFinitePose(const Rigid3d& pose) {
  return pose.rotation.coeffs().allFinite() && pose.translation.allFinite() &&
         pose.rotation.norm() > 1e-6;
}

// The tracks with an observation in frames [begin, end), in track order.
std::vector<Track> TracksOfFrames(const IncrementalMapper& core, size_t begin, size_t end) {
  std::vector<size_t> indices;
  for (size_t i = begin; i < end; ++i) {
    indices.insert(indices.end(), core.TracksOfFrame(i).begin(), core.TracksOfFrame(i).end());
  }
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  std::vector<Track> subset;
  subset.reserve(indices.size());
  for (const size_t index : indices) subset.push_back(core.tracks()[index]);
  return subset;
}

// Throws InputError for a pair naming an image not in `images` or a match
// indexing a keypoint its image does not have; `first_label` numbers the
// pairs in the messages.
void ValidateVerifiedPairs(const std::vector<MapperImage>& images,
                           const std::vector<ImagePairMatches>& pairs, size_t first_label) {
  std::unordered_map<image_t, size_t> keypoints_of_image;
  for (const MapperImage& image : images)
    keypoints_of_image[image.image_id] = image.keypoints.size();
  for (size_t p = 0; p < pairs.size(); ++p) {
    const ImagePairMatches& pair = pairs[p];
    const auto it1 = keypoints_of_image.find(pair.image_id1);
    const auto it2 = keypoints_of_image.find(pair.image_id2);
    const std::string pair_label = "verified pair " + std::to_string(first_label + p) +
                                   " (images " + std::to_string(pair.image_id1) + ", " +
                                   std::to_string(pair.image_id2) + ")";
    if (it1 == keypoints_of_image.end() || it2 == keypoints_of_image.end()) {
      throw InputError(
          kInputLabel, 0,
          pair_label + " refers to unknown image id " +
              std::to_string(it1 == keypoints_of_image.end() ? pair.image_id1 : pair.image_id2));
    }
    for (size_t m = 0; m < pair.matches.size(); ++m) {
      const FeatureMatch& match = pair.matches[m];
      const bool bad1 = match.point2D_idx1 >= it1->second;
      if (bad1 || match.point2D_idx2 >= it2->second) {
        throw InputError(kInputLabel, 0,
                         pair_label + ": match " + std::to_string(m) + " indexes keypoint " +
                             std::to_string(bad1 ? match.point2D_idx1 : match.point2D_idx2) +
                             " of image " + std::to_string(bad1 ? pair.image_id1 : pair.image_id2) +
                             ", which has " + std::to_string(bad1 ? it1->second : it2->second) +
                             " keypoints");
      }
    }
  }
}

std::string JoinModelSizes(const std::vector<int>& sizes) {
  std::ostringstream out;
  for (size_t m = 0; m < sizes.size(); ++m) out << (m > 0 ? ", " : "") << sizes[m];
  return out.str();
}

}  // namespace

std::string BatchedMapperOptions::Validate() const {
  if (batch_size < 1) return "batch_size must be >= 1";
  if (std::string error = tracks.Validate(); !error.empty()) return "tracks." + error;
  if (std::string error = triangulation.Validate(); !error.empty()) {
    return "triangulation." + error;
  }
  if (std::string error = ba.Validate(); !error.empty()) return "ba." + error;
  if (std::string error = filter.Validate(); !error.empty()) return "filter." + error;
  if (ba_window_batches < 0) return "ba_window_batches must be >= 0";
  if (ba_window_max_held_views < 0) return "ba_window_max_held_views must be >= 0";
  if (batch_ba_max_num_iterations < 0) return "batch_ba_max_num_iterations must be >= 0";
  for (const int span : bridge_spans) {
    if (span < 2) return "bridge_spans must be >= 2 frames each";
  }
  if (bridge_max_matches < 0) return "bridge_max_matches must be >= 0";
  if (std::string error = vio_uncertainty.Validate(); !error.empty()) {
    return "vio_uncertainty." + error;
  }
  if (std::string error = registration.Validate(); !error.empty()) {
    return "registration." + error;
  }
  if (std::string error = incremental.Validate(); !error.empty()) {
    return "incremental." + error;
  }
  if (std::string error = gyro.Validate(); !error.empty()) return "gyro." + error;
  if (std::string error = inertial.Validate(); !error.empty()) return "inertial." + error;
  if (final_ba_max_refinements < 0) return "final_ba_max_refinements must be >= 0";
  if (!(final_ba_refine_min_change >= 0.0)) return "final_ba_refine_min_change must be >= 0";
  if (num_threads < 1) return "num_threads must be >= 1";
  return "";
}

std::string BatchedMapperSummary::Headline() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "batched mapper: " << num_registered << " of "
      << num_images << " images registered in " << batches.size() << " batches, " << num_points
      << " points, " << mean_reprojection_error_px << " px, " << std::setprecision(1)
      << seconds_total << " s";
  return out.str();
}

std::string BatchedMapperSummary::ToString() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "batched mapper: " << num_registered << " of "
      << num_images << " images registered in " << batches.size() << " batches, " << num_points
      << " points, " << num_observations << " observations, mean track length " << mean_track_length
      << ", mean reprojection error " << mean_reprojection_error_px << " px, " << seconds_total
      << " s (tracks " << seconds_tracks << " s)\n"
      << "  frames: " << num_supported << " supported by the images, " << num_vio_only
      << " placed by the VIO only, " << num_unposed << " without a pose; " << num_reposed
      << " re-posed from the images (VIO disagreed; " << num_reposed_after_adjustment
      << " of them after an adjustment), " << num_registered_without_vio
      << " registered from the images without a VIO prediction, " << num_without_vio_pose
      << " without a VIO pose; VIO segments " << num_vio_segments_joined << " of "
      << num_vio_segments << " joined, " << num_vio_breaks << " VIO jump(s) found, "
      << num_vio_jumps_refused << " refused by the frame's matches\n"
      << "  models: " << frames_per_model.size() << " (frames " << JoinModelSizes(frames_per_model)
      << "), " << num_models_merged << " merged into others"
      << (images_only ? "; no VIO pose: the images alone" : "") << "\n"
      << "  relative-pose priors: " << num_consecutive_priors << " consecutive, "
      << num_bridging_priors << " bridging, " << num_gyro_priors << " from the gyro\n"
      << "  " << tracks.Summary();
  if (num_points_merged > 0 || num_observations_split_off > 0) {
    out << "; as later pairs changed the tracks, " << num_points_merged << " points joined, "
        << num_observations_split_off << " observations split off";
  }
  if (!final_ba.termination.empty()) {
    out << "\n  final " << final_ba.ToString() << "\n  final adjustment refined "
        << num_final_ba_refinements << " time(s); its filtering and re-triangulation then changed "
        << std::setprecision(2) << 100.0 * final_ba_last_change << " % of the observations";
  }
  return out.str();
}

namespace {

// The input's cameras: valid ids, unique, with their model's parameters;
// returns their ids. Throws InputError naming the first problem.
std::unordered_set<camera_t> ValidateCameras(const std::vector<Camera>& cameras) {
  std::unordered_set<camera_t> camera_ids;
  for (const Camera& camera : cameras) {
    if (camera.camera_id == kInvalidCameraId) {
      throw InputError(kInputLabel, 0, "a camera has the invalid camera id");
    }
    if (!camera_ids.insert(camera.camera_id).second) {
      throw InputError(kInputLabel, 0, "duplicate camera id " + std::to_string(camera.camera_id));
    }
    if (!camera.HasValidParams()) {
      throw InputError(kInputLabel, 0,
                       "camera " + std::to_string(camera.camera_id) + " (model " +
                           camera.ModelName() + ") has " + std::to_string(camera.params.size()) +
                           " parameters, not those of its model");
    }
  }
  return camera_ids;
}

}  // namespace

// The images of the input as they come (all at once, or a batch at a time):
// each checked against the cameras and the images before it.
class ImageValidator {
 public:
  explicit ImageValidator(std::unordered_set<camera_t> camera_ids)
      : camera_ids_(std::move(camera_ids)) {}

  // images[from, size): InputError naming the first problem.
  void Check(const std::vector<MapperImage>& images, size_t from) {
    for (size_t i = from; i < images.size(); ++i) {
      const MapperImage& image = images[i];
      if (image.image_id == kInvalidImageId) {
        throw InputError(kInputLabel, 0,
                         "image " + std::to_string(i) + " has the invalid image id");
      }
      if (!image_ids_.insert(image.image_id).second) {
        throw InputError(kInputLabel, 0, "duplicate image id " + std::to_string(image.image_id));
      }
      if (image.name.empty()) {
        throw InputError(kInputLabel, 0, DescribeImage(image) + " has an empty name");
      }
      if (!names_.insert(image.name).second) {
        throw InputError(kInputLabel, 0, "duplicate image name '" + image.name + "'");
      }
      if (camera_ids_.count(image.camera_id) == 0) {
        throw InputError(kInputLabel, 0,
                         DescribeImage(image) + " refers to unknown camera id " +
                             std::to_string(image.camera_id));
      }
      if (i > 0 && image.timestamp_ns <= images[i - 1].timestamp_ns) {
        throw InputError(kInputLabel, 0,
                         "images not in strictly increasing time order: " + DescribeImage(image) +
                             " at " + FormatNsAsSeconds(image.timestamp_ns) + " s follows " +
                             DescribeImage(images[i - 1]) + " at " +
                             FormatNsAsSeconds(images[i - 1].timestamp_ns) + " s");
      }
      if (image.vio_cam_from_world && !IsFinitePose(*image.vio_cam_from_world)) {
        throw InputError(kInputLabel, 0,
                         DescribeImage(image) + " has a non-finite or zero-rotation VIO pose");
      }
    }
  }

 private:
  std::unordered_set<camera_t> camera_ids_;
  std::unordered_set<image_t> image_ids_;
  std::unordered_set<std::string> names_;
};

void ValidateBatchedMapperInput(const BatchedMapperInput& input) {
  if (input.images.empty()) throw InputError(kInputLabel, 0, "no images to reconstruct");
  ImageValidator validator(ValidateCameras(input.cameras));
  validator.Check(input.images, 0);
  ValidateVerifiedPairs(input.images, input.verified_pairs, 0);
}

namespace {

BundleAdjustmentOptions WithThreads(BundleAdjustmentOptions options, int num_threads) {
  options.num_threads = num_threads;
  return options;
}

const std::vector<image_t> kNoImages;

}  // namespace

BatchedMapper::BatchedMapper(const BatchedMapperInput& input, const BatchedMapperOptions& options,
                             VerifiedPairStream* stream)
    : input_(input),
      options_(options),
      registration_(options.registration),
      stream_(stream),
      core_(options.incremental, options.triangulation, options.filter, options.registration,
            options.num_threads),
      ba_options_(WithThreads(options.ba, options.num_threads)),
      solver_chooser_(ba_options_) {}

BatchedMapper::~BatchedMapper() = default;

const std::vector<image_t>& BatchedMapper::MainRegistered() const {
  return core_.NumModels() > 0 ? core_.model(0).registered : kNoImages;
}

bool BatchedMapper::MainModelHasGauge() const {
  if (core_.NumModels() == 0) return false;
  const image_t gauge = core_.model(0).gauge_image;
  return gauge != kInvalidImageId && core_.IsRegistered(core_.FrameIndex(gauge));
}

void BatchedMapper::AddNewImages() {
  for (size_t i = num_images_; i < images().size(); ++i) {
    const MapperImage& input_image = images()[i];
    if (track_builder_)
      track_builder_->AddImage(input_image.image_id, input_image.keypoints.size());
    vio_poses_.emplace_back();
    if (input_image.vio_cam_from_world) {
      vio_poses_[i] = *input_image.vio_cam_from_world;
      vio_poses_[i]->rotation.normalize();
      segments_.insert(input_image.vio_odometer.segment);
      if (gauge_image_ == kInvalidImageId) {
        gauge_index_ = i;
        gauge_image_ = input_image.image_id;
      }
    } else {
      ++summary_.num_without_vio_pose;
    }
    Image image;
    image.image_id = input_image.image_id;
    image.camera_id = input_image.camera_id;
    image.name = input_image.name;
    image.timestamp_ns = input_image.timestamp_ns;
    image.cam_from_world = vio_poses_[i].value_or(Rigid3d());
    image.points2D.resize(input_image.keypoints.size());
    for (size_t j = 0; j < input_image.keypoints.size(); ++j) {
      image.points2D[j].xy =
          Eigen::Vector2d(input_image.keypoints[j].x, input_image.keypoints[j].y);
    }
    core_.AddFrame(std::move(image));
    summary_.frames.emplace_back();
    summary_.frames.back().image_id = input_image.image_id;
    is_break_.push_back(0);
    // Frames known up front join in the batch of their index; streamed ones
    // in the batch that takes them.
    batch_of_frame_.push_back(frames_streamed_ ? current_batch_
                                               : i / static_cast<size_t>(options_.batch_size));
  }
  num_images_ = images().size();
  summary_.num_images = static_cast<int>(num_images_);
  summary_.num_vio_segments = static_cast<int>(segments_.size());
}

void BatchedMapper::BuildTracks(const std::vector<ImagePairMatches>& new_pairs) {
  const Timer timer;
  TrackBuildResult track_result;
  if (track_builder_) {
    track_builder_->AddPairs(new_pairs);
    track_result = track_builder_->Result();
  } else {
    track_result = viosfm::BuildTracks(*pairs_, options_.tracks);
  }
  summary_.tracks = track_result.statistics;
  core_.SetTracks(std::move(track_result.tracks));
  summary_.seconds_tracks += timer.ElapsedSeconds();
}

void BatchedMapper::BuildPriors() {
  if (!options_.ba.use_relative_pose_priors) return;
  RelativePosePriorOptions prior_options;
  prior_options.bridge_spans = options_.bridge_spans;
  prior_options.bridge_max_matches = options_.bridge_max_matches;
  prior_options.weighting = options_.ba.prior_weighting;
  prior_options.vio_uncertainty = options_.vio_uncertainty;
  all_priors_ = MakeRelativePosePriors(images(), *pairs_, prior_options);
  consecutive_pairs_.clear();
  for (size_t p = 0; p < all_priors_.priors.size(); ++p) {
    if (!all_priors_.bridging[p]) {
      consecutive_pairs_.insert(
          ImagePairToPairId(all_priors_.priors[p].image_id1, all_priors_.priors[p].image_id2));
    }
  }
  summary_.num_consecutive_priors = all_priors_.num_consecutive;
  summary_.num_bridging_priors = all_priors_.num_bridging;
}

bool BatchedMapper::TakeStreamedBatch(size_t begin, size_t* end, bool last) {
  // The batch's frames (streamed) and the pairs among them and the frames
  // before them: complete once the verification has passed the batch.
  VerifiedPairStream::Taken taken = stream_->Take(begin + static_cast<size_t>(options_.batch_size));
  if (frames_streamed_) {
    const size_t first_new = streamed_images_.size();
    std::move(taken.frames.begin(), taken.frames.end(), std::back_inserter(streamed_images_));
    streamed_validator_->Check(streamed_images_, first_new);
    AddNewImages();
    *end = num_images_;
    last = taken.last;
  }
  ValidateVerifiedPairs(images(), taken.pairs, streamed_pairs_.size());
  BuildTracks(taken.pairs);
  // No pair comes after the last batch's: the builder's graph (every match)
  // goes before the final adjustment needs the memory.
  if (last) track_builder_.reset();
  std::move(taken.pairs.begin(), taken.pairs.end(), std::back_inserter(streamed_pairs_));
  BuildPriors();
  // Points as the tracks are now: split where the new pairs split a track
  // (a conflict they revealed), joined where they joined two.
  Reconstruction& reconstruction = core_.reconstruction();
  summary_.num_observations_split_off +=
      static_cast<int>(SplitPointsByTracks(&reconstruction, core_.tracks()));
  const std::vector<point3D_t> merged =
      MergeTrackPoints(&reconstruction, core_.tracks(), options_.triangulation);
  summary_.num_points_merged += static_cast<int>(merged.size());
  changed_since_filter_.insert(changed_since_filter_.end(), merged.begin(), merged.end());
  if (last) {
    if (frames_streamed_ && num_images_ == 0) {
      throw InputError(kInputLabel, 0, "no images to reconstruct");
    }
    VIOSFM_LOG(INFO) << "batched mapper: " << num_images_ << " images, " << pairs_->size()
                     << " verified pairs (streamed)" << LogDetails() << "; "
                     << summary_.tracks.Summary();
  }
  return last;
}

size_t BatchedMapper::RegisterFromImages(bool may_start_model) {
  if (!registration_.verify_with_images) return 0;
  // The frames without a VIO pose wait for the images; those with one are
  // the VIO chain's (TryRegister).
  const auto candidates = [&]() {
    std::vector<size_t> frames;
    for (const size_t i : pending_) {
      if (!vio_poses_[i]) frames.push_back(i);
    }
    return frames;
  };
  if (may_start_model && summary_.images_only && core_.NumModels() == 0) StartModelFromImages();
  size_t added = 0;
  while (true) {
    const std::vector<size_t> registered = core_.RegisterNextFrames(candidates());
    for (const size_t i : registered) {
      MapperFrameStatus& status = summary_.frames[i];
      status.source = FramePoseSource::kImagesWithoutVio;
      newly_registered_.push_back(i);
    }
    added += registered.size();
    pending_.erase(std::remove_if(pending_.begin(), pending_.end(),
                                  [&](size_t i) { return core_.IsRegistered(i); }),
                   pending_.end());
    // Frames the models could not take for a whole batch start a model of
    // their own, where two of them make an initial pair (images only;
    // with a VIO, only once every batch is in: see Run).
    if (!may_start_model || !summary_.images_only) break;
    std::vector<size_t> waiting;
    for (const size_t i : candidates()) {
      if (batch_of_frame_[i] < current_batch_) waiting.push_back(i);
    }
    if (waiting.size() < 2 || !StartModelFromImages()) break;
  }
  return added;
}

bool BatchedMapper::StartModelFromImages() {
  if (!registration_.verify_with_images) return false;
  std::vector<size_t> candidates;
  for (const size_t i : pending_) {
    if (!vio_poses_[i]) candidates.push_back(i);
  }
  if (candidates.size() < 2) return false;
  const std::optional<InitialPair> pair = core_.FindInitialPair(candidates, *pairs_);
  if (!pair) return false;
  const int m = core_.InitializeModel(*pair);
  if (m < 0) return false;
  for (const size_t i : {pair->frame1, pair->frame2}) {
    summary_.frames[i].source = FramePoseSource::kImagesWithoutVio;
    newly_registered_.push_back(i);
  }
  pending_.erase(std::remove_if(pending_.begin(), pending_.end(),
                                [&](size_t i) { return core_.IsRegistered(i); }),
                 pending_.end());
  return true;
}

bool BatchedMapper::StartModelFromVioSegment() {
  // The earliest pending frame with a VIO pose: its segment is joined to no
  // model, so it starts one of its own where the VIO puts it.
  for (const size_t i : pending_) {
    if (!vio_poses_[i]) continue;
    const int m = core_.NewModel(/*vio_anchored=*/true);
    core_.SetGauge(m, images()[i].image_id);
    RegisterFrame(i, m, *vio_poses_[i], FramePoseSource::kVio);
    pending_.erase(std::remove(pending_.begin(), pending_.end(), i), pending_.end());
    VIOSFM_LOG(INFO) << "batched mapper: " << DescribeImage(images()[i])
                     << " starts a separate model where its VIO segment "
                     << images()[i].vio_odometer.segment
                     << " puts it (the images join none of its frames to the others)";
    return true;
  }
  return false;
}

void BatchedMapper::MergeModels() {
  while (const std::optional<ModelMerge> merge = core_.TryMergeModels()) {
    ++summary_.num_models_merged;
    all_changed_since_filter_ = true;
  }
}

TriangulationStatistics BatchedMapper::RegisterBatch(size_t begin, size_t end,
                                                     MapperBatchStatistics* stats) {
  // 2. Registration: each frame by its VIO pose relative to the latest
  // registered frame of its VIO segment, checked against the images.
  newly_registered_.clear();
  Timer timer;
  for (size_t i = begin; i < end; ++i) {
    if (!TryRegister(i)) pending_.push_back(i);
  }
  stats->seconds_registration = timer.ElapsedSeconds();

  // 3. Triangulation of the tracks seen by the batch, then the frames that
  // the new points (or a newly registered frame of their VIO segment)
  // allow, and those the images alone register.
  timer.Start();
  const std::vector<Track> batch_tracks = TracksOfFrames(core_, begin, end);
  TriangulationStatistics triangulation;
  for (int m = 0; m < core_.NumModels(); ++m) {
    const TriangulationStatistics statistics = TriangulateReconstruction(
        &core_.reconstruction(), batch_tracks, core_.model(m).registered, options_.triangulation);
    if (m == 0) triangulation = statistics;
    changed_since_filter_.insert(changed_since_filter_.end(), statistics.changed_point_ids.begin(),
                                 statistics.changed_point_ids.end());
  }
  RetryPending();
  RegisterFromImages(/*may_start_model=*/true);
  stats->seconds_triangulation = timer.ElapsedSeconds();
  return triangulation;
}

size_t BatchedMapper::RegisterLateFrames() {
  // After the final adjustment: the frames that only the final model allows
  // to register, and separate models for those the images join to none
  // (a VIO segment where its VIO puts it, or an initial pair of their own).
  size_t registered = RetryPending() + RegisterFromImages(/*may_start_model=*/true);
  while (!pending_.empty() && (StartModelFromVioSegment() || StartModelFromImages())) {
    registered += RetryPending() + RegisterFromImages(/*may_start_model=*/false);
  }
  return registered;
}

void BatchedMapper::RefineFinalModel(bool frames_changed, double final_change, bool global) {
  // Another global adjustment for the frames re-posed, registered or merged
  // after the final one, and, after a final global one, while its filtering
  // and re-triangulation change the model (final_ba_refine_min_change).
  while (frames_changed ||
         (global && final_change > options_.final_ba_refine_min_change &&
          summary_.num_final_ba_refinements < options_.final_ba_max_refinements)) {
    if (!frames_changed) {
      ++summary_.num_final_ba_refinements;
      VIOSFM_LOG(INFO) << std::fixed << std::setprecision(2)
                       << "final bundle adjustment: refinement "
                       << summary_.num_final_ba_refinements << " of at most "
                       << options_.final_ba_max_refinements << LogDetails()
                       << ": filtering and re-triangulation changed " << 100.0 * final_change
                       << " % of the observations";
    }
    frames_changed = false;
    summary_.final_ba = Adjust(0, true);
    AdjustOtherModels(true);
    final_change = FilterAndRetriangulateAll();
  }
  if (global) summary_.final_ba_last_change = final_change;
}

void BatchedMapper::MapBatch(size_t b, size_t num_batches, const MapperBatchCallback& on_batch,
                             bool* last_out) {
  const Timer batch_timer;
  current_batch_ = b;
  const size_t batch_size = static_cast<size_t>(options_.batch_size);
  bool last = b + 1 == num_batches;
  const size_t begin = b * batch_size;
  size_t end = std::min(num_images_, begin + batch_size);
  if (stream_ != nullptr) last = TakeStreamedBatch(begin, &end, last);
  *last_out = last;
  MapperBatchStatistics stats;
  stats.batch_index = static_cast<int>(b);
  stats.num_images = static_cast<int>(end - begin);
  const TriangulationStatistics triangulation = RegisterBatch(begin, end, &stats);

  // 4. Bundle adjustment: the last batch's is the final global one.
  const bool global = last && options_.final_global_ba;
  size_t window_begin = 0;
  const size_t num_main = MainRegistered().size();
  if (!global && options_.ba_window_batches > 0 &&
      num_main > static_cast<size_t>(options_.ba_window_batches) * batch_size) {
    window_begin = num_main - static_cast<size_t>(options_.ba_window_batches) * batch_size;
  }
  if (options_.ba_after_each_batch || global) {
    const BundleAdjustmentSummary ba_summary = Adjust(window_begin, global);
    stats.seconds_ba = ba_summary.time_s;
    stats.num_ba_iterations = ba_summary.num_iterations;
    stats.ba_linear_solver = ba_summary.linear_solver;
    stats.num_ba_free_images = static_cast<int>(MainRegistered().size() - window_begin);
    stats.num_ba_observations = ba_summary.num_observations;
    if (global) summary_.final_ba = ba_summary;
    AdjustOtherModels(global);
  }

  // 5. Filtering and re-triangulation of the tracks left without a point;
  // after the final adjustment, the share of the observations they change.
  const Timer timer;
  double final_change = 0.0;
  if (window_begin == 0) {
    final_change = FilterAndRetriangulateAll();
  } else {
    FilterAndRetriangulateWindow(window_begin);
  }
  // 6. The frames placed by the VIO alone that the adjusted model now
  // re-poses; after the final adjustment the frames only it registers, and
  // the models merged, then the final model refined.
  const size_t reposed_after_adjustment = RecheckVioPlaced();
  summary_.num_reposed_after_adjustment += static_cast<int>(reposed_after_adjustment);
  const size_t registered_late = last ? RegisterLateFrames() : 0;
  const int merged_before = summary_.num_models_merged;
  MergeModels();
  const size_t changed = reposed_after_adjustment + registered_late +
                         static_cast<size_t>(summary_.num_models_merged - merged_before);
  RefineFinalModel(last && changed > 0 && (options_.ba_after_each_batch || global), final_change,
                   global);
  stats.seconds_filtering = timer.ElapsedSeconds();

  const Reconstruction& reconstruction = core_.reconstruction();
  stats.num_registered_total = static_cast<int>(MainRegistered().size());
  stats.num_points_total = static_cast<int>(reconstruction.NumPoints3D());
  stats.mean_reprojection_error_px =
      window_begin == 0 ? MeanReprojectionError(reconstruction, options_.num_threads)
                        : MeanReprojectionErrorInImages(reconstruction, WindowImages(window_begin),
                                                        options_.num_threads);
  stats.seconds_total = batch_timer.ElapsedSeconds();
  VIOSFM_LOG(INFO) << std::fixed << std::setprecision(3) << "batch " << b + 1
                   << (frames_streamed_ ? std::string() : "/" + std::to_string(num_batches))
                   << ": images " << stats.num_registered_total << " (+" << stats.num_images
                   << "), points " << stats.num_points_total << " (+"
                   << triangulation.num_points_added << " new), "
                   << stats.mean_reprojection_error_px << " px, " << stats.seconds_total << " s"
                   << LogDetails() << "; BA over " << stats.num_ba_free_images << " images "
                   << stats.seconds_ba << " s (" << stats.num_ba_iterations << " iterations, "
                   << BaLinearSolverName(stats.ba_linear_solver) << ")";
  if (on_batch && !last) on_batch(reconstruction, stats);
  summary_.batches.push_back(stats);
}

void BatchedMapper::JudgeFrames() {
  // 7. Every frame's verdict.
  std::set<int> joined_segments;
  Reconstruction& reconstruction = core_.reconstruction();
  for (size_t i = 0; i < num_images_; ++i) {
    MapperFrameStatus& status = summary_.frames[i];
    const MapperImage& input_image = images()[i];
    if (core_.IsRegistered(i)) {
      status.num_supporting_observations = CountSupportingObservations(
          reconstruction, input_image.image_id, registration_.support_max_error_px);
      status.supported =
          status.num_supporting_observations >= registration_.min_supporting_observations;
      if (!status.supported && !vio_poses_[i]) {
        // Registered from the images, but the final model no longer
        // supports it, and no VIO pose places it: no pose.
        core_.Deregister(i);
        status.source = FramePoseSource::kNone;
        status.reason = "registered from the images, but too few of its observations (" +
                        std::to_string(status.num_supporting_observations) +
                        ") agree with the final model";
      }
    }
    if (core_.IsRegistered(i)) {
      if (vio_poses_[i]) joined_segments.insert(input_image.vio_odometer.segment);
      ++(status.supported ? summary_.num_supported : summary_.num_vio_only);
      if (status.source == FramePoseSource::kImagesReposed) ++summary_.num_reposed;
      if (status.source == FramePoseSource::kImagesWithoutVio) {
        ++summary_.num_registered_without_vio;
      }
      if (status.vio_break) ++summary_.num_vio_breaks;
      continue;
    }
    ++summary_.num_unposed;
    if (!status.reason.empty()) continue;
    if (!vio_poses_[i]) {
      status.reason = registration_.verify_with_images
                          ? "no VIO pose, and too few 2D-3D matches (" +
                                std::to_string(status.num_correspondences) +
                                ") to register it from the images"
                          : "no VIO pose (registration from the images is off)";
    } else {
      status.reason = "its VIO segment " + std::to_string(input_image.vio_odometer.segment) +
                      " was never joined to the model (none of its frames could be registered "
                      "from the images; last try: " +
                      std::to_string(status.num_correspondences) + " 2D-3D matches)";
    }
  }
  summary_.num_vio_segments_joined = static_cast<int>(joined_segments.size());
  if (summary_.num_unposed > 0) {
    VIOSFM_LOG(WARNING) << "batched mapper: " << summary_.num_unposed << " of " << num_images_
                        << " frames have no pose";
  }
}

Reconstruction BatchedMapper::Run(BatchedMapperSummary* summary_out,
                                  const MapperBatchCallback& on_batch,
                                  std::vector<Reconstruction>* other_models) {
  const Timer total_timer;
  if (!options_.Check()) throw InputError("batched mapper options: " + options_.Validate());
  // The frames come from the stream, a batch at a time, or are all in the
  // input.
  frames_streamed_ = stream_ != nullptr && !stream_->frames_up_front();
  if (stream_ != nullptr) {
    VIOSFM_CHECK(input_.verified_pairs.empty()) << "verified pairs given and streamed";
    if (frames_streamed_) {
      VIOSFM_CHECK(input_.images.empty()) << "frames given and streamed";
      streamed_validator_ = std::make_unique<ImageValidator>(ValidateCameras(input_.cameras));
    } else {
      VIOSFM_CHECK_EQ(stream_->num_frames(), input_.images.size());
    }
  }
  if (!frames_streamed_) ValidateBatchedMapperInput(input_);
  images_ = frames_streamed_ ? &streamed_images_ : &input_.images;
  pairs_ = stream_ != nullptr ? &streamed_pairs_ : &input_.verified_pairs;
  if (stream_ != nullptr) {
    track_builder_.emplace(std::vector<std::pair<image_t, size_t>>{}, options_.tracks);
  }
  for (const Camera& camera : input_.cameras) core_.reconstruction().AddCamera(camera);
  AddNewImages();
  if (stream_ == nullptr) {
    BuildTracks(*pairs_);
    VIOSFM_LOG(INFO) << "batched mapper: " << num_images_ << " images, " << pairs_->size()
                     << " verified pairs" << LogDetails() << "; " << summary_.tracks.Summary();
  }
  if (!frames_streamed_) BuildPriors();
  summary_.images_only = !frames_streamed_ && gauge_image_ == kInvalidImageId;
  if (summary_.images_only) {
    VIOSFM_LOG(INFO) << "batched mapper: no frame has a VIO pose: the images alone start, carry "
                        "and join the models";
  }

  const size_t batch_size = static_cast<size_t>(options_.batch_size);
  // Streamed frames: as many batches as the stream brings.
  const size_t num_batches = frames_streamed_ ? 0 : (num_images_ + batch_size - 1) / batch_size;
  ProgressBar progress("batched mapping", static_cast<int64_t>(num_batches),
                       options_.show_progress && !frames_streamed_ ? ProgressBar::Mode::kAuto
                                                                   : ProgressBar::Mode::kNever);
  for (size_t b = 0; frames_streamed_ || b < num_batches; ++b) {
    bool last = false;
    MapBatch(b, num_batches, on_batch, &last);
    progress.Update();
    if (last) break;
  }
  progress.Finish();
  JudgeFrames();

  // The main model: the one the VIO's first frame anchors, else the largest.
  int main_model = 0;
  for (int m = 1; m < core_.NumModels(); ++m) {
    if (core_.model(main_model).vio_anchored) break;
    if (core_.model(m).registered.size() > core_.model(main_model).registered.size()) {
      main_model = m;
    }
  }
  std::vector<int> output_order;
  if (core_.NumModels() > 0) output_order.push_back(main_model);
  for (int m = 0; m < core_.NumModels(); ++m) {
    if (m != main_model && !core_.model(m).registered.empty()) output_order.push_back(m);
  }
  std::vector<int> output_index(static_cast<size_t>(core_.NumModels()), -1);
  for (size_t k = 0; k < output_order.size(); ++k)
    output_index[output_order[k]] = static_cast<int>(k);
  for (size_t i = 0; i < num_images_; ++i) {
    const int m = core_.ModelOf(i);
    summary_.frames[i].model = m >= 0 ? output_index[m] : -1;
  }
  for (const int m : output_order) {
    summary_.frames_per_model.push_back(static_cast<int>(core_.model(m).registered.size()));
  }
  Reconstruction reconstruction;
  if (output_order.size() <= 1) {
    reconstruction = std::move(core_.reconstruction());
  } else {
    for (size_t k = 1; k < output_order.size(); ++k) {
      summary_.num_frames_in_other_models += summary_.frames_per_model[k];
      if (other_models != nullptr) other_models->push_back(core_.ExtractModel(output_order[k]));
    }
    VIOSFM_LOG(WARNING) << "batched mapper: the images join " << summary_.num_frames_in_other_models
                        << " frames to none of the main model's: they form "
                        << output_order.size() - 1 << " separate model(s)";
    reconstruction = core_.ExtractModel(main_model);
  }
  // Frames of the separate models are not posed in the main one.
  summary_.num_supported = 0;
  summary_.num_vio_only = 0;
  for (const MapperFrameStatus& status : summary_.frames) {
    if (status.model != 0) continue;
    ++(status.supported ? summary_.num_supported : summary_.num_vio_only);
  }
  summary_.num_registered = static_cast<int>(reconstruction.NumRegImages());
  summary_.num_points = static_cast<int>(reconstruction.NumPoints3D());
  summary_.num_observations = static_cast<int>(reconstruction.ComputeNumObservations());
  summary_.mean_track_length = reconstruction.ComputeMeanTrackLength();
  summary_.mean_reprojection_error_px = MeanReprojectionError(reconstruction, options_.num_threads);
  summary_.seconds_total = total_timer.ElapsedSeconds();
  VIOSFM_LOG(INFO) << summary_.Headline() << LogDetails() << "\n" << summary_.ToString();
  if (summary_out != nullptr) *summary_out = std::move(summary_);
  return reconstruction;
}

Reconstruction RunBatchedMapper(const BatchedMapperInput& input,
                                const BatchedMapperOptions& options, BatchedMapperSummary* summary,
                                VerifiedPairStream* stream, const MapperBatchCallback& on_batch,
                                std::vector<Reconstruction>* other_models) {
  BatchedMapper mapper(input, options, stream);
  return mapper.Run(summary, on_batch, other_models);
}

}  // namespace viosfm
