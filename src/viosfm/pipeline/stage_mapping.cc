#include "viosfm/pipeline/stage_mapping.h"

#include <iomanip>
#include <sstream>

#include "viosfm/pipeline/frame_ingest.h"
#include "viosfm/pipeline/metric_scale.h"
#include "viosfm/scene/reprojection.h"
#include "viosfm/util/logging.h"

namespace viosfm {

BatchedMapperInput LoadMapperImages(const SelectedFrames& frames, const VioPoses& vio,
                                    ColmapDatabase* database) {
  BatchedMapperInput input;
  const FrameRollingShutter& rolling_shutter = frames.rolling_shutter;
  input.rolling_shutter_readout_s = rolling_shutter.active() ? rolling_shutter.readout_s : 0.0;
  // The features stage stored every frame's features: each is read back.
  FrameIngest ingest(database, kInvalidCameraId, frames.sequence.rig.body_from_cam,
                     input.rolling_shutter_readout_s);
  for (size_t i = 0; i < frames.sequence.images.size(); ++i) {
    ArrivingFrame frame{&frames.sequence.images[i], std::nullopt, Eigen::Vector3d::Zero()};
    if (const std::optional<size_t> pose_index = frames.vio_index[i]) {
      frame.vio_pose = FrameVioPose{vio.world_from_body.poses[*pose_index].world_from_frame,
                                    vio.odometers[*pose_index]};
    }
    if (rolling_shutter.active()) frame.cam_angular_rate = rolling_shutter.cam_angular_rate[i];
    input.images.push_back(
        ingest.MapperImageOf(frame, ingest.Store(*frame.image, /*features=*/nullptr)));
  }
  input.cameras = ingest.Cameras();
  // For the gyro's priors in the final adjustment: the IMU and the rig the
  // VIO used (its clock offset and noise, when it estimated them).
  input.imu = frames.sequence.imu;
  input.rig = vio.own_vio_rig.value_or(frames.sequence.rig);
  return input;
}

BatchedMapperInput LoadMapperInputStage(const SelectedFrames& frames, const VioPoses& vio,
                                        const VerificationResult& verification,
                                        ColmapDatabase* database, VioGapSummary* gaps) {
  BatchedMapperInput input = LoadMapperImages(frames, vio, database);
  size_t num_inlier_matches = 0;
  for (const PairDecision& decision : verification.decisions) {
    if (!decision.accepted) continue;
    ImagePairMatches pair;
    pair.image_id1 = decision.image_id1;
    pair.image_id2 = decision.image_id2;
    pair.matches =
        database->ReadTwoViewGeometry(decision.image_id1, decision.image_id2).inlier_matches;
    pair.vio_contradicted = decision.vio_contradicted;
    num_inlier_matches += pair.matches.size();
    input.verified_pairs.push_back(std::move(pair));
  }
  VIOSFM_LOG(INFO) << "run: " << input.verified_pairs.size() << " accepted pairs, "
                   << num_inlier_matches << " inlier matches";
  const VioGapSummary decided = DecideVioGaps(&input);
  if (gaps != nullptr) *gaps = decided;
  return input;
}

BatchedMapperOptions MapperOptionsOfRun(const Sequence& sequence, const PipelineOptions& options) {
  BatchedMapperOptions mapper = options.EffectiveMapperOptions();
  // A guessed camera's focal length, distortion and principal point are
  // the adjustment's to find (see docs/benchmarks.md, "Without a VIO, or with a sparse one").
  if (sequence.camera_guessed) {
    mapper.ba.refine_intrinsics = true;
    mapper.ba.refine_principal_point = true;
  }
  return mapper;
}

Reconstruction MapStage(const BatchedMapperInput& input, const Sequence& sequence,
                        const VioPoses& vio, const PipelineOptions& options,
                        PipelineSummary* summary, VerifiedPairStream* stream,
                        std::vector<Reconstruction>* other_models) {
  Reconstruction reconstruction = RunBatchedMapper(input, MapperOptionsOfRun(sequence, options),
                                                   &summary->mapper, stream, {}, other_models);
  FinishMapping(sequence, vio, options, summary, &reconstruction);
  return reconstruction;
}

void FinishMapping(const Sequence& sequence, const VioPoses& vio, const PipelineOptions& options,
                   PipelineSummary* summary, Reconstruction* reconstruction) {
  if (sequence.camera_guessed) {
    const Camera& camera = reconstruction->GetCamera(sequence.rig.camera.camera_id);
    std::ostringstream params;
    for (size_t k = 0; k < camera.params.size(); ++k)
      params << (k > 0 ? " " : "") << camera.params[k];
    summary->camera_refined = camera.ModelName() + " " + params.str();
    VIOSFM_LOG(INFO) << "run: the guessed camera refined by the adjustment: "
                     << summary->camera_refined;
  }
  if (vio.absent && !sequence.has_imu()) {
    summary->metric_scale.message =
        "images only: the model has the scale and frame of its first two views, not metres";
    VIOSFM_LOG(WARNING) << "run: " << summary->metric_scale.message;
  } else if (options.use_imu_scale) {
    // Without a VIO the IMU's scale is the only one (the VIO's taken as
    // unknown).
    const double vio_scale_sigma = vio.absent ? 1e6 : options.vio_uncertainty.scale_sigma;
    summary->metric_scale =
        ApplyImuMetricScale(sequence, vio.own_vio_rig.value_or(sequence.rig), vio_scale_sigma,
                            options.imu_scale, reconstruction, summary->mapper.inertial_scale);
    if (summary->metric_scale.vio_scale_refuted) {
      VIOSFM_LOG(WARNING) << "run: metric scale: " << summary->metric_scale.message;
    } else {
      const MetricScaleSummary& scale = summary->metric_scale;
      VIOSFM_LOG(INFO) << std::fixed << std::setprecision(5)
                       << "run: metric scale: the model times " << scale.applied_scale << " (+- "
                       << std::setprecision(2) << 100.0 * scale.applied_scale_sigma << " %)"
                       << LogDetails() << "; " << scale.message;
    }
  }
  summary->num_frames_registered = static_cast<size_t>(summary->mapper.num_supported);
  summary->num_frames_vio_only = static_cast<size_t>(summary->mapper.num_vio_only);
  summary->num_frames_unposed = static_cast<size_t>(summary->mapper.num_unposed);
  for (const MapperFrameStatus& frame : summary->mapper.frames) {
    if (frame.reason.empty()) continue;
    VIOSFM_LOG(WARNING) << "run: no pose for " << reconstruction->GetImage(frame.image_id).name
                        << ": " << frame.reason;
  }
  summary->num_points = reconstruction->NumPoints3D();
  summary->num_observations = reconstruction->ComputeNumObservations();
  summary->mean_track_length = reconstruction->ComputeMeanTrackLength();
  summary->mean_reprojection_error_px = UpdateReprojectionErrors(reconstruction);
}

}  // namespace viosfm
