#include "viosfm/sfm/incremental_mapper.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_set>

#include "viosfm/estimators/two_view_geometry.h"
#include "viosfm/geometry/alignment.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/triangulation.h"
#include "viosfm/scene/reprojection.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

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

// SplitMix64 finaliser: an independent seed per use.
uint64_t MixSeed(uint64_t seed, uint64_t index) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Largest reprojection error (px) of `point_in_world` in the frames that
// observe `point` of `reconstruction`; infinity behind a camera.
double MaxReprojectionError(const Reconstruction& reconstruction, const Point3D& point,
                            const Eigen::Vector3d& point_in_world) {
  double worst = 0.0;
  for (const TrackElement& element : point.track) {
    const Image& image = reconstruction.GetImage(element.image_id);
    const std::optional<Eigen::Vector2d> pixel =
        Project(reconstruction.GetCamera(image.camera_id), image.cam_from_world * point_in_world);
    if (!pixel) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, (*pixel - image.points2D[element.point2D_idx].xy).norm());
  }
  return worst;
}

}  // namespace

std::string IncrementalMapperOptions::Validate() const {
  if (init_min_num_inliers < 5) return "init_min_num_inliers must be >= 5";
  if (!(init_max_error_px > 0.0)) return "init_max_error_px must be > 0";
  if (!(init_lowest_triangulation_angle_deg > 0.0)) {
    return "init_lowest_triangulation_angle_deg must be > 0";
  }
  if (!(init_min_triangulation_angle_deg >= init_lowest_triangulation_angle_deg)) {
    return "init_min_triangulation_angle_deg must be >= init_lowest_triangulation_angle_deg";
  }
  if (init_max_pairs_tried < 1) return "init_max_pairs_tried must be >= 1";
  if (local_ba_num_images < 0) return "local_ba_num_images must be >= 0";
  if (local_ba_max_iterations < 1) return "local_ba_max_iterations must be >= 1";
  if (merge_min_common_points < 3) return "merge_min_common_points must be >= 3";
  if (!(merge_min_inlier_ratio > 0.0 && merge_min_inlier_ratio <= 1.0)) {
    return "merge_min_inlier_ratio must be in (0, 1]";
  }
  if (!(merge_max_error_px > 0.0)) return "merge_max_error_px must be > 0";
  return "";
}

IncrementalMapper::IncrementalMapper(const IncrementalMapperOptions& options,
                                     const TriangulationOptions& triangulation,
                                     const PointFilterOptions& filter,
                                     const FrameRegistrationOptions& registration, int num_threads)
    : options_(options),
      triangulation_(triangulation),
      filter_(filter),
      registration_(registration),
      num_threads_(num_threads) {}

size_t IncrementalMapper::AddFrame(Image image) {
  const size_t frame = frame_ids_.size();
  frame_ids_.push_back(image.image_id);
  index_of_image_[image.image_id] = frame;
  model_of_frame_.push_back(-1);
  tracks_of_frame_.emplace_back();
  image.registered = false;
  reconstruction_.AddImage(std::move(image));
  return frame;
}

void IncrementalMapper::SetTracks(std::vector<Track> tracks) {
  tracks_ = std::move(tracks);
  tracks_of_frame_.assign(frame_ids_.size(), {});
  for (size_t t = 0; t < tracks_.size(); ++t) {
    for (const TrackElement& element : tracks_[t].elements) {
      tracks_of_frame_[index_of_image_.at(element.image_id)].push_back(t);
    }
  }
}

int IncrementalMapper::NewModel(bool vio_anchored) {
  models_.emplace_back();
  models_.back().vio_anchored = vio_anchored;
  return static_cast<int>(models_.size()) - 1;
}

size_t IncrementalMapper::NumRegistered() const {
  size_t count = 0;
  for (const Model& model : models_) count += model.registered.size();
  return count;
}

void IncrementalMapper::Register(size_t frame, int m, const Rigid3d& cam_from_world) {
  VIOSFM_CHECK(m >= 0 && m < NumModels()) << "no model " << m;
  VIOSFM_CHECK(!IsRegistered(frame)) << "frame " << frame << " registered twice";
  Image& image = reconstruction_.GetImage(frame_ids_[frame]);
  image.cam_from_world = cam_from_world;
  image.cam_from_world.rotation.normalize();
  image.registered = true;
  model_of_frame_[frame] = m;
  models_[m].registered.push_back(image.image_id);
}

void IncrementalMapper::Deregister(size_t frame) {
  const int m = model_of_frame_[frame];
  if (m < 0) return;
  const image_t image_id = frame_ids_[frame];
  Image& image = reconstruction_.GetImage(image_id);
  for (point2D_t k = 0; k < image.points2D.size(); ++k) {
    if (image.points2D[k].HasPoint3D()) reconstruction_.DeleteObservation(image_id, k);
  }
  image.registered = false;
  model_of_frame_[frame] = -1;
  std::vector<image_t>& registered = models_[m].registered;
  registered.erase(std::remove(registered.begin(), registered.end(), image_id), registered.end());
}

point3D_t IncrementalMapper::PointOfTrackInModel(const Track& track, int m) const {
  for (const TrackElement& element : track.elements) {
    if (model_of_frame_[index_of_image_.at(element.image_id)] != m) continue;
    const point3D_t point =
        reconstruction_.GetImage(element.image_id).points2D[element.point2D_idx].point3D_id;
    if (point != kInvalidPoint3DId) return point;
  }
  return kInvalidPoint3DId;
}

FrameCorrespondences IncrementalMapper::Correspondences(size_t frame, int m) const {
  FrameCorrespondences result;
  const image_t image_id = frame_ids_[frame];
  const Image& image = reconstruction_.GetImage(image_id);
  const Camera& camera = reconstruction_.GetCamera(image.camera_id);
  for (const size_t t : tracks_of_frame_[frame]) {
    point2D_t own = kInvalidPoint2DIdx;
    point3D_t point = kInvalidPoint3DId;
    for (const TrackElement& element : tracks_[t].elements) {
      if (element.image_id == image_id) {
        own = element.point2D_idx;
        continue;
      }
      if (point != kInvalidPoint3DId) continue;
      if (model_of_frame_[index_of_image_.at(element.image_id)] != m) continue;
      const point3D_t candidate =
          reconstruction_.GetImage(element.image_id).points2D[element.point2D_idx].point3D_id;
      if (candidate != kInvalidPoint3DId) point = candidate;
    }
    if (own == kInvalidPoint2DIdx || point == kInvalidPoint3DId) continue;
    result.points_normalized.push_back(ImageToCam(camera, image.points2D[own].xy));
    result.points_in_world.push_back(reconstruction_.GetPoint3D(point).xyz);
  }
  return result;
}

AbsolutePoseResult IncrementalMapper::EstimatePose(size_t frame,
                                                   const FrameCorrespondences& correspondences,
                                                   const std::optional<Rigid3d>& predicted) const {
  const Image& image = reconstruction_.GetImage(frame_ids_[frame]);
  AbsolutePoseOptions pnp = registration_.pnp;
  pnp.seed = registration_.pnp.seed + image.image_id;
  return EstimateAbsolutePose(correspondences.points_normalized, correspondences.points_in_world,
                              MeanFocalLength(reconstruction_.GetCamera(image.camera_id)), pnp,
                              predicted);
}

std::optional<InitialPair> IncrementalMapper::FindInitialPair(
    const std::vector<size_t>& candidates, const std::vector<ImagePairMatches>& pairs) const {
  const std::unordered_set<size_t> candidate_set(candidates.begin(), candidates.end());
  // The candidates' pairs with enough matches, and each frame's total.
  std::vector<const ImagePairMatches*> usable;
  std::unordered_map<size_t, size_t> matches_of_frame;
  for (const ImagePairMatches& pair : pairs) {
    const auto it1 = index_of_image_.find(pair.image_id1);
    const auto it2 = index_of_image_.find(pair.image_id2);
    if (it1 == index_of_image_.end() || it2 == index_of_image_.end()) continue;
    if (candidate_set.count(it1->second) == 0 || candidate_set.count(it2->second) == 0) continue;
    if (IsRegistered(it1->second) || IsRegistered(it2->second)) continue;
    if (static_cast<int>(pair.matches.size()) < options_.init_min_num_inliers) continue;
    usable.push_back(&pair);
    matches_of_frame[it1->second] += pair.matches.size();
    matches_of_frame[it2->second] += pair.matches.size();
  }
  // The best-connected frames first, each with every one of its pairs (the
  // widest baselines among them too), until init_max_pairs_tried.
  std::vector<std::pair<size_t, size_t>> frames_by_matches;
  for (const auto& [frame, count] : matches_of_frame) frames_by_matches.emplace_back(count, frame);
  std::sort(frames_by_matches.begin(), frames_by_matches.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  std::vector<const ImagePairMatches*> ranked;
  std::unordered_set<const ImagePairMatches*> taken;
  for (const auto& [count, frame] : frames_by_matches) {
    if (ranked.size() >= static_cast<size_t>(options_.init_max_pairs_tried)) break;
    std::vector<const ImagePairMatches*> of_frame;
    for (const ImagePairMatches* pair : usable) {
      if (index_of_image_.at(pair->image_id1) == frame ||
          index_of_image_.at(pair->image_id2) == frame) {
        of_frame.push_back(pair);
      }
    }
    std::sort(of_frame.begin(), of_frame.end(),
              [](const ImagePairMatches* a, const ImagePairMatches* b) {
                if (a->matches.size() != b->matches.size()) {
                  return a->matches.size() > b->matches.size();
                }
                return ImagePairToPairId(a->image_id1, a->image_id2) <
                       ImagePairToPairId(b->image_id1, b->image_id2);
              });
    for (const ImagePairMatches* pair : of_frame) {
      if (ranked.size() >= static_cast<size_t>(options_.init_max_pairs_tried)) break;
      if (taken.insert(pair).second) ranked.push_back(pair);
    }
  }
  // Each pair's geometry and the median angle of its points.
  std::vector<InitialPair> evaluated;
  for (const ImagePairMatches* pair : ranked) {
    const size_t frame1 = index_of_image_.at(pair->image_id1);
    const size_t frame2 = index_of_image_.at(pair->image_id2);
    const Image& image1 = reconstruction_.GetImage(pair->image_id1);
    const Image& image2 = reconstruction_.GetImage(pair->image_id2);
    const Camera& camera1 = reconstruction_.GetCamera(image1.camera_id);
    const Camera& camera2 = reconstruction_.GetCamera(image2.camera_id);
    std::vector<Eigen::Vector2d> points1, points2;
    FeatureMatches matches;
    for (const FeatureMatch& match : pair->matches) {
      matches.push_back(
          {static_cast<point2D_t>(points1.size()), static_cast<point2D_t>(points2.size())});
      points1.push_back(ImageToCam(camera1, image1.points2D[match.point2D_idx1].xy));
      points2.push_back(ImageToCam(camera2, image2.points2D[match.point2D_idx2].xy));
    }
    TwoViewGeometryOptions geometry;
    geometry.max_error_px = options_.init_max_error_px;
    geometry.min_num_inliers = options_.init_min_num_inliers;
    geometry.seed = MixSeed(options_.seed, ImagePairToPairId(pair->image_id1, pair->image_id2));
    const TwoViewGeometryResult result =
        EstimateCalibratedTwoViewGeometry(points1, points2, matches, camera1, camera2, geometry);
    if (!result.accepted() || result.config != TwoViewGeometryConfig::kCalibrated) continue;
    const Rigid3d cam1_from_world;
    const Rigid3d& cam2_from_world = result.cam2_from_cam1;
    const Eigen::Vector3d center2 = ProjectionCenter(cam2_from_world);
    std::vector<double> angles;
    for (const FeatureMatch& match : result.inlier_matches) {
      const std::optional<Eigen::Vector3d> point =
          TriangulateMidpoint(cam1_from_world, cam2_from_world, points1[match.point2D_idx1],
                              points2[match.point2D_idx2]);
      if (!point || !HasPositiveDepth(cam1_from_world, *point) ||
          !HasPositiveDepth(cam2_from_world, *point)) {
        continue;
      }
      angles.push_back(TriangulationAngle(Eigen::Vector3d::Zero(), center2, *point));
    }
    if (static_cast<int>(angles.size()) < options_.init_min_num_inliers) continue;
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    InitialPair candidate;
    candidate.frame1 = frame1;
    candidate.frame2 = frame2;
    candidate.cam2_from_cam1 = result.cam2_from_cam1;
    candidate.num_inliers = static_cast<int>(angles.size());
    candidate.median_angle_deg = angles[angles.size() / 2] * kDegreesPerRadian;
    evaluated.push_back(candidate);
  }
  // The bound relaxed until some pair reaches it; among those, the most inliers.
  for (double bound = options_.init_min_triangulation_angle_deg;
       bound >= options_.init_lowest_triangulation_angle_deg - 1e-12; bound /= 2.0) {
    const InitialPair* best = nullptr;
    for (const InitialPair& candidate : evaluated) {
      if (candidate.median_angle_deg < bound) continue;
      if (best == nullptr || candidate.num_inliers > best->num_inliers) best = &candidate;
    }
    if (best != nullptr) return *best;
  }
  return std::nullopt;
}

int IncrementalMapper::InitializeModel(const InitialPair& pair) {
  const int m = NewModel(/*vio_anchored=*/false);
  Register(pair.frame1, m, Rigid3d());
  Register(pair.frame2, m, pair.cam2_from_cam1);
  SetGauge(m, frame_ids_[pair.frame1]);
  TriangulateFrames({pair.frame1, pair.frame2});
  BundleAdjustmentOptions ba;
  ba.num_threads = num_threads_;
  AdjustModel(m, ba);
  FilterPoints(&reconstruction_, filter_, num_threads_);
  size_t num_points = 0;
  for (const Point2D& point2D : reconstruction_.GetImage(frame_ids_[pair.frame1]).points2D) {
    if (point2D.HasPoint3D()) ++num_points;
  }
  if (static_cast<int>(num_points) < registration_.min_num_correspondences) {
    Deregister(pair.frame2);
    Deregister(pair.frame1);
    models_.pop_back();
    return -1;
  }
  VIOSFM_LOG(INFO) << "mapper: a model started from the images of "
                   << reconstruction_.GetImage(frame_ids_[pair.frame1]).name << " and "
                   << reconstruction_.GetImage(frame_ids_[pair.frame2]).name << " ("
                   << pair.num_inliers << " inliers, median triangulation angle "
                   << pair.median_angle_deg << " deg, " << num_points << " points)";
  return m;
}

std::pair<int, int> IncrementalMapper::BestModelFor(size_t frame) const {
  int best_model = -1;
  int best_count = 0;
  for (int m = 0; m < NumModels(); ++m) {
    const int count = static_cast<int>(Correspondences(frame, m).size());
    if (count > best_count) {
      best_model = m;
      best_count = count;
    }
  }
  if (best_count < registration_.min_num_correspondences) return {-1, best_count};
  return {best_model, best_count};
}

std::vector<size_t> IncrementalMapper::RegisterNextFrames(const std::vector<size_t>& candidates) {
  std::vector<size_t> registered;
  // Frames PnP could not register since the models last changed.
  std::unordered_set<size_t> failed;
  while (true) {
    size_t best_frame = 0;
    int best_model = -1;
    int best_count = 0;
    for (const size_t frame : candidates) {
      if (IsRegistered(frame) || failed.count(frame) > 0) continue;
      const auto [m, count] = BestModelFor(frame);
      if (m >= 0 && count > best_count) {
        best_frame = frame;
        best_model = m;
        best_count = count;
      }
    }
    if (best_model < 0) {
      VIOSFM_LOG(DEBUG) << "mapper: no frame of " << candidates.size() - registered.size()
                        << " candidates has " << registration_.min_num_correspondences
                        << " 2D-3D matches with a model";
      break;
    }
    const FrameCorrespondences correspondences = Correspondences(best_frame, best_model);
    const AbsolutePoseResult result = EstimatePose(best_frame, correspondences, std::nullopt);
    if (!result.success) {
      VIOSFM_LOG(DEBUG) << "mapper: " << reconstruction_.GetImage(frame_ids_[best_frame]).name
                        << ": PnP found no pose from " << correspondences.size()
                        << " 2D-3D matches (" << result.num_inliers << " inliers)";
      failed.insert(best_frame);
      continue;
    }
    Register(best_frame, best_model, result.cam_from_world);
    TriangulateFrames({best_frame});
    if (!models_[best_model].vio_anchored && options_.local_ba_num_images > 0) {
      BundleAdjustmentOptions ba;
      ba.num_threads = num_threads_;
      AdjustLocal(best_frame, ba);
    }
    registered.push_back(best_frame);
    failed.clear();
  }
  return registered;
}

TriangulationStatistics IncrementalMapper::TriangulateFrames(const std::vector<size_t>& frames) {
  TriangulationStatistics total;
  for (int m = 0; m < NumModels(); ++m) {
    std::vector<size_t> track_indices;
    for (const size_t frame : frames) {
      if (model_of_frame_[frame] != m) continue;
      track_indices.insert(track_indices.end(), tracks_of_frame_[frame].begin(),
                           tracks_of_frame_[frame].end());
    }
    if (track_indices.empty()) continue;
    std::sort(track_indices.begin(), track_indices.end());
    track_indices.erase(std::unique(track_indices.begin(), track_indices.end()),
                        track_indices.end());
    std::vector<Track> subset;
    subset.reserve(track_indices.size());
    for (const size_t t : track_indices) subset.push_back(tracks_[t]);
    const TriangulationStatistics statistics =
        TriangulateReconstruction(&reconstruction_, subset, models_[m].registered, triangulation_);
    total.num_tracks_tried += statistics.num_tracks_tried;
    total.num_points_added += statistics.num_points_added;
    total.num_new_point_observations += statistics.num_new_point_observations;
    total.num_points_extended += statistics.num_points_extended;
    total.num_extension_observations += statistics.num_extension_observations;
    total.num_rejected_observations += statistics.num_rejected_observations;
    total.changed_point_ids.insert(total.changed_point_ids.end(),
                                   statistics.changed_point_ids.begin(),
                                   statistics.changed_point_ids.end());
  }
  return total;
}

TriangulationStatistics IncrementalMapper::TriangulateAll() {
  TriangulationStatistics total;
  for (int m = 0; m < NumModels(); ++m) {
    const TriangulationStatistics statistics =
        TriangulateReconstruction(&reconstruction_, tracks_, models_[m].registered, triangulation_);
    total.num_points_added += statistics.num_points_added;
    total.num_points_extended += statistics.num_points_extended;
    total.changed_point_ids.insert(total.changed_point_ids.end(),
                                   statistics.changed_point_ids.begin(),
                                   statistics.changed_point_ids.end());
  }
  return total;
}

BundleAdjustmentSummary IncrementalMapper::Adjust(const std::vector<image_t>& free_images,
                                                  image_t held_neighbour, image_t gauge_image,
                                                  const std::vector<RelativePosePrior>& priors,
                                                  const BundleAdjustmentOptions& options,
                                                  int max_held_views,
                                                  BundleAdjustmentTerms* terms) {
  Reconstruction* reconstruction = &reconstruction_;
  if (free_images.size() == reconstruction->NumRegImages()) {
    return BundleAdjust(reconstruction, priors, {gauge_image}, options, terms);
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

  const BundleAdjustmentSummary summary = BundleAdjust(&sub, priors, constant, options, terms);

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

BundleAdjustmentSummary IncrementalMapper::AdjustLocal(size_t frame,
                                                       const BundleAdjustmentOptions& options) {
  const int m = model_of_frame_[frame];
  VIOSFM_CHECK(m >= 0) << "frame " << frame << " is not registered";
  const image_t image_id = frame_ids_[frame];
  // The frames of the model sharing the most points with this one.
  std::unordered_map<image_t, int> shared;
  for (const Point2D& point2D : reconstruction_.GetImage(image_id).points2D) {
    if (!point2D.HasPoint3D()) continue;
    for (const TrackElement& element : reconstruction_.GetPoint3D(point2D.point3D_id).track) {
      if (element.image_id != image_id) ++shared[element.image_id];
    }
  }
  std::vector<std::pair<int, image_t>> ranked;
  for (const auto& [other, count] : shared) ranked.emplace_back(count, other);
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  std::vector<image_t> free_images = {image_id};
  for (const auto& [count, other] : ranked) {
    if (free_images.size() >= static_cast<size_t>(options_.local_ba_num_images)) break;
    free_images.push_back(other);
  }
  BundleAdjustmentOptions local = options;
  local.max_num_iterations = options_.local_ba_max_iterations;
  local.refine_intrinsics = false;
  local.use_relative_pose_priors = false;
  const BundleAdjustmentSummary summary =
      Adjust(free_images, kInvalidImageId, models_[m].gauge_image, {}, local, 0, nullptr);
  // The adjusted points checked again.
  std::vector<point3D_t> point_ids;
  for (const image_t free_image : free_images) {
    for (const Point2D& point2D : reconstruction_.GetImage(free_image).points2D) {
      if (point2D.HasPoint3D()) point_ids.push_back(point2D.point3D_id);
    }
  }
  std::sort(point_ids.begin(), point_ids.end());
  point_ids.erase(std::unique(point_ids.begin(), point_ids.end()), point_ids.end());
  FilterPoints(&reconstruction_, filter_, point_ids, num_threads_);
  return summary;
}

BundleAdjustmentSummary IncrementalMapper::AdjustModel(int m,
                                                       const BundleAdjustmentOptions& options) {
  BundleAdjustmentOptions global = options;
  global.use_relative_pose_priors = false;
  return Adjust(models_[m].registered, kInvalidImageId, models_[m].gauge_image, {}, global, 0,
                nullptr);
}

std::vector<std::pair<point3D_t, point3D_t>> IncrementalMapper::CommonPoints(int a, int b) const {
  std::vector<std::pair<point3D_t, point3D_t>> common;
  for (const Track& track : tracks_) {
    const point3D_t in_a = PointOfTrackInModel(track, a);
    if (in_a == kInvalidPoint3DId) continue;
    const point3D_t in_b = PointOfTrackInModel(track, b);
    if (in_b != kInvalidPoint3DId) common.emplace_back(in_a, in_b);
  }
  return common;
}

std::optional<Sim3d> IncrementalMapper::EstimateModelSimilarity(
    int into, int from, const std::vector<std::pair<point3D_t, point3D_t>>& common,
    int* num_inliers) const {
  (void)into;
  (void)from;
  std::vector<Eigen::Vector3d> src, dst;
  for (const auto& [point_into, point_from] : common) {
    dst.push_back(reconstruction_.GetPoint3D(point_into).xyz);
    src.push_back(reconstruction_.GetPoint3D(point_from).xyz);
  }
  // Inliers of a similarity: each moved point reprojects into the frames of
  // the other model, and each point of the other model into its frames.
  const auto inliers_of = [&](const Sim3d& into_from_from) {
    const Sim3d from_from_into = into_from_from.Inverse();
    std::vector<size_t> inliers;
    for (size_t k = 0; k < common.size(); ++k) {
      const Point3D& point_into = reconstruction_.GetPoint3D(common[k].first);
      const Point3D& point_from = reconstruction_.GetPoint3D(common[k].second);
      if (MaxReprojectionError(reconstruction_, point_into, into_from_from * src[k]) <=
              options_.merge_max_error_px &&
          MaxReprojectionError(reconstruction_, point_from, from_from_into * dst[k]) <=
              options_.merge_max_error_px) {
        inliers.push_back(k);
      }
    }
    return inliers;
  };
  Random random(MixSeed(options_.seed, common.size()));
  std::optional<Sim3d> best;
  std::vector<size_t> best_inliers;
  const int num_trials = 200;
  for (int trial = 0; trial < num_trials; ++trial) {
    std::vector<Eigen::Vector3d> sample_src, sample_dst;
    std::unordered_set<size_t> chosen;
    while (chosen.size() < 3) {
      chosen.insert(
          static_cast<size_t>(random.UniformInt(0, static_cast<int64_t>(src.size()) - 1)));
    }
    for (const size_t k : chosen) {
      sample_src.push_back(src[k]);
      sample_dst.push_back(dst[k]);
    }
    const std::optional<Sim3d> estimate = AlignPointsUmeyama(sample_src, sample_dst, true);
    if (!estimate || !(estimate->scale > 0.0)) continue;
    std::vector<size_t> inliers = inliers_of(*estimate);
    if (inliers.size() > best_inliers.size()) {
      best = estimate;
      best_inliers = std::move(inliers);
    }
  }
  if (!best || best_inliers.size() < 3) return std::nullopt;
  // Refitted to every inlier, once.
  std::vector<Eigen::Vector3d> inlier_src, inlier_dst;
  for (const size_t k : best_inliers) {
    inlier_src.push_back(src[k]);
    inlier_dst.push_back(dst[k]);
  }
  if (const std::optional<Sim3d> refined = AlignPointsUmeyama(inlier_src, inlier_dst, true)) {
    std::vector<size_t> inliers = inliers_of(*refined);
    if (inliers.size() >= best_inliers.size()) {
      best = refined;
      best_inliers = std::move(inliers);
    }
  }
  *num_inliers = static_cast<int>(best_inliers.size());
  return best;
}

void IncrementalMapper::MoveModel(int from, int into, const Sim3d& into_from_from) {
  TransformFrames(into_from_from, models_[from].registered, &reconstruction_);
  for (const image_t image_id : models_[from].registered) {
    model_of_frame_[index_of_image_.at(image_id)] = into;
    models_[into].registered.push_back(image_id);
  }
  models_[from].registered.clear();
}

std::optional<ModelMerge> IncrementalMapper::TryMergeModels() {
  if (NumModels() < 2) return std::nullopt;
  int best_a = -1, best_b = -1;
  std::vector<std::pair<point3D_t, point3D_t>> best_common;
  for (int a = 0; a < NumModels(); ++a) {
    for (int b = a + 1; b < NumModels(); ++b) {
      std::vector<std::pair<point3D_t, point3D_t>> common = CommonPoints(a, b);
      if (common.size() > best_common.size()) {
        best_a = a;
        best_b = b;
        best_common = std::move(common);
      }
    }
  }
  if (static_cast<int>(best_common.size()) < options_.merge_min_common_points) return std::nullopt;
  // The model the VIO holds, else the larger, stays where it is.
  const auto keeps = [&](int a, int b) {
    if (models_[a].vio_anchored != models_[b].vio_anchored) return models_[a].vio_anchored;
    return models_[a].registered.size() >= models_[b].registered.size();
  };
  int into = best_a, from = best_b;
  if (!keeps(best_a, best_b)) std::swap(into, from);
  std::vector<std::pair<point3D_t, point3D_t>> common = best_common;
  if (into != best_a) {
    for (auto& [p, q] : common) std::swap(p, q);
  }
  int num_inliers = 0;
  const std::optional<Sim3d> into_from_from =
      EstimateModelSimilarity(into, from, common, &num_inliers);
  ModelMerge merge;
  merge.into_model = into;
  merge.from_model = from;
  merge.num_common_points = static_cast<int>(common.size());
  merge.num_inliers = num_inliers;
  if (!into_from_from || num_inliers < options_.merge_min_common_points ||
      num_inliers < options_.merge_min_inlier_ratio * static_cast<double>(common.size())) {
    VIOSFM_LOG(DEBUG) << "mapper: models " << into << " and " << from << " share " << common.size()
                      << " points, " << num_inliers << " of them agree on a similarity: not merged";
    return std::nullopt;
  }
  merge.into_from_from = *into_from_from;
  const size_t num_moved = models_[from].registered.size();
  MoveModel(from, into, *into_from_from);
  MergeTrackPoints(&reconstruction_, tracks_, triangulation_);
  // The merged model at the lower index, the other removed.
  const int kept = std::min(into, from);
  const int removed = std::max(into, from);
  if (into != kept) std::swap(models_[kept], models_[removed]);
  models_.erase(models_.begin() + removed);
  for (int& m : model_of_frame_) {
    if (m == into || m == from) {
      m = kept;
    } else if (m > removed) {
      --m;
    }
  }
  std::vector<size_t> frames;
  for (const image_t image_id : models_[kept].registered) {
    frames.push_back(index_of_image_.at(image_id));
  }
  TriangulateFrames(frames);
  VIOSFM_LOG(INFO) << "mapper: " << num_moved << " frames of a separate model joined the model of "
                   << models_[kept].registered.size() - num_moved << " frames (" << num_inliers
                   << " of " << common.size() << " common points agree, scale "
                   << into_from_from->scale << ")";
  merge.into_model = kept;
  return merge;
}

Reconstruction IncrementalMapper::ExtractModel(int m) const {
  Reconstruction copy = reconstruction_;
  for (size_t frame = 0; frame < frame_ids_.size(); ++frame) {
    if (model_of_frame_[frame] < 0 || model_of_frame_[frame] == m) continue;
    Image& image = copy.GetImage(frame_ids_[frame]);
    for (point2D_t k = 0; k < image.points2D.size(); ++k) {
      if (image.points2D[k].HasPoint3D()) copy.DeleteObservation(image.image_id, k);
    }
    image.registered = false;
  }
  return copy;
}

void TransformFrames(const Sim3d& b_from_a, const std::vector<image_t>& image_ids,
                     Reconstruction* reconstruction) {
  std::unordered_set<point3D_t> points;
  const Eigen::Quaterniond rotation = b_from_a.rotation.normalized();
  for (const image_t image_id : image_ids) {
    Image& image = reconstruction->GetImage(image_id);
    for (const Point2D& point2D : image.points2D) {
      if (point2D.HasPoint3D()) points.insert(point2D.point3D_id);
    }
    // x_b = s R x_a + t, and the camera's coordinates scaled by s see the
    // same image: cam_from_b = (R_c R^T, s t_c - R_c R^T t).
    const Eigen::Quaterniond cam_rotation = image.cam_from_world.rotation * rotation.conjugate();
    image.cam_from_world.translation =
        b_from_a.scale * image.cam_from_world.translation - (cam_rotation * b_from_a.translation);
    image.cam_from_world.rotation = cam_rotation.normalized();
  }
  for (const point3D_t point3D_id : points) {
    Point3D& point = reconstruction->GetPoint3D(point3D_id);
    point.xyz = b_from_a * point.xyz;
  }
}

}  // namespace viosfm
