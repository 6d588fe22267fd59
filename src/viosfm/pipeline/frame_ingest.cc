#include "viosfm/pipeline/frame_ingest.h"

#include <memory>
#include <utility>

#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/util/errors.h"

namespace viosfm {

FrameIngest::FrameIngest(ColmapDatabase* database, camera_t camera_id, const Rigid3d& body_from_cam,
                         double readout_s)
    : database_(database),
      camera_id_(camera_id),
      body_from_cam_(body_from_cam),
      readout_s_(readout_s) {}

IngestedFrame FrameIngest::Store(const SequenceImage& image, const ImageFeatures* features) {
  IngestedFrame stored;
  stored.name = DatabaseImageName(image);
  const std::optional<DatabaseImage> row = database_->ReadImageWithName(stored.name);
  if (row && database_->ExistsFeatures(row->image_id)) {
    stored.image_id = row->image_id;
    stored.camera_id = row->camera_id;
    stored.keypoints = database_->ReadKeypoints(row->image_id);
    return stored;
  }
  VIOSFM_CHECK(features != nullptr) << "image " << stored.name << " has no stored features";
  ColmapDatabase::Transaction transaction(*database_);
  stored.image_id = row ? row->image_id : database_->WriteImage(stored.name, camera_id_);
  stored.camera_id = row ? row->camera_id : camera_id_;
  database_->WriteFeatures(stored.image_id, features->keypoints, features->descriptors);
  transaction.Commit();
  stored.keypoints = features->keypoints;
  return stored;
}

const Camera& FrameIngest::CameraOf(camera_t camera_id) {
  auto camera = cameras_.find(camera_id);
  if (camera == cameras_.end()) {
    camera = cameras_.emplace(camera_id, database_->ReadCamera(camera_id)).first;
  }
  return camera->second;
}

std::vector<Camera> FrameIngest::Cameras() const {
  std::vector<Camera> cameras;
  for (const auto& [camera_id, camera] : cameras_) cameras.push_back(camera);
  return cameras;
}

MapperImage FrameIngest::MapperImageOf(const ArrivingFrame& frame, const IngestedFrame& stored) {
  MapperImage mapper_image;
  mapper_image.image_id = stored.image_id;
  mapper_image.camera_id = stored.camera_id;
  mapper_image.name = stored.name;
  mapper_image.timestamp_ns = frame.image->timestamp_ns;
  mapper_image.keypoints = stored.keypoints;
  CompensateRollingShutterRotation(CameraOf(stored.camera_id), readout_s_, frame.cam_angular_rate,
                                   &mapper_image.keypoints);
  if (frame.vio_pose) {
    mapper_image.vio_cam_from_world = (frame.vio_pose->world_from_body * body_from_cam_).Inverse();
    mapper_image.vio_odometer = frame.vio_pose->odometer;
  }
  return mapper_image;
}

PairImage FrameIngest::PairImageOf(const ArrivingFrame& frame, const IngestedFrame& stored,
                                   const FeatureDescriptors& descriptors, bool use_vio_prior,
                                   bool guided) {
  PairImage pair_image;
  pair_image.image_id = stored.image_id;
  pair_image.name = stored.name;
  pair_image.camera_id = stored.camera_id;
  pair_image.timestamp_ns = frame.image->timestamp_ns;
  if (frame.vio_pose && use_vio_prior) {
    pair_image.world_from_body = frame.vio_pose->world_from_body;
    pair_image.odometer = frame.vio_pose->odometer;
  }
  pair_image.cam_angular_rate = frame.cam_angular_rate;
  SetPairImageKeypoints(CameraOf(stored.camera_id), stored.keypoints, readout_s_, guided,
                        &pair_image);
  pair_image.stored_descriptors = std::make_shared<const FeatureDescriptors>(descriptors);
  return pair_image;
}

}  // namespace viosfm
