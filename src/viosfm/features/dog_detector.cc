#include "viosfm/features/dog_detector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <tuple>

namespace viosfm {
namespace {

constexpr double kInitialSigma = 1.6;  // sigma_0 of the first layer
constexpr double kInputBlur = 0.5;     // blur assumed in the input image
constexpr int kBorder = 5;             // pixels left out at each octave's border
constexpr int kMaxRefinementSteps = 5;
constexpr int kOrientationBins = 36;
constexpr float kOrientationSigmaFactor = 1.5f;  // of the keypoint's scale in the octave
constexpr float kOrientationRadiusFactor = 3.0f * kOrientationSigmaFactor;
constexpr float kOrientationPeakRatio = 0.8f;
constexpr float kIntensityScale = 1.0f / 255.0f;  // layers hold 8-bit intensities as floats

struct ScaleSpace {
  int num_octaves = 0;
  int num_layers = 0;
  std::vector<cv::Mat> gaussians;  // [octave * (num_layers + 3) + layer], CV_32F
  std::vector<cv::Mat> dogs;  // [octave * (num_layers + 2) + layer]: gaussian layer + 1 - layer

  const cv::Mat& Gaussian(int octave, int layer) const {
    return gaussians[octave * (num_layers + 3) + layer];
  }
  const cv::Mat& Dog(int octave, int layer) const {
    return dogs[octave * (num_layers + 2) + layer];
  }
};

ScaleSpace BuildScaleSpace(const cv::Mat& image, int num_layers) {
  ScaleSpace space;
  space.num_layers = num_layers;
  space.num_octaves = static_cast<int>(
      std::lround(std::log2(static_cast<double>(std::min(image.cols, image.rows))) - 2.0));
  if (space.num_octaves < 1) return space;
  const int per_octave = num_layers + 3;
  // Blur added to layer i - 1 to reach layer i: sigma_i^2 - sigma_{i-1}^2.
  std::vector<double> increments(per_octave);
  const double k = std::pow(2.0, 1.0 / num_layers);
  for (int i = 1; i < per_octave; ++i) {
    const double previous = kInitialSigma * std::pow(k, i - 1);
    increments[i] = previous * std::sqrt(k * k - 1.0);
  }
  space.gaussians.resize(static_cast<size_t>(space.num_octaves) * per_octave);
  cv::Mat input;
  image.convertTo(input, CV_32F);
  const double base_blur =
      std::sqrt(std::max(kInitialSigma * kInitialSigma - kInputBlur * kInputBlur, 0.01));
  for (int o = 0; o < space.num_octaves; ++o) {
    for (int i = 0; i < per_octave; ++i) {
      cv::Mat& layer = space.gaussians[o * per_octave + i];
      if (o == 0 && i == 0) {
        cv::GaussianBlur(input, layer, cv::Size(), base_blur, base_blur);
      } else if (i == 0) {
        const cv::Mat& source = space.gaussians[(o - 1) * per_octave + num_layers];
        cv::resize(source, layer, cv::Size(source.cols / 2, source.rows / 2), 0.0, 0.0,
                   cv::INTER_NEAREST);
      } else {
        cv::GaussianBlur(space.gaussians[o * per_octave + i - 1], layer, cv::Size(), increments[i],
                         increments[i]);
      }
    }
  }
  space.dogs.resize(static_cast<size_t>(space.num_octaves) * (num_layers + 2));
  for (int o = 0; o < space.num_octaves; ++o) {
    for (int i = 0; i < num_layers + 2; ++i) {
      cv::subtract(space.Gaussian(o, i + 1), space.Gaussian(o, i),
                   space.dogs[o * (num_layers + 2) + i]);
    }
  }
  return space;
}

// Whether dog(octave, layer) at (row, col) is at least as large as (value
// > 0) or at least as small as (value < 0) its 26 neighbours.
bool IsExtremum(const ScaleSpace& space, int octave, int layer, int row, int col) {
  const float value = space.Dog(octave, layer).at<float>(row, col);
  for (int l = layer - 1; l <= layer + 1; ++l) {
    const cv::Mat& dog = space.Dog(octave, l);
    for (int r = row - 1; r <= row + 1; ++r) {
      const float* values = dog.ptr<float>(r);
      for (int c = col - 1; c <= col + 1; ++c) {
        if (value > 0.0f ? values[c] > value : values[c] < value) return false;
      }
    }
  }
  return true;
}

struct Refined {
  int row, col, layer;
  float dx, dy, dlayer;  // offsets from (col, row, layer), each within 0.5
  float contrast;        // interpolated DoG, intensities in [0, 1]
};

// Gradient and Hessian of the DoG at (row, col, layer) in (x, y, layer),
// intensities in [0, 1].
void Derivatives(const ScaleSpace& space, int octave, int layer, int row, int col,
                 cv::Vec3f& gradient, cv::Matx33f& hessian) {
  const cv::Mat& below = space.Dog(octave, layer - 1);
  const cv::Mat& here = space.Dog(octave, layer);
  const cv::Mat& above = space.Dog(octave, layer + 1);
  auto at = [](const cv::Mat& m, int r, int c) { return m.at<float>(r, c); };
  const float v2 = 2.0f * at(here, row, col);
  gradient = cv::Vec3f(at(here, row, col + 1) - at(here, row, col - 1),
                       at(here, row + 1, col) - at(here, row - 1, col),
                       at(above, row, col) - at(below, row, col)) *
             (0.5f * kIntensityScale);
  const float dxx = (at(here, row, col + 1) + at(here, row, col - 1) - v2) * kIntensityScale;
  const float dyy = (at(here, row + 1, col) + at(here, row - 1, col) - v2) * kIntensityScale;
  const float dss = (at(above, row, col) + at(below, row, col) - v2) * kIntensityScale;
  const float cross = 0.25f * kIntensityScale;
  const float dxy = (at(here, row + 1, col + 1) - at(here, row + 1, col - 1) -
                     at(here, row - 1, col + 1) + at(here, row - 1, col - 1)) *
                    cross;
  const float dxs = (at(above, row, col + 1) - at(above, row, col - 1) - at(below, row, col + 1) +
                     at(below, row, col - 1)) *
                    cross;
  const float dys = (at(above, row + 1, col) - at(above, row - 1, col) - at(below, row + 1, col) +
                     at(below, row - 1, col)) *
                    cross;
  hessian = cv::Matx33f(dxx, dxy, dxs, dxy, dyy, dys, dxs, dys, dss);
}

// The quadratic fit around a DoG extremum, moved to the neighbour its offset
// points to until the offset is within half a sample; nullopt if it leaves
// the octave, does not settle, is too weak or lies on an edge.
std::optional<Refined> Refine(const ScaleSpace& space, int octave, int layer, int row, int col,
                              const DogDetectorOptions& options) {
  const cv::Mat& first = space.Dog(octave, 0);
  cv::Vec3f gradient;
  cv::Matx33f hessian;
  cv::Vec3f offset;
  int step = 0;
  for (; step < kMaxRefinementSteps; ++step) {
    Derivatives(space, octave, layer, row, col, gradient, hessian);
    offset = -(hessian.solve(gradient, cv::DECOMP_LU));
    if (std::abs(offset[0]) < 0.5f && std::abs(offset[1]) < 0.5f && std::abs(offset[2]) < 0.5f) {
      break;
    }
    constexpr float kFar = 1e6f;
    if (!(std::abs(offset[0]) < kFar && std::abs(offset[1]) < kFar && std::abs(offset[2]) < kFar)) {
      return std::nullopt;
    }
    col += static_cast<int>(std::lround(offset[0]));
    row += static_cast<int>(std::lround(offset[1]));
    layer += static_cast<int>(std::lround(offset[2]));
    if (layer < 1 || layer > space.num_layers || col < kBorder || col >= first.cols - kBorder ||
        row < kBorder || row >= first.rows - kBorder) {
      return std::nullopt;
    }
  }
  if (step >= kMaxRefinementSteps) return std::nullopt;
  const float value = space.Dog(octave, layer).at<float>(row, col) * kIntensityScale;
  const float contrast = value + 0.5f * gradient.dot(offset);
  if (std::abs(contrast) < options.peak_threshold) return std::nullopt;
  // Principal curvatures in x, y: trace^2 / det below (r + 1)^2 / r.
  const float trace = hessian(0, 0) + hessian(1, 1);
  const float det = hessian(0, 0) * hessian(1, 1) - hessian(0, 1) * hessian(0, 1);
  const double r = options.edge_threshold;
  if (det <= 0.0f || trace * trace * r >= (r + 1.0) * (r + 1.0) * det) return std::nullopt;
  return Refined{row, col, layer, offset[0], offset[1], offset[2], contrast};
}

// Smoothed histogram of gradient directions (y down: from +x towards +y)
// around (row, col) of a Gaussian layer; returns its highest bin.
float OrientationHistogram(const cv::Mat& layer, int row, int col, int radius, float sigma,
                           std::array<float, kOrientationBins>& histogram) {
  std::array<float, kOrientationBins + 4> raw{};  // two bins of wrap-around each side
  // The Gaussian weight exp(-(i^2 + j^2) / (2 sigma^2)) is a product of one
  // factor per axis.
  std::vector<float> axis_weights(2 * radius + 1);
  for (int i = -radius; i <= radius; ++i) {
    axis_weights[i + radius] = std::exp(-static_cast<float>(i * i) / (2.0f * sigma * sigma));
  }
  // Gradients of the disc's pixels first, then their directions and
  // magnitudes in one vectorised pass each.
  const size_t capacity = static_cast<size_t>(2 * radius + 1) * (2 * radius + 1);
  std::vector<float> buffer(5 * capacity);
  float* dxs = buffer.data();
  float* dys = dxs + capacity;
  float* weights = dys + capacity;
  float* angles = weights + capacity;
  float* magnitudes = angles + capacity;
  int count = 0;
  for (int i = -radius; i <= radius; ++i) {
    const int y = row + i;
    if (y <= 0 || y >= layer.rows - 1) continue;
    const float* above = layer.ptr<float>(y - 1);
    const float* here = layer.ptr<float>(y);
    const float* below = layer.ptr<float>(y + 1);
    for (int j = -radius; j <= radius; ++j) {
      const int x = col + j;
      if (x <= 0 || x >= layer.cols - 1) continue;
      dxs[count] = here[x + 1] - here[x - 1];
      dys[count] = below[x] - above[x];
      weights[count] = axis_weights[i + radius] * axis_weights[j + radius];
      ++count;
    }
  }
  // Degrees in [0, 360), within 0.3 degree.
  cv::hal::fastAtan32f(dys, dxs, angles, count, true);
  cv::hal::magnitude32f(dxs, dys, magnitudes, count);
  for (int k = 0; k < count; ++k) {
    int bin = static_cast<int>(std::lround(angles[k] * (kOrientationBins / 360.0f)));
    if (bin >= kOrientationBins) bin -= kOrientationBins;
    raw[bin + 2] += weights[k] * magnitudes[k];
  }
  raw[0] = raw[kOrientationBins];
  raw[1] = raw[kOrientationBins + 1];
  raw[kOrientationBins + 2] = raw[2];
  raw[kOrientationBins + 3] = raw[3];
  float highest = 0.0f;
  for (int i = 0; i < kOrientationBins; ++i) {
    histogram[i] = (raw[i] + raw[i + 4]) * (1.0f / 16.0f) +
                   (raw[i + 1] + raw[i + 3]) * (4.0f / 16.0f) + raw[i + 2] * (6.0f / 16.0f);
    highest = std::max(highest, histogram[i]);
  }
  return highest;
}

}  // namespace

std::vector<cv::KeyPoint> DetectDogKeypoints(const cv::Mat& image,
                                             const DogDetectorOptions& options) {
  CV_Assert(image.type() == CV_8UC1);
  const ScaleSpace space = BuildScaleSpace(image, options.num_layers);
  // Candidates: |DoG| above half the peak threshold (Lowe's prefilter).
  const float candidate_threshold =
      static_cast<float>(0.5 * options.peak_threshold / kIntensityScale);
  std::vector<std::pair<int, Refined>> extrema;  // octave, refined extremum
  for (int o = 0; o < space.num_octaves; ++o) {
    for (int layer = 1; layer <= space.num_layers; ++layer) {
      const cv::Mat& dog = space.Dog(o, layer);
      for (int row = kBorder; row < dog.rows - kBorder; ++row) {
        const float* values = dog.ptr<float>(row);
        for (int col = kBorder; col < dog.cols - kBorder; ++col) {
          if (!(std::abs(values[col]) > candidate_threshold)) continue;
          if (!IsExtremum(space, o, layer, row, col)) continue;
          if (const std::optional<Refined> refined = Refine(space, o, layer, row, col, options)) {
            extrema.emplace_back(o, *refined);
          }
        }
      }
    }
  }
  // The same extremum reached from two neighbouring candidates counts once.
  const auto key = [](const std::pair<int, Refined>& e) {
    return std::make_tuple(e.first, e.second.layer, e.second.row, e.second.col, e.second.dx,
                           e.second.dy, e.second.dlayer);
  };
  std::sort(extrema.begin(), extrema.end(),
            [&key](const auto& a, const auto& b) { return key(a) < key(b); });
  extrema.erase(std::unique(extrema.begin(), extrema.end(),
                            [&key](const auto& a, const auto& b) { return key(a) == key(b); }),
                extrema.end());
  // The strongest first (ties by position, so the order is deterministic);
  // only those kept are given orientations.
  std::stable_sort(extrema.begin(), extrema.end(), [](const auto& a, const auto& b) {
    return std::abs(a.second.contrast) > std::abs(b.second.contrast);
  });
  if (options.max_num_extrema > 0 &&
      extrema.size() > static_cast<size_t>(options.max_num_extrema)) {
    extrema.resize(options.max_num_extrema);
  }

  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(extrema.size() * 5 / 4);
  for (const auto& [o, refined] : extrema) {
    const float octave_scale = static_cast<float>(1 << o);
    const float scale_in_octave =
        static_cast<float>(kInitialSigma) *
        std::pow(2.0f, (refined.layer + refined.dlayer) / space.num_layers);
    cv::KeyPoint keypoint;
    keypoint.pt = cv::Point2f((refined.col + refined.dx) * octave_scale,
                              (refined.row + refined.dy) * octave_scale);
    keypoint.size = 2.0f * scale_in_octave * octave_scale;
    keypoint.response = std::abs(refined.contrast);
    // cv::SIFT's packing: octave in the low byte, layer in the next, the
    // sub-layer offset scaled to [0, 255] in the third.
    keypoint.octave = o + (refined.layer << 8) +
                      (static_cast<int>(std::lround((refined.dlayer + 0.5f) * 255.0f)) << 16);
    std::array<float, kOrientationBins> histogram;
    const float highest = OrientationHistogram(
        space.Gaussian(o, refined.layer), refined.row, refined.col,
        static_cast<int>(std::lround(kOrientationRadiusFactor * scale_in_octave)),
        kOrientationSigmaFactor * scale_in_octave, histogram);
    for (int j = 0; j < kOrientationBins; ++j) {
      const int left = j > 0 ? j - 1 : kOrientationBins - 1;
      const int right = j < kOrientationBins - 1 ? j + 1 : 0;
      if (!(histogram[j] > histogram[left] && histogram[j] > histogram[right] &&
            histogram[j] >= kOrientationPeakRatio * highest)) {
        continue;
      }
      float bin = j + 0.5f * (histogram[left] - histogram[right]) /
                          (histogram[left] - 2.0f * histogram[j] + histogram[right]);
      if (bin < 0.0f) bin += kOrientationBins;
      if (bin >= kOrientationBins) bin -= kOrientationBins;
      keypoint.angle = bin * (360.0f / kOrientationBins);
      keypoints.push_back(keypoint);
    }
  }
  return keypoints;
}

}  // namespace viosfm
