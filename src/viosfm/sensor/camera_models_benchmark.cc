// Undistorting one frame's keypoints (2250, EuRoC-sized image): viosfm's
// camera model against OpenCV's cv::undistortPoints on the same points, in
// the same run.
#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <random>
#include <vector>

#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

constexpr int kNumKeypoints = 2250;

Camera EurocCamera() {
  return MakeCamera(
      CameraModelId::kOpenCV, 752, 480,
      {458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
}

std::vector<Eigen::Vector2d> RandomPixels() {
  std::mt19937_64 rng(0);
  std::uniform_real_distribution<double> x(0.0, 752.0), y(0.0, 480.0);
  std::vector<Eigen::Vector2d> pixels(kNumKeypoints);
  for (auto& pixel : pixels) pixel = Eigen::Vector2d(x(rng), y(rng));
  return pixels;
}

void BM_ViosfmImageToCam(benchmark::State& state) {
  const Camera camera = EurocCamera();
  const std::vector<Eigen::Vector2d> pixels = RandomPixels();
  std::vector<Eigen::Vector2d> normalized(pixels.size());
  for (auto _ : state) {
    for (size_t i = 0; i < pixels.size(); ++i) normalized[i] = ImageToCam(camera, pixels[i]);
    benchmark::DoNotOptimize(normalized.data());
  }
  state.SetItemsProcessed(state.iterations() * kNumKeypoints);
}
BENCHMARK(BM_ViosfmImageToCam);

void BM_OpenCvUndistortPoints(benchmark::State& state) {
  const Camera camera = EurocCamera();
  const auto& p = camera.params;
  const cv::Matx33d K(p[0], 0, p[2], 0, p[1], p[3], 0, 0, 1);
  const cv::Vec4d distortion(p[4], p[5], p[6], p[7]);
  std::vector<cv::Point2d> pixels;
  for (const auto& pixel : RandomPixels()) pixels.emplace_back(pixel.x(), pixel.y());
  std::vector<cv::Point2d> normalized;
  // OpenCV's default: 5 fixed-point iterations (less accurate than viosfm's
  // solve to 1e-12); the stricter criterion below is the like-for-like one.
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                  static_cast<int>(state.range(0)), 1e-12);
  for (auto _ : state) {
    cv::undistortPoints(pixels, normalized, K, distortion, cv::noArray(), cv::noArray(), criteria);
    benchmark::DoNotOptimize(normalized.data());
  }
  state.SetItemsProcessed(state.iterations() * kNumKeypoints);
}
BENCHMARK(BM_OpenCvUndistortPoints)->Arg(5)->Arg(20);

}  // namespace
}  // namespace viosfm
