#include "viosfm/sfm/batched_mapper.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "viosfm/scene/reprojection.h"
#include "viosfm/sfm/linear_solver_chooser.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

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

// Bundle adjustment of the poses of `free_images` and of the points they
// observe. Every other image observing those points is held constant, and so
// is `held_neighbour` (the image before the window, for its relative-pose
// term, if valid) and `gauge_image` (if it is free). When `free_images` are
// all the registered images this is BundleAdjust with the gauge image held;
// otherwise the sub-problem is solved on a copy and the result copied back.
BundleAdjustmentSummary AdjustImages(Reconstruction* reconstruction,
                                     const std::vector<image_t>& free_images,
                                     image_t held_neighbour, image_t gauge_image,
                                     const std::vector<RelativePosePrior>& priors,
                                     const BundleAdjustmentOptions& options) {
  if (free_images.size() == reconstruction->NumRegImages()) {
    return BundleAdjust(reconstruction, priors, {gauge_image}, options);
  }
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
  for (const image_t image_id : free_images) {
    for (const Point2D& point2D : reconstruction->GetImage(image_id).points2D) {
      if (!point2D.HasPoint3D() || !point_seen.insert(point2D.point3D_id).second) continue;
      point_ids.push_back(point2D.point3D_id);
      for (const TrackElement& element : reconstruction->GetPoint3D(point2D.point3D_id).track) {
        hold(element.image_id);
      }
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
  for (const point3D_t point3D_id : point_ids) {
    sub.AddPoint3DWithId(point3D_id, reconstruction->GetPoint3D(point3D_id));
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
  if (batch_ba_max_num_iterations < 0) return "batch_ba_max_num_iterations must be >= 0";
  for (const int span : bridge_spans) {
    if (span < 2) return "bridge_spans must be >= 2 frames each";
  }
  if (bridge_max_matches < 0) return "bridge_max_matches must be >= 0";
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
      << "  relative-pose priors: " << num_consecutive_priors << " consecutive, "
      << num_bridging_priors << " bridging\n"
      << "  " << tracks.Summary();
  if (!final_ba.termination.empty()) out << "\n  final " << final_ba.ToString();
  return out.str();
}

void ValidateBatchedMapperInput(const BatchedMapperInput& input) {
  if (input.images.empty()) throw InputError(kInputLabel, 0, "no images to reconstruct");
  std::unordered_set<camera_t> camera_ids;
  for (const Camera& camera : input.cameras) {
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
  std::unordered_map<image_t, size_t> keypoints_of_image;
  std::unordered_set<std::string> names;
  for (size_t i = 0; i < input.images.size(); ++i) {
    const MapperImage& image = input.images[i];
    if (image.image_id == kInvalidImageId) {
      throw InputError(kInputLabel, 0, "image " + std::to_string(i) + " has the invalid image id");
    }
    if (!keypoints_of_image.emplace(image.image_id, image.keypoints.size()).second) {
      throw InputError(kInputLabel, 0, "duplicate image id " + std::to_string(image.image_id));
    }
    if (image.name.empty()) {
      throw InputError(kInputLabel, 0, DescribeImage(image) + " has an empty name");
    }
    if (!names.insert(image.name).second) {
      throw InputError(kInputLabel, 0, "duplicate image name '" + image.name + "'");
    }
    if (camera_ids.count(image.camera_id) == 0) {
      throw InputError(
          kInputLabel, 0,
          DescribeImage(image) + " refers to unknown camera id " + std::to_string(image.camera_id));
    }
    if (i > 0 && image.timestamp_ns <= input.images[i - 1].timestamp_ns) {
      throw InputError(kInputLabel, 0,
                       "images not in strictly increasing time order: " + DescribeImage(image) +
                           " at " + FormatNsAsSeconds(image.timestamp_ns) + " s follows " +
                           DescribeImage(input.images[i - 1]) + " at " +
                           FormatNsAsSeconds(input.images[i - 1].timestamp_ns) + " s");
    }
    if (!IsFinitePose(image.vio_cam_from_world)) {
      throw InputError(kInputLabel, 0,
                       DescribeImage(image) + " has a non-finite or zero-rotation VIO pose");
    }
  }
  for (size_t p = 0; p < input.verified_pairs.size(); ++p) {
    const ImagePairMatches& pair = input.verified_pairs[p];
    const auto it1 = keypoints_of_image.find(pair.image_id1);
    const auto it2 = keypoints_of_image.find(pair.image_id2);
    const std::string pair_label = "verified pair " + std::to_string(p) + " (images " +
                                   std::to_string(pair.image_id1) + ", " +
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

std::vector<RelativePosePrior> MakeConsecutiveRelativePosePriors(const BatchedMapperInput& input) {
  std::unordered_map<image_pair_t, int> num_matches;
  for (const ImagePairMatches& pair : input.verified_pairs) {
    if (pair.image_id1 == pair.image_id2) continue;
    int& count = num_matches[ImagePairToPairId(pair.image_id1, pair.image_id2)];
    count = std::max(count, static_cast<int>(pair.matches.size()));
  }
  std::vector<RelativePosePrior> priors;
  for (size_t i = 1; i < input.images.size(); ++i) {
    const MapperImage& image1 = input.images[i - 1];
    const MapperImage& image2 = input.images[i];
    RelativePosePrior prior;
    prior.image_id1 = image1.image_id;
    prior.image_id2 = image2.image_id;
    prior.cam2_from_cam1 = image2.vio_cam_from_world * image1.vio_cam_from_world.Inverse();
    prior.cam2_from_cam1.rotation.normalize();
    const auto it = num_matches.find(ImagePairToPairId(image1.image_id, image2.image_id));
    prior.num_verified_matches = it == num_matches.end() ? 0 : it->second;
    priors.push_back(prior);
  }
  return priors;
}

std::vector<RelativePosePrior> MakeBridgingRelativePosePriors(
    const BatchedMapperInput& input, const std::vector<RelativePosePrior>& consecutive,
    const std::vector<int>& spans, int max_matches) {
  VIOSFM_CHECK(consecutive.size() + 1 == input.images.size() || input.images.empty())
      << consecutive.size() << " consecutive priors for " << input.images.size() << " images";
  std::vector<RelativePosePrior> priors;
  const size_t num_images = input.images.size();
  for (const int span_int : spans) {
    const size_t span = static_cast<size_t>(span_int);
    if (span < 2 || span >= num_images) continue;
    for (size_t i = 0; i + span < num_images; ++i) {
      int fewest = std::numeric_limits<int>::max();
      for (size_t j = i; j < i + span; ++j) {
        fewest = std::min(fewest, consecutive[j].num_verified_matches);
      }
      if (fewest >= max_matches) continue;
      const MapperImage& image1 = input.images[i];
      const MapperImage& image2 = input.images[i + span];
      RelativePosePrior prior;
      prior.image_id1 = image1.image_id;
      prior.image_id2 = image2.image_id;
      prior.cam2_from_cam1 = image2.vio_cam_from_world * image1.vio_cam_from_world.Inverse();
      prior.cam2_from_cam1.rotation.normalize();
      prior.num_verified_matches = fewest;
      prior.rotation_only = true;
      priors.push_back(prior);
    }
  }
  return priors;
}

Reconstruction RunBatchedMapper(const BatchedMapperInput& input,
                                const BatchedMapperOptions& options,
                                BatchedMapperSummary* summary_out) {
  const Timer total_timer;
  if (!options.Check()) throw InputError("batched mapper options: " + options.Validate());
  ValidateBatchedMapperInput(input);
  BatchedMapperSummary summary;
  const size_t num_images = input.images.size();
  summary.num_images = static_cast<int>(num_images);

  // 1. Tracks, and the tracks of each image.
  Timer timer;
  const TrackBuildResult track_result = BuildTracks(input.verified_pairs, options.tracks);
  const std::vector<Track>& tracks = track_result.tracks;
  summary.tracks = track_result.statistics;
  summary.seconds_tracks = timer.ElapsedSeconds();
  VIOSFM_LOG(INFO) << "batched mapper: " << num_images << " images, " << input.verified_pairs.size()
                   << " verified pairs; " << summary.tracks.Summary();
  std::unordered_map<image_t, size_t> index_of_image;
  for (size_t i = 0; i < num_images; ++i) index_of_image[input.images[i].image_id] = i;
  std::vector<std::vector<size_t>> tracks_of_image(num_images);
  for (size_t t = 0; t < tracks.size(); ++t) {
    for (const TrackElement& element : tracks[t].elements) {
      tracks_of_image[index_of_image.at(element.image_id)].push_back(t);
    }
  }

  // The model: all images, unregistered, with their keypoints.
  Reconstruction reconstruction;
  for (const Camera& camera : input.cameras) reconstruction.AddCamera(camera);
  std::vector<Rigid3d> vio_poses(num_images);
  for (size_t i = 0; i < num_images; ++i) {
    const MapperImage& input_image = input.images[i];
    vio_poses[i] = input_image.vio_cam_from_world;
    vio_poses[i].rotation.normalize();
    Image image;
    image.image_id = input_image.image_id;
    image.camera_id = input_image.camera_id;
    image.name = input_image.name;
    image.timestamp_ns = input_image.timestamp_ns;
    image.cam_from_world = vio_poses[i];
    image.points2D.resize(input_image.keypoints.size());
    for (size_t j = 0; j < input_image.keypoints.size(); ++j) {
      image.points2D[j].xy =
          Eigen::Vector2d(input_image.keypoints[j].x, input_image.keypoints[j].y);
    }
    reconstruction.AddImage(std::move(image));
  }
  std::vector<RelativePosePrior> priors = MakeConsecutiveRelativePosePriors(input);
  // Without the relative-pose term (w/o RPC) the BA ignores every prior: count none.
  summary.num_consecutive_priors =
      options.ba.use_relative_pose_priors ? static_cast<int>(priors.size()) : 0;
  if (options.ba.use_relative_pose_priors) {
    const std::vector<RelativePosePrior> bridging = MakeBridgingRelativePosePriors(
        input, priors, options.bridge_spans, options.bridge_max_matches);
    summary.num_bridging_priors = static_cast<int>(bridging.size());
    priors.insert(priors.end(), bridging.begin(), bridging.end());
  }
  BundleAdjustmentOptions ba_options = options.ba;
  ba_options.num_threads = options.num_threads;
  const image_t gauge_image = input.images.front().image_id;
  LinearSolverChooser solver_chooser(ba_options);

  const size_t batch_size = static_cast<size_t>(options.batch_size);
  const size_t num_batches = (num_images + batch_size - 1) / batch_size;
  std::vector<image_t> registered;
  ProgressBar progress(
      "batched mapping", static_cast<int64_t>(num_batches),
      options.show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
  for (size_t b = 0; b < num_batches; ++b) {
    const Timer batch_timer;
    const bool last = b + 1 == num_batches;
    const size_t begin = b * batch_size;
    const size_t end = std::min(num_images, begin + batch_size);
    MapperBatchStatistics stats;
    stats.batch_index = static_cast<int>(b);
    stats.num_images = static_cast<int>(end - begin);

    // 2. Registration: batch 0 at its VIO poses, later batches attached to the
    // refined last image of the previous batch by the VIO relative poses.
    Rigid3d cam_first_from_world = vio_poses[begin];
    if (b > 0) {
      const Rigid3d& previous =
          reconstruction.GetImage(input.images[begin - 1].image_id).cam_from_world;
      cam_first_from_world = vio_poses[begin] * vio_poses[begin - 1].Inverse() * previous;
    }
    const Rigid3d world_from_vio_first = vio_poses[begin].Inverse();
    for (size_t i = begin; i < end; ++i) {
      Image& image = reconstruction.GetImage(input.images[i].image_id);
      image.cam_from_world = vio_poses[i] * world_from_vio_first * cam_first_from_world;
      image.cam_from_world.rotation.normalize();
      image.registered = true;
      registered.push_back(image.image_id);
    }

    // 3. Triangulation of the tracks seen by the batch.
    timer.Start();
    const TriangulationStatistics triangulation = TriangulateReconstruction(
        &reconstruction, TracksOfImages(tracks, tracks_of_image, begin, end), registered,
        options.triangulation);
    stats.seconds_triangulation = timer.ElapsedSeconds();

    // 4. Bundle adjustment: the last batch's is the final global one.
    const bool global = last && options.final_global_ba;
    const bool adjust = options.ba_after_each_batch || global;
    size_t window_begin = 0;
    if (!global && options.ba_window_batches > 0 &&
        b + 1 > static_cast<size_t>(options.ba_window_batches)) {
      window_begin = (b + 1 - options.ba_window_batches) * batch_size;
    }
    if (adjust) {
      const std::vector<image_t> free_images(registered.begin() + window_begin, registered.end());
      const image_t held_neighbour =
          window_begin > 0 ? registered[window_begin - 1] : kInvalidImageId;
      BundleAdjustmentOptions batch_ba_options = ba_options;
      if (!global && options.batch_ba_max_num_iterations > 0) {
        batch_ba_options.max_num_iterations = options.batch_ba_max_num_iterations;
      }
      batch_ba_options.linear_solver = solver_chooser.Next(free_images.size(), global);
      const BundleAdjustmentSummary ba_summary = AdjustImages(
          &reconstruction, free_images, held_neighbour, gauge_image, priors, batch_ba_options);
      solver_chooser.Record(ba_summary, free_images.size());
      stats.seconds_ba = ba_summary.time_s;
      stats.num_ba_iterations = ba_summary.num_iterations;
      stats.ba_linear_solver = ba_summary.linear_solver;
      stats.num_ba_free_images = static_cast<int>(free_images.size());
      if (global) summary.final_ba = ba_summary;
      if (!ba_summary.usable && ba_summary.termination != "nothing to adjust") {
        VIOSFM_LOG(WARNING) << "batch " << b << ": " << ba_summary.ToString();
      }
    }

    // 5. Filtering and re-triangulation of the tracks left without a point.
    timer.Start();
    FilterPoints(&reconstruction, options.filter);
    if (options.retriangulate) {
      if (window_begin == 0) {
        TriangulateReconstruction(&reconstruction, tracks, registered, options.triangulation);
      } else {
        TriangulateReconstruction(&reconstruction,
                                  TracksOfImages(tracks, tracks_of_image, window_begin, end),
                                  registered, options.triangulation);
      }
    }
    stats.seconds_filtering = timer.ElapsedSeconds();

    stats.num_registered_total = static_cast<int>(registered.size());
    stats.num_points_total = static_cast<int>(reconstruction.NumPoints3D());
    stats.mean_reprojection_error_px = MeanReprojectionError(reconstruction);
    stats.seconds_total = batch_timer.ElapsedSeconds();
    VIOSFM_LOG(INFO) << std::fixed << std::setprecision(3) << "batch " << b + 1 << "/"
                     << num_batches << ": images " << stats.num_registered_total << " (+"
                     << stats.num_images << "), points " << stats.num_points_total << " (+"
                     << triangulation.num_points_added << " new), reprojection error "
                     << stats.mean_reprojection_error_px << " px, BA over "
                     << stats.num_ba_free_images << " images " << stats.seconds_ba << " s ("
                     << stats.num_ba_iterations << " iterations, "
                     << BaLinearSolverName(stats.ba_linear_solver) << "), " << stats.seconds_total
                     << " s";
    summary.batches.push_back(stats);
    progress.Update();
  }
  progress.Finish();

  summary.num_registered = static_cast<int>(reconstruction.NumRegImages());
  summary.num_points = static_cast<int>(reconstruction.NumPoints3D());
  summary.num_observations = static_cast<int>(reconstruction.ComputeNumObservations());
  summary.mean_track_length = reconstruction.ComputeMeanTrackLength();
  summary.mean_reprojection_error_px = MeanReprojectionError(reconstruction);
  summary.seconds_total = total_timer.ElapsedSeconds();
  VIOSFM_LOG(INFO) << summary.ToString();
  if (summary_out != nullptr) *summary_out = std::move(summary);
  return reconstruction;
}

}  // namespace viosfm
