// SIFT extraction speed per frame: ExtractSift with the scale
// space's first octave at -1 (cv::SIFT's own detector on the image doubled)
// and at 0 (features/dog_detector.h from the image itself, cv::SIFT's
// descriptors), both measured in the same run, on one rendered frame of the
// `room` scenario and, with VIOSFM_DATA_DIR set, on a real EuRoC frame
// (752x480) and a frame of the real handheld recording (1280x720).
// Arguments: first octave, maximum features.
//
// OpenCV parallelises inside cv::SIFT: run with OPENCV_FOR_THREADS_NUM=1
// for one core, as the feature extraction's workers each are.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/io/image_io.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/sequence_simulator.h"

namespace viosfm {
namespace {

const GreyImage& RoomFrame() {
  static const GreyImage image = [] {
    SimulationOptions options;
    options.scenario = "room";
    options.duration_s = 4.0;
    options.static_start_s = 0.0;
    options.seed = 0;
    const SimulatedSequence simulated = SimulateSequence(options);
    const RayTable rays(options.camera);
    return RenderSimulatedFrame(simulated, rays, simulated.sequence.images.size() - 1, options, 2);
  }();
  return image;
}

// The middle image of a real sequence in VIOSFM_DATA_DIR (its mav0/cam0/data
// folder), or an empty image without the data.
GreyImage RealFrame(const std::string& name) {
  const char* root = std::getenv("VIOSFM_DATA_DIR");
  if (root == nullptr) return GreyImage();
  const std::filesystem::path folder = std::filesystem::path(root) / name / "mav0/cam0/data";
  if (!std::filesystem::is_directory(folder)) return GreyImage();
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  return paths.empty() ? GreyImage() : ReadGreyImage(paths[paths.size() / 2]);
}

void ExtractOn(benchmark::State& state, const GreyImage& image) {
  if (image.empty()) {
    state.SkipWithError("no image (set VIOSFM_DATA_DIR for the real frames)");
    return;
  }
  SiftOptions options;
  options.first_octave = static_cast<int>(state.range(0));
  options.max_num_features = static_cast<int>(state.range(1));
  size_t keypoints = 0;
  for (auto _ : state) {
    const ImageFeatures features = ExtractSift(image, options);
    keypoints = features.keypoints.size();
    benchmark::DoNotOptimize(features.descriptors.data());
  }
  state.counters["keypoints"] = static_cast<double>(keypoints);
}

void BM_ExtractSiftRoom(benchmark::State& state) {
  ExtractOn(state, RoomFrame());
}
// EuRoC V1_01, 752x480.
void BM_ExtractSiftEuroc(benchmark::State& state) {
  static const GreyImage image = RealFrame("euroc_v101_static_micro");
  ExtractOn(state, image);
}
// The handheld RealSense recording, 1280x720.
void BM_ExtractSiftRealsense(benchmark::State& state) {
  static const GreyImage image = RealFrame("realsense_room_30s");
  ExtractOn(state, image);
}

BENCHMARK(BM_ExtractSiftRoom)
    ->ArgsProduct({{-1, 0}, {1000, 8192}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ExtractSiftEuroc)
    ->ArgsProduct({{-1, 0}, {1000, 8192}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ExtractSiftRealsense)
    ->ArgsProduct({{-1, 0}, {1000, 8192}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace viosfm
