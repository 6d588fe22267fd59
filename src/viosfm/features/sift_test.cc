#include "viosfm/features/sift.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>

#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/scene_model.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// Camera at (0, 0, 1.4) in the room, looking along +x (z forward, y down).
Rigid3d RoomCamFromWorld(double yaw = 0.0) {
  Eigen::Matrix3d world_from_cam;
  world_from_cam << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * world_from_cam;
  return Rigid3d(rotation, Eigen::Vector3d(0.0, 0.0, 1.4)).Inverse();
}

const GreyImage& RoomImage() {
  static const GreyImage image = [] {
    const Scene scene = MakeRoomScene(RoomSceneOptions{});
    return Render(scene, SimulationOptions::DefaultCamera(), RoomCamFromWorld(), RenderOptions{});
  }();
  return image;
}

const ImageFeatures& RoomFeatures() {
  static const ImageFeatures features = ExtractSift(RoomImage(), SiftOptions{});
  return features;
}

// Index of the keypoint nearest to `point`, and its distance.
std::pair<int, double> Nearest(const FeatureKeypoints& keypoints, const Eigen::Vector2d& point) {
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const double distance = (Eigen::Vector2d(keypoints[i].x, keypoints[i].y) - point).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best = static_cast<int>(i);
    }
  }
  return {best, best_distance};
}

double Median(std::vector<double> values) {
  EXPECT_FALSE(values.empty());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

TEST(SiftOptions, Validate) {
  EXPECT_TRUE(SiftOptions{}.Check());
  EXPECT_EQ(SiftOptions{}.max_num_features, 8192);
  SiftOptions options;
  options.max_num_features = 0;
  EXPECT_NE(options.Validate().find("max_num_features"), std::string::npos);
  options = SiftOptions{};
  options.num_threads = 0;
  EXPECT_NE(options.Validate().find("num_threads"), std::string::npos);
  options = SiftOptions{};
  options.peak_threshold = -1.0;
  EXPECT_NE(options.Validate().find("peak_threshold"), std::string::npos);
  EXPECT_THROW(ExtractSift(GreyImage(10, 10), options), InputError);
}

TEST(Sift, RenderedRoomFrameHasManyFeatures) {
  const ImageFeatures& features = RoomFeatures();
  std::cout << "rendered room frame: " << features.keypoints.size() << " features\n";
  EXPECT_GE(features.keypoints.size(), 500u);
  ASSERT_EQ(features.descriptors.rows(), static_cast<Eigen::Index>(features.keypoints.size()));
  ASSERT_EQ(features.descriptors.cols(), 128);
  for (const FeatureKeypoint& keypoint : features.keypoints) {
    ASSERT_GE(keypoint.x, 0.0f);
    ASSERT_LE(keypoint.x, 752.0f);
    ASSERT_GE(keypoint.y, 0.0f);
    ASSERT_LE(keypoint.y, 480.0f);
    ASSERT_GT(keypoint.Scale(), 0.5f);
  }
  // Same image, same features (no randomness).
  const ImageFeatures again = ExtractSift(RoomImage(), SiftOptions{});
  EXPECT_EQ(again.descriptors, features.descriptors);
}

TEST(Sift, CapKeepsTheRequestedNumber) {
  SiftOptions options;
  options.max_num_features = 100;
  const ImageFeatures capped = ExtractSift(RoomImage(), options);
  EXPECT_EQ(capped.keypoints.size(), 100u);
  EXPECT_EQ(capped.descriptors.rows(), 100);
  // They are among the strongest of the uncapped set: most of them are
  // keypoints of the full extraction too.
  int found = 0;
  for (const FeatureKeypoint& keypoint : capped.keypoints) {
    found += Nearest(RoomFeatures().keypoints, {keypoint.x, keypoint.y}).second < 1e-3;
  }
  EXPECT_GE(found, 95);
}

TEST(Sift, DescriptorNormalisationAndQuantisation) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> uniform(0.0f, 100.0f);
  FeatureDescriptorsFloat raw(20, 128);
  for (Eigen::Index i = 0; i < raw.size(); ++i) raw.data()[i] = uniform(rng);
  raw.row(3).setZero();
  const FeatureDescriptorsFloat root = RootSiftNormalizeDescriptors(raw);
  const FeatureDescriptorsFloat l2 = L2NormalizeDescriptors(raw);
  for (Eigen::Index r = 0; r < raw.rows(); ++r) {
    if (r == 3) continue;
    EXPECT_NEAR(root.row(r).norm(), 1.0f, 1e-5f);
    EXPECT_NEAR(root.row(r).squaredNorm(), (raw.row(r) / raw.row(r).sum()).sum(), 1e-5f);
    EXPECT_NEAR(l2.row(r).norm(), 1.0f, 1e-5f);
  }
  EXPECT_TRUE(root.row(3).isZero(0.0f));

  FeatureDescriptorsFloat values(1, 5);
  values << 0.0f, 0.1f, 0.2f, 0.6f, -0.01f;
  const FeatureDescriptors quantized = QuantizeDescriptors(values);
  EXPECT_EQ(quantized(0, 0), 0);
  EXPECT_EQ(quantized(0, 1), 51);   // round(51.2)
  EXPECT_EQ(quantized(0, 2), 102);  // round(102.4)
  EXPECT_EQ(quantized(0, 3), 255);  // clamped
  EXPECT_EQ(quantized(0, 4), 0);    // clamped

  // The stored RootSIFT descriptors are unit vectors scaled by 512 (up to
  // rounding and the rare clamp at 255).
  const FeatureDescriptors& descriptors = RoomFeatures().descriptors;
  for (Eigen::Index r = 0; r < descriptors.rows(); ++r) {
    const double norm = descriptors.row(r).cast<double>().norm();
    ASSERT_NEAR(norm, 512.0, 10.0) << r;
  }
}

// A shifted copy of an image: shifted(x + dx, y + dy) = image(x, y); the
// uncovered border repeats the nearest pixel.
GreyImage Shifted(const GreyImage& image, int dx, int dy) {
  GreyImage shifted(image.width, image.height);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      shifted.at(x, y) =
          image.at(std::clamp(x - dx, 0, image.width - 1), std::clamp(y - dy, 0, image.height - 1));
    }
  }
  return shifted;
}

SiftOptions WithFirstOctave(int first_octave) {
  SiftOptions options;
  options.first_octave = first_octave;
  return options;
}

// The geometric tests below hold for both first octaves: -1 (the image
// doubled, cv::SIFT's own) and 0 (cv::SIFT given the image halved, its
// keypoints mapped back).
class SiftGeometry : public ::testing::TestWithParam<int> {
 protected:
  SiftOptions Options() const { return WithFirstOctave(GetParam()); }
  const ImageFeatures& Features() const {
    static const ImageFeatures doubled = ExtractSift(RoomImage(), WithFirstOctave(-1));
    static const ImageFeatures itself = ExtractSift(RoomImage(), WithFirstOctave(0));
    return GetParam() == -1 ? doubled : itself;
  }
};

INSTANTIATE_TEST_SUITE_P(FirstOctave, SiftGeometry, ::testing::Values(-1, 0),
                         [](const ::testing::TestParamInfo<int>& info) {
                           return info.param == -1 ? std::string("Doubled") : std::string("Itself");
                         });

// Keypoints of the image shifted by (dx, dy) pixels, against the keypoints
// of the image moved by (dx, dy): the median distance, and the fraction of
// the interior keypoints found within a pixel.
std::pair<double, double> ShiftErrors(const ImageFeatures& features, const SiftOptions& options,
                                      int dx, int dy) {
  const ImageFeatures shifted = ExtractSift(Shifted(RoomImage(), dx, dy), options);
  std::vector<double> errors;
  int interior = 0;
  for (const FeatureKeypoint& keypoint : features.keypoints) {
    // Away from the borders the shifted image holds the same content.
    if (keypoint.x < 40 || keypoint.x > 752 - 60 || keypoint.y < 40 || keypoint.y > 480 - 50) {
      continue;
    }
    ++interior;
    const auto [index, distance] =
        Nearest(shifted.keypoints, Eigen::Vector2d(keypoint.x + dx, keypoint.y + dy));
    if (distance < 1.0) errors.push_back(distance);
  }
  EXPECT_GT(interior, 300);
  return {Median(errors), static_cast<double>(errors.size()) / interior};
}

TEST_P(SiftGeometry, KeypointsMoveWithAnEvenShift) {
  const auto [median, found] = ShiftErrors(Features(), Options(), 16, 8);
  EXPECT_GE(found, 0.9);
  EXPECT_LT(median, 1e-3);
}

// With the first octave at 0 an odd shift changes which pixels are averaged
// together: the keypoints still follow, to a few hundredths of a pixel. A
// wrong phase in mapping the halved image back would show as 0.5 pixel.
TEST_P(SiftGeometry, KeypointsMoveWithAnOddShift) {
  const auto [median, found] = ShiftErrors(Features(), Options(), 17, 9);
  std::cout << "odd shift: median error " << median << " px, " << 100.0 * found << " % found\n";
  EXPECT_GE(found, 0.8);
  EXPECT_LT(median, 0.06);
}

// Rotating the image by 90 degrees clockwise (on screen) maps the pixel
// centre (x, y) to (H - 1 - y, x) (H the height; pixel centres at integer
// coordinates, viosfm's convention) and adds
// pi / 2 to the orientation (measured from +x towards +y, y down).
TEST_P(SiftGeometry, RotationMovesPositionsAndOrientations) {
  const GreyImage& image = RoomImage();
  GreyImage rotated(image.height, image.width);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) rotated.at(image.height - 1 - y, x) = image.at(x, y);
  }
  const ImageFeatures rotated_features = ExtractSift(rotated, Options());
  std::vector<double> position_errors;
  std::vector<double> angle_errors;
  std::vector<double> scale_ratios;
  std::vector<double> descriptor_distances;
  for (size_t i = 0; i < Features().keypoints.size(); ++i) {
    const FeatureKeypoint& keypoint = Features().keypoints[i];
    const Eigen::Vector2d expected(image.height - 1 - keypoint.y, keypoint.x);
    const auto [index, distance] = Nearest(rotated_features.keypoints, expected);
    if (distance > 0.5) continue;
    const FeatureKeypoint& match = rotated_features.keypoints[index];
    position_errors.push_back(distance);
    descriptor_distances.push_back((Features().descriptors.row(i).cast<double>() -
                                    rotated_features.descriptors.row(index).cast<double>())
                                       .norm());
    const double difference = match.Orientation() - keypoint.Orientation() - std::numbers::pi / 2;
    angle_errors.push_back(std::abs(std::remainder(difference, 2.0 * std::numbers::pi)));
    scale_ratios.push_back(match.Scale() / keypoint.Scale());
  }
  ASSERT_GE(position_errors.size(), 0.5 * Features().keypoints.size());
  EXPECT_LT(Median(position_errors), 0.05);
  EXPECT_LT(Median(angle_errors), 0.02);
  EXPECT_NEAR(Median(scale_ratios), 1.0, 0.01);
  // The descriptor turns with the orientation: the rotated keypoint's
  // descriptor is (almost) the same vector, of norm 512.
  std::cout << "rotation: median descriptor distance " << Median(descriptor_distances) << "\n";
  EXPECT_LT(Median(descriptor_distances), 60.0);
}

// Without the doubled octave no keypoint is finer than the initial blur.
// The room frame enlarged twice by pixel replication, extracted with
// max_image_size at the frame's own size: the area reduction gives the
// frame back exactly, so the keypoints are the frame's, at the enlarged
// image's pixel centres (pixel centre x of the frame is the middle of
// pixels 2x and 2x + 1: 2x + 0.5) and twice the scale.
TEST(Sift, MaxImageSizeGivesKeypointsInTheImagesOwnPixels) {
  const GreyImage& image = RoomImage();
  GreyImage enlarged(2 * image.width, 2 * image.height);
  for (int y = 0; y < enlarged.height; ++y) {
    for (int x = 0; x < enlarged.width; ++x) enlarged.at(x, y) = image.at(x / 2, y / 2);
  }
  SiftOptions options;
  options.max_image_size = std::max(image.width, image.height);
  const ImageFeatures reduced = ExtractSift(enlarged, options);
  const ImageFeatures& original = RoomFeatures();
  ASSERT_EQ(reduced.keypoints.size(), original.keypoints.size());
  for (size_t i = 0; i < original.keypoints.size(); ++i) {
    EXPECT_NEAR(reduced.keypoints[i].x, 2.0f * original.keypoints[i].x + 0.5f, 1e-3) << i;
    EXPECT_NEAR(reduced.keypoints[i].y, 2.0f * original.keypoints[i].y + 0.5f, 1e-3) << i;
    EXPECT_NEAR(reduced.keypoints[i].Scale(), 2.0f * original.keypoints[i].Scale(), 1e-3);
  }
  EXPECT_EQ(reduced.descriptors, original.descriptors);
  options.max_image_size = -1;
  EXPECT_NE(options.Validate().find("max_image_size"), std::string::npos);
}

TEST(Sift, FirstOctaveZeroHasNoKeypointBelowSigma16) {
  const ImageFeatures features = ExtractSift(RoomImage(), WithFirstOctave(0));
  EXPECT_GE(features.keypoints.size(), 500u);
  float smallest = std::numeric_limits<float>::infinity();
  for (const FeatureKeypoint& keypoint : features.keypoints) {
    smallest = std::min(smallest, keypoint.Scale());
  }
  EXPECT_GE(smallest, 1.6f * 0.99f);
  float smallest_doubled = std::numeric_limits<float>::infinity();
  for (const FeatureKeypoint& keypoint : RoomFeatures().keypoints) {
    smallest_doubled = std::min(smallest_doubled, keypoint.Scale());
  }
  EXPECT_LT(smallest_doubled, 1.6f);
  SiftOptions options;
  options.first_octave = 1;
  EXPECT_NE(options.Validate().find("first_octave"), std::string::npos);
}

// Bright Gaussian blobs drawn at the projections of known 3D points (pixel
// positions as Project() returns them): SIFT finds them at those positions,
// and UndistortKeypoints gives back the points' normalised coordinates. The
// same on the image cropped to an odd width and height.
TEST_P(SiftGeometry, ProjectedPointsUndistortToTheirNormalisedCoordinates) {
  const Camera camera = SimulationOptions::DefaultCamera();
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.5, 0.5);
  for (int i = 0; i < 9; ++i) {
    for (int j = 0; j < 6; ++j) {
      const Eigen::Vector3d point(-0.65 + 0.16 * i + 0.02 * jitter(rng),
                                  -0.40 + 0.16 * j + 0.02 * jitter(rng), 1.0);
      points.push_back(point * (2.0 + jitter(rng)));
      pixels.push_back(*Project(camera, points.back()));
    }
  }
  constexpr double kSigma = 2.5;  // pixels
  for (const int crop : {0, 1}) {
    GreyImage image(static_cast<int>(camera.width) - crop, static_cast<int>(camera.height) - crop,
                    20);
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) {
        double value = 20.0;
        for (const Eigen::Vector2d& pixel : pixels) {
          const double d2 = (Eigen::Vector2d(x, y) - pixel).squaredNorm();
          if (d2 < 100.0) value += 200.0 * std::exp(-d2 / (2.0 * kSigma * kSigma));
        }
        image.at(x, y) = static_cast<uint8_t>(std::min(255.0, std::round(value)));
      }
    }
    const ImageFeatures features = ExtractSift(image, Options());
    const std::vector<Eigen::Vector2d> normalized = UndistortKeypoints(camera, features.keypoints);
    ASSERT_EQ(normalized.size(), features.keypoints.size());
    const double focal = MeanFocalLength(camera);
    std::vector<double> pixel_errors;
    std::vector<double> normalized_errors;
    std::vector<double> scales;
    for (size_t i = 0; i < points.size(); ++i) {
      const auto [index, distance] = Nearest(features.keypoints, pixels[i]);
      ASSERT_LT(distance, 0.2) << "blob " << i << " at " << pixels[i].transpose() << ", crop "
                               << crop;
      pixel_errors.push_back(distance);
      scales.push_back(features.keypoints[index].Scale());
      const Eigen::Vector2d expected = points[i].hnormalized();
      normalized_errors.push_back((normalized[index] - expected).norm() * focal);
    }
    // Sub-pixel localisation of a sampled blob: a few hundredths of a pixel.
    // A half-pixel convention error would show as ~0.7 pixel.
    EXPECT_LT(Median(pixel_errors), 0.05) << "crop " << crop;
    EXPECT_LT(Median(normalized_errors), 0.06) << "crop " << crop;
    // The normalised Laplacian of a Gaussian blob of sigma s peaks at scale
    // s. The DoG of layers sigma and k sigma (k = 2^(1/3)) approximates it
    // at about sqrt(k) sigma but is reported at sigma, so the blob's
    // keypoint is reported at s / sqrt(k) = 2.23 pixels.
    const double expected_scale = kSigma / std::pow(2.0, 1.0 / 6.0);
    EXPECT_NEAR(Median(scales), expected_scale, 0.05 * expected_scale) << "crop " << crop;
    std::cout << image.width << " x " << image.height << ": blob localisation median "
              << Median(pixel_errors) << " px, scale " << Median(scales) << " px\n";
  }
}

TEST(Sift, RealEurocFrames) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  const Sequence sequence = ReadEurocDataset(root);
  ASSERT_GE(sequence.images.size(), 5u);
  constexpr int kFrames = 5;
  for (const int first_octave : {-1, 0}) {
    size_t total = 0;
    double seconds = 0.0;
    for (int i = 0; i < kFrames; ++i) {
      const size_t index = i * (sequence.images.size() / kFrames);
      const GreyImage image = ReadGreyImage(sequence.images[index].path);
      ASSERT_EQ(image.width, 752);
      ASSERT_EQ(image.height, 480);
      Timer timer;
      const ImageFeatures features = ExtractSift(image, WithFirstOctave(first_octave));
      seconds += timer.ElapsedSeconds();
      EXPECT_GE(features.keypoints.size(), 500u) << sequence.images[index].path;
      total += features.keypoints.size();
    }
    std::cout << "EuRoC V1_01 752x480, first octave " << first_octave << ": "
              << static_cast<double>(total) / kFrames << " features per frame, "
              << 1e3 * seconds / kFrames << " ms per frame (one image at a time)\n";
  }
}

}  // namespace
}  // namespace viosfm
