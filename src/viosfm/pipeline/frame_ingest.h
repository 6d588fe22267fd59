// The one step that brings a selected frame into a run: its features into
// the database (unless the database holds them already, so a resumed run
// skips them), then the frame as the verification takes it (`PairImage`)
// and as the mapper takes it (`MapperImage`). A run in turn ingests every
// frame after the features stage has stored them all; the stream
// (stream.h) ingests each frame as it arrives, with the features extracted
// beside the VIO.
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>

#include "viosfm/features/sift.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/matching/pair_verification.h"
#include "viosfm/matching/verification_driver.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/sfm/mapper_input.h"

namespace viosfm {

// One selected frame as it arrives: the image, the VIO pose associated
// with it (none: the images alone place it), and the camera's angular rate
// at its stamp (used only with a rolling shutter's readout).
struct ArrivingFrame {
  const SequenceImage* image = nullptr;
  std::optional<FrameVioPose> vio_pose;
  Eigen::Vector3d cam_angular_rate = Eigen::Vector3d::Zero();
};

// A frame once ingested: its row in the database and its keypoints as
// stored (raw pixels; not compensated for a rolling shutter).
struct IngestedFrame {
  image_t image_id = kInvalidImageId;
  camera_t camera_id = kInvalidCameraId;
  std::string name;  // DatabaseImageName
  FeatureKeypoints keypoints;
};

class FrameIngest {
 public:
  // New frames are written with `camera_id` (a camera of `database`); the
  // VIO's body poses become camera poses through `body_from_cam`; with a
  // rolling shutter's `readout_s` (0: a global shutter) the keypoints the
  // verification and the mapper take are moved to the frame's stamp.
  FrameIngest(ColmapDatabase* database, camera_t camera_id, const Rigid3d& body_from_cam,
              double readout_s);

  // Writes the frame's features, or, where the database holds the frame
  // with its features (a resumed run, or the features stage of a run in
  // turn), reads its keypoints back. `features` null: the features must be
  // stored already.
  IngestedFrame Store(const SequenceImage& image, const ImageFeatures* features);

  // The frame as the mapper takes it.
  MapperImage MapperImageOf(const ArrivingFrame& frame, const IngestedFrame& stored);

  // The frame as the verification takes it: its VIO pose (when
  // `use_vio_prior`), keypoints prepared for matching (in pixels too when
  // `guided`) and the stored descriptors.
  PairImage PairImageOf(const ArrivingFrame& frame, const IngestedFrame& stored,
                        const FeatureDescriptors& descriptors, bool use_vio_prior, bool guided);

  // The cameras of the frames ingested so far, in id order.
  std::vector<Camera> Cameras() const;
  const Camera& CameraOf(camera_t camera_id);
  double readout_s() const { return readout_s_; }

 private:
  ColmapDatabase* database_;
  camera_t camera_id_;
  Rigid3d body_from_cam_;
  double readout_s_;
  std::map<camera_t, Camera> cameras_;  // each read once from the database
};

}  // namespace viosfm
