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

// A registered image's velocity is taken from its registered neighbours at
// most this far apart in time (ns).
constexpr timestamp_ns_t kRollingShutterVelocityMaxGapNs = 500'000'000;

const char kInputLabel[] = "batched mapper input";

std::string DescribeImage(const MapperImage& image) {
  std::ostringstream out;
  out << "image " << image.image_id << " (" << image.name << ")";
  return out.str();
}

bool IsFinitePose(const Rigid3d& pose) {
  return pose.rotation.coeffs().allFinite() && pose.translation.allFinite() &&
         pose.rotation.norm() > 1e-6;
}

// Copy of an image for a sub-problem: the same keypoints, linked to no point.
Image CopyImageWithoutPoints(const Image& image) {
  Image copy;
  copy.image_id = image.image_id;
  copy.camera_id = image.camera_id;
  copy.name = image.name;
  copy.cam_from_world = image.cam_from_world;
  copy.registered = true;
  copy.timestamp_ns = image.timestamp_ns;
  copy.points2D = image.points2D;
  for (Point2D& point2D : copy.points2D) point2D.point3D_id = kInvalidPoint3DId;
  return copy;
}

// Several callers' terms in one adjustment.
class CombinedTerms : public BundleAdjustmentTerms {
 public:
  explicit CombinedTerms(std::vector<BundleAdjustmentTerms*> parts) : parts_(std::move(parts)) {}
  size_t NumParameters() const override {
    size_t size = 0;
    for (const BundleAdjustmentTerms* part : parts_) {
      if (part != nullptr) size += part->NumParameters();
    }
    return size;
  }
  std::vector<double*> AddTo(ceres::Problem* problem,
                             const std::function<double*(image_t)>& pose_block,
                             double* storage) override {
    std::vector<double*> blocks;
    for (BundleAdjustmentTerms* part : parts_) {
      if (part == nullptr) continue;
      const std::vector<double*> added = part->AddTo(problem, pose_block, storage);
      blocks.insert(blocks.end(), added.begin(), added.end());
      storage += part->NumParameters();
    }
    return blocks;
  }
  void TakeSolution(const double* storage) override {
    for (BundleAdjustmentTerms* part : parts_) {
      if (part == nullptr) continue;
      part->TakeSolution(storage);
      storage += part->NumParameters();
    }
  }

 private:
  std::vector<BundleAdjustmentTerms*> parts_;
};

// Bundle adjustment of the poses of `free_images` and of the points they
// observe. Every other image observing those points is held constant, and so
// is `held_neighbour` (the image before the window, for its relative-pose
// term, if valid) and `gauge_image` (if it is free). With max_held_views >
// 0, each point keeps the observations of at most that many held images,
// the latest (highest image ids, which follow time): they anchor the point
// as well as all of them would, and the problem stops growing with the
// number of older images that saw the point. When `free_images` are
// all the registered images this is BundleAdjust with the gauge image held;
// otherwise the sub-problem is solved on a copy and the result copied back.
BundleAdjustmentSummary AdjustImages(Reconstruction* reconstruction,
                                     const std::vector<image_t>& free_images,
                                     image_t held_neighbour, image_t gauge_image,
                                     const std::vector<RelativePosePrior>& priors,
                                     const BundleAdjustmentOptions& options, int max_held_views,
                                     BundleAdjustmentTerms* terms) {
  if (free_images.size() == reconstruction->NumRegImages()) {
    return BundleAdjust(reconstruction, priors, {gauge_image}, options, terms);
  }
  VIOSFM_CHECK(terms == nullptr) << "terms are only added to a global adjustment";
  const std::unordered_set<image_t> free(free_images.begin(), free_images.end());
  std::vector<point3D_t> point_ids;
  std::unordered_set<point3D_t> point_seen;
  std::vector<image_t> held_images;
  std::unordered_set<image_t> held_seen;
  const auto hold = [&](image_t image_id) {
    if (free.count(image_id) == 0 && held_seen.insert(image_id).second) {
      held_images.push_back(image_id);
    }
  };
  // The track of each point in the sub-problem: every free observation, and
  // the held ones max_held_views allows.
  std::vector<std::vector<TrackElement>> tracks;
  for (const image_t image_id : free_images) {
    for (const Point2D& point2D : reconstruction->GetImage(image_id).points2D) {
      if (!point2D.HasPoint3D() || !point_seen.insert(point2D.point3D_id).second) continue;
      point_ids.push_back(point2D.point3D_id);
      std::vector<TrackElement> track;
      std::vector<TrackElement> held;
      for (const TrackElement& element : reconstruction->GetPoint3D(point2D.point3D_id).track) {
        (free.count(element.image_id) > 0 ? track : held).push_back(element);
      }
      if (max_held_views > 0 && held.size() > static_cast<size_t>(max_held_views)) {
        std::sort(held.begin(), held.end(), [](const TrackElement& a, const TrackElement& b) {
          return a.image_id != b.image_id ? a.image_id > b.image_id : a.point2D_idx < b.point2D_idx;
        });
        held.resize(static_cast<size_t>(max_held_views));
      }
      for (const TrackElement& element : held) hold(element.image_id);
      track.insert(track.end(), held.begin(), held.end());
      tracks.push_back(std::move(track));
    }
  }
  if (held_neighbour != kInvalidImageId) hold(held_neighbour);

  Reconstruction sub;
  for (const camera_t camera_id : reconstruction->CameraIds()) {
    sub.AddCamera(reconstruction->GetCamera(camera_id));
  }
  for (const image_t image_id : free_images) {
    sub.AddImage(CopyImageWithoutPoints(reconstruction->GetImage(image_id)));
  }
  for (const image_t image_id : held_images) {
    sub.AddImage(CopyImageWithoutPoints(reconstruction->GetImage(image_id)));
  }
  for (size_t k = 0; k < point_ids.size(); ++k) {
    Point3D point3D = reconstruction->GetPoint3D(point_ids[k]);
    if (max_held_views > 0) point3D.track = std::move(tracks[k]);
    sub.AddPoint3DWithId(point_ids[k], std::move(point3D));
  }
  std::vector<image_t> constant = held_images;
  if (free.count(gauge_image) > 0) constant.push_back(gauge_image);

  const BundleAdjustmentSummary summary = BundleAdjust(&sub, priors, constant, options);

  for (const image_t image_id : free_images) {
    reconstruction->GetImage(image_id).cam_from_world = sub.GetImage(image_id).cam_from_world;
  }
  for (const point3D_t point3D_id : point_ids) {
    const Point3D& adjusted = sub.GetPoint3D(point3D_id);
    Point3D& point3D = reconstruction->GetPoint3D(point3D_id);
    point3D.xyz = adjusted.xyz;
    point3D.error = adjusted.error;
  }
  if (options.refine_intrinsics) {
    for (const camera_t camera_id : reconstruction->CameraIds()) {
      reconstruction->GetCamera(camera_id).params = sub.GetCamera(camera_id).params;
    }
  }
  return summary;
}

// The tracks with an observation in images [begin, end) (indices in time
// order), in track order.
std::vector<Track> TracksOfImages(const std::vector<Track>& tracks,
                                  const std::vector<std::vector<size_t>>& tracks_of_image,
                                  size_t begin, size_t end) {
  std::vector<size_t> indices;
  for (size_t i = begin; i < end; ++i) {
    indices.insert(indices.end(), tracks_of_image[i].begin(), tracks_of_image[i].end());
  }
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  std::vector<Track> subset;
  subset.reserve(indices.size());
  for (const size_t index : indices) subset.push_back(tracks[index]);
  return subset;
}

// The rolling shutter's translation share (scene/rolling_shutter.h left it:
// it depends on each point's depth, which only the model knows). Each
// registered image's camera velocity from the model's camera centres around
// it (its registered neighbours in time, at most max_gap_ns away), and each
// observation of a point not moved yet (`moved`, per image and keypoint)
// moved by what that motion over its row's time offset changes in the
// point's projection: to where the camera at the stamp sees it. Appends
// each move's length (px) to `move_lengths`.
void CompensateRollingShutterMotion(Reconstruction* reconstruction,
                                    std::vector<std::pair<timestamp_ns_t, image_t>> stamped_images,
                                    double readout_s, timestamp_ns_t max_gap_ns,
                                    std::unordered_map<image_t, std::vector<char>>* moved,
                                    std::vector<float>* move_lengths) {
  std::sort(stamped_images.begin(), stamped_images.end());
  for (size_t k = 0; k < stamped_images.size(); ++k) {
    const auto center = [&](size_t j) {
      return ProjectionCenter(reconstruction->GetImage(stamped_images[j].second).cam_from_world);
    };
    const size_t before =
        k > 0 && stamped_images[k].first - stamped_images[k - 1].first <= max_gap_ns ? k - 1 : k;
    const size_t after = k + 1 < stamped_images.size() &&
                                 stamped_images[k + 1].first - stamped_images[k].first <= max_gap_ns
                             ? k + 1
                             : k;
    if (before == after) continue;
    Image& image = reconstruction->GetImage(stamped_images[k].second);
    std::vector<char>& image_moved = (*moved)[image.image_id];
    image_moved.resize(image.points2D.size(), 0);
    const Camera& camera = reconstruction->GetCamera(image.camera_id);
    const double span_s = NsToSeconds(stamped_images[after].first - stamped_images[before].first);
    const Eigen::Vector3d cam_velocity =
        image.cam_from_world.rotation * ((center(after) - center(before)) / span_s);
    for (size_t p = 0; p < image.points2D.size(); ++p) {
      Point2D& point2D = image.points2D[p];
      if (!point2D.HasPoint3D() || image_moved[p]) continue;
      const Eigen::Vector3d in_cam =
          image.cam_from_world * reconstruction->GetPoint3D(point2D.point3D_id).xyz;
      const double offset_s =
          RowTimeOffset(point2D.xy.y(), static_cast<int>(camera.height), readout_s);
      const std::optional<Eigen::Vector2d> at_stamp = Project(camera, in_cam);
      const std::optional<Eigen::Vector2d> at_row =
          Project(camera, in_cam - cam_velocity * offset_s);
      if (!at_stamp || !at_row) continue;
      const Eigen::Vector2d move = *at_stamp - *at_row;
      point2D.xy += move;
      image_moved[p] = 1;
      move_lengths->push_back(static_cast<float>(move.norm()));
    }
  }
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
  if (std::string error = gyro.Validate(); !error.empty()) return "gyro." + error;
  if (std::string error = inertial.Validate(); !error.empty()) return "inertial." + error;
  if (final_ba_max_refinements < 0) return "final_ba_max_refinements must be >= 0";
  if (!(final_ba_refine_min_change >= 0.0)) return "final_ba_refine_min_change must be >= 0";
  if (num_threads < 1) return "num_threads must be >= 1";
  return "";
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
      any_vio_pose_ = any_vio_pose_ || image.vio_cam_from_world.has_value();
    }
  }
  // Some image has a VIO pose: InputError otherwise.
  void CheckAnyVioPose() const {
    if (!any_vio_pose_) {
      throw InputError(kInputLabel, 0,
                       "no image has a VIO pose (the VIO gives the world frame and the scale)");
    }
  }

 private:
  std::unordered_set<camera_t> camera_ids_;
  std::unordered_set<image_t> image_ids_;
  std::unordered_set<std::string> names_;
  bool any_vio_pose_ = false;
};

}  // namespace

void ValidateBatchedMapperInput(const BatchedMapperInput& input) {
  if (input.images.empty()) throw InputError(kInputLabel, 0, "no images to reconstruct");
  ImageValidator validator(ValidateCameras(input.cameras));
  validator.Check(input.images, 0);
  validator.CheckAnyVioPose();
  ValidateVerifiedPairs(input.images, input.verified_pairs, 0);
}

// A VIO jump is refused where the frame's verified matches with the
// registered frames fit the VIO's pose more than this many times as often as
// the PnP pose (FrameRegistrationOptions). Measured on the simulated
// corridor: the look-alike places refused fit 2.6 to 170 times as many
// matches at the VIO's pose; a pose further along the baseline fits them
// about as well (3419 against 3398), which tells nothing.
constexpr double kJumpRefutingMatchRatio = 2.0;

Reconstruction RunBatchedMapper(const BatchedMapperInput& input,
                                const BatchedMapperOptions& options,
                                BatchedMapperSummary* summary_out, VerifiedPairStream* stream,
                                const MapperBatchCallback& on_batch) {
  const Timer total_timer;
  if (!options.Check()) throw InputError("batched mapper options: " + options.Validate());
  // The frames come from the stream, a batch at a time (frames_streamed),
  // or are all in the input.
  const bool frames_streamed = stream != nullptr && !stream->frames_up_front();
  std::optional<ImageValidator> streamed_validator;
  if (stream != nullptr) {
    VIOSFM_CHECK(input.verified_pairs.empty()) << "verified pairs given and streamed";
    if (frames_streamed) {
      VIOSFM_CHECK(input.images.empty()) << "frames given and streamed";
      streamed_validator.emplace(ValidateCameras(input.cameras));
    } else {
      VIOSFM_CHECK_EQ(stream->num_frames(), input.images.size());
    }
  }
  if (!frames_streamed) ValidateBatchedMapperInput(input);
  std::vector<MapperImage> streamed_images;
  const std::vector<MapperImage>& images = frames_streamed ? streamed_images : input.images;
  // The frames known so far: all of them unless streamed.
  size_t num_images = images.size();
  BatchedMapperSummary summary;
  const FrameRegistrationOptions& registration = options.registration;

  // 1. Tracks, and the tracks of each image: of every verified pair or,
  // streamed, of those taken so far (built again as each batch takes more;
  // verified_pair_stream.h).
  std::vector<ImagePairMatches> streamed_pairs;
  const std::vector<ImagePairMatches>& pairs = stream ? streamed_pairs : input.verified_pairs;
  std::unordered_map<image_t, size_t> index_of_image;
  std::vector<Track> tracks;
  std::vector<std::vector<size_t>> tracks_of_image;
  std::optional<IncrementalTrackBuilder> track_builder;
  if (stream != nullptr)
    track_builder.emplace(std::vector<std::pair<image_t, size_t>>{}, options.tracks);
  // The tracks of every pair, or, streamed, of those taken so far, the
  // `new_pairs` among them just taken.
  const auto build_tracks = [&](const std::vector<ImagePairMatches>& new_pairs) {
    const Timer timer;
    TrackBuildResult track_result;
    if (track_builder) {
      track_builder->AddPairs(new_pairs);
      track_result = track_builder->Result();
    } else {
      track_result = BuildTracks(pairs, options.tracks);
    }
    tracks = std::move(track_result.tracks);
    summary.tracks = track_result.statistics;
    tracks_of_image.assign(num_images, {});
    for (size_t t = 0; t < tracks.size(); ++t) {
      for (const TrackElement& element : tracks[t].elements) {
        tracks_of_image[index_of_image.at(element.image_id)].push_back(t);
      }
    }
    summary.seconds_tracks += timer.ElapsedSeconds();
  };

  // The model: all images, unregistered, with their keypoints; per image
  // its VIO pose and its registration state. Streamed frames join as their
  // batch is taken.
  Reconstruction reconstruction;
  for (const Camera& camera : input.cameras) reconstruction.AddCamera(camera);
  std::vector<std::optional<Rigid3d>> vio_poses;
  std::set<int> segments;
  std::vector<MapperFrameStatus>& frames = summary.frames;
  // A break at frame k (the VIO jumped between k and the frame before it)
  // ends a run of frames whose VIO poses can be chained.
  std::vector<char> is_break;
  std::vector<char> is_registered;
  // The first frame with a VIO pose: placed where the VIO puts it, held in
  // every adjustment (the gauge); num_images until there is one.
  size_t gauge_index = std::numeric_limits<size_t>::max();
  image_t gauge_image = kInvalidImageId;
  // Images [num_images, images.size()) join the model.
  const auto add_images = [&]() {
    for (size_t i = num_images; i < images.size(); ++i) {
      const MapperImage& input_image = images[i];
      index_of_image[input_image.image_id] = i;
      if (track_builder)
        track_builder->AddImage(input_image.image_id, input_image.keypoints.size());
      vio_poses.emplace_back();
      if (input_image.vio_cam_from_world) {
        vio_poses[i] = *input_image.vio_cam_from_world;
        vio_poses[i]->rotation.normalize();
        segments.insert(input_image.vio_odometer.segment);
        if (gauge_image == kInvalidImageId) {
          gauge_index = i;
          gauge_image = input_image.image_id;
        }
      } else {
        ++summary.num_without_vio_pose;
      }
      Image image;
      image.image_id = input_image.image_id;
      image.camera_id = input_image.camera_id;
      image.name = input_image.name;
      image.timestamp_ns = input_image.timestamp_ns;
      image.cam_from_world = vio_poses[i].value_or(Rigid3d());
      image.points2D.resize(input_image.keypoints.size());
      for (size_t j = 0; j < input_image.keypoints.size(); ++j) {
        image.points2D[j].xy =
            Eigen::Vector2d(input_image.keypoints[j].x, input_image.keypoints[j].y);
      }
      reconstruction.AddImage(std::move(image));
      frames.emplace_back();
      frames.back().image_id = input_image.image_id;
      is_break.push_back(0);
      is_registered.push_back(0);
    }
    num_images = images.size();
    tracks_of_image.resize(num_images);
    summary.num_images = static_cast<int>(num_images);
    summary.num_vio_segments = static_cast<int>(segments.size());
  };
  num_images = 0;
  add_images();
  Timer timer;
  if (stream == nullptr) {
    build_tracks(pairs);
    VIOSFM_LOG(INFO) << "batched mapper: " << num_images << " images, " << pairs.size()
                     << " verified pairs; " << summary.tracks.Summary();
  }

  // Relative-pose priors (none without the relative-pose term: the w/o RPC
  // ablation), of the pairs known (built again with the tracks when
  // streamed: the priors between the frames taken so far are those of
  // every pair).
  RelativePosePriors all_priors;
  std::unordered_set<image_pair_t> consecutive_pairs;  // those of the consecutive priors
  const auto build_priors = [&]() {
    if (!options.ba.use_relative_pose_priors) return;
    RelativePosePriorOptions prior_options;
    prior_options.bridge_spans = options.bridge_spans;
    prior_options.bridge_max_matches = options.bridge_max_matches;
    prior_options.weighting = options.ba.prior_weighting;
    prior_options.vio_uncertainty = options.vio_uncertainty;
    all_priors = MakeRelativePosePriors(images, pairs, prior_options);
    consecutive_pairs.clear();
    for (size_t p = 0; p < all_priors.priors.size(); ++p) {
      if (!all_priors.bridging[p]) {
        consecutive_pairs.insert(
            ImagePairToPairId(all_priors.priors[p].image_id1, all_priors.priors[p].image_id2));
      }
    }
    summary.num_consecutive_priors = all_priors.num_consecutive;
    summary.num_bridging_priors = all_priors.num_bridging;
  };
  if (!frames_streamed) build_priors();

  // Registration state.
  const auto same_run = [&](size_t i, size_t j) {
    if (!vio_poses[i] || !vio_poses[j] ||
        images[i].vio_odometer.segment != images[j].vio_odometer.segment) {
      return false;
    }
    for (size_t k = std::min(i, j) + 1; k <= std::max(i, j); ++k) {
      if (is_break[k]) return false;
    }
    return true;
  };
  // The registered frame nearest to i (earlier first) whose VIO pose chains to i's.
  const auto find_reference = [&](size_t i) -> std::optional<size_t> {
    for (size_t j = i; j-- > 0;) {
      if (!same_run(i, j)) break;
      if (is_registered[j]) return j;
    }
    for (size_t j = i + 1; j < num_images; ++j) {
      if (!same_run(i, j)) break;
      if (is_registered[j]) return j;
    }
    return std::nullopt;
  };
  std::vector<image_t> registered;  // in order of registration
  std::vector<size_t> newly_registered;
  const auto register_frame = [&](size_t i, const Rigid3d& cam_from_world, FramePoseSource source) {
    Image& image = reconstruction.GetImage(images[i].image_id);
    image.cam_from_world = cam_from_world;
    image.cam_from_world.rotation.normalize();
    image.registered = true;
    is_registered[i] = 1;
    frames[i].source = source;
    registered.push_back(image.image_id);
    newly_registered.push_back(i);
  };
  // Registers frame i if the VIO or the images allow (frame_registration.h).
  // The camera's velocity at frame i in its own frame, from the VIO poses of
  // its neighbours in the same VIO segment (for the rolling shutter's
  // motion share at registration); none without them.
  const auto vio_cam_velocity = [&](size_t i) -> std::optional<Eigen::Vector3d> {
    if (!vio_poses[i]) return std::nullopt;
    const auto neighbour = [&](size_t j) {
      return j < num_images && vio_poses[j] &&
             images[j].vio_odometer.segment == images[i].vio_odometer.segment &&
             std::abs(images[j].timestamp_ns - images[i].timestamp_ns) <=
                 kRollingShutterVelocityMaxGapNs;
    };
    const size_t before = i > 0 && neighbour(i - 1) ? i - 1 : i;
    const size_t after = neighbour(i + 1) ? i + 1 : i;
    if (before == after) return std::nullopt;
    const double span_s = NsToSeconds(images[after].timestamp_ns - images[before].timestamp_ns);
    return vio_poses[i]->rotation *
           ((ProjectionCenter(*vio_poses[after]) - ProjectionCenter(*vio_poses[before])) / span_s);
  };
  // Whether `images_pose` lies beyond the drift the VIO model allows between
  // frame i and its reference frame from `vio_pose` (break_sigmas standard
  // deviations plus the floors, FrameRegistrationOptions); the distances
  // through `position_difference` and `rotation_difference`.
  const auto beyond_vio_drift = [&](size_t i, size_t reference, const Rigid3d& images_pose,
                                    const Rigid3d& vio_pose, double* position_difference,
                                    double* rotation_difference) {
    const RelativePoseSigmas sigmas = LargestSigmas(RelativePoseCovariance(
        options.vio_uncertainty, VioSampleOfImage(images[reference]), VioSampleOfImage(images[i])));
    *position_difference = (ProjectionCenter(images_pose) - ProjectionCenter(vio_pose)).norm();
    *rotation_difference = images_pose.rotation.angularDistance(vio_pose.rotation);
    return *position_difference > registration.break_sigmas * sigmas.translation_m +
                                      registration.break_min_translation_m ||
           *rotation_difference > registration.break_sigmas * sigmas.rotation_rad +
                                      registration.break_min_rotation_rad;
  };
  const auto try_register = [&](size_t i) -> bool {
    MapperFrameStatus& status = frames[i];
    std::optional<Rigid3d> predicted;
    std::optional<size_t> reference;
    if (vio_poses[i]) {
      if (i == gauge_index) {
        predicted = *vio_poses[i];
      } else if ((reference = find_reference(i))) {
        predicted = *vio_poses[i] * vio_poses[*reference]->Inverse() *
                    reconstruction.GetImage(images[*reference].image_id).cam_from_world;
      }
    }
    if (registration.verify_with_images && i != gauge_index) {
      FrameCorrespondences correspondences = CollectFrameCorrespondences(
          reconstruction, tracks, tracks_of_image[i], images[i].image_id);
      // A rolling shutter's motion share: each observation moved to where
      // the predicted camera at the stamp sees its point (the points'
      // depths from the model, the velocity from the VIO).
      const std::optional<Eigen::Vector3d> velocity =
          input.rolling_shutter_readout_s > 0.0 && predicted ? vio_cam_velocity(i) : std::nullopt;
      if (velocity) {
        const Camera& camera = reconstruction.GetCamera(images[i].camera_id);
        for (size_t c = 0; c < correspondences.size(); ++c) {
          const Eigen::Vector3d in_cam = *predicted * correspondences.points_in_world[c];
          const double offset_s =
              RowTimeOffset(CamToImage(camera, correspondences.points_normalized[c]).y(),
                            static_cast<int>(camera.height), input.rolling_shutter_readout_s);
          const Eigen::Vector3d at_row = in_cam - *velocity * offset_s;
          if (in_cam.z() <= 0.0 || at_row.z() <= 0.0) continue;
          correspondences.points_normalized[c] += in_cam.hnormalized() - at_row.hnormalized();
        }
      }
      status.num_correspondences = static_cast<int>(correspondences.size());
      if (static_cast<int>(correspondences.size()) >= registration.min_num_correspondences) {
        const Camera& camera = reconstruction.GetCamera(images[i].camera_id);
        AbsolutePoseOptions pnp = registration.pnp;
        pnp.seed = registration.pnp.seed + images[i].image_id;
        const AbsolutePoseResult result =
            EstimateAbsolutePose(correspondences.points_normalized, correspondences.points_in_world,
                                 MeanFocalLength(camera), pnp, predicted);
        status.num_predicted_inliers = static_cast<int>(result.num_predicted_inliers);
        status.num_pnp_inliers = result.success ? static_cast<int>(result.num_inliers) : 0;
        if (result.success && !predicted) {
          register_frame(i, result.cam_from_world, FramePoseSource::kImagesWithoutVio);
          return true;
        }
        if (result.success) {
          const int pnp_inliers = static_cast<int>(result.num_inliers);
          const int predicted_inliers = static_cast<int>(result.num_predicted_inliers);
          const bool prediction_supported = predicted_inliers >= registration.pnp.min_num_inliers;
          if (prediction_supported && static_cast<double>(predicted_inliers) >=
                                          registration.min_predicted_inlier_ratio * pnp_inliers) {
            register_frame(i, *predicted, FramePoseSource::kVioVerified);
            return true;
          }
          // How far the images' pose is from the VIO's, against the drift
          // the model allows between the frame and its reference.
          double position_difference = 0.0, rotation_difference = 0.0;
          const bool beyond_drift =
              beyond_vio_drift(i, *reference, result.cam_from_world, *predicted,
                               &position_difference, &rotation_difference);
          if (pnp_inliers >= registration.min_reposing_inliers && !beyond_drift) {
            // The images refine a drifted prediction.
            register_frame(i, result.cam_from_world, FramePoseSource::kImagesReposed);
            return true;
          }
          // The images do not support the VIO's pose at all and strongly
          // support one far beyond its drift: the VIO jumped, unless the
          // frame's verified matches with the registered frames clearly show
          // the VIO's pose rather than the PnP's (kJumpRefutingMatchRatio;
          // then the 2D-3D matches are a look-alike place's, merged into its
          // tracks by a wrong pair).
          const auto jump_refuted = [&]() {
            const image_t image_id = images[i].image_id;
            const int by_images =
                CountExplainedPairMatches(reconstruction, image_id, result.cam_from_world, pairs,
                                          registration.support_max_error_px);
            const int by_vio = CountExplainedPairMatches(reconstruction, image_id, *predicted,
                                                         pairs, registration.support_max_error_px);
            if (by_vio <= kJumpRefutingMatchRatio * by_images) return false;
            ++summary.num_vio_jumps_refused;
            VIOSFM_LOG(INFO) << "batched mapper: " << DescribeImage(images[i])
                             << ": the VIO's pose is " << position_difference << " m and "
                             << rotation_difference << " rad off the images' (" << predicted_inliers
                             << " of " << pnp_inliers << " 2D-3D inliers), but its matches with "
                             << "the registered frames show the VIO's pose (" << by_vio
                             << " of them against " << by_images << "): not a VIO jump";
            return true;
          };
          if (!prediction_supported && beyond_drift &&
              pnp_inliers >= 2 * registration.min_reposing_inliers && !jump_refuted()) {
            is_break[std::max(i, *reference)] = 1;
            status.vio_break = true;
            VIOSFM_LOG(INFO) << "batched mapper: " << DescribeImage(images[i])
                             << ": the VIO's pose is " << position_difference << " m and "
                             << rotation_difference << " rad off the images' (" << predicted_inliers
                             << " of " << pnp_inliers
                             << " inliers): a VIO jump, no prior crosses it";
            register_frame(i, result.cam_from_world, FramePoseSource::kImagesReposed);
            return true;
          }
          // A weak PnP, or an ambiguous one (repeated structure: the images
          // support the VIO's pose too, and another far from it): the VIO's
          // pose stands.
          register_frame(
              i, *predicted,
              prediction_supported ? FramePoseSource::kVioVerified : FramePoseSource::kVio);
          return true;
        }
      }
    }
    if (predicted) {
      register_frame(i, *predicted, FramePoseSource::kVio);
      return true;
    }
    return false;
  };
  std::vector<size_t> pending;  // frames not registered yet, in time order
  // The points triangulated or extended since the last filtering, and
  // whether a triangulation of every track may have changed any point.
  std::vector<point3D_t> changed_since_filter;
  bool all_changed_since_filter = true;
  const auto note_changes = [&](const TriangulationStatistics& triangulation) {
    changed_since_filter.insert(changed_since_filter.end(), triangulation.changed_point_ids.begin(),
                                triangulation.changed_point_ids.end());
  };
  // Triangulates (or extends) the tracks the given frames observe.
  const auto triangulate_tracks_of = [&](const std::vector<size_t>& frame_indices) {
    std::vector<size_t> track_indices;
    for (const size_t i : frame_indices) {
      track_indices.insert(track_indices.end(), tracks_of_image[i].begin(),
                           tracks_of_image[i].end());
    }
    std::sort(track_indices.begin(), track_indices.end());
    track_indices.erase(std::unique(track_indices.begin(), track_indices.end()),
                        track_indices.end());
    std::vector<Track> subset;
    for (const size_t t : track_indices) subset.push_back(tracks[t]);
    note_changes(
        TriangulateReconstruction(&reconstruction, subset, registered, options.triangulation));
  };
  // The points a filtering after a windowed adjustment must check: those
  // the window's images observe (the adjustment moved them or their
  // cameras) and those triangulated or extended since the last filtering.
  // The others are as the last filtering left them, so checking them again
  // would change nothing.
  const auto points_to_filter = [&](size_t window_begin) {
    std::vector<point3D_t> point_ids;
    for (size_t r = window_begin; r < registered.size(); ++r) {
      for (const Point2D& point2D : reconstruction.GetImage(registered[r]).points2D) {
        if (point2D.HasPoint3D()) point_ids.push_back(point2D.point3D_id);
      }
    }
    point_ids.insert(point_ids.end(), changed_since_filter.begin(), changed_since_filter.end());
    std::sort(point_ids.begin(), point_ids.end());
    point_ids.erase(std::unique(point_ids.begin(), point_ids.end()), point_ids.end());
    return point_ids;
  };
  // Tries the pending frames again (the VIO chain, or PnP against the points
  // triangulated since), triangulating after each round, until none is added.
  const auto retry_pending = [&]() {
    size_t added = 0;
    bool changed = true;
    while (changed && !pending.empty()) {
      changed = false;
      newly_registered.clear();
      std::vector<size_t> still_pending;
      for (const size_t i : pending) {
        if (!try_register(i)) still_pending.push_back(i);
      }
      pending = std::move(still_pending);
      if (!newly_registered.empty()) {
        changed = true;
        added += newly_registered.size();
        triangulate_tracks_of(newly_registered);
      }
    }
    return added;
  };
  // A second look at the frames placed by the VIO alone that the images do
  // not support: the gauge frame (placed where the VIO puts it, to fix the
  // model's frame) and the frames registered before the model had points to
  // check them (a first batch's) or too few. Where the VIO's relative pose
  // to their neighbours was off, the triangulation took their observations
  // for outliers and the adjustment had nothing to move them by. Against the
  // adjusted model their 2D-3D matches are checked as try_register does: a
  // PnP pose of at least min_reposing_inliers inliers within the drift the
  // VIO model allows since the nearest registered frame replaces the pose
  // the images do not support; then the frame's tracks are triangulated
  // again so that its observations join the points. Returns how many frames
  // were re-posed.
  const auto recheck_vio_placed = [&]() -> size_t {
    if (!registration.verify_with_images || !registration.recheck_after_adjustment) return 0;
    std::vector<size_t> reposed;
    for (const image_t image_id : registered) {
      const size_t i = index_of_image.at(image_id);
      if (frames[i].source != FramePoseSource::kVio) continue;
      if (CountSupportingObservations(reconstruction, image_id,
                                      registration.support_max_error_px) >=
          registration.min_supporting_observations) {
        continue;
      }
      const std::optional<size_t> reference = find_reference(i);
      if (!reference) continue;
      const FrameCorrespondences correspondences =
          CollectFrameCorrespondences(reconstruction, tracks, tracks_of_image[i], image_id);
      if (static_cast<int>(correspondences.size()) < registration.min_num_correspondences) continue;
      const Rigid3d current = reconstruction.GetImage(image_id).cam_from_world;
      const Camera& camera = reconstruction.GetCamera(images[i].camera_id);
      AbsolutePoseOptions pnp = registration.pnp;
      pnp.seed = registration.pnp.seed + image_id;
      const AbsolutePoseResult result =
          EstimateAbsolutePose(correspondences.points_normalized, correspondences.points_in_world,
                               MeanFocalLength(camera), pnp, current);
      const int pnp_inliers = result.success ? static_cast<int>(result.num_inliers) : 0;
      const int current_inliers = static_cast<int>(result.num_predicted_inliers);
      if (pnp_inliers < registration.min_reposing_inliers) continue;
      if (current_inliers >= registration.pnp.min_num_inliers &&
          static_cast<double>(current_inliers) >=
              registration.min_predicted_inlier_ratio * pnp_inliers) {
        continue;  // the images support the pose it has
      }
      double position_difference = 0.0, rotation_difference = 0.0;
      if (beyond_vio_drift(i, *reference, result.cam_from_world, current, &position_difference,
                           &rotation_difference)) {
        continue;  // beyond the VIO's drift: not a refinement
      }
      Image& image = reconstruction.GetImage(image_id);
      image.cam_from_world = result.cam_from_world;
      image.cam_from_world.rotation.normalize();
      frames[i].source = FramePoseSource::kImagesReposed;
      frames[i].num_correspondences = static_cast<int>(correspondences.size());
      frames[i].num_predicted_inliers = current_inliers;
      frames[i].num_pnp_inliers = pnp_inliers;
      VIOSFM_LOG(DEBUG) << "batched mapper: " << DescribeImage(images[i])
                        << " placed by the VIO and unsupported by the images, re-posed from "
                        << pnp_inliers << " PnP inliers (" << current_inliers
                        << " at its pose), moved " << position_difference << " m and "
                        << rotation_difference << " rad";
      reposed.push_back(i);
    }
    if (!reposed.empty()) triangulate_tracks_of(reposed);
    return reposed.size();
  };
  // The priors not crossing a VIO jump found so far (without the bridging
  // ones if `with_bridging` is false).
  const auto active_priors = [&](bool with_bridging) {
    std::vector<int> breaks_before(num_images + 1, 0);
    for (size_t k = 0; k < num_images; ++k) breaks_before[k + 1] = breaks_before[k] + is_break[k];
    std::vector<RelativePosePrior> active;
    for (size_t p = 0; p < all_priors.priors.size(); ++p) {
      const auto [i, j] = all_priors.frame_indices[p];
      if (!with_bridging && all_priors.bridging[p]) continue;
      if (breaks_before[j + 1] - breaks_before[i + 1] == 0) active.push_back(all_priors.priors[p]);
    }
    return active;
  };
  BundleAdjustmentOptions ba_options = options.ba;
  ba_options.num_threads = options.num_threads;
  LinearSolverChooser solver_chooser(ba_options);
  // The rolling shutter's translation share, compensated before every
  // adjustment for the observations of points not compensated yet
  // (CompensateRollingShutterMotion).
  std::unordered_map<image_t, std::vector<char>> rolling_shutter_moved;
  std::vector<float> rolling_shutter_moves;
  // Bundle adjustment of the last registered images (all when window_begin
  // is 0), the gauge held.
  int num_batch_adjustments = 0;
  // Set once a global adjustment has left the IMU's factors out (the rig's
  // rotations too far from the gyro, or the factors' scale beyond
  // max_scale_change): the later global adjustments (refinements, frames
  // re-posed after the final one) take the gyro's priors straight away.
  bool inertial_declined = false;
  // The inflation of the gyro's priors and of the IMU factors' covariance
  // that the first global adjustment measured (gyro_priors.h,
  // inertial_terms.h): a later one starts from a model those terms pulled
  // toward the gyro, whose disagreement with it no longer measures the
  // rig's, so it keeps at least that inflation.
  double gyro_sigma_floor = 1.0;
  double inertial_sigma_floor = 1.0;
  const auto adjust = [&](size_t window_begin, bool global) {
    BundleAdjustmentSummary ba_summary;
    if (gauge_image == kInvalidImageId || !is_registered[gauge_index]) return ba_summary;
    std::unique_ptr<InertialTerms> inertial_terms;
    const std::vector<image_t> free_images(registered.begin() + window_begin, registered.end());
    const image_t held_neighbour =
        window_begin > 0 ? registered[window_begin - 1] : kInvalidImageId;
    BundleAdjustmentOptions batch_ba_options = ba_options;
    // The first per-batch adjustment (no earlier one refined any pose) may
    // run uncapped.
    const bool first_adjustment = num_batch_adjustments++ == 0;
    if (!global && options.batch_ba_max_num_iterations > 0 &&
        !(first_adjustment && options.converge_first_batch_ba)) {
      batch_ba_options.max_num_iterations = options.batch_ba_max_num_iterations;
    }
    if (global && ba_options.linear_solver == BaLinearSolver::kAuto) {
      const BaProblemStructure structure =
          ComputeBaProblemStructure(reconstruction, free_images, /*with_factorization=*/true);
      batch_ba_options.linear_solver = solver_chooser.Next(structure, /*final=*/true);
      VIOSFM_LOG(INFO) << "final bundle adjustment: " << structure.num_free_images
                       << " images, factorisation work per image "
                       << structure.FactorizationPerImage() << " (per observation "
                       << structure.FactorizationPerObservation()
                       << "): " << OptionText(batch_ba_options.linear_solver);
    } else {
      batch_ba_options.linear_solver = solver_chooser.Next(free_images.size(), global);
    }
    if (input.rolling_shutter_readout_s > 0.0) {
      std::vector<std::pair<timestamp_ns_t, image_t>> stamped;
      for (const image_t image_id : registered) {
        stamped.emplace_back(images[index_of_image.at(image_id)].timestamp_ns, image_id);
      }
      CompensateRollingShutterMotion(
          &reconstruction, std::move(stamped), input.rolling_shutter_readout_s,
          kRollingShutterVelocityMaxGapNs, &rolling_shutter_moved, &rolling_shutter_moves);
      if (global) {
        std::vector<float> lengths = rolling_shutter_moves;
        double median_px = 0.0, max_px = 0.0;
        if (!lengths.empty()) {
          std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
          median_px = lengths[lengths.size() / 2];
          max_px = *std::max_element(lengths.begin(), lengths.end());
        }
        std::ostringstream message;
        message << std::fixed << std::setprecision(3) << "rolling shutter: " << lengths.size()
                << " observations moved by the camera's motion over their row's time before "
                   "the adjustments (median "
                << median_px << " px, largest " << max_px << " px)";
        summary.rolling_shutter_message = message.str();
        VIOSFM_LOG(INFO) << "final bundle adjustment: " << summary.rolling_shutter_message;
      }
    }
    std::vector<RelativePosePrior> priors = active_priors(/*with_bridging=*/true);
    std::optional<GyroPriors> gyro_priors;
    if (global && options.gyro.enabled && !input.imu.empty()) {
      // The gyro's relative rotations between consecutive registered frames,
      // with the biases the current rotations give (gyro_priors.h).
      std::vector<GyroFrame> frames;
      for (const image_t image_id : registered) {
        frames.push_back({image_id, images[index_of_image.at(image_id)].timestamp_ns,
                          reconstruction.GetImage(image_id).cam_from_world,
                          CountSupportingObservations(reconstruction, image_id,
                                                      registration.support_max_error_px) >=
                              registration.min_supporting_observations});
      }
      std::sort(frames.begin(), frames.end(), [](const GyroFrame& a, const GyroFrame& b) {
        return a.timestamp_ns < b.timestamp_ns;
      });
      gyro_priors = MakeGyroPriors(frames, input.imu, input.rig, options.gyro, gyro_sigma_floor);
      gyro_sigma_floor = gyro_priors->sigma_factor;
      const GyroPriors& gyro = *gyro_priors;
      if (options.inertial.enabled && ba_options.use_relative_pose_priors && !inertial_declined) {
        // The IMU's factors, started from the gyro priors' bias fit (the
        // median of its windows'), in their place.
        Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
        if (!gyro.gyro_biases.empty()) {
          for (int d = 0; d < 3; ++d) {
            std::vector<double> values;
            for (const Eigen::Vector3d& bias : gyro.gyro_biases) values.push_back(bias[d]);
            std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
            gyro_bias[d] = values[values.size() / 2];
          }
        }
        std::vector<InertialFrame> inertial_frames;
        for (const GyroFrame& frame : frames) {
          inertial_frames.push_back({frame.image_id, frame.timestamp_ns, frame.cam_from_world});
        }
        inertial_terms = std::make_unique<InertialTerms>(inertial_frames, input.imu, input.rig,
                                                         gyro_bias, options.inertial);
        if (inertial_terms->Initialise(options.num_threads, inertial_sigma_floor)) {
          inertial_sigma_floor = inertial_terms->sigma_factor();
          summary.num_inertial_factors = inertial_terms->num_factors();
          // The IMU holds the stretches the images barely see, where the
          // bridging priors carried the VIO's drift over seconds: they no
          // longer earn their place in the final adjustment (two_floors_kf
          // 24.5 -> 14.7 mm, two_floors_10hz 15.7 -> 10.0 mm without them
          // there; the per-batch adjustments keep them).
          priors = active_priors(/*with_bridging=*/false);
          VIOSFM_LOG(INFO) << "final bundle adjustment: before it, " << inertial_terms->Message();
        } else {
          summary.inertial_message = inertial_terms->Message();
          VIOSFM_LOG(INFO) << "final bundle adjustment: " << summary.inertial_message
                           << "; the gyro's priors instead";
          inertial_terms.reset();
          inertial_declined = true;
        }
      }
    }
    // The gyro's priors with the bridging priors, where the IMU's factors
    // are not used.
    const auto use_gyro_priors = [&]() {
      const GyroPriors& gyro = *gyro_priors;
      summary.num_gyro_priors = static_cast<int>(gyro.priors.size());
      summary.gyro_message = gyro.message;
      VIOSFM_LOG(INFO) << "final bundle adjustment: " << gyro.message;
      priors = active_priors(/*with_bridging=*/true);
      priors.insert(priors.end(), gyro.priors.begin(), gyro.priors.end());
    };
    if (gyro_priors && inertial_terms == nullptr) use_gyro_priors();
    // What the factors' adjustment may have to undo (max_scale_change).
    std::vector<std::pair<image_t, Rigid3d>> poses_before;
    std::vector<std::pair<point3D_t, Eigen::Vector3d>> points_before;
    std::unordered_map<camera_t, Camera> cameras_before;
    if (inertial_terms != nullptr) {
      for (const auto& [image_id, image] : reconstruction.Images()) {
        if (image.registered) poses_before.emplace_back(image_id, image.cam_from_world);
      }
      for (const auto& [point_id, point] : reconstruction.Points3D()) {
        points_before.emplace_back(point_id, point.xyz);
      }
      cameras_before = reconstruction.Cameras();
    }
    // The final adjustment with the VIO's drift states in place of its
    // consecutive priors (vio_drift_terms.h).
    std::unique_ptr<VioDriftTerms> drift_terms;
    const auto take_drift_states = [&]() {
      drift_terms.reset();
      if (!global || !options.vio_drift_states || !ba_options.use_relative_pose_priors ||
          ba_options.prior_weighting != PriorWeighting::kCovariance) {
        return;
      }
      std::vector<VioDriftFrame> frames;
      std::vector<VioDriftLink> links;
      std::unordered_map<image_t, size_t> frame_of_image;
      const auto frame_index = [&](image_t image_id) {
        const auto [it, inserted] = frame_of_image.emplace(image_id, frames.size());
        if (inserted) {
          frames.push_back({image_id, VioSampleOfImage(images[index_of_image.at(image_id)])});
        }
        return it->second;
      };
      std::vector<RelativePosePrior> kept;
      for (const RelativePosePrior& prior : priors) {
        if (prior.from_gyro ||
            consecutive_pairs.count(ImagePairToPairId(prior.image_id1, prior.image_id2)) == 0) {
          kept.push_back(prior);
          continue;
        }
        const size_t first = frame_index(prior.image_id1);
        const size_t second = frame_index(prior.image_id2);
        links.push_back({first, second, prior.num_verified_matches});
      }
      if (links.empty()) return;
      priors = std::move(kept);
      VioDriftTermsOptions drift_options;
      drift_options.vio_uncertainty = options.vio_uncertainty;
      drift_options.prior_beta = ba_options.prior_beta;
      drift_options.prior_loss_scale = ba_options.prior_loss_scale;
      drift_options.image_noise_px = ba_options.image_noise_px;
      drift_terms =
          std::make_unique<VioDriftTerms>(std::move(frames), std::move(links), drift_options);
    };
    take_drift_states();
    CombinedTerms combined({inertial_terms.get(), drift_terms.get()});
    ba_summary = AdjustImages(&reconstruction, free_images, held_neighbour, gauge_image, priors,
                              batch_ba_options, global ? 0 : options.ba_window_max_held_views,
                              inertial_terms || drift_terms ? &combined : nullptr);
    if (drift_terms != nullptr) {
      VIOSFM_LOG(INFO) << "final bundle adjustment: the VIO as drift states ("
                       << drift_terms->num_frame_terms() << " frames, "
                       << drift_terms->num_drift_terms()
                       << " links) in place of its consecutive priors";
    }
    if (inertial_terms != nullptr && std::abs(std::log(inertial_terms->scale())) >
                                         std::log1p(options.inertial.max_scale_change)) {
      // The factors took the model somewhere no VIO's scale error explains:
      // the rig is further from the IMU model than their start showed. The
      // adjustment again, from where it started, with the gyro's priors.
      std::ostringstream message;
      message << std::fixed << std::setprecision(5)
              << "the IMU factors put the model's metric scale at " << inertial_terms->scale()
              << ", further from 1 than max_scale_change " << options.inertial.max_scale_change
              << ": dropped, the adjustment again with the gyro's priors";
      VIOSFM_LOG(WARNING) << "final bundle adjustment: " << message.str();
      for (const auto& [image_id, pose] : poses_before) {
        reconstruction.GetImage(image_id).cam_from_world = pose;
      }
      for (const auto& [point_id, xyz] : points_before) {
        if (reconstruction.ExistsPoint3D(point_id)) reconstruction.GetPoint3D(point_id).xyz = xyz;
      }
      for (const auto& [camera_id, camera] : cameras_before) {
        reconstruction.GetCamera(camera_id) = camera;
      }
      inertial_terms.reset();
      inertial_declined = true;
      summary.num_inertial_factors = 0;
      summary.inertial_message = message.str();
      use_gyro_priors();
      take_drift_states();
      ba_summary = AdjustImages(&reconstruction, free_images, held_neighbour, gauge_image, priors,
                                batch_ba_options, global ? 0 : options.ba_window_max_held_views,
                                drift_terms.get());
    }
    if (inertial_terms != nullptr) {
      summary.inertial_scale = inertial_terms->scale();
      std::ostringstream message;
      message << inertial_terms->Message()
              << " (in place of the gyro's priors and the bridging priors); after it: scale "
              << std::fixed << std::setprecision(5) << inertial_terms->scale() << ", median "
              << std::setprecision(2) << inertial_terms->MedianWhitenedResidual(reconstruction)
              << " sigma";
      summary.inertial_message = message.str();
      VIOSFM_LOG(INFO) << "final bundle adjustment: " << summary.inertial_message;
    }
    solver_chooser.Record(ba_summary, free_images.size());
    if (!ba_summary.usable && ba_summary.termination != "nothing to adjust") {
      VIOSFM_LOG(WARNING) << "bundle adjustment: " << ba_summary.ToString();
    }
    return ba_summary;
  };

  // Filters every point and re-triangulates every track; returns the share
  // of the model's observations that changed: those it left without a point
  // plus those it attached that had none. An observation the filtering took
  // out and the re-triangulation put back (one near the filter's threshold,
  // its point deleted and triangulated again) is not a change: the
  // adjustment had it.
  const auto filter_and_retriangulate_all = [&]() {
    const ObservedKeypoints before(reconstruction, registered);
    FilterPoints(&reconstruction, options.filter, options.num_threads);
    changed_since_filter.clear();
    all_changed_since_filter = false;
    if (options.retriangulate) {
      TriangulateReconstruction(&reconstruction, tracks, registered, options.triangulation);
      all_changed_since_filter = true;
    }
    return static_cast<double>(before.CountChanged(reconstruction)) /
           static_cast<double>(std::max<size_t>(1, reconstruction.ComputeNumObservations()));
  };

  const size_t batch_size = static_cast<size_t>(options.batch_size);
  // Streamed frames: as many batches as the stream brings.
  const size_t num_batches = frames_streamed ? 0 : (num_images + batch_size - 1) / batch_size;
  ProgressBar progress("batched mapping", static_cast<int64_t>(num_batches),
                       options.show_progress && !frames_streamed ? ProgressBar::Mode::kAuto
                                                                 : ProgressBar::Mode::kNever);
  for (size_t b = 0; frames_streamed || b < num_batches; ++b) {
    const Timer batch_timer;
    bool last = b + 1 == num_batches;
    const size_t begin = b * batch_size;
    size_t end = std::min(num_images, begin + batch_size);
    if (stream != nullptr) {
      // The batch's frames (streamed) and the pairs among them and the frames
      // before them: complete once the verification has passed the batch.
      VerifiedPairStream::Taken taken = stream->Take(begin + batch_size);
      if (frames_streamed) {
        const size_t first_new = streamed_images.size();
        std::move(taken.frames.begin(), taken.frames.end(), std::back_inserter(streamed_images));
        streamed_validator->Check(streamed_images, first_new);
        add_images();
        end = num_images;
        last = taken.last;
      }
      ValidateVerifiedPairs(images, taken.pairs, streamed_pairs.size());
      build_tracks(taken.pairs);
      // No pair comes after the last batch's: the builder's graph (every
      // match) goes before the final adjustment needs the memory.
      if (last) track_builder.reset();
      std::move(taken.pairs.begin(), taken.pairs.end(), std::back_inserter(streamed_pairs));
      build_priors();
      // Points as the tracks are now: split where the new pairs split a
      // track (a conflict they revealed), joined where they joined two.
      summary.num_observations_split_off +=
          static_cast<int>(SplitPointsByTracks(&reconstruction, tracks));
      const std::vector<point3D_t> merged =
          MergeTrackPoints(&reconstruction, tracks, options.triangulation);
      summary.num_points_merged += static_cast<int>(merged.size());
      changed_since_filter.insert(changed_since_filter.end(), merged.begin(), merged.end());
      if (last) {
        if (frames_streamed) {
          if (num_images == 0) throw InputError(kInputLabel, 0, "no images to reconstruct");
          streamed_validator->CheckAnyVioPose();
        }
        VIOSFM_LOG(INFO) << "batched mapper: " << num_images << " images, " << pairs.size()
                         << " verified pairs (streamed); " << summary.tracks.Summary();
      }
    }
    MapperBatchStatistics stats;
    stats.batch_index = static_cast<int>(b);
    stats.num_images = static_cast<int>(end - begin);

    // 2. Registration: each frame by its VIO pose relative to the latest
    // registered frame of its VIO segment, checked against the images.
    newly_registered.clear();
    timer.Start();
    for (size_t i = begin; i < end; ++i) {
      if (!try_register(i)) pending.push_back(i);
    }
    stats.seconds_registration = timer.ElapsedSeconds();

    // 3. Triangulation of the tracks seen by the batch, then the frames
    // that the new points (or a newly registered frame of their VIO segment)
    // allow.
    timer.Start();
    const TriangulationStatistics triangulation = TriangulateReconstruction(
        &reconstruction, TracksOfImages(tracks, tracks_of_image, begin, end), registered,
        options.triangulation);
    note_changes(triangulation);
    retry_pending();
    stats.seconds_triangulation = timer.ElapsedSeconds();

    // 4. Bundle adjustment: the last batch's is the final global one.
    const bool global = last && options.final_global_ba;
    size_t window_begin = 0;
    if (!global && options.ba_window_batches > 0 &&
        registered.size() > static_cast<size_t>(options.ba_window_batches) * batch_size) {
      window_begin =
          registered.size() - static_cast<size_t>(options.ba_window_batches) * batch_size;
    }
    if (options.ba_after_each_batch || global) {
      const BundleAdjustmentSummary ba_summary = adjust(window_begin, global);
      stats.seconds_ba = ba_summary.time_s;
      stats.num_ba_iterations = ba_summary.num_iterations;
      stats.ba_linear_solver = ba_summary.linear_solver;
      stats.num_ba_free_images = static_cast<int>(registered.size() - window_begin);
      stats.num_ba_observations = ba_summary.num_observations;
      if (global) summary.final_ba = ba_summary;
    }

    // 5. Filtering and re-triangulation of the tracks left without a point.
    timer.Start();
    // After the final adjustment: the share of the observations they change.
    double final_change = 0.0;
    if (window_begin == 0) {
      final_change = filter_and_retriangulate_all();
    } else {
      if (all_changed_since_filter) {
        FilterPoints(&reconstruction, options.filter, options.num_threads);
      } else {
        FilterPoints(&reconstruction, options.filter, points_to_filter(window_begin),
                     options.num_threads);
      }
      changed_since_filter.clear();
      all_changed_since_filter = false;
      if (options.retriangulate) {
        std::vector<size_t> window_frames;
        for (size_t r = window_begin; r < registered.size(); ++r) {
          window_frames.push_back(index_of_image.at(registered[r]));
        }
        triangulate_tracks_of(window_frames);
      }
    }
    // 6. The frames placed by the VIO alone that the adjusted model now
    // re-poses (recheck_vio_placed); after the final bundle adjustment also
    // the frames that only the final model allows to register, and then
    // another global adjustment.
    const size_t reposed_after_adjustment = recheck_vio_placed();
    summary.num_reposed_after_adjustment += static_cast<int>(reposed_after_adjustment);
    const size_t registered_late = last ? retry_pending() : 0;
    // Another global adjustment for the frames re-posed or registered after
    // the final one, and while its filtering and re-triangulation change the
    // model (final_ba_refine_min_change).
    bool frames_changed = last && reposed_after_adjustment + registered_late > 0 &&
                          (options.ba_after_each_batch || options.final_global_ba);
    while (frames_changed ||
           (global && final_change > options.final_ba_refine_min_change &&
            summary.num_final_ba_refinements < options.final_ba_max_refinements)) {
      if (!frames_changed) {
        ++summary.num_final_ba_refinements;
        VIOSFM_LOG(INFO) << std::fixed << std::setprecision(2)
                         << "final bundle adjustment: filtering and re-triangulation changed "
                         << 100.0 * final_change << " % of the observations: refinement "
                         << summary.num_final_ba_refinements << " of at most "
                         << options.final_ba_max_refinements;
      }
      frames_changed = false;
      summary.final_ba = adjust(0, true);
      final_change = filter_and_retriangulate_all();
    }
    if (global) summary.final_ba_last_change = final_change;
    stats.seconds_filtering = timer.ElapsedSeconds();

    stats.num_registered_total = static_cast<int>(registered.size());
    stats.num_points_total = static_cast<int>(reconstruction.NumPoints3D());
    stats.mean_reprojection_error_px = MeanReprojectionError(reconstruction, options.num_threads);
    stats.seconds_total = batch_timer.ElapsedSeconds();
    VIOSFM_LOG(INFO) << std::fixed << std::setprecision(3) << "batch " << b + 1
                     << (frames_streamed ? std::string() : "/" + std::to_string(num_batches))
                     << ": images " << stats.num_registered_total << " (+" << stats.num_images
                     << "), points " << stats.num_points_total << " (+"
                     << triangulation.num_points_added << " new), reprojection error "
                     << stats.mean_reprojection_error_px << " px, BA over "
                     << stats.num_ba_free_images << " images " << stats.seconds_ba << " s ("
                     << stats.num_ba_iterations << " iterations, "
                     << BaLinearSolverName(stats.ba_linear_solver) << "), " << stats.seconds_total
                     << " s";
    if (on_batch && !last) on_batch(reconstruction, stats);
    summary.batches.push_back(stats);
    progress.Update();
    if (last) break;
  }
  progress.Finish();

  // 7. Every frame's verdict.
  std::set<int> joined_segments;
  for (size_t i = 0; i < num_images; ++i) {
    MapperFrameStatus& status = frames[i];
    const MapperImage& input_image = images[i];
    if (is_registered[i]) {
      status.num_supporting_observations = CountSupportingObservations(
          reconstruction, input_image.image_id, registration.support_max_error_px);
      status.supported =
          status.num_supporting_observations >= registration.min_supporting_observations;
      if (!status.supported && !vio_poses[i]) {
        // Registered from the images, but the final model no longer
        // supports it, and no VIO pose places it: no pose.
        Image& image = reconstruction.GetImage(input_image.image_id);
        for (point2D_t k = 0; k < image.points2D.size(); ++k) {
          if (image.points2D[k].HasPoint3D()) reconstruction.DeleteObservation(image.image_id, k);
        }
        image.registered = false;
        is_registered[i] = 0;
        status.source = FramePoseSource::kNone;
        status.reason = "registered from the images, but too few of its observations (" +
                        std::to_string(status.num_supporting_observations) +
                        ") agree with the final model";
      }
    }
    if (is_registered[i]) {
      if (vio_poses[i]) joined_segments.insert(input_image.vio_odometer.segment);
      ++(status.supported ? summary.num_supported : summary.num_vio_only);
      if (status.source == FramePoseSource::kImagesReposed) ++summary.num_reposed;
      if (status.source == FramePoseSource::kImagesWithoutVio) ++summary.num_registered_without_vio;
      if (status.vio_break) ++summary.num_vio_breaks;
      continue;
    }
    ++summary.num_unposed;
    if (!status.reason.empty()) continue;
    if (!vio_poses[i]) {
      status.reason = registration.verify_with_images
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
  summary.num_vio_segments_joined = static_cast<int>(joined_segments.size());
  if (summary.num_unposed > 0) {
    VIOSFM_LOG(WARNING) << "batched mapper: " << summary.num_unposed << " of " << num_images
                        << " frames have no pose";
  }

  summary.num_registered = static_cast<int>(reconstruction.NumRegImages());
  summary.num_points = static_cast<int>(reconstruction.NumPoints3D());
  summary.num_observations = static_cast<int>(reconstruction.ComputeNumObservations());
  summary.mean_track_length = reconstruction.ComputeMeanTrackLength();
  summary.mean_reprojection_error_px = MeanReprojectionError(reconstruction, options.num_threads);
  summary.seconds_total = total_timer.ElapsedSeconds();
  VIOSFM_LOG(INFO) << summary.ToString();
  if (summary_out != nullptr) *summary_out = std::move(summary);
  return reconstruction;
}

}  // namespace viosfm
