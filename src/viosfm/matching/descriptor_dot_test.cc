#include "viosfm/matching/descriptor_dot.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <iostream>
#include <random>
#include <vector>

namespace viosfm {
namespace {

// Sums in int64, one product at a time: the truth both kernels must give.
int64_t NaiveDot(const uint8_t* a, const uint8_t* b, int dims) {
  int64_t sum = 0;
  for (int d = 0; d < dims; ++d) sum += static_cast<int64_t>(a[d]) * static_cast<int64_t>(b[d]);
  return sum;
}

TEST(DescriptorDotProducts, BothKernelsGiveTheExactIntegers) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> byte(0, 255);
  // 128 (SIFT), lengths with a tail beyond the 16-wide steps, none, and the
  // largest allowed.
  for (const int dims : {128, 130, 15, 16, 0, 1, 1024}) {
    SCOPED_TRACE("dims " + std::to_string(dims));
    const int num_rows = 50;
    const int64_t stride = dims + 3;  // rows need not be packed
    std::vector<uint8_t> rows(num_rows * stride + 1);
    for (uint8_t& value : rows) value = static_cast<uint8_t>(byte(rng));
    // Saturated rows: the largest products must not overflow.
    for (int d = 0; d < dims; ++d) rows[7 * stride + d] = 255;
    std::vector<uint8_t> query(dims + 1);
    for (uint8_t& value : query) value = static_cast<uint8_t>(byte(rng));
    std::vector<uint8_t> saturated_query(dims + 1, 255);
    const std::vector<int32_t> all_indices = {0, 7, 49, 3, 3, 12, 7};
    // Odd and even counts: the AVX2 kernel takes candidates two at a time.
    for (const size_t count : {size_t{1}, size_t{2}, size_t{6}, all_indices.size()}) {
      const std::vector<int32_t> indices(all_indices.begin(), all_indices.begin() + count);
      for (const std::vector<uint8_t>* q : {&query, &saturated_query}) {
        std::vector<int32_t> fast(indices.size(), -1), portable(indices.size(), -1);
        DescriptorDotProducts(q->data(), rows.data(), stride, dims, indices.data(),
                              static_cast<int>(indices.size()), fast.data());
        DescriptorDotProductsPortable(q->data(), rows.data(), stride, dims, indices.data(),
                                      static_cast<int>(indices.size()), portable.data());
        for (size_t k = 0; k < indices.size(); ++k) {
          const int64_t truth = NaiveDot(q->data(), rows.data() + indices[k] * stride, dims);
          EXPECT_EQ(fast[k], truth) << "candidate " << k << " of " << count;
          EXPECT_EQ(portable[k], truth) << "candidate " << k << " of " << count;
        }
      }
    }
  }
  std::cout << "kernel: " << (DescriptorDotProductsUseAvx2() ? "AVX2" : "portable") << "\n";
}

TEST(DescriptorDotProducts, NoCandidatesWritesNothing) {
  const std::vector<uint8_t> query(128, 1);
  int32_t untouched = -7;
  DescriptorDotProducts(query.data(), query.data(), 128, 128, nullptr, 0, &untouched);
  EXPECT_EQ(untouched, -7);
}

}  // namespace
}  // namespace viosfm
