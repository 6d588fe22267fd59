#include "viosfm/matching/verification_driver.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "viosfm/features/sift.h"
#include "viosfm/geometry/epipolar.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// SplitMix64 finaliser: an independent seed per pair.
uint64_t MixSeed64(uint64_t seed, uint64_t index) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

struct ImageInfo {
  image_t image_id = kInvalidImageId;
  std::string name;
  camera_t camera_id = kInvalidCameraId;
  timestamp_ns_t timestamp_ns = 0;
  std::optional<Rigid3d> world_from_body;                      // the VIO pose, if associated
  VioOdometer odometer;                                        // of that pose
  Eigen::Vector3d cam_angular_rate = Eigen::Vector3d::Zero();  // rad/s, for the rolling shutter
};

// Both frames have a VIO pose in the same segment: the VIO's relative pose
// between them means something.
bool HasVioPrior(const ImageInfo& info1, const ImageInfo& info2) {
  return info1.world_from_body && info2.world_from_body &&
         info1.odometer.segment == info2.odometer.segment;
}

// Features of one image as the per-pair steps use them.
struct ImageData {
  std::vector<Eigen::Vector2d> points_normalized;  // undistorted x/z, y/z
  std::vector<Eigen::Vector2d> points_px;          // undistorted pixels (guided matching)
  // The descriptors as stored (guided matching), and normalised to float
  // (brute-force matching); null where the batch does not need them.
  std::shared_ptr<const FeatureDescriptors> stored_descriptors;
  std::shared_ptr<const FloatDescriptors> descriptors;
};

// What a batch needs of an image: nothing beyond its keypoints (stored
// pairs only), its stored descriptors (guided matching), or also the
// normalised ones (brute-force matching).
struct ImageNeeds {
  bool stored_descriptors = false;
  bool normalised_descriptors = false;
};

// The result of one pair's worker.
struct PairWork {
  PairDecision decision;
  FeatureMatches matches;  // to store (new pairs only)
  std::optional<TwoViewGeometry> geometry;
  // Re-verified from stored matches (options.reverify_stored_matches): the
  // matches are not written again; had_geometry: a geometry was stored.
  bool reverified = false;
  bool had_geometry = false;
};

}  // namespace

std::string VerificationOptions::Validate() const {
  if (std::string error = pairs.Validate(); !error.empty()) return "pairs." + error;
  if (pairs.mode == PairMode::kPairList) return "pairs.mode: pair_list is not supported here";
  if (pairs.mode == PairMode::kTemporalRetrieval && pairs.num_retrieval_neighbors > 0) {
    RetrievalOptions checked = retrieval;
    checked.num_neighbors = pairs.num_retrieval_neighbors;
    if (std::string error = checked.Validate(); !error.empty()) return "retrieval." + error;
  }
  if (std::string error = matching.Validate(); !error.empty()) return "matching." + error;
  if (std::string error = prior.Validate(); !error.empty()) return "prior." + error;
  if (std::string error = vio_uncertainty.Validate(); !error.empty()) {
    return "vio_uncertainty." + error;
  }
  if (!(band_sigmas >= 0.0) || !std::isfinite(band_sigmas)) return "band_sigmas must be >= 0";
  if (!(band_depth_m > 0.0) || !std::isfinite(band_depth_m)) return "band_depth_m must be > 0";
  if (!(max_correction_sigmas >= 0.0)) return "max_correction_sigmas must be >= 0";
  if (!(guided_band_px > 0.0) || !std::isfinite(guided_band_px)) {
    return "guided_band_px must be positive";
  }
  if (std::string error = geometry.Validate(); !error.empty()) return "geometry." + error;
  if (max_pose_time_difference_ns < 0) return "max_pose_time_difference_ns must be >= 0";
  if (batch_size < 1) return "batch_size must be >= 1";
  return "";
}

std::vector<std::pair<std::string, std::string>> VerificationOptions::ToKeyValues() const {
  return OptionsToKeyValues(*this);
}

std::string FormatVerificationSummary(const VerificationSummary& s) {
  std::ostringstream out;
  out << s.num_pairs << " pairs of " << s.num_images << " images (" << s.num_images_with_prior
      << " with a VIO pose): " << s.num_accepted << " accepted";
  if (s.num_accepted_corrected > 0) {
    out << " (" << s.num_accepted_corrected << " under the VIO's pose corrected within its drift)";
  }
  out << ", " << s.num_vio_rejected << " rejected by VIO";
  if (s.num_vio_depth_rejected > 0) out << " (" << s.num_vio_depth_rejected << " by depth)";
  out << ", " << s.num_ransac_rejected << " by RANSAC, " << s.num_no_matches << " without matches";
  if (s.num_pairs_without_prior > 0) out << "; " << s.num_pairs_without_prior << " RANSAC only";
  if (s.num_resumed > 0) out << "; " << s.num_resumed << " already stored";
  if (s.num_reverified > 0) out << "; " << s.num_reverified << " re-verified from stored matches";
  out << std::fixed << std::setprecision(2) << "; " << s.seconds_total << " s (pairs "
      << s.seconds_pair_generation << " s, loading " << s.seconds_loading << " s, writing "
      << s.seconds_writing << " s; thread-seconds: matching " << s.seconds_matching << ", VIO "
      << s.seconds_vio << ", RANSAC " << s.seconds_ransac << ")";
  return out.str();
}

double DriftEpipolarBandPx(const Eigen::Matrix<double, 6, 6>& covariance,
                           const Rigid3d& cam2_from_cam1, double focal_length_px,
                           const VerificationOptions& options) {
  const RelativePoseSigmas sigmas = LargestSigmas(covariance);
  // The translation's covariance across the baseline.
  Eigen::Matrix3d across = Eigen::Matrix3d::Identity();
  if (cam2_from_cam1.translation.norm() > 1e-9) {
    const Eigen::Vector3d direction = cam2_from_cam1.translation.normalized();
    across -= direction * direction.transpose();
  }
  const Eigen::Matrix3d translation = across * covariance.bottomRightCorner<3, 3>() * across;
  const double sigma_across = std::sqrt(std::max(
      0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(translation, Eigen::EigenvaluesOnly)
               .eigenvalues()
               .maxCoeff()));
  const double expected_px = options.band_sigmas * focal_length_px *
                             (sigmas.rotation_rad + sigma_across / options.band_depth_m);
  const double base = options.prior.max_epipolar_error_px;
  return std::sqrt(base * base + expected_px * expected_px);
}

VerificationResult RunVerification(const Sequence& sequence, const Trajectory& vio_world_from_body,
                                   ColmapDatabase* database, const VerificationOptions& options,
                                   const std::vector<int>& vio_segments) {
  VIOSFM_CHECK(vio_segments.empty() || vio_segments.size() == vio_world_from_body.size())
      << vio_segments.size() << " segment indices for " << vio_world_from_body.size() << " poses";
  std::vector<std::optional<FrameVioPose>> frame_poses(sequence.images.size());
  if (options.use_vio_prior && !vio_world_from_body.empty()) {
    const std::vector<VioOdometer> odometers =
        ComputeVioOdometers(vio_world_from_body, vio_segments);
    for (size_t i = 0; i < sequence.images.size(); ++i) {
      if (const std::optional<size_t> index =
              NearestPoseIndex(vio_world_from_body, sequence.images[i].timestamp_ns,
                               options.max_pose_time_difference_ns)) {
        frame_poses[i] =
            FrameVioPose{vio_world_from_body.poses[*index].world_from_frame, odometers[*index]};
      }
    }
  }
  return RunVerification(sequence, frame_poses, database, options);
}

VerificationResult RunVerification(const Sequence& sequence,
                                   const std::vector<std::optional<FrameVioPose>>& frame_poses,
                                   ColmapDatabase* database, const VerificationOptions& options,
                                   const FrameRollingShutter& rolling_shutter,
                                   const VerifiedPairsCallback& on_verified) {
  VIOSFM_CHECK(database != nullptr);
  VIOSFM_CHECK(!rolling_shutter.active() ||
               rolling_shutter.cam_angular_rate.size() == sequence.images.size());
  VIOSFM_CHECK(frame_poses.size() == sequence.images.size())
      << frame_poses.size() << " frame poses for " << sequence.images.size() << " images";
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid verification options: " + error);
  }
  Timer total_timer;
  VerificationResult result;
  VerificationSummary& summary = result.summary;
  summary.options = options.ToKeyValues();
  const std::string database_path = database->path().string();
  summary.database_path = database_path;

  // Images: the database's images that belong to the sequence, in time order.
  Timer step_timer;
  std::unordered_map<std::string, size_t> frame_by_name;
  for (size_t i = 0; i < sequence.images.size(); ++i) {
    frame_by_name.emplace(DatabaseImageName(sequence.images[i]), i);
  }
  std::vector<ImageInfo> images;
  for (const DatabaseImage& row : database->ReadAllImages()) {
    const auto it = frame_by_name.find(row.name);
    if (it == frame_by_name.end()) continue;
    if (!database->ExistsFeatures(row.image_id)) {
      throw InputError(database_path, 0,
                       "image '" + row.name +
                           "' has no keypoints/descriptors (run `viosfm "
                           "features` first)");
    }
    ImageInfo info;
    info.image_id = row.image_id;
    info.name = row.name;
    info.camera_id = row.camera_id;
    info.timestamp_ns = sequence.images[it->second].timestamp_ns;
    if (rolling_shutter.active())
      info.cam_angular_rate = rolling_shutter.cam_angular_rate[it->second];
    if (options.use_vio_prior && frame_poses[it->second]) {
      info.world_from_body = frame_poses[it->second]->world_from_body;
      info.odometer = frame_poses[it->second]->odometer;
    }
    images.push_back(std::move(info));
  }
  std::sort(images.begin(), images.end(),
            [](const ImageInfo& a, const ImageInfo& b) { return a.timestamp_ns < b.timestamp_ns; });
  summary.num_images = images.size();
  bool any_prior = false;
  for (const std::optional<FrameVioPose>& pose : frame_poses) any_prior = any_prior || pose;
  const bool use_prior = options.use_vio_prior && any_prior;
  for (const ImageInfo& info : images) {
    if (info.world_from_body) ++summary.num_images_with_prior;
  }
  if (use_prior && summary.num_images_with_prior < images.size()) {
    VIOSFM_LOG(WARNING) << "verification: " << images.size() - summary.num_images_with_prior
                        << " of " << images.size() << " images have no VIO pose within "
                        << FormatNsAsSeconds(options.max_pose_time_difference_ns, 3)
                        << " s; their pairs are verified by RANSAC only";
  }
  std::unordered_map<image_t, size_t> index_by_id;
  for (size_t k = 0; k < images.size(); ++k) index_by_id[images[k].image_id] = k;
  std::map<camera_t, Camera> cameras;
  for (const ImageInfo& info : images) {
    if (!cameras.count(info.camera_id)) {
      cameras.emplace(info.camera_id, database->ReadCamera(info.camera_id));
    }
  }

  // Pairs.
  PairGeneratorInput input;
  for (const ImageInfo& info : images) input.images.push_back({info.image_id, info.timestamp_ns});
  const int n1 = options.pairs.num_temporal_neighbors;
  const int n2 = options.pairs.num_retrieval_neighbors;
  std::set<ImagePair> temporal_pairs;
  if (options.pairs.mode == PairMode::kTemporalRetrieval) {
    std::vector<std::vector<image_t>> exclude(images.size());
    for (size_t k = 0; k < images.size(); ++k) {
      for (const size_t j : TemporalNeighbors(input.images, k, n1)) {
        exclude[k].push_back(images[j].image_id);
        temporal_pairs.insert(ImagePair::Ordered(images[k].image_id, images[j].image_id));
      }
    }
    // Retrieval only if some image has candidates beyond its temporal neighbours.
    if (n2 > 0 && images.size() > static_cast<size_t>(n1) + 1) {
      RetrievalOptions retrieval = options.retrieval;
      retrieval.num_neighbors = n2;
      retrieval.num_threads = options.num_threads;
      retrieval.vocabulary.num_threads = options.num_threads;
      retrieval.vocabulary.seed = options.seed;
      std::vector<image_t> ids;
      for (const ImageInfo& info : images) ids.push_back(info.image_id);
      const DescriptorLoader load = [&](size_t index) {
        return database->ReadDescriptors(ids[index]);
      };
      input.retrieval = RetrieveSimilarImages(ids, load, exclude, retrieval);
    }
  }
  const std::vector<ImagePair> pairs = GeneratePairs(input, options.pairs);
  summary.seconds_pair_generation = step_timer.ElapsedSeconds();
  summary.num_pairs = pairs.size();
  VIOSFM_LOG(INFO) << "verification: " << pairs.size() << " pairs of " << images.size()
                   << " images (" << PairModeName(options.pairs.mode) << ", "
                   << (use_prior ? "VIO prior + RANSAC" : "RANSAC only") << ")";

  std::vector<bool> stored(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    stored[i] = database->ExistsMatches(pairs[i].image_id1, pairs[i].image_id2);
  }

  const int num_workers =
      NumThreadsFor(std::max<int64_t>(1, options.batch_size), options.num_threads);
  std::vector<double> matching_seconds(num_workers), vio_seconds(num_workers),
      ransac_seconds(num_workers);
  DescriptorMatchingOptions matching = options.matching;
  matching.num_threads = 1;
  GuidedMatchingOptions guided;
  guided.matching = matching;
  guided.max_epipolar_distance_px = options.guided_band_px;
  const Rigid3d& body_from_cam = sequence.rig.body_from_cam;

  // For on_verified: the earliest stamp among the frames of pairs[k..].
  std::vector<timestamp_ns_t> pending_from_ns(pairs.size() + 1,
                                              std::numeric_limits<timestamp_ns_t>::max());
  for (size_t k = pairs.size(); k-- > 0;) {
    pending_from_ns[k] =
        std::min({pending_from_ns[k + 1], images[index_by_id.at(pairs[k].image_id1)].timestamp_ns,
                  images[index_by_id.at(pairs[k].image_id2)].timestamp_ns});
  }

  ProgressBar progress(
      "verifying pairs", static_cast<int64_t>(pairs.size()),
      options.show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
  std::unordered_map<image_t, ImageData> cache;
  result.decisions.reserve(pairs.size());
  for (size_t begin = 0; begin < pairs.size(); begin += options.batch_size) {
    const size_t end = std::min(pairs.size(), begin + static_cast<size_t>(options.batch_size));

    // Load the batch's features (kept from the previous batch where needed again).
    step_timer.Start();
    std::unordered_map<image_t, ImageNeeds> needed;
    for (size_t i = begin; i < end; ++i) {
      ImageNeeds& needs1 = needed[pairs[i].image_id1];
      ImageNeeds& needs2 = needed[pairs[i].image_id2];
      if (stored[i]) continue;
      const bool guided =
          options.guided_matching && HasVioPrior(images[index_by_id.at(pairs[i].image_id1)],
                                                 images[index_by_id.at(pairs[i].image_id2)]);
      for (ImageNeeds* needs : {&needs1, &needs2}) {
        needs->stored_descriptors = true;
        needs->normalised_descriptors |= !guided;
      }
    }
    for (auto it = cache.begin(); it != cache.end();) {
      it = needed.count(it->first) ? std::next(it) : cache.erase(it);
    }
    for (const auto& [image_id, needs] : needed) {
      ImageData& data = cache[image_id];
      const Camera& camera = cameras.at(images[index_by_id.at(image_id)].camera_id);
      if (data.points_normalized.empty()) {
        FeatureKeypoints keypoints = database->ReadKeypoints(image_id);
        CompensateRollingShutterRotation(camera, rolling_shutter.readout_s,
                                         images[index_by_id.at(image_id)].cam_angular_rate,
                                         &keypoints);
        data.points_normalized = UndistortKeypoints(camera, keypoints);
        if (options.guided_matching) {
          const Eigen::Matrix3d K = CalibrationMatrix(camera);
          data.points_px.reserve(data.points_normalized.size());
          for (const Eigen::Vector2d& x : data.points_normalized) {
            data.points_px.push_back((K * x.homogeneous()).hnormalized());
          }
        }
      }
      if (needs.stored_descriptors && !data.stored_descriptors) {
        data.stored_descriptors =
            std::make_shared<const FeatureDescriptors>(database->ReadDescriptors(image_id));
      }
      if (needs.normalised_descriptors && !data.descriptors) {
        data.descriptors = std::make_shared<const FloatDescriptors>(
            NormalizeDescriptors(*data.stored_descriptors));
      }
    }
    std::vector<PairWork> work(end - begin);
    for (size_t i = begin; i < end; ++i) {
      PairDecision& decision = work[i - begin].decision;
      const ImageInfo& info1 = images[index_by_id.at(pairs[i].image_id1)];
      const ImageInfo& info2 = images[index_by_id.at(pairs[i].image_id2)];
      decision.image_id1 = info1.image_id;
      decision.image_id2 = info2.image_id;
      decision.name1 = info1.name;
      decision.name2 = info2.name;
      decision.source = options.pairs.mode == PairMode::kTemporalRetrieval
                            ? (temporal_pairs.count(pairs[i]) ? "temporal" : "retrieval")
                            : PairModeName(options.pairs.mode);
      decision.has_vio_prior = HasVioPrior(info1, info2);
      if (stored[i] && options.reverify_stored_matches) {
        work[i - begin].reverified = true;
        work[i - begin].matches = database->ReadMatches(info1.image_id, info2.image_id);
        work[i - begin].had_geometry =
            database->ExistsTwoViewGeometry(info1.image_id, info2.image_id);
      } else if (stored[i]) {
        decision.resumed = true;
        work[i - begin].matches = database->ReadMatches(info1.image_id, info2.image_id);
        if (database->ExistsTwoViewGeometry(info1.image_id, info2.image_id)) {
          decision.num_inliers = static_cast<int>(
              database->ReadTwoViewGeometry(info1.image_id, info2.image_id).inlier_matches.size());
          decision.accepted = decision.num_inliers > 0;
        }
        if (!decision.accepted) decision.num_inliers = 0;
      }
    }
    summary.seconds_loading += step_timer.ElapsedSeconds();

    // Match and verify, in parallel over the batch's pairs.
    ParallelFor(static_cast<int64_t>(end - begin), options.num_threads, [&](int64_t k, int thread) {
      PairWork& pair_work = work[k];
      PairDecision& decision = pair_work.decision;
      const ImageInfo& info1 = images[index_by_id.at(decision.image_id1)];
      const ImageInfo& info2 = images[index_by_id.at(decision.image_id2)];
      const ImageData& data1 = cache.at(decision.image_id1);
      const ImageData& data2 = cache.at(decision.image_id2);
      const Camera& camera1 = cameras.at(info1.camera_id);
      const Camera& camera2 = cameras.at(info2.camera_id);
      Timer timer;
      // The VIO's relative pose, and with band_follows_drift its covariance
      // and the epipolar band its drift allows.
      Rigid3d cam2_from_cam1;
      std::optional<Eigen::Matrix<double, 6, 6>> covariance;
      double drift_band_px = options.prior.max_epipolar_error_px;
      if (decision.has_vio_prior) {
        cam2_from_cam1 = RelativePoseFromVio(*info1.world_from_body, *info2.world_from_body,
                                             body_from_cam, body_from_cam);
        if (options.band_follows_drift) {
          const VioSample frame1{info1.timestamp_ns, *info1.world_from_body * body_from_cam,
                                 info1.odometer};
          const VioSample frame2{info2.timestamp_ns, *info2.world_from_body * body_from_cam,
                                 info2.odometer};
          covariance = RelativePoseCovariance(options.vio_uncertainty, frame1, frame2);
          drift_band_px = DriftEpipolarBandPx(
              *covariance, cam2_from_cam1,
              0.5 * (MeanFocalLength(camera1) + MeanFocalLength(camera2)), options);
        }
        vio_seconds[thread] += timer.ElapsedSeconds();
        timer.Start();
      }
      if (!decision.resumed && !pair_work.reverified) {
        if (options.guided_matching && decision.has_vio_prior) {
          const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(
              cam2_from_cam1, CalibrationMatrix(camera1), CalibrationMatrix(camera2));
          // The band the VIO's drift allows, so that the two visits of a
          // loop keep their matches; step 1 then judges them under the fixed
          // T_EE, and under the corrected pose.
          GuidedMatchingOptions pair_guided = guided;
          pair_guided.max_epipolar_distance_px =
              std::max(options.guided_band_px, options.band_follows_drift ? drift_band_px : 0.0);
          decision.guided_band_px = pair_guided.max_epipolar_distance_px;
          pair_work.matches =
              MatchDescriptorsGuided(*data1.stored_descriptors, *data2.stored_descriptors,
                                     data1.points_px, data2.points_px, fundamental, pair_guided);
        } else {
          pair_work.matches = MatchDescriptors(*data1.descriptors, *data2.descriptors, matching);
        }
        matching_seconds[thread] += timer.ElapsedSeconds();
      }
      const FeatureMatches& matches = pair_work.matches;
      decision.num_matches = static_cast<int>(matches.size());
      std::vector<bool> depth_inconsistent;  // per match (with the depth check)

      // Step 1: the VIO prior.
      if (decision.has_vio_prior && !matches.empty()) {
        timer.Start();
        PriorVerificationOptions prior = options.prior;
        if (covariance && !options.correct_within_drift) {
          prior.max_epipolar_error_px = drift_band_px;
        }
        decision.vio_band_px = prior.max_epipolar_error_px;
        PriorVerificationResult check =
            VerifyPairWithPrior(camera1, camera2, cam2_from_cam1, data1.points_normalized,
                                data2.points_normalized, matches, prior);
        // A pair the VIO's pose does not explain: judged again under the pose
        // its matches show, if that is within the VIO's drift.
        if (covariance && options.correct_within_drift && !check.accepted && !check.rotation_only) {
          const DriftCorrection correction = CorrectRelativePoseWithinDrift(
              camera1, camera2, cam2_from_cam1, *covariance, data1.points_normalized,
              data2.points_normalized, matches, drift_band_px, options.max_correction_sigmas,
              prior);
          decision.vio_correction_sigmas = correction.mahalanobis;
          if (correction.corrected) {
            decision.vio_corrected = true;
            check = VerifyPairWithPrior(camera1, camera2, correction.cam2_from_cam1,
                                        data1.points_normalized, data2.points_normalized, matches,
                                        prior);
          }
        }
        decision.vio_outlier_ratio = check.outlier_ratio;
        decision.vio_rotation_only = check.rotation_only;
        decision.vio_depth_applied = check.depth_applied;
        decision.vio_depth_inconsistent_ratio = check.depth_inconsistent_ratio;
        decision.vio_depth_rejected = check.depth_rejected;
        decision.vio_rejected = !check.accepted;
        depth_inconsistent = check.depth_inconsistent;
        vio_seconds[thread] += timer.ElapsedSeconds();
      }
      if (decision.resumed && decision.accepted) {
        // The stored geometry is the decision.
        decision.vio_rejected = false;
        decision.reason = kPairAccepted;
        return;
      }
      // A stored pair without a geometry was rejected: decided again below
      // from its stored matches (the same steps with the same seed, so the
      // same decision, inlier count and reason as when it was stored).
      if (matches.empty()) {
        decision.reason = kPairNoMatches;
        return;
      }
      if (decision.vio_rejected) {
        decision.reason = decision.vio_depth_rejected ? kPairVioDepth : kPairVioOutlierRatio;
        return;
      }

      // Beyond the paper: the depth-inconsistent matches (impossible under
      // the VIO pose) do not enter RANSAC.
      const FeatureMatches* ransac_matches = &matches;
      FeatureMatches consistent;
      if (decision.has_vio_prior && decision.vio_depth_applied) {
        for (size_t m = 0; m < matches.size(); ++m) {
          if (!depth_inconsistent[m]) consistent.push_back(matches[m]);
        }
        ransac_matches = &consistent;
      }

      // Step 2: RANSAC.
      timer.Start();
      TwoViewGeometryOptions geometry = options.geometry;
      geometry.seed =
          MixSeed64(options.seed, ImagePairToPairId(decision.image_id1, decision.image_id2));
      const TwoViewGeometryResult estimate =
          EstimateCalibratedTwoViewGeometry(data1.points_normalized, data2.points_normalized,
                                            *ransac_matches, camera1, camera2, geometry);
      ransac_seconds[thread] += timer.ElapsedSeconds();
      decision.num_inliers = estimate.num_inliers();
      decision.accepted = estimate.accepted();
      decision.reason = decision.accepted ? kPairAccepted : kPairTooFewInliers;
      if (decision.accepted) pair_work.geometry = estimate.ToTwoViewGeometry();
    });

    // Store: matches and geometry of a pair together.
    step_timer.Start();
    std::vector<ImagePairMatches> accepted;
    for (PairWork& pair_work : work) {
      const PairDecision& decision = pair_work.decision;
      if (on_verified && decision.accepted) {
        accepted.push_back(
            {decision.image_id1, decision.image_id2,
             pair_work.geometry
                 ? pair_work.geometry->inlier_matches
                 : database->ReadTwoViewGeometry(decision.image_id1, decision.image_id2)
                       .inlier_matches});
      }
      // A resumed pair is written again only if it is now accepted without
      // a stored geometry (it cannot be with the options it was stored with,
      // which the caller keeps; the database then holds what the decision says).
      if (!decision.resumed || pair_work.geometry) {
        ColmapDatabase::Transaction transaction(*database);
        if (!pair_work.reverified && !decision.resumed) {
          database->WriteMatches(decision.image_id1, decision.image_id2, pair_work.matches);
        }
        if (pair_work.geometry) {
          database->WriteTwoViewGeometry(decision.image_id1, decision.image_id2,
                                         *pair_work.geometry);
        } else if (pair_work.had_geometry) {
          // Now rejected: no inliers (as COLMAP records a failed pair).
          database->WriteTwoViewGeometry(decision.image_id1, decision.image_id2, TwoViewGeometry());
        }
        if (pair_work.reverified) ++summary.num_reverified;
        transaction.Commit();
      }
      result.decisions.push_back(std::move(pair_work.decision));
    }
    summary.seconds_writing += step_timer.ElapsedSeconds();
    if (on_verified) on_verified(std::move(accepted), pending_from_ns[end]);
    progress.Update(static_cast<int64_t>(end - begin));
  }
  progress.Finish();

  for (const PairDecision& decision : result.decisions) {
    if (!decision.has_vio_prior) ++summary.num_pairs_without_prior;
    if (decision.resumed) ++summary.num_resumed;
    if (decision.accepted) {
      ++summary.num_accepted;
      if (decision.vio_corrected) ++summary.num_accepted_corrected;
    } else if (decision.reason == kPairNoMatches) {
      ++summary.num_no_matches;
    } else if (decision.vio_rejected) {
      ++summary.num_vio_rejected;
      if (decision.vio_depth_rejected) ++summary.num_vio_depth_rejected;
    } else {
      ++summary.num_ransac_rejected;
    }
  }
  for (int t = 0; t < num_workers; ++t) {
    summary.seconds_matching += matching_seconds[t];
    summary.seconds_vio += vio_seconds[t];
    summary.seconds_ransac += ransac_seconds[t];
  }
  summary.seconds_total = total_timer.ElapsedSeconds();
  VIOSFM_LOG(INFO) << "verification: " << FormatVerificationSummary(summary);
  return result;
}

}  // namespace viosfm
