// Descriptor matching of one pair at 2000 x 2000 SIFT-like descriptors:
// brute force on one thread and on all threads, epipolar-guided (752x480
// image, bands of 20 and 4 px, one thread), normalising one image's
// descriptors, and the guided matcher's dot-product kernel. (These timings
// used to be printed by a test.)
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/matching/descriptor_dot.h"
#include "viosfm/matching/descriptor_matcher.h"

namespace viosfm {
namespace {

constexpr int kDim = 128;
constexpr int kNum = 2000;

// Two images of kNum descriptors: 1500 noisy copies of image 1's first 1500
// at their projected positions, the rest unrelated.
struct Pair {
  FeatureDescriptors raw1, raw2;
  FloatDescriptors d1, d2;
  std::vector<Eigen::Vector2d> points1, points2;
  Eigen::Matrix3d F;
};

const Pair& MakePair() {
  static const Pair pair = [] {
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.03);
    Eigen::Matrix3d K;
    K << 458.0, 0.0, 367.0, 0.0, 457.0, 248.0, 0.0, 0.0, 1.0;
    const Rigid3d cam2_from_cam1(
        Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())),
        Eigen::Vector3d(-0.4, 0.05, 0.1));
    Pair p;
    p.F = FundamentalFromRelativePose(cam2_from_cam1, K, K);
    FeatureDescriptors raw1(kNum, kDim), raw2(kNum, kDim);
    const auto set_row = [](FeatureDescriptors& d, int row, const Eigen::VectorXd& v) {
      const double scale = 255.0 / v.maxCoeff();
      for (int k = 0; k < kDim; ++k) {
        d(row, k) = static_cast<uint8_t>(std::lround(std::clamp(v[k] * scale, 0.0, 255.0)));
      }
    };
    const auto random_descriptor = [&] {
      Eigen::VectorXd v(kDim);
      for (int k = 0; k < kDim; ++k) v[k] = uniform(rng);
      return Eigen::VectorXd(v.normalized());
    };
    for (int i = 0; i < kNum; ++i) {
      const Eigen::Vector2d pixel(752.0 * uniform(rng), 480.0 * uniform(rng));
      const Eigen::Vector3d point =
          (K.inverse() * pixel.homogeneous()) * (2.0 + 6.0 * uniform(rng));
      const Eigen::VectorXd descriptor = random_descriptor();
      set_row(raw1, i, descriptor);
      p.points1.push_back(pixel);
      if (i < 1500) {
        Eigen::VectorXd copy = descriptor;
        for (int k = 0; k < kDim; ++k) copy[k] = std::max(0.0, copy[k] + noise(rng));
        set_row(raw2, i, copy.normalized());
        p.points2.push_back((K * (cam2_from_cam1 * point)).hnormalized());
      } else {
        set_row(raw2, i, random_descriptor());
        p.points2.emplace_back(752.0 * uniform(rng), 480.0 * uniform(rng));
      }
    }
    p.d1 = NormalizeDescriptors(raw1);
    p.d2 = NormalizeDescriptors(raw2);
    p.raw1 = raw1;
    p.raw2 = raw2;
    return p;
  }();
  return pair;
}

// Argument: threads (-1: all).
void BM_MatchDescriptors(benchmark::State& state) {
  const Pair& pair = MakePair();
  DescriptorMatchingOptions options;
  options.num_threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(MatchDescriptors(pair.d1, pair.d2, options));
  }
}
BENCHMARK(BM_MatchDescriptors)->Arg(1)->Arg(-1)->Unit(benchmark::kMillisecond);

// Argument: the band's half width in px.
void BM_MatchDescriptorsGuided(benchmark::State& state) {
  const Pair& pair = MakePair();
  GuidedMatchingOptions options;
  options.matching.num_threads = 1;
  options.max_epipolar_distance_px = static_cast<double>(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        MatchDescriptorsGuided(pair.raw1, pair.raw2, pair.points1, pair.points2, pair.F, options));
  }
}
BENCHMARK(BM_MatchDescriptorsGuided)->Arg(20)->Arg(4)->Unit(benchmark::kMillisecond);

// The guided matcher's kernel: one query row against 200 rows of image 2
// (about the candidates of a 20 px band), exact uint8 dot products.
// Argument: 1 the kernel the CPU gets (AVX2 where it has it), 0 the
// portable one.
void BM_DescriptorDotProducts(benchmark::State& state) {
  const Pair& pair = MakePair();
  std::vector<int32_t> indices;
  for (int32_t j = 0; j < 200; ++j) indices.push_back((j * 37) % kNum);
  std::vector<int32_t> dots(indices.size());
  const bool dispatched = state.range(0) != 0;
  int64_t row = 0;
  for (auto _ : state) {
    const uint8_t* query = pair.raw1.row(row++ % kNum).data();
    if (dispatched) {
      DescriptorDotProducts(query, pair.raw2.data(), kDim, kDim, indices.data(),
                            static_cast<int>(indices.size()), dots.data());
    } else {
      DescriptorDotProductsPortable(query, pair.raw2.data(), kDim, kDim, indices.data(),
                                    static_cast<int>(indices.size()), dots.data());
    }
    benchmark::DoNotOptimize(dots.data());
  }
  state.SetLabel(dispatched && DescriptorDotProductsUseAvx2() ? "avx2" : "portable");
}
BENCHMARK(BM_DescriptorDotProducts)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

void BM_NormalizeDescriptors(benchmark::State& state) {
  FeatureDescriptors raw(kNum, kDim);
  raw.setConstant(17);
  for (auto _ : state) benchmark::DoNotOptimize(NormalizeDescriptors(raw));
}
BENCHMARK(BM_NormalizeDescriptors)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace viosfm
