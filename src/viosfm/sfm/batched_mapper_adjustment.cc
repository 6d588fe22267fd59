// The batched mapper's adjustments (batched_mapper.h): the per-batch and the
// global bundle adjustments with the VIO's priors, the gyro's rotations, the
// IMU's factors and the VIO's drift states, and the filtering and
// re-triangulation after them.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "viosfm/scene/reprojection.h"
#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sfm/ba_problem_structure.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/imu_scale.h"
#include "viosfm/sfm/vio_drift_terms.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

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

// The median of each coordinate.
Eigen::Vector3d MedianOf(const std::vector<Eigen::Vector3d>& vectors) {
  Eigen::Vector3d median = Eigen::Vector3d::Zero();
  if (vectors.empty()) return median;
  for (int d = 0; d < 3; ++d) {
    std::vector<double> values;
    for (const Eigen::Vector3d& vector : vectors) values.push_back(vector[d]);
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    median[d] = values[values.size() / 2];
  }
  return median;
}

// The registered frames' poses, the points and the cameras of a model, to
// put back.
class ModelSnapshot {
 public:
  explicit ModelSnapshot(const Reconstruction& reconstruction)
      : cameras_(reconstruction.Cameras()) {
    for (const auto& [image_id, image] : reconstruction.Images()) {
      if (image.registered) poses_.emplace_back(image_id, image.cam_from_world);
    }
    for (const auto& [point_id, point] : reconstruction.Points3D()) {
      points_.emplace_back(point_id, point.xyz);
    }
  }
  void Restore(Reconstruction* reconstruction) const {
    for (const auto& [image_id, pose] : poses_) {
      reconstruction->GetImage(image_id).cam_from_world = pose;
    }
    for (const auto& [point_id, xyz] : points_) {
      if (reconstruction->ExistsPoint3D(point_id)) reconstruction->GetPoint3D(point_id).xyz = xyz;
    }
    for (const auto& [camera_id, camera] : cameras_) reconstruction->GetCamera(camera_id) = camera;
  }

 private:
  std::vector<std::pair<image_t, Rigid3d>> poses_;
  std::vector<std::pair<point3D_t, Eigen::Vector3d>> points_;
  std::unordered_map<camera_t, Camera> cameras_;
};

}  // namespace

BaLinearSolver BatchedMapper::ChooseLinearSolver(const std::vector<image_t>& free_images,
                                                 bool global) {
  if (!global || ba_options_.linear_solver != BaLinearSolver::kAuto) {
    return solver_chooser_.Next(free_images.size(), global);
  }
  // The final adjustment: by the work of the reduced camera matrix's
  // factorisation (linear_solver_chooser.h).
  const BaProblemStructure structure =
      ComputeBaProblemStructure(core_.reconstruction(), free_images, /*with_factorization=*/true);
  const BaLinearSolver solver = solver_chooser_.Next(structure, /*final=*/true);
  VIOSFM_LOG(INFO) << "final bundle adjustment: " << structure.num_free_images << " images, "
                   << OptionText(solver) << LogDetails() << "; factorisation work per image "
                   << structure.FactorizationPerImage() << " (per observation "
                   << structure.FactorizationPerObservation() << ")";
  return solver;
}

std::vector<RelativePosePrior> BatchedMapper::ActivePriors(bool with_bridging) const {
  // The priors not crossing a VIO jump found so far.
  std::vector<int> breaks_before(num_images_ + 1, 0);
  for (size_t k = 0; k < num_images_; ++k) breaks_before[k + 1] = breaks_before[k] + is_break_[k];
  std::vector<RelativePosePrior> active;
  for (size_t p = 0; p < all_priors_.priors.size(); ++p) {
    const auto [i, j] = all_priors_.frame_indices[p];
    if (!with_bridging && all_priors_.bridging[p]) continue;
    if (breaks_before[j + 1] - breaks_before[i + 1] == 0) active.push_back(all_priors_.priors[p]);
  }
  return active;
}

void BatchedMapper::CompensateRollingShutter(bool global) {
  // The rolling shutter's translation share, compensated before every
  // adjustment for the observations of points not compensated yet.
  if (input_.rolling_shutter_readout_s <= 0.0) return;
  std::vector<std::pair<timestamp_ns_t, image_t>> stamped;
  for (const image_t image_id : MainRegistered()) {
    stamped.emplace_back(images()[core_.FrameIndex(image_id)].timestamp_ns, image_id);
  }
  CompensateRollingShutterMotion(&core_.reconstruction(), std::move(stamped),
                                 input_.rolling_shutter_readout_s, kVelocityMaxGapNs,
                                 &rolling_shutter_moved_, &rolling_shutter_moves_);
  if (!global) return;
  std::vector<float> lengths = rolling_shutter_moves_;
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
  summary_.rolling_shutter_message = message.str();
  VIOSFM_LOG(INFO) << "final bundle adjustment: " << summary_.rolling_shutter_message;
}

std::vector<GyroFrame> BatchedMapper::GyroFramesOfMainModel() const {
  // The main model's frames in time order, each marked whether the images
  // support it (a frame placed by the VIO alone turns with its drift).
  std::vector<GyroFrame> frames;
  const Reconstruction& reconstruction = core_.reconstruction();
  for (const image_t image_id : MainRegistered()) {
    frames.push_back({image_id, images()[core_.FrameIndex(image_id)].timestamp_ns,
                      reconstruction.GetImage(image_id).cam_from_world,
                      CountSupportingObservations(reconstruction, image_id,
                                                  registration_.support_max_error_px) >=
                          registration_.min_supporting_observations});
  }
  std::sort(frames.begin(), frames.end(),
            [](const GyroFrame& a, const GyroFrame& b) { return a.timestamp_ns < b.timestamp_ns; });
  return frames;
}

std::unique_ptr<InertialTerms> BatchedMapper::MakeInertialTerms(
    const GyroPriors& gyro, const std::vector<GyroFrame>& frames) {
  // The IMU's factors, started from the gyro priors' bias fit (the median
  // of its windows').
  std::vector<InertialFrame> inertial_frames;
  for (const GyroFrame& frame : frames) {
    inertial_frames.push_back({frame.image_id, frame.timestamp_ns, frame.cam_from_world});
  }
  auto terms = std::make_unique<InertialTerms>(inertial_frames, input_.imu, input_.rig,
                                               MedianOf(gyro.gyro_biases), options_.inertial);
  if (terms->Initialise(options_.num_threads, inertial_sigma_floor_)) {
    inertial_sigma_floor_ = terms->sigma_factor();
    summary_.num_inertial_factors = terms->num_factors();
    VIOSFM_LOG(INFO) << "final bundle adjustment: " << terms->num_factors() << " IMU factors"
                     << LogDetails() << "; before it, " << terms->Message();
    return terms;
  }
  summary_.inertial_message = terms->Message();
  VIOSFM_LOG(INFO) << "final bundle adjustment: the gyro's priors instead of IMU factors"
                   << LogDetails() << ": " << summary_.inertial_message;
  inertial_declined_ = true;
  return nullptr;
}

void BatchedMapper::AlignMainModelToImu() {
  // A model the images alone made has the scale and frame of its initial
  // pair: the IMU gives it gravity's direction and a metric scale before its
  // IMU factors refine both (inertial_terms.h).
  imu_aligned_ = true;
  std::vector<image_t> registered = MainRegistered();
  Reconstruction& reconstruction = core_.reconstruction();
  const Rigid3d cam_from_body = input_.rig.body_from_cam.Inverse();
  const auto body_trajectory = [&]() {
    Trajectory body;
    for (const image_t image_id : registered) {
      const Image& image = reconstruction.GetImage(image_id);
      body.poses.push_back({input_.rig.CamToImuTime(*image.timestamp_ns),
                            image.cam_from_world.Inverse() * cam_from_body});
    }
    std::sort(body.poses.begin(), body.poses.end(), [](const StampedPose& a, const StampedPose& b) {
      return a.timestamp_ns < b.timestamp_ns;
    });
    return body;
  };
  Trajectory body = body_trajectory();
  if (body.size() < 4) return;
  // Up at first: the specific force averaged over the recording, each
  // sample turned by the nearest frame's rotation (the motion's own
  // accelerations average out over seconds; gravity does not).
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  size_t k = 0;
  for (const ImuSample& sample : input_.imu) {
    while (k + 1 < body.size() && std::abs(body.poses[k + 1].timestamp_ns - sample.timestamp_ns) <=
                                      std::abs(body.poses[k].timestamp_ns - sample.timestamp_ns)) {
      ++k;
    }
    if (std::abs(body.poses[k].timestamp_ns - sample.timestamp_ns) > 500'000'000) continue;
    up += body.poses[k].world_from_frame.rotation * sample.accel;
  }
  if (!(up.norm() > 0.0)) return;
  TransformFrames(Sim3d(1.0, Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ()),
                        Eigen::Vector3d::Zero()),
                  registered, &reconstruction);
  ImuScaleOptions scale_options;
  scale_options.max_scale_factor = 1e12;
  const ImuScaleResult fit =
      EstimateImuScale(body_trajectory(), input_.imu, input_.rig.imu_noise, scale_options);
  std::ostringstream message;
  if (!(fit.scale > 0.0) || !(fit.scale_sigma < 0.2) || !(fit.gravity_in_world.norm() > 0.0)) {
    message << "the IMU could not scale the images' model (" << fit.message
            << "): it keeps the scale of its initial pair";
    summary_.imu_alignment_message = message.str();
    VIOSFM_LOG(WARNING) << "batched mapper: " << summary_.imu_alignment_message;
    return;
  }
  const Eigen::Quaterniond level = Eigen::Quaterniond::FromTwoVectors(
      fit.gravity_in_world.normalized(), -Eigen::Vector3d::UnitZ());
  TransformFrames(Sim3d(fit.scale, level, Eigen::Vector3d::Zero()), registered, &reconstruction);
  message << std::setprecision(4) << "the images' model scaled by " << fit.scale << " (+- "
          << 100.0 * fit.scale_sigma << " %) and levelled with the IMU's gravity before its "
          << "IMU factors";
  summary_.imu_alignment_message = message.str();
  VIOSFM_LOG(INFO) << "batched mapper: " << summary_.imu_alignment_message;
}

std::unique_ptr<VioDriftTerms> BatchedMapper::MakeDriftTerms(
    bool global, std::vector<RelativePosePrior>* priors) const {
  // The final adjustment with the VIO's drift states in place of its
  // consecutive priors (vio_drift_terms.h).
  if (!global || !options_.vio_drift_states || !ba_options_.use_relative_pose_priors ||
      ba_options_.prior_weighting != PriorWeighting::kCovariance) {
    return nullptr;
  }
  std::vector<VioDriftFrame> frames;
  std::vector<VioDriftLink> links;
  std::unordered_map<image_t, size_t> frame_of_image;
  const auto frame_index = [&](image_t image_id) {
    const auto [it, inserted] = frame_of_image.emplace(image_id, frames.size());
    if (inserted) {
      frames.push_back({image_id, VioSampleOfImage(images()[core_.FrameIndex(image_id)])});
    }
    return it->second;
  };
  std::vector<RelativePosePrior> kept;
  for (const RelativePosePrior& prior : *priors) {
    if (prior.from_gyro ||
        consecutive_pairs_.count(ImagePairToPairId(prior.image_id1, prior.image_id2)) == 0) {
      kept.push_back(prior);
      continue;
    }
    const size_t first = frame_index(prior.image_id1);
    const size_t second = frame_index(prior.image_id2);
    links.push_back({first, second, prior.num_verified_matches});
  }
  if (links.empty()) return nullptr;
  *priors = std::move(kept);
  VioDriftTermsOptions drift_options;
  drift_options.vio_uncertainty = options_.vio_uncertainty;
  drift_options.prior_beta = ba_options_.prior_beta;
  drift_options.prior_loss_scale = ba_options_.prior_loss_scale;
  drift_options.image_noise_px = ba_options_.image_noise_px;
  return std::make_unique<VioDriftTerms>(std::move(frames), std::move(links), drift_options);
}

BundleAdjustmentSummary BatchedMapper::Adjust(size_t window_begin, bool global) {
  // Bundle adjustment of the main model's last registered frames (all when
  // window_begin is 0), its gauge held.
  BundleAdjustmentSummary ba_summary;
  if (!MainModelHasGauge()) return ba_summary;
  if (global && !core_.model(0).vio_anchored && !imu_aligned_ && !input_.imu.empty() &&
      options_.inertial.enabled) {
    AlignMainModelToImu();
  }
  Reconstruction& reconstruction = core_.reconstruction();
  const std::vector<image_t>& registered = MainRegistered();
  const image_t gauge = core_.model(0).gauge_image;
  const std::vector<image_t> free_images(registered.begin() + window_begin, registered.end());
  const image_t held_neighbour = window_begin > 0 ? registered[window_begin - 1] : kInvalidImageId;
  BundleAdjustmentOptions batch_ba_options = ba_options_;
  // The first per-batch adjustment (no earlier one refined any pose) may
  // run uncapped.
  const bool first_adjustment = num_batch_adjustments_++ == 0;
  if (!global && options_.batch_ba_max_num_iterations > 0 &&
      !(first_adjustment && options_.converge_first_batch_ba)) {
    batch_ba_options.max_num_iterations = options_.batch_ba_max_num_iterations;
  }
  batch_ba_options.linear_solver = ChooseLinearSolver(free_images, global);
  CompensateRollingShutter(global);
  std::vector<RelativePosePrior> priors = ActivePriors(/*with_bridging=*/true);
  std::optional<GyroPriors> gyro_priors;
  std::unique_ptr<InertialTerms> inertial_terms;
  if (global && options_.gyro.enabled && !input_.imu.empty()) {
    // The gyro's relative rotations between consecutive registered frames,
    // with the biases the current rotations give (gyro_priors.h).
    const std::vector<GyroFrame> frames = GyroFramesOfMainModel();
    gyro_priors = MakeGyroPriors(frames, input_.imu, input_.rig, options_.gyro, gyro_sigma_floor_);
    gyro_sigma_floor_ = gyro_priors->sigma_factor;
    if (options_.inertial.enabled && (ba_options_.use_relative_pose_priors || imu_aligned_) &&
        !inertial_declined_) {
      inertial_terms = MakeInertialTerms(*gyro_priors, frames);
      // The IMU holds the stretches the images barely see, where the
      // bridging priors carried the VIO's drift over seconds: they leave the
      // final adjustment (the per-batch adjustments keep them).
      if (inertial_terms) priors = ActivePriors(/*with_bridging=*/false);
    }
  }
  // The gyro's priors with the bridging priors, where the IMU's factors are
  // not used.
  const auto use_gyro_priors = [&]() {
    summary_.num_gyro_priors = static_cast<int>(gyro_priors->priors.size());
    summary_.gyro_message = gyro_priors->message;
    VIOSFM_LOG(INFO) << "final bundle adjustment: " << gyro_priors->priors.size()
                     << " gyro rotation priors" << LogDetails() << "; " << gyro_priors->message;
    priors = ActivePriors(/*with_bridging=*/true);
    priors.insert(priors.end(), gyro_priors->priors.begin(), gyro_priors->priors.end());
  };
  if (gyro_priors && inertial_terms == nullptr) use_gyro_priors();
  // What the factors' adjustment may have to undo (max_scale_change).
  std::optional<ModelSnapshot> before;
  if (inertial_terms != nullptr) before.emplace(reconstruction);
  std::unique_ptr<VioDriftTerms> drift_terms = MakeDriftTerms(global, &priors);
  CombinedTerms combined({inertial_terms.get(), drift_terms.get()});
  const int max_held_views = global ? 0 : options_.ba_window_max_held_views;
  ba_summary = core_.Adjust(free_images, held_neighbour, gauge, priors, batch_ba_options,
                            max_held_views, inertial_terms || drift_terms ? &combined : nullptr);
  if (drift_terms != nullptr) {
    VIOSFM_LOG(INFO) << "final bundle adjustment: the VIO as drift states ("
                     << drift_terms->num_frame_terms() << " frames, "
                     << drift_terms->num_drift_terms()
                     << " links) in place of its consecutive priors";
  }
  if (inertial_terms != nullptr && std::abs(std::log(inertial_terms->scale())) >
                                       std::log1p(options_.inertial.max_scale_change)) {
    // The factors took the model somewhere no VIO's scale error explains:
    // the rig is further from the IMU model than their start showed. The
    // adjustment again, from where it started, with the gyro's priors.
    std::ostringstream message;
    message << std::fixed << std::setprecision(5)
            << "the IMU factors put the model's metric scale at " << inertial_terms->scale()
            << ", further from 1 than max_scale_change " << options_.inertial.max_scale_change
            << ": dropped, the adjustment again with the gyro's priors";
    VIOSFM_LOG(WARNING) << "final bundle adjustment: " << message.str();
    before->Restore(&reconstruction);
    inertial_terms.reset();
    inertial_declined_ = true;
    summary_.num_inertial_factors = 0;
    summary_.inertial_message = message.str();
    use_gyro_priors();
    drift_terms = MakeDriftTerms(global, &priors);
    ba_summary = core_.Adjust(free_images, held_neighbour, gauge, priors, batch_ba_options,
                              max_held_views, drift_terms.get());
  }
  if (inertial_terms != nullptr) {
    summary_.inertial_scale = inertial_terms->scale();
    std::ostringstream message;
    message << inertial_terms->Message()
            << " (in place of the gyro's priors and the bridging priors); after it: scale "
            << std::fixed << std::setprecision(5) << inertial_terms->scale() << ", median "
            << std::setprecision(2) << inertial_terms->MedianWhitenedResidual(reconstruction)
            << " sigma";
    summary_.inertial_message = message.str();
    VIOSFM_LOG(INFO) << "final bundle adjustment: IMU factors: metric scale " << std::fixed
                     << std::setprecision(5) << inertial_terms->scale() << LogDetails() << "; "
                     << summary_.inertial_message;
  }
  solver_chooser_.Record(ba_summary, free_images.size());
  if (!ba_summary.usable && ba_summary.termination != "nothing to adjust") {
    VIOSFM_LOG(WARNING) << "bundle adjustment: " << ba_summary.ToString();
  }
  return ba_summary;
}

void BatchedMapper::AdjustOtherModels(bool global) {
  // The separate models, each with its own gauge held and the VIO's priors
  // among its frames.
  for (int m = 1; m < core_.NumModels(); ++m) {
    const IncrementalMapper::Model& model = core_.model(m);
    if (model.registered.size() < 2 || model.gauge_image == kInvalidImageId ||
        !core_.IsRegistered(core_.FrameIndex(model.gauge_image))) {
      continue;
    }
    BundleAdjustmentOptions options = ba_options_;
    if (!global && options_.batch_ba_max_num_iterations > 0) {
      options.max_num_iterations = options_.batch_ba_max_num_iterations;
    }
    core_.Adjust(model.registered, kInvalidImageId, model.gauge_image, ActivePriors(true), options,
                 0, nullptr);
  }
}

double BatchedMapper::FilterAndRetriangulateAll() {
  // Filters every point and re-triangulates every track; returns the share
  // of the main model's observations that changed: those it left without a
  // point plus those it attached that had none (one filtered out and put
  // back is no change: the adjustment had it).
  Reconstruction& reconstruction = core_.reconstruction();
  const ObservedKeypoints before(reconstruction, MainRegistered());
  FilterPoints(&reconstruction, options_.filter, options_.num_threads);
  changed_since_filter_.clear();
  all_changed_since_filter_ = false;
  if (options_.retriangulate) {
    core_.TriangulateAll();
    all_changed_since_filter_ = true;
  }
  return static_cast<double>(before.CountChanged(reconstruction)) /
         static_cast<double>(std::max<size_t>(1, reconstruction.ComputeNumObservations()));
}

std::vector<point3D_t> BatchedMapper::PointsToFilter(size_t window_begin) const {
  // The points a filtering after a windowed adjustment must check: those
  // the window's frames observe (the adjustment moved them or their
  // cameras) and those triangulated or extended since the last filtering.
  std::vector<point3D_t> point_ids;
  const std::vector<image_t>& registered = MainRegistered();
  for (size_t r = window_begin; r < registered.size(); ++r) {
    for (const Point2D& point2D : core_.reconstruction().GetImage(registered[r]).points2D) {
      if (point2D.HasPoint3D()) point_ids.push_back(point2D.point3D_id);
    }
  }
  point_ids.insert(point_ids.end(), changed_since_filter_.begin(), changed_since_filter_.end());
  std::sort(point_ids.begin(), point_ids.end());
  point_ids.erase(std::unique(point_ids.begin(), point_ids.end()), point_ids.end());
  return point_ids;
}

std::vector<image_t> BatchedMapper::WindowImages(size_t window_begin) const {
  const std::vector<image_t>& registered = MainRegistered();
  const size_t begin = std::min(window_begin, registered.size());
  return std::vector<image_t>(registered.begin() + static_cast<std::ptrdiff_t>(begin),
                              registered.end());
}

void BatchedMapper::FilterAndRetriangulateWindow(size_t window_begin) {
  Reconstruction& reconstruction = core_.reconstruction();
  if (all_changed_since_filter_) {
    FilterPoints(&reconstruction, options_.filter, options_.num_threads);
  } else {
    FilterPoints(&reconstruction, options_.filter, PointsToFilter(window_begin),
                 options_.num_threads);
  }
  changed_since_filter_.clear();
  all_changed_since_filter_ = false;
  if (!options_.retriangulate) return;
  std::vector<size_t> window_frames;
  for (const image_t image_id : WindowImages(window_begin)) {
    window_frames.push_back(core_.FrameIndex(image_id));
  }
  TriangulateTracksOf(window_frames);
}

}  // namespace viosfm
