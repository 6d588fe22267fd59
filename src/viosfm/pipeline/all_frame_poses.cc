#include "viosfm/pipeline/all_frame_poses.h"

#include <algorithm>
#include <map>

#include "viosfm/util/errors.h"

namespace viosfm {

std::string AllFramePoseCounts::ToString() const {
  return std::to_string(num_images) + " images: " + std::to_string(num_from_model) +
         " from the model, " + std::to_string(num_between) + " between model frames, " +
         std::to_string(num_beyond) + " beyond the first or last of their VIO segment, " +
         std::to_string(num_unposed()) + " without a pose (" +
         std::to_string(num_without_vio_pose) + " without a VIO pose, " +
         std::to_string(num_without_model_frame) + " in a VIO segment without a model frame)";
}

AllFramePoses PoseAllFrames(const std::vector<timestamp_ns_t>& image_stamps,
                            const std::vector<ModelFramePose>& model_frames,
                            const Trajectory& vio_world_from_body,
                            const std::vector<int>& vio_segments,
                            timestamp_ns_t max_vio_time_difference_ns) {
  VIOSFM_CHECK_EQ(vio_segments.size(), vio_world_from_body.size());
  // The anchors of each VIO segment: the model frames with a VIO pose there,
  // time ordered.
  std::map<int, std::vector<const ModelFramePose*>> anchors;
  std::map<timestamp_ns_t, const ModelFramePose*> by_stamp;
  for (const ModelFramePose& frame : model_frames) {
    by_stamp[frame.timestamp_ns] = &frame;
    if (!frame.vio_index) continue;
    VIOSFM_CHECK_LT(*frame.vio_index, vio_world_from_body.size());
    anchors[vio_segments[*frame.vio_index]].push_back(&frame);
  }
  for (auto& [segment, frames] : anchors) {
    std::sort(frames.begin(), frames.end(), [](const ModelFramePose* a, const ModelFramePose* b) {
      return a->timestamp_ns < b->timestamp_ns;
    });
  }
  const auto vio_pose = [&](size_t index) -> const Rigid3d& {
    return vio_world_from_body.poses[index].world_from_frame;
  };
  // The image's pose as the VIO moved it from an anchor.
  const auto from_anchor = [&](const ModelFramePose& anchor, const Rigid3d& vio_world_from_image) {
    return anchor.world_from_body * vio_pose(*anchor.vio_index).Inverse() * vio_world_from_image;
  };

  AllFramePoses result;
  result.counts.num_images = image_stamps.size();
  for (const timestamp_ns_t stamp : image_stamps) {
    if (const auto it = by_stamp.find(stamp); it != by_stamp.end()) {
      result.world_from_body.poses.push_back({stamp, it->second->world_from_body});
      result.source.push_back(AllFramePoseSource::kModel);
      ++result.counts.num_from_model;
      continue;
    }
    const std::optional<size_t> vio_index =
        NearestPoseIndex(vio_world_from_body, stamp, max_vio_time_difference_ns);
    if (!vio_index) {
      ++result.counts.num_without_vio_pose;
      continue;
    }
    const auto segment_anchors = anchors.find(vio_segments[*vio_index]);
    if (segment_anchors == anchors.end()) {
      ++result.counts.num_without_model_frame;
      continue;
    }
    const std::vector<const ModelFramePose*>& frames = segment_anchors->second;
    const auto after = std::lower_bound(
        frames.begin(), frames.end(), stamp,
        [](const ModelFramePose* frame, timestamp_ns_t t) { return frame->timestamp_ns < t; });
    const Rigid3d& vio_world_from_image = vio_pose(*vio_index);
    Rigid3d world_from_body;
    AllFramePoseSource source = AllFramePoseSource::kBeyond;
    if (after == frames.begin()) {
      world_from_body = from_anchor(**after, vio_world_from_image);
    } else if (after == frames.end()) {
      world_from_body = from_anchor(*frames.back(), vio_world_from_image);
    } else {
      const ModelFramePose& a = **std::prev(after);
      const ModelFramePose& b = **after;
      const Rigid3d from_a = from_anchor(a, vio_world_from_image);
      const Rigid3d from_b = from_anchor(b, vio_world_from_image);
      const double s = static_cast<double>(stamp - a.timestamp_ns) /
                       static_cast<double>(b.timestamp_ns - a.timestamp_ns);
      world_from_body.rotation = from_a.rotation.slerp(s, from_b.rotation).normalized();
      world_from_body.translation = (1.0 - s) * from_a.translation + s * from_b.translation;
      source = AllFramePoseSource::kBetween;
    }
    result.world_from_body.poses.push_back({stamp, world_from_body});
    result.source.push_back(source);
    ++(source == AllFramePoseSource::kBetween ? result.counts.num_between
                                              : result.counts.num_beyond);
  }
  return result;
}

}  // namespace viosfm
