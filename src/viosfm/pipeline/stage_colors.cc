#include "viosfm/pipeline/stage_colors.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <unordered_map>
#include <utility>

#include "viosfm/io/image_io.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// Mean grey value of each point over its observations in registered images.
void ColorPoints(const std::unordered_map<image_t, fs::path>& image_paths, bool show_progress,
                 Reconstruction* reconstruction) {
  std::unordered_map<point3D_t, std::pair<double, int>> sums;
  const std::vector<image_t> image_ids = reconstruction->RegImageIds();
  ProgressBar progress("colors", static_cast<int64_t>(image_ids.size()),
                       show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
  for (const image_t image_id : image_ids) {
    const Image& image = reconstruction->GetImage(image_id);
    const auto path = image_paths.find(image_id);
    VIOSFM_CHECK(path != image_paths.end()) << "image " << image_id << " has no file";
    const GreyImage pixels = ReadGreyImage(path->second);
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      // viosfm's pixel convention: pixel (x, y) has its centre at (x, y).
      const int x = std::clamp(static_cast<int>(std::lround(point2D.xy.x())), 0, pixels.width - 1);
      const int y = std::clamp(static_cast<int>(std::lround(point2D.xy.y())), 0, pixels.height - 1);
      auto& [sum, count] = sums[point2D.point3D_id];
      sum += pixels.at(x, y);
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

}  // namespace

void ColorPointsStage(const SelectedFrames& frames, const BatchedMapperInput& input,
                      bool show_progress, Reconstruction* reconstruction) {
  std::unordered_map<image_t, fs::path> image_paths;
  for (size_t i = 0; i < input.images.size(); ++i) {
    image_paths.emplace(input.images[i].image_id, frames.sequence.images[i].path);
  }
  ColorPoints(image_paths, show_progress, reconstruction);
}

}  // namespace viosfm
