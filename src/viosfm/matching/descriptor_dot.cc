#include "viosfm/matching/descriptor_dot.h"

#include <array>

#include "viosfm/util/errors.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define VIOSFM_HAVE_AVX2_KERNEL 1
#endif

namespace viosfm {
namespace {

constexpr int kMaxDims = 1024;

#ifdef VIOSFM_HAVE_AVX2_KERNEL
// The sum of the eight int32 lanes.
__attribute__((target("avx2"))) inline int32_t SumLanes(__m256i sum) {
  __m128i half = _mm_add_epi32(_mm256_castsi256_si128(sum), _mm256_extracti128_si256(sum, 1));
  half = _mm_add_epi32(half, _mm_shuffle_epi32(half, 0x4e));
  half = _mm_add_epi32(half, _mm_shuffle_epi32(half, 0xb1));
  return _mm_cvtsi128_si32(half);
}

// The tail dimensions (dims not a multiple of 16), one by one.
inline int32_t TailDot(const uint8_t* query, const uint8_t* row, int from, int dims) {
  int32_t dot = 0;
  for (int d = from; d < dims; ++d) {
    dot += static_cast<int32_t>(query[d]) * static_cast<int32_t>(row[d]);
  }
  return dot;
}

// Dimensions [d, d + 16) of a widened query, and of a row widened to int16.
__attribute__((target("avx2"))) inline __m256i LoadWide(const int16_t* query16, int d) {
  return _mm256_load_si256(reinterpret_cast<const __m256i*>(query16 + d));
}
__attribute__((target("avx2"))) inline __m256i LoadRow(const uint8_t* row, int d) {
  return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row + d)));
}

// 16 dimensions per step: both rows widened to int16, multiplied and summed
// in pairs to int32 (vpmaddwd; 255 * 255 * 2 fits). The query is widened
// once; two rows go side by side, so their sums do not wait on each other.
// Integer sums: the order does not change the result.
__attribute__((target("avx2"))) void DotProductsAvx2(const uint8_t* query, const uint8_t* rows,
                                                     int64_t row_stride, int dims,
                                                     const int32_t* indices, int count,
                                                     int32_t* dots) {
  const int vector_dims = dims - dims % 16;
  alignas(32) std::array<int16_t, kMaxDims> wide;  // only [0, vector_dims) is read
  for (int d = 0; d < vector_dims; ++d) wide[d] = query[d];
  const int16_t* const query16 = wide.data();
  int k = 0;
  for (; k + 1 < count; k += 2) {
    const uint8_t* row0 = rows + static_cast<int64_t>(indices[k]) * row_stride;
    const uint8_t* row1 = rows + static_cast<int64_t>(indices[k + 1]) * row_stride;
    __m256i sum0 = _mm256_setzero_si256();
    __m256i sum1 = _mm256_setzero_si256();
    for (int d = 0; d < vector_dims; d += 16) {
      const __m256i a = LoadWide(query16, d);
      sum0 = _mm256_add_epi32(sum0, _mm256_madd_epi16(a, LoadRow(row0, d)));
      sum1 = _mm256_add_epi32(sum1, _mm256_madd_epi16(a, LoadRow(row1, d)));
    }
    dots[k] = SumLanes(sum0) + TailDot(query, row0, vector_dims, dims);
    dots[k + 1] = SumLanes(sum1) + TailDot(query, row1, vector_dims, dims);
  }
  if (k < count) {
    const uint8_t* row = rows + static_cast<int64_t>(indices[k]) * row_stride;
    __m256i sum = _mm256_setzero_si256();
    for (int d = 0; d < vector_dims; d += 16) {
      sum = _mm256_add_epi32(sum, _mm256_madd_epi16(LoadWide(query16, d), LoadRow(row, d)));
    }
    dots[k] = SumLanes(sum) + TailDot(query, row, vector_dims, dims);
  }
}

bool CpuHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

}  // namespace

void DescriptorDotProductsPortable(const uint8_t* query, const uint8_t* rows, int64_t row_stride,
                                   int dims, const int32_t* indices, int count, int32_t* dots) {
  VIOSFM_CHECK(dims >= 0 && dims <= kMaxDims) << "descriptor length " << dims;
  for (int k = 0; k < count; ++k) {
    const uint8_t* row = rows + static_cast<int64_t>(indices[k]) * row_stride;
    int32_t dot = 0;
    for (int d = 0; d < dims; ++d) {
      dot += static_cast<int32_t>(query[d]) * static_cast<int32_t>(row[d]);
    }
    dots[k] = dot;
  }
}

void DescriptorDotProducts(const uint8_t* query, const uint8_t* rows, int64_t row_stride, int dims,
                           const int32_t* indices, int count, int32_t* dots) {
  VIOSFM_CHECK(dims >= 0 && dims <= kMaxDims) << "descriptor length " << dims;
#ifdef VIOSFM_HAVE_AVX2_KERNEL
  if (CpuHasAvx2()) {
    DotProductsAvx2(query, rows, row_stride, dims, indices, count, dots);
    return;
  }
#endif
  DescriptorDotProductsPortable(query, rows, row_stride, dims, indices, count, dots);
}

bool DescriptorDotProductsUseAvx2() {
#ifdef VIOSFM_HAVE_AVX2_KERNEL
  return CpuHasAvx2();
#else
  return false;
#endif
}

}  // namespace viosfm
