// Seeded random numbers. Every random choice in viosfm takes its seed from an
// Options struct, so a run is reproducible.
#pragma once

#include <cstdint>
#include <random>

namespace viosfm {

inline constexpr uint64_t kDefaultRandomSeed = 0;

class Random {
 public:
  explicit Random(uint64_t seed = kDefaultRandomSeed) : engine_(seed) {}

  // Uniform in [low, high).
  double Uniform(double low = 0.0, double high = 1.0) {
    return std::uniform_real_distribution<double>(low, high)(engine_);
  }
  // Uniform integer in [low, high] (both included).
  int64_t UniformInt(int64_t low, int64_t high) {
    return std::uniform_int_distribution<int64_t>(low, high)(engine_);
  }
  double Normal(double mean = 0.0, double stddev = 1.0) {
    return std::normal_distribution<double>(mean, stddev)(engine_);
  }
  std::mt19937_64& engine() { return engine_; }

 private:
  std::mt19937_64 engine_;
};

}  // namespace viosfm
