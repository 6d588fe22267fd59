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
#include "viosfm/matching/pair_decider.h"
#include "viosfm/matching/pair_verification.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// What a batch needs of an image: nothing beyond its keypoints (stored
// pairs only), its stored descriptors (guided matching), or also the
// normalised ones (brute-force matching).
struct ImageNeeds {
  bool stored_descriptors = false;
  bool normalised_descriptors = false;
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

std::string FormatVerificationHeadline(const VerificationSummary& s) {
  std::ostringstream out;
  out << s.num_accepted << " of " << s.num_pairs
      << " pairs accepted; rejected: " << s.num_vio_rejected << " by the VIO, "
      << s.num_ransac_rejected << " by RANSAC, " << s.num_no_matches << " without matches";
  return out.str();
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
      << s.seconds_pair_generation << " s, loading " << s.seconds_loading
      << " s, matching, verifying and storing " << s.seconds_deciding
      << " s; thread-seconds: matching " << s.seconds_matching << ", VIO " << s.seconds_vio
      << ", RANSAC " << s.seconds_ransac << ")";
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

namespace {

// The database's images that belong to the sequence, in time order, with
// their VIO poses and the camera's angular rates (a rolling shutter).
std::vector<PairImage> ReadPairImages(const Sequence& sequence,
                                      const std::vector<std::optional<FrameVioPose>>& frame_poses,
                                      ColmapDatabase* database, const VerificationOptions& options,
                                      const FrameRollingShutter& rolling_shutter) {
  std::unordered_map<std::string, size_t> frame_by_name;
  for (size_t i = 0; i < sequence.images.size(); ++i) {
    frame_by_name.emplace(DatabaseImageName(sequence.images[i]), i);
  }
  std::vector<PairImage> images;
  for (const DatabaseImage& row : database->ReadAllImages()) {
    const auto it = frame_by_name.find(row.name);
    if (it == frame_by_name.end()) continue;
    if (!database->ExistsFeatures(row.image_id)) {
      throw InputError(database->path().string(), 0,
                       "image '" + row.name +
                           "' has no keypoints/descriptors (run `viosfm "
                           "features` first)");
    }
    PairImage info;
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
            [](const PairImage& a, const PairImage& b) { return a.timestamp_ns < b.timestamp_ns; });
  return images;
}

// The candidate pairs of the images (in time order), and which of them are
// temporal neighbours.
struct CandidatePairs {
  std::vector<ImagePair> pairs;
  std::set<ImagePair> temporal;
};

CandidatePairs GenerateCandidatePairs(const std::vector<PairImage>& images,
                                      ColmapDatabase* database,
                                      const VerificationOptions& options) {
  CandidatePairs candidates;
  PairGeneratorInput input;
  for (const PairImage& info : images) input.images.push_back({info.image_id, info.timestamp_ns});
  const int n1 = options.pairs.num_temporal_neighbors;
  const int n2 = options.pairs.num_retrieval_neighbors;
  if (options.pairs.mode == PairMode::kTemporalRetrieval) {
    std::vector<std::vector<image_t>> exclude(images.size());
    for (size_t k = 0; k < images.size(); ++k) {
      for (const size_t j : TemporalNeighbors(input.images, k, n1)) {
        exclude[k].push_back(images[j].image_id);
        candidates.temporal.insert(ImagePair::Ordered(images[k].image_id, images[j].image_id));
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
      for (const PairImage& info : images) ids.push_back(info.image_id);
      const DescriptorLoader load = [&](size_t index) {
        return database->ReadDescriptors(ids[index]);
      };
      input.retrieval = RetrieveSimilarImages(ids, load, exclude, retrieval);
    }
  }
  candidates.pairs = GeneratePairs(input, options.pairs);
  return candidates;
}

// The images of the pairs being verified with their features, read from
// the database a batch at a time (kept from one batch to the next where
// needed again).
class BatchImages {
 public:
  BatchImages(const std::vector<PairImage>& images, ColmapDatabase* database,
              const VerificationOptions& options, const FrameRollingShutter& rolling_shutter)
      : images_(images), database_(database), options_(options), rolling_shutter_(rolling_shutter) {
    for (size_t k = 0; k < images.size(); ++k) index_by_id_[images[k].image_id] = k;
    for (const PairImage& info : images) {
      if (!cameras_.count(info.camera_id)) {
        cameras_.emplace(info.camera_id, database->ReadCamera(info.camera_id));
      }
    }
  }

  const PairImage& Info(image_t image_id) const { return images_[index_by_id_.at(image_id)]; }
  const Camera& camera(camera_t camera_id) const { return cameras_.at(camera_id); }
  const PairImage& Loaded(image_t image_id) const { return cache_.at(image_id); }

  // Pairs [begin, end)'s images loaded with what their matching needs:
  // keypoints only for stored pairs, the stored descriptors for guided
  // matching, the normalised ones too for brute-force matching.
  void Load(const std::vector<ImagePair>& pairs, size_t begin, size_t end,
            const std::vector<bool>& stored) {
    std::unordered_map<image_t, ImageNeeds> needed;
    for (size_t i = begin; i < end; ++i) {
      ImageNeeds& needs1 = needed[pairs[i].image_id1];
      ImageNeeds& needs2 = needed[pairs[i].image_id2];
      if (stored[i]) continue;
      const bool guided = options_.guided_matching &&
                          HasVioPrior(Info(pairs[i].image_id1), Info(pairs[i].image_id2));
      for (ImageNeeds* needs : {&needs1, &needs2}) {
        needs->stored_descriptors = true;
        needs->normalised_descriptors |= !guided;
      }
    }
    for (auto it = cache_.begin(); it != cache_.end();) {
      it = needed.count(it->first) ? std::next(it) : cache_.erase(it);
    }
    for (const auto& [image_id, needs] : needed) {
      const auto [entry, inserted] = cache_.try_emplace(image_id);
      PairImage& data = entry->second;
      const PairImage& info = Info(image_id);
      if (inserted) {
        data = info;
        SetPairImageKeypoints(cameras_.at(info.camera_id), database_->ReadKeypoints(image_id),
                              rolling_shutter_.readout_s, options_.guided_matching, &data);
      }
      if (needs.stored_descriptors && !data.stored_descriptors) {
        data.stored_descriptors =
            std::make_shared<const FeatureDescriptors>(database_->ReadDescriptors(image_id));
      }
      if (needs.normalised_descriptors && !data.descriptors) {
        data.descriptors = std::make_shared<const FloatDescriptors>(
            NormalizeDescriptors(*data.stored_descriptors));
      }
    }
  }

 private:
  const std::vector<PairImage>& images_;
  ColmapDatabase* database_;
  const VerificationOptions& options_;
  const FrameRollingShutter& rolling_shutter_;
  std::unordered_map<image_t, size_t> index_by_id_;
  std::map<camera_t, Camera> cameras_;
  std::unordered_map<image_t, PairImage> cache_;
};

// The decider's counts and times into the run's summary.
void TakeDecisionCounts(const VerificationSummary& counts, VerificationSummary* summary) {
  summary->num_resumed = counts.num_resumed;
  summary->num_reverified = counts.num_reverified;
  summary->num_pairs_without_prior = counts.num_pairs_without_prior;
  summary->num_no_matches = counts.num_no_matches;
  summary->num_vio_rejected = counts.num_vio_rejected;
  summary->num_vio_depth_rejected = counts.num_vio_depth_rejected;
  summary->num_accepted_corrected = counts.num_accepted_corrected;
  summary->num_ransac_rejected = counts.num_ransac_rejected;
  summary->num_accepted = counts.num_accepted;
  summary->seconds_matching = counts.seconds_matching;
  summary->seconds_vio = counts.seconds_vio;
  summary->seconds_ransac = counts.seconds_ransac;
}

}  // namespace

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
  summary.database_path = database->path().string();

  // Images: the database's images that belong to the sequence, in time order.
  Timer step_timer;
  const std::vector<PairImage> images =
      ReadPairImages(sequence, frame_poses, database, options, rolling_shutter);
  summary.num_images = images.size();
  bool any_prior = false;
  for (const std::optional<FrameVioPose>& pose : frame_poses) any_prior = any_prior || pose;
  const bool use_prior = options.use_vio_prior && any_prior;
  for (const PairImage& info : images) {
    if (info.world_from_body) ++summary.num_images_with_prior;
  }
  if (use_prior && summary.num_images_with_prior < images.size()) {
    VIOSFM_LOG(WARNING) << "verification: " << images.size() - summary.num_images_with_prior
                        << " of " << images.size() << " images have no VIO pose within "
                        << FormatNsAsSeconds(options.max_pose_time_difference_ns, 3)
                        << " s; their pairs are verified by RANSAC only";
  }
  BatchImages batch_images(images, database, options, rolling_shutter);

  // Pairs.
  const CandidatePairs candidates = GenerateCandidatePairs(images, database, options);
  const std::vector<ImagePair>& pairs = candidates.pairs;
  summary.seconds_pair_generation = step_timer.ElapsedSeconds();
  summary.num_pairs = pairs.size();
  VIOSFM_LOG(INFO) << "verification: " << pairs.size() << " pairs of " << images.size()
                   << " images (" << PairModeName(options.pairs.mode) << ", "
                   << (use_prior ? "VIO prior + RANSAC" : "RANSAC only") << ")";

  PairDecider decider(options, sequence.rig.body_from_cam, database);
  std::vector<bool> stored(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    stored[i] = decider.IsStored(pairs[i].image_id1, pairs[i].image_id2);
  }

  // For on_verified: the earliest stamp among the frames of pairs[k..].
  std::vector<timestamp_ns_t> pending_from_ns(pairs.size() + 1,
                                              std::numeric_limits<timestamp_ns_t>::max());
  for (size_t k = pairs.size(); k-- > 0;) {
    pending_from_ns[k] =
        std::min({pending_from_ns[k + 1], batch_images.Info(pairs[k].image_id1).timestamp_ns,
                  batch_images.Info(pairs[k].image_id2).timestamp_ns});
  }

  ProgressBar progress(
      "verifying pairs", static_cast<int64_t>(pairs.size()),
      options.show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
  for (size_t begin = 0; begin < pairs.size(); begin += options.batch_size) {
    const size_t end = std::min(pairs.size(), begin + static_cast<size_t>(options.batch_size));

    // Load the batch's features.
    step_timer.Start();
    batch_images.Load(pairs, begin, end, stored);
    std::vector<PairToDecide> batch;
    for (size_t i = begin; i < end; ++i) {
      const PairImage& image1 = batch_images.Loaded(pairs[i].image_id1);
      const PairImage& image2 = batch_images.Loaded(pairs[i].image_id2);
      const std::string source =
          options.pairs.mode == PairMode::kTemporalRetrieval
              ? (candidates.temporal.count(pairs[i]) ? "temporal" : "retrieval")
              : PairModeName(options.pairs.mode);
      batch.push_back({&image1, &image2, &batch_images.camera(image1.camera_id),
                       &batch_images.camera(image2.camera_id), source});
    }
    summary.seconds_loading += step_timer.ElapsedSeconds();

    // Match, verify (in parallel over the batch's pairs) and store.
    step_timer.Start();
    std::vector<ImagePairMatches> accepted = decider.Decide(batch);
    summary.seconds_deciding += step_timer.ElapsedSeconds();
    if (on_verified) on_verified(std::move(accepted), pending_from_ns[end]);
    progress.Update(static_cast<int64_t>(end - begin));
  }
  progress.Finish();

  VerificationResult decided = decider.TakeResult();
  result.decisions = std::move(decided.decisions);
  TakeDecisionCounts(decided.summary, &summary);
  summary.seconds_total = total_timer.ElapsedSeconds();
  VIOSFM_LOG(INFO) << "verification: " << FormatVerificationHeadline(summary) << LogDetails()
                   << " (" << FormatVerificationSummary(summary) << ")";
  return result;
}

}  // namespace viosfm
