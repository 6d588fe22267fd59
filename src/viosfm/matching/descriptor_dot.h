// Exact integer dot products of uint8 descriptor rows (SIFT's quantised
// histograms, as the database stores them): the guided matcher's inner loop.
//
// A dot product of two uint8 rows is an integer, so it has one right answer:
// the AVX2 kernel (used where the CPU has AVX2, checked once at run time) and
// the portable one return the same integers, and a match does not depend on
// the machine. A row of 128 uint8 is a quarter of the float row it replaces,
// so an image's 1000 descriptors (128 KiB) stay in the core's cache while
// many epipolar lines are walked against them.
#pragma once

#include <cstdint>

namespace viosfm {

// dots[k] = sum_d query[d] * rows[indices[k] * row_stride + d], d < dims, for
// k < count. dims <= 1024 (a 1024-long row of 255s sums to 66 585 600, far
// within int32).
void DescriptorDotProducts(const uint8_t* query, const uint8_t* rows, int64_t row_stride, int dims,
                           const int32_t* indices, int count, int32_t* dots);

// The same with the portable kernel, whatever the CPU (for tests and the
// benchmark).
void DescriptorDotProductsPortable(const uint8_t* query, const uint8_t* rows, int64_t row_stride,
                                   int dims, const int32_t* indices, int count, int32_t* dots);

// True if DescriptorDotProducts uses the AVX2 kernel on this machine.
bool DescriptorDotProductsUseAvx2();

}  // namespace viosfm
