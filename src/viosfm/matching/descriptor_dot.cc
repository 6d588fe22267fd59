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
// 16 dimensions per step: both rows widened to int16, multiplied and summed
// in pairs to int32 (vpmaddwd; 255 * 255 * 2 fits). The query is widened
// once. Tail dimensions (dims not a multiple of 16) are summed one by one.
__attribute__((target("avx2"))) void DotProductsAvx2(const uint8_t* query, const uint8_t* rows,
                                                     int64_t row_stride, int dims,
                                                     const int32_t* indices, int count,
                                                     int32_t* dots) {
  const int vector_dims = dims - dims % 16;
  alignas(32) std::array<int16_t, kMaxDims> wide{};
  for (int d = 0; d < vector_dims; ++d) wide[d] = query[d];
  for (int k = 0; k < count; ++k) {
    const uint8_t* row = rows + static_cast<int64_t>(indices[k]) * row_stride;
    __m256i sum = _mm256_setzero_si256();
    for (int d = 0; d < vector_dims; d += 16) {
      const __m256i a = _mm256_load_si256(reinterpret_cast<const __m256i*>(wide.data() + d));
      const __m256i b =
          _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row + d)));
      sum = _mm256_add_epi32(sum, _mm256_madd_epi16(a, b));
    }
    __m128i half = _mm_add_epi32(_mm256_castsi256_si128(sum), _mm256_extracti128_si256(sum, 1));
    half = _mm_add_epi32(half, _mm_shuffle_epi32(half, 0x4e));
    half = _mm_add_epi32(half, _mm_shuffle_epi32(half, 0xb1));
    int32_t dot = _mm_cvtsi128_si32(half);
    for (int d = vector_dims; d < dims; ++d) {
      dot += static_cast<int32_t>(query[d]) * static_cast<int32_t>(row[d]);
    }
    dots[k] = dot;
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
