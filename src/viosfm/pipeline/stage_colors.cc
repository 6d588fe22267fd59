#include "viosfm/pipeline/stage_colors.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"

namespace viosfm {

std::vector<uint8_t> SampleKeypointGreyValues(const GreyImage& pixels,
                                              const FeatureKeypoints& keypoints) {
  std::vector<uint8_t> values;
  values.reserve(keypoints.size());
  for (const FeatureKeypoint& keypoint : keypoints) {
    const int x = std::clamp(static_cast<int>(std::lround(static_cast<double>(keypoint.x))), 0,
                             pixels.width - 1);
    const int y = std::clamp(static_cast<int>(std::lround(static_cast<double>(keypoint.y))), 0,
                             pixels.height - 1);
    values.push_back(pixels.at(x, y));
  }
  return values;
}

void KeypointGreyValues::Sample(image_t image_id, const GreyImage& pixels,
                                const FeatureKeypoints& keypoints) {
  Set(image_id, SampleKeypointGreyValues(pixels, keypoints));
}

void KeypointGreyValues::Set(image_t image_id, std::vector<uint8_t> values) {
  std::lock_guard<std::mutex> lock(mutex_);
  values_[image_id] = std::move(values);
}

const std::vector<uint8_t>* KeypointGreyValues::Find(image_t image_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = values_.find(image_id);
  return it == values_.end() ? nullptr : &it->second;
}

void ColorPointsStage(const SelectedFrames& frames, const BatchedMapperInput& input,
                      bool show_progress, KeypointGreyValues* values, FrameCache* frame_cache,
                      Reconstruction* reconstruction) {
  std::unordered_map<image_t, size_t> frame_of_image;
  for (size_t i = 0; i < input.images.size(); ++i) frame_of_image[input.images[i].image_id] = i;
  std::unordered_map<point3D_t, std::pair<double, int>> sums;
  const std::vector<image_t> image_ids = reconstruction->RegImageIds();
  ProgressBar progress("colors", static_cast<int64_t>(image_ids.size()),
                       show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
  for (const image_t image_id : image_ids) {
    const Image& image = reconstruction->GetImage(image_id);
    const std::vector<uint8_t>* image_values = values->Find(image_id);
    if (image_values == nullptr) {
      // Features stored by an earlier run: sampled from the image now.
      const auto frame = frame_of_image.find(image_id);
      VIOSFM_CHECK(frame != frame_of_image.end()) << "image " << image_id << " has no file";
      values->Sample(image_id, *frame_cache->Take(frames.sequence.images[frame->second].path),
                     input.images[frame->second].keypoints);
      image_values = values->Find(image_id);
    }
    VIOSFM_CHECK(image_values->size() == image.points2D.size())
        << "image " << image_id << ": " << image_values->size() << " sampled values for "
        << image.points2D.size() << " keypoints";
    for (size_t j = 0; j < image.points2D.size(); ++j) {
      const Point2D& point2D = image.points2D[j];
      if (!point2D.HasPoint3D()) continue;
      auto& [sum, count] = sums[point2D.point3D_id];
      sum += (*image_values)[j];
      ++count;
    }
    progress.Update();
  }
  progress.Finish();
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    const auto it = sums.find(point3D_id);
    if (it == sums.end() || it->second.second == 0) continue;
    const auto value = static_cast<uint8_t>(
        std::clamp(std::lround(it->second.first / it->second.second), 0L, 255L));
    reconstruction->GetPoint3D(point3D_id).color = Vector3ub::Constant(value);
  }
}

}  // namespace viosfm
