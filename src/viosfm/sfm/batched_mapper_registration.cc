// The batched mapper's registration of a frame by the VIO's prediction,
// checked against the images (batched_mapper.h, frame_registration.h).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

// A VIO jump is refused where the frame's verified matches with the
// registered frames fit the VIO's pose more than this many times as often as
// the PnP pose (FrameRegistrationOptions; docs/history/benchmarks-2026.md "A look-alike
// place is not a VIO jump").
constexpr double kJumpRefutingMatchRatio = 2.0;

std::string Describe(const MapperImage& image) {
  std::ostringstream out;
  out << "image " << image.image_id << " (" << image.name << ")";
  return out.str();
}

}  // namespace

bool BatchedMapper::SameRun(size_t i, size_t j) const {
  if (!vio_poses_[i] || !vio_poses_[j] ||
      images()[i].vio_odometer.segment != images()[j].vio_odometer.segment) {
    return false;
  }
  for (size_t k = std::min(i, j) + 1; k <= std::max(i, j); ++k) {
    if (is_break_[k]) return false;
  }
  return true;
}

std::optional<size_t> BatchedMapper::FindReference(size_t i) const {
  // The registered frame nearest to i (earlier first) whose VIO pose chains to i's.
  for (size_t j = i; j-- > 0;) {
    if (!SameRun(i, j)) break;
    if (core_.IsRegistered(j)) return j;
  }
  for (size_t j = i + 1; j < num_images_; ++j) {
    if (!SameRun(i, j)) break;
    if (core_.IsRegistered(j)) return j;
  }
  return std::nullopt;
}

std::optional<Eigen::Vector3d> BatchedMapper::VioCamVelocity(size_t i) const {
  // From the VIO poses of its neighbours in the same VIO segment (the
  // rolling shutter's motion share at registration).
  if (!vio_poses_[i]) return std::nullopt;
  const auto neighbour = [&](size_t j) {
    return j < num_images_ && vio_poses_[j] &&
           images()[j].vio_odometer.segment == images()[i].vio_odometer.segment &&
           std::abs(images()[j].timestamp_ns - images()[i].timestamp_ns) <= kVelocityMaxGapNs;
  };
  const size_t before = i > 0 && neighbour(i - 1) ? i - 1 : i;
  const size_t after = neighbour(i + 1) ? i + 1 : i;
  if (before == after) return std::nullopt;
  const double span_s = NsToSeconds(images()[after].timestamp_ns - images()[before].timestamp_ns);
  return vio_poses_[i]->rotation *
         ((ProjectionCenter(*vio_poses_[after]) - ProjectionCenter(*vio_poses_[before])) / span_s);
}

bool BatchedMapper::BeyondVioDrift(size_t i, size_t reference, const Rigid3d& images_pose,
                                   const Rigid3d& vio_pose, double* position_difference,
                                   double* rotation_difference) const {
  const RelativePoseSigmas sigmas = LargestSigmas(
      RelativePoseCovariance(options_.vio_uncertainty, VioSampleOfImage(images()[reference]),
                             VioSampleOfImage(images()[i])));
  *position_difference = (ProjectionCenter(images_pose) - ProjectionCenter(vio_pose)).norm();
  *rotation_difference = images_pose.rotation.angularDistance(vio_pose.rotation);
  return *position_difference > registration_.break_sigmas * sigmas.translation_m +
                                    registration_.break_min_translation_m ||
         *rotation_difference > registration_.break_sigmas * sigmas.rotation_rad +
                                    registration_.break_min_rotation_rad;
}

void BatchedMapper::RegisterFrame(size_t i, int model, const Rigid3d& cam_from_world,
                                  FramePoseSource source) {
  core_.Register(i, model, cam_from_world);
  summary_.frames[i].source = source;
  newly_registered_.push_back(i);
}

void BatchedMapper::MoveToStamp(size_t i, const Rigid3d& predicted,
                                FrameCorrespondences* correspondences) const {
  // A rolling shutter's motion share: each observation moved to where the
  // predicted camera at the stamp sees its point (the points' depths from
  // the model, the velocity from the VIO).
  const std::optional<Eigen::Vector3d> velocity =
      input_.rolling_shutter_readout_s > 0.0 ? VioCamVelocity(i) : std::nullopt;
  if (!velocity) return;
  const Camera& camera = core_.reconstruction().GetCamera(images()[i].camera_id);
  for (size_t c = 0; c < correspondences->size(); ++c) {
    const Eigen::Vector3d in_cam = predicted * correspondences->points_in_world[c];
    const double offset_s =
        RowTimeOffset(CamToImage(camera, correspondences->points_normalized[c]).y(),
                      static_cast<int>(camera.height), input_.rolling_shutter_readout_s);
    const Eigen::Vector3d at_row = in_cam - *velocity * offset_s;
    if (in_cam.z() <= 0.0 || at_row.z() <= 0.0) continue;
    correspondences->points_normalized[c] += in_cam.hnormalized() - at_row.hnormalized();
  }
}

bool BatchedMapper::TryRegister(size_t i) {
  // Frames without a VIO pose are the images' alone (RegisterFromImages).
  if (!vio_poses_[i]) return false;
  MapperFrameStatus& status = summary_.frames[i];
  std::optional<Rigid3d> predicted;
  std::optional<size_t> reference;
  int model = -1;
  if (i == gauge_index_) {
    predicted = *vio_poses_[i];
    if (core_.NumModels() == 0) {
      core_.NewModel(/*vio_anchored=*/true);
      core_.SetGauge(0, images()[i].image_id);
    }
    model = 0;
  } else if ((reference = FindReference(i))) {
    model = core_.ModelOf(*reference);
    predicted = *vio_poses_[i] * vio_poses_[*reference]->Inverse() *
                core_.reconstruction().GetImage(images()[*reference].image_id).cam_from_world;
  }
  if (registration_.verify_with_images && i != gauge_index_) {
    const int against = predicted ? model : core_.BestModelFor(i).first;
    FrameCorrespondences correspondences =
        against >= 0 ? core_.Correspondences(i, against) : FrameCorrespondences();
    if (predicted) MoveToStamp(i, *predicted, &correspondences);
    status.num_correspondences = static_cast<int>(correspondences.size());
    if (static_cast<int>(correspondences.size()) >= registration_.min_num_correspondences) {
      const AbsolutePoseResult result = core_.EstimatePose(i, correspondences, predicted);
      status.num_predicted_inliers = static_cast<int>(result.num_predicted_inliers);
      status.num_pnp_inliers = result.success ? static_cast<int>(result.num_inliers) : 0;
      if (result.success && !predicted) {
        RegisterFrame(i, against, result.cam_from_world, FramePoseSource::kImagesWithoutVio);
        return true;
      }
      if (result.success) return RegisterAgainstPrediction(i, *reference, *predicted, result);
    }
  }
  if (predicted) {
    RegisterFrame(i, model, *predicted, FramePoseSource::kVio);
    return true;
  }
  return false;
}

bool BatchedMapper::RegisterAgainstPrediction(size_t i, size_t reference, const Rigid3d& predicted,
                                              const AbsolutePoseResult& result) {
  MapperFrameStatus& status = summary_.frames[i];
  const int model = core_.ModelOf(reference);
  const int pnp_inliers = static_cast<int>(result.num_inliers);
  const int predicted_inliers = static_cast<int>(result.num_predicted_inliers);
  const bool prediction_supported = predicted_inliers >= registration_.pnp.min_num_inliers;
  if (prediction_supported && static_cast<double>(predicted_inliers) >=
                                  registration_.min_predicted_inlier_ratio * pnp_inliers) {
    RegisterFrame(i, model, predicted, FramePoseSource::kVioVerified);
    return true;
  }
  // How far the images' pose is from the VIO's, against the drift the
  // model allows between the frame and its reference.
  double position_difference = 0.0, rotation_difference = 0.0;
  const bool beyond_drift = BeyondVioDrift(i, reference, result.cam_from_world, predicted,
                                           &position_difference, &rotation_difference);
  if (pnp_inliers >= registration_.min_reposing_inliers && !beyond_drift) {
    // The images refine a drifted prediction.
    RegisterFrame(i, model, result.cam_from_world, FramePoseSource::kImagesReposed);
    return true;
  }
  // The images do not support the VIO's pose at all and strongly support one
  // far beyond its drift: the VIO jumped, unless the frame's verified matches
  // with the registered frames clearly show the VIO's pose (JumpRefuted).
  if (!prediction_supported && beyond_drift &&
      pnp_inliers >= 2 * registration_.min_reposing_inliers &&
      !JumpRefuted(i, predicted, result, position_difference, rotation_difference)) {
    is_break_[std::max(i, reference)] = 1;
    status.vio_break = true;
    VIOSFM_LOG(INFO) << "batched mapper: " << Describe(images()[i]) << ": the VIO's pose is "
                     << position_difference << " m and " << rotation_difference
                     << " rad off the images' (" << predicted_inliers << " of " << pnp_inliers
                     << " inliers): a VIO jump, no prior crosses it";
    RegisterFrame(i, model, result.cam_from_world, FramePoseSource::kImagesReposed);
    return true;
  }
  // A weak PnP, or an ambiguous one (repeated structure: the images support
  // the VIO's pose too, and another far from it): the VIO's pose stands.
  RegisterFrame(i, model, predicted,
                prediction_supported ? FramePoseSource::kVioVerified : FramePoseSource::kVio);
  return true;
}

bool BatchedMapper::JumpRefuted(size_t i, const Rigid3d& predicted,
                                const AbsolutePoseResult& result, double position_difference,
                                double rotation_difference) {
  // The 2D-3D matches are then a look-alike place's, merged into the
  // frame's tracks by a wrong pair.
  const image_t image_id = images()[i].image_id;
  const Reconstruction& reconstruction = core_.reconstruction();
  const int by_images = CountExplainedPairMatches(reconstruction, image_id, result.cam_from_world,
                                                  *pairs_, registration_.support_max_error_px);
  const int by_vio = CountExplainedPairMatches(reconstruction, image_id, predicted, *pairs_,
                                               registration_.support_max_error_px);
  if (by_vio <= kJumpRefutingMatchRatio * by_images) return false;
  ++summary_.num_vio_jumps_refused;
  VIOSFM_LOG(INFO) << "batched mapper: " << Describe(images()[i]) << ": the VIO's pose is "
                   << position_difference << " m and " << rotation_difference
                   << " rad off the images' (" << result.num_predicted_inliers << " of "
                   << result.num_inliers << " 2D-3D inliers), but its matches with "
                   << "the registered frames show the VIO's pose (" << by_vio << " of them against "
                   << by_images << "): not a VIO jump";
  return true;
}

void BatchedMapper::TriangulateTracksOf(const std::vector<size_t>& frame_indices) {
  const TriangulationStatistics statistics = core_.TriangulateFrames(frame_indices);
  changed_since_filter_.insert(changed_since_filter_.end(), statistics.changed_point_ids.begin(),
                               statistics.changed_point_ids.end());
}

size_t BatchedMapper::RetryPending() {
  // The pending frames again (the VIO chain, or PnP against the points
  // triangulated since), triangulating after each round, until none is added.
  size_t added = 0;
  bool changed = true;
  while (changed && !pending_.empty()) {
    changed = false;
    newly_registered_.clear();
    std::vector<size_t> still_pending;
    for (const size_t i : pending_) {
      if (!TryRegister(i)) still_pending.push_back(i);
    }
    pending_ = std::move(still_pending);
    if (!newly_registered_.empty()) {
      changed = true;
      added += newly_registered_.size();
      TriangulateTracksOf(newly_registered_);
    }
  }
  return added;
}

size_t BatchedMapper::RecheckVioPlaced() {
  // A second look at the frames placed by the VIO alone that the images do
  // not support (the gauge frame; frames registered before the model had
  // points to check them): their 2D-3D matches against the adjusted model,
  // re-posed from them under TryRegister's rules, and their tracks
  // triangulated again. Returns how many frames were re-posed.
  if (!registration_.verify_with_images || !registration_.recheck_after_adjustment) return 0;
  std::vector<size_t> reposed;
  Reconstruction& reconstruction = core_.reconstruction();
  for (int m = 0; m < core_.NumModels(); ++m) {
    for (const image_t image_id : core_.model(m).registered) {
      const size_t i = core_.FrameIndex(image_id);
      MapperFrameStatus& status = summary_.frames[i];
      if (status.source != FramePoseSource::kVio) continue;
      if (CountSupportingObservations(reconstruction, image_id,
                                      registration_.support_max_error_px) >=
          registration_.min_supporting_observations) {
        continue;
      }
      const std::optional<size_t> reference = FindReference(i);
      if (!reference) continue;
      const FrameCorrespondences correspondences = core_.Correspondences(i, m);
      if (static_cast<int>(correspondences.size()) < registration_.min_num_correspondences) {
        continue;
      }
      const Rigid3d current = reconstruction.GetImage(image_id).cam_from_world;
      const AbsolutePoseResult result = core_.EstimatePose(i, correspondences, current);
      const int pnp_inliers = result.success ? static_cast<int>(result.num_inliers) : 0;
      const int current_inliers = static_cast<int>(result.num_predicted_inliers);
      if (pnp_inliers < registration_.min_reposing_inliers) continue;
      if (current_inliers >= registration_.pnp.min_num_inliers &&
          static_cast<double>(current_inliers) >=
              registration_.min_predicted_inlier_ratio * pnp_inliers) {
        continue;  // the images support the pose it has
      }
      double position_difference = 0.0, rotation_difference = 0.0;
      if (BeyondVioDrift(i, *reference, result.cam_from_world, current, &position_difference,
                         &rotation_difference)) {
        continue;  // beyond the VIO's drift: not a refinement
      }
      Image& image = reconstruction.GetImage(image_id);
      image.cam_from_world = result.cam_from_world;
      image.cam_from_world.rotation.normalize();
      status.source = FramePoseSource::kImagesReposed;
      status.num_correspondences = static_cast<int>(correspondences.size());
      status.num_predicted_inliers = current_inliers;
      status.num_pnp_inliers = pnp_inliers;
      VIOSFM_LOG(DEBUG) << "batched mapper: " << Describe(images()[i])
                        << " placed by the VIO and unsupported by the images, re-posed from "
                        << pnp_inliers << " PnP inliers (" << current_inliers
                        << " at its pose), moved " << position_difference << " m and "
                        << rotation_difference << " rad";
      reposed.push_back(i);
    }
  }
  if (!reposed.empty()) TriangulateTracksOf(reposed);
  return reposed.size();
}

}  // namespace viosfm
