// A pose for every image of the recording, not only for the frames in the
// model. Frame selection keeps a subset of the images (the static ends
// trimmed, the rest downsampled to frame_selection.target_rate_hz); a user
// who needs a pose per image (to colour a lidar scan, to tag photos) gets
// the model's poses at the frames it holds and, at every other image, the
// VIO's relative motion from the model frames around it:
//
//   from the model frame a before it:  world_from_body_a * vio_a^-1 * vio_t
//   from the model frame b after it:   world_from_body_b * vio_b^-1 * vio_t
//
// blended by the image's place in time between a and b (rotation slerped,
// position linear), so that the correction the model made to the VIO at a
// and b is spread over the frames between them and the trajectory is
// continuous at both. a and b are the nearest model frames with a VIO pose
// in the image's own VIO segment (nothing joins two segments but the
// images). Before the first or after the last such frame of its segment
// (the static ends) an image takes the one side. An image without a VIO
// pose (within the selection's max time difference), or whose segment has
// no model frame, gets no pose; both are counted.
//
// The VIO's relative motion is taken at its own scale; between frames a
// tenth of a second apart the model's metric correction (under 1 %) is
// below a tenth of a millimetre.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "viosfm/scene/trajectory.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// A frame of the model: its final pose and the index of its VIO pose.
struct ModelFramePose {
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d world_from_body;
  std::optional<size_t>
      vio_index;  // into the VIO trajectory; none: registered from the images alone
};

enum class AllFramePoseSource {
  kModel,    // the image is a frame of the model
  kBetween,  // between two model frames of its VIO segment
  kBeyond,   // before the first or after the last model frame of its segment
};

// How the images of the recording were posed.
struct AllFramePoseCounts {
  size_t num_images = 0;
  size_t num_from_model = 0;
  size_t num_between = 0;
  size_t num_beyond = 0;
  size_t num_without_vio_pose = 0;     // not in the model and no VIO pose at the image
  size_t num_without_model_frame = 0;  // not in the model and no model frame in its VIO segment
  size_t num_unposed() const { return num_without_vio_pose + num_without_model_frame; }
  // "1001 images: 979 from the model, 20 between model frames, 2 beyond, 0 without a pose".
  std::string ToString() const;
};

struct AllFramePoses {
  Trajectory world_from_body;              // time ordered, the posed images only
  std::vector<AllFramePoseSource> source;  // per pose
  AllFramePoseCounts counts;
};

// image_stamps: every image of the recording, time ordered. model_frames:
// the frames of the model, time ordered; their stamps are among
// image_stamps. vio_segments: the segment of each VIO pose.
// max_vio_time_difference_ns: how far an image's VIO pose may be from it.
AllFramePoses PoseAllFrames(const std::vector<timestamp_ns_t>& image_stamps,
                            const std::vector<ModelFramePose>& model_frames,
                            const Trajectory& vio_world_from_body,
                            const std::vector<int>& vio_segments,
                            timestamp_ns_t max_vio_time_difference_ns);

}  // namespace viosfm
