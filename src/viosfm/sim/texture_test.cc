#include "viosfm/sim/texture.h"

#include <gtest/gtest.h>

#include <cmath>

namespace viosfm {
namespace {

ProceduralTextureOptions SmallOptions(uint64_t seed) {
  ProceduralTextureOptions options;
  options.width = 256;
  options.height = 128;
  options.seed = seed;
  return options;
}

std::vector<float> Level0(const Texture& texture) {
  std::vector<float> texels;
  for (int j = 0; j < texture.height(); ++j) {
    for (int i = 0; i < texture.width(); ++i) texels.push_back(texture.Texel(0, i, j));
  }
  return texels;
}

TEST(Texture, SameSeedSameTexelsOtherSeedOtherTexels) {
  const std::vector<float> a = Level0(MakeProceduralTexture(SmallOptions(3)));
  const std::vector<float> b = Level0(MakeProceduralTexture(SmallOptions(3)));
  const std::vector<float> c = Level0(MakeProceduralTexture(SmallOptions(4)));
  EXPECT_EQ(a, b);
  int num_different = 0;
  for (size_t k = 0; k < a.size(); ++k) num_different += a[k] != c[k];
  EXPECT_GT(num_different, static_cast<int>(a.size()) * 9 / 10);
}

TEST(Texture, ProceduralTextureHasContrastAtFineAndCoarseScales) {
  const Texture texture = MakeProceduralTexture(SmallOptions(11));
  const std::vector<float> texels = Level0(texture);
  double sum = 0.0;
  double sum_sq = 0.0;
  float lo = 1.0f;
  float hi = 0.0f;
  for (float t : texels) {
    sum += t;
    sum_sq += t * t;
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  const double mean = sum / texels.size();
  const double stddev = std::sqrt(sum_sq / texels.size() - mean * mean);
  EXPECT_GE(lo, 0.0f);
  EXPECT_LE(hi, 1.0f);
  EXPECT_GT(stddev, 0.15);
  // Fine detail: mean absolute difference of horizontal neighbours.
  double gradient = 0.0;
  for (int j = 0; j < texture.height(); ++j) {
    for (int i = 0; i < texture.width(); ++i) {
      gradient += std::abs(texture.Texel(0, i + 1, j) - texture.Texel(0, i, j));
    }
  }
  gradient /= texels.size();
  EXPECT_GT(gradient, 0.03);
}

TEST(Texture, MipLevelsAreBoxAverages) {
  const Texture texture = MakeProceduralTexture(SmallOptions(5));
  ASSERT_EQ(texture.num_levels(), 8);  // 256x128 -> 2x1
  for (int level = 1; level < texture.num_levels(); ++level) {
    for (int j = 0; j < (texture.height() >> level); j += 7) {
      for (int i = 0; i < (texture.width() >> level); i += 5) {
        const float expected = 0.25f * (texture.Texel(level - 1, 2 * i, 2 * j) +
                                        texture.Texel(level - 1, 2 * i + 1, 2 * j) +
                                        texture.Texel(level - 1, 2 * i, 2 * j + 1) +
                                        texture.Texel(level - 1, 2 * i + 1, 2 * j + 1));
        EXPECT_NEAR(texture.Texel(level, i, j), expected, 1e-6f);
      }
    }
  }
}

TEST(Texture, SampleIsExactAtTexelCentresAndBilinearBetween) {
  const Texture texture = MakeProceduralTexture(SmallOptions(6));
  EXPECT_FLOAT_EQ(texture.Sample(10.5, 20.5, 0.5), texture.Texel(0, 10, 20));
  EXPECT_FLOAT_EQ(texture.Sample(11.0, 20.5, 1.0),
                  0.5f * (texture.Texel(0, 10, 20) + texture.Texel(0, 11, 20)));
  // At footprint 2 exactly level 1; at 2^1.5 halfway between levels 1 and 2.
  EXPECT_FLOAT_EQ(texture.Sample(9.0, 21.0, 2.0), texture.Texel(1, 4, 10));
  EXPECT_NEAR(texture.Sample(9.0, 21.0, std::pow(2.0, 1.5)),
              0.5f * (texture.SampleLevel(1, 9.0, 21.0) + texture.SampleLevel(2, 9.0, 21.0)), 1e-6);
}

TEST(Texture, TilesInBothDirections) {
  const Texture texture = MakeProceduralTexture(SmallOptions(7));
  for (double footprint : {0.5, 3.0, 40.0}) {
    EXPECT_FLOAT_EQ(texture.Sample(3.3, 4.7, footprint),
                    texture.Sample(3.3 + 2 * texture.width(), 4.7 - texture.height(), footprint));
  }
  // Across the seam: bilinear between the last and the first texel.
  EXPECT_FLOAT_EQ(texture.Sample(0.0, 0.5, 0.5),
                  0.5f * (texture.Texel(0, 0, 0) + texture.Texel(0, texture.width() - 1, 0)));
}

TEST(Texture, HugeFootprintGivesTheMean) {
  const Texture texture = MakeProceduralTexture(SmallOptions(8));
  const std::vector<float> texels = Level0(texture);
  double mean = 0.0;
  for (float t : texels) mean += t;
  mean /= texels.size();
  // Coarsest level is 2x1: the means of the two halves; sampling at their
  // common edge averages them.
  EXPECT_NEAR(texture.Sample(128.0, 64.0, 1e6), mean, 1e-5);
}

TEST(Texture, CheckerboardLayout) {
  const Texture checker = MakeCheckerboardTexture(64, 32, 8, 0.2f, 0.8f);
  EXPECT_FLOAT_EQ(checker.Texel(0, 0, 0), 0.2f);
  EXPECT_FLOAT_EQ(checker.Texel(0, 8, 0), 0.8f);
  EXPECT_FLOAT_EQ(checker.Texel(0, 8, 8), 0.2f);
  EXPECT_FLOAT_EQ(checker.Texel(0, 7, 15), 0.8f);
  // On a square edge, half way between the two values.
  EXPECT_FLOAT_EQ(checker.Sample(8.0, 4.5, 0.5), 0.5f);
  EXPECT_NEAR(checker.Sample(5.0, 5.0, 1e6), 0.5f, 1e-6);
}

TEST(Texture, OptionsValidation) {
  ProceduralTextureOptions options;
  EXPECT_TRUE(options.Check());
  options.width = 300;
  EXPECT_NE(options.Validate().find("width"), std::string::npos);
  EXPECT_EQ(NextPowerOfTwo(1), 1);
  EXPECT_EQ(NextPowerOfTwo(384), 512);
  EXPECT_EQ(NextPowerOfTwo(512), 512);
}

}  // namespace
}  // namespace viosfm

namespace viosfm {
namespace {

TEST(TextureFromImage, CopiesBoxFiltersAndEnlarges) {
  GreyImage image(96, 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 96; ++x) image.at(x, y) = static_cast<uint8_t>((7 * x + 13 * y) % 256);
  }
  // The centred 64 x 64 square starts at column 16.
  const Texture same = TextureFromImage(image, 64);
  ASSERT_EQ(same.width(), 64);
  for (int j : {0, 5, 63}) {
    for (int i : {0, 17, 63})
      EXPECT_FLOAT_EQ(same.Texel(0, i, j), image.at(16 + i, 63 - j) / 255.0f);
  }
  const Texture half = TextureFromImage(image, 32);
  for (int j : {0, 9, 31}) {
    for (int i : {0, 20, 31}) {
      const int x = 16 + 2 * i;
      const int y = 2 * (31 - j);  // rows flipped
      const double mean =
          (image.at(x, y) + image.at(x + 1, y) + image.at(x, y + 1) + image.at(x + 1, y + 1)) /
          (4 * 255.0);
      EXPECT_NEAR(half.Texel(0, i, j), mean, 1e-6);
    }
  }
  GreyImage ramp(4, 4);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) ramp.at(x, y) = static_cast<uint8_t>(50 * x);
  }
  const Texture large = TextureFromImage(ramp, 8);
  // Texel 3's centre is at source x = (3.5) / 2 - 0.5 = 1.25.
  EXPECT_NEAR(large.Texel(0, 3, 2), 1.25 * 50 / 255.0, 1e-6);
  EXPECT_NEAR(large.Texel(0, 0, 2), 0.0, 1e-6);  // clamped at the edge
}

TEST(CropTexture, WrapsAround) {
  const Texture texture = MakeProceduralTexture(SmallOptions(3));
  const Texture window = CropTexture(texture, 250, 100, 16, 64);
  ASSERT_EQ(window.width(), 16);
  ASSERT_EQ(window.height(), 64);
  for (int j : {0, 27, 28, 63}) {
    for (int i : {0, 5, 6, 15}) {
      EXPECT_EQ(window.Texel(0, i, j), texture.Texel(0, (250 + i) % 256, (100 + j) % 128));
    }
  }
}

}  // namespace
}  // namespace viosfm
