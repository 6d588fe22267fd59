#include "viosfm/features/sift.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "viosfm/features/dog_detector.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// cv::SIFT in OpenCV 4.6 doubles the image with cv::resize (INTER_LINEAR,
// which puts pixel j of the doubled image at j / 2 - 0.25 of the original)
// and later halves with INTER_NEAREST (pixel i at 2 i), but maps keypoints
// back as if pixel j were at j / 2: every position it reports is 0.25 pixel
// too large in x and y, at every octave. (OpenCV 4.8's
// enable_precise_upscale removes this.) Checked by the rotation and
// projected-blob tests in sift_test.cc.
constexpr double kOpenCvSiftPositionBias = 0.25;
// cv::SIFT's initial blur (Lowe's sigma_0), as VLFeat's and COLMAP's.
constexpr double kSiftSigma = 1.6;
// Scale applied to unit-norm descriptors before rounding (COLMAP).
constexpr float kDescriptorQuantizationScale = 512.0f;

}  // namespace

std::string SiftOptions::Validate() const {
  if (max_num_features < 1) return "max_num_features must be >= 1";
  if (!(peak_threshold >= 0.0)) return "peak_threshold must be >= 0";
  if (!(edge_threshold > 0.0)) return "edge_threshold must be > 0";
  if (num_octave_layers < 1) return "num_octave_layers must be >= 1";
  if (first_octave != -1 && first_octave != 0) return "first_octave must be -1 or 0";
  if (max_image_size < 0) return "max_image_size must be >= 0 (0: no limit)";
  if (num_threads < 1) return "num_threads must be >= 1";
  return "";
}

FeatureDescriptorsFloat L2NormalizeDescriptors(const FeatureDescriptorsFloat& descriptors) {
  FeatureDescriptorsFloat normalized = descriptors;
  for (Eigen::Index r = 0; r < normalized.rows(); ++r) {
    const float norm = normalized.row(r).norm();
    if (norm > 0.0f) normalized.row(r) /= norm;
  }
  return normalized;
}

FeatureDescriptorsFloat RootSiftNormalizeDescriptors(const FeatureDescriptorsFloat& descriptors) {
  FeatureDescriptorsFloat normalized = descriptors;
  for (Eigen::Index r = 0; r < normalized.rows(); ++r) {
    // SIFT histograms are non-negative; the absolute value guards the sqrt.
    const float norm = normalized.row(r).lpNorm<1>();
    if (norm > 0.0f) normalized.row(r) = (normalized.row(r).array().abs() / norm).sqrt();
  }
  return normalized;
}

FeatureDescriptors QuantizeDescriptors(const FeatureDescriptorsFloat& descriptors) {
  FeatureDescriptors quantized(descriptors.rows(), descriptors.cols());
  for (Eigen::Index i = 0; i < descriptors.size(); ++i) {
    const float value = std::round(kDescriptorQuantizationScale * descriptors.data()[i]);
    quantized.data()[i] = static_cast<uint8_t>(std::clamp(value, 0.0f, 255.0f));
  }
  return quantized;
}

ImageFeatures ExtractSift(const GreyImage& image, const SiftOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("SiftOptions: " + error);
  }
  VIOSFM_CHECK(image.width >= 0 && image.height >= 0 &&
               image.pixels.size() == static_cast<size_t>(image.width) * image.height)
      << "image of " << image.width << " x " << image.height << " pixels has "
      << image.pixels.size() << " values";
  ImageFeatures features;
  features.descriptors.resize(0, 128);
  if (image.empty()) return features;

  // OpenCV divides contrastThreshold by nOctaveLayers before comparing it
  // with the DoG (intensities in [0, 1]); VLFeat/COLMAP compare directly.
  const double contrast_threshold = options.peak_threshold * options.num_octave_layers;
  cv::Ptr<cv::SIFT> sift =
      cv::SIFT::create(options.max_num_features, options.num_octave_layers, contrast_threshold,
                       options.edge_threshold, kSiftSigma, CV_32F);
  // A view of the pixels (cv::Mat does not take ownership), reduced when
  // larger than max_image_size: a pixel centre x of the reduced image is
  // (x + 0.5) / scale - 0.5 of the image.
  const cv::Mat full(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.pixels.data()));
  cv::Mat mat = full;
  double scale_x = 1.0, scale_y = 1.0;
  const int longest = std::max(image.width, image.height);
  if (options.max_image_size > 0 && longest > options.max_image_size) {
    const double scale = static_cast<double>(options.max_image_size) / longest;
    cv::resize(full, mat,
               cv::Size(std::max(1, static_cast<int>(std::lround(image.width * scale))),
                        std::max(1, static_cast<int>(std::lround(image.height * scale)))),
               0.0, 0.0, cv::INTER_AREA);
    scale_x = static_cast<double>(mat.cols) / image.width;
    scale_y = static_cast<double>(mat.rows) / image.height;
  }
  std::vector<cv::KeyPoint> cv_keypoints;
  cv::Mat cv_descriptors;
  // cv::SIFT's own detector starts from the image doubled and reports
  // positions kOpenCvSiftPositionBias too large; DetectDogKeypoints starts from the
  // image itself, and cv::SIFT then describes its keypoints on a pyramid
  // that starts there too (the keypoints' packed octaves are all >= 0).
  double position_bias = kOpenCvSiftPositionBias;
  if (options.first_octave == 0) {
    DogDetectorOptions detector;
    detector.num_layers = options.num_octave_layers;
    detector.peak_threshold = options.peak_threshold;
    detector.edge_threshold = options.edge_threshold;
    detector.max_num_extrema = options.max_num_features;
    cv_keypoints = DetectDogKeypoints(mat, detector);
    if (!cv_keypoints.empty()) sift->compute(mat, cv_keypoints, cv_descriptors);
    position_bias = 0.0;
  } else {
    sift->detectAndCompute(mat, cv::noArray(), cv_keypoints, cv_descriptors);
  }
  VIOSFM_CHECK(cv_descriptors.rows == static_cast<int>(cv_keypoints.size()))
      << cv_keypoints.size() << " keypoints but " << cv_descriptors.rows << " descriptors";

  // OpenCV keeps every keypoint tied with the n-th response, so there may be
  // a few more than asked for: order by response and cut.
  std::vector<int> order(cv_keypoints.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&cv_keypoints](int a, int b) {
    return cv_keypoints[a].response > cv_keypoints[b].response;
  });
  if (order.size() > static_cast<size_t>(options.max_num_features)) {
    order.resize(options.max_num_features);
  }

  const int num_cols = cv_descriptors.empty() ? 128 : cv_descriptors.cols;
  FeatureDescriptorsFloat raw(static_cast<Eigen::Index>(order.size()), num_cols);
  features.keypoints.reserve(order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    const cv::KeyPoint& k = cv_keypoints[order[i]];
    // KeyPoint::size is the diameter 2 sigma.
    const float scale = static_cast<float>(0.5 * k.size / std::sqrt(scale_x * scale_y));
    const float orientation = k.angle * static_cast<float>(std::numbers::pi / 180.0);
    features.keypoints.push_back(FeatureKeypoint::FromScaleOrientation(
        static_cast<float>((k.pt.x - position_bias + 0.5) / scale_x - 0.5),
        static_cast<float>((k.pt.y - position_bias + 0.5) / scale_y - 0.5), scale, orientation));
    const float* row = cv_descriptors.ptr<float>(order[i]);
    std::copy(row, row + num_cols, raw.row(static_cast<Eigen::Index>(i)).data());
  }
  features.descriptors = QuantizeDescriptors(options.root_sift ? RootSiftNormalizeDescriptors(raw)
                                                               : L2NormalizeDescriptors(raw));
  return features;
}

std::vector<Eigen::Vector2d> UndistortKeypoints(const Camera& camera,
                                                const FeatureKeypoints& keypoints) {
  std::vector<Eigen::Vector2d> normalized;
  normalized.reserve(keypoints.size());
  for (const FeatureKeypoint& keypoint : keypoints) {
    normalized.push_back(ImageToCam(camera, Eigen::Vector2d(keypoint.x, keypoint.y)));
  }
  return normalized;
}

}  // namespace viosfm
