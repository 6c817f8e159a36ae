// Compiled with -mavx2 (stages/sfm/CMakeLists.txt); called only when
// HaveDescriptorDotsAvx2() says the CPU has AVX2. No standard-library or
// Eigen templates here (see descriptor_dots.h).
#include <immintrin.h>

#include "stages/sfm/descriptor_dots.h"

namespace docunfold::sfm {
namespace {

// Two values of a row, as one 32-bit lane to broadcast.
inline int32_t PairAt(const int16_t* row, int p) {
  int32_t pair;
  __builtin_memcpy(&pair, row + 2 * p, sizeof pair);
  return pair;
}

}  // namespace

// Per block of 8 rows of b: each pair of dimensions of a row of a, broadcast,
// times the 8 rows' pairs (vpmaddwd) adds 8 partial sums, one per row of b,
// so no horizontal sums are needed; 4 rows of a share each load of b.
void DescriptorDotsAvx2(const int16_t* a, int na, const int16_t* b_packed, int blocks,
                        int32_t* dots, size_t stride) {
  int i = 0;
  for (; i + 4 <= na; i += 4) {
    const int16_t* a0 = a + size_t(i) * 128;
    const int16_t *a1 = a0 + 128, *a2 = a1 + 128, *a3 = a2 + 128;
    for (int q = 0; q < blocks; ++q) {
      const auto* bq = reinterpret_cast<const __m256i*>(b_packed + size_t(q) * kDotBlockValues);
      __m256i c0 = _mm256_setzero_si256(), c1 = c0, c2 = c0, c3 = c0;
      for (int p = 0; p < 64; ++p) {
        const __m256i bv = _mm256_loadu_si256(bq + p);
        c0 = _mm256_add_epi32(c0, _mm256_madd_epi16(_mm256_set1_epi32(PairAt(a0, p)), bv));
        c1 = _mm256_add_epi32(c1, _mm256_madd_epi16(_mm256_set1_epi32(PairAt(a1, p)), bv));
        c2 = _mm256_add_epi32(c2, _mm256_madd_epi16(_mm256_set1_epi32(PairAt(a2, p)), bv));
        c3 = _mm256_add_epi32(c3, _mm256_madd_epi16(_mm256_set1_epi32(PairAt(a3, p)), bv));
      }
      int32_t* out = dots + size_t(i) * stride + size_t(q) * kDotBlockRows;
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), c0);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + stride), c1);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 2 * stride), c2);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 3 * stride), c3);
    }
  }
  for (; i < na; ++i) {
    const int16_t* a0 = a + size_t(i) * 128;
    for (int q = 0; q < blocks; ++q) {
      const auto* bq = reinterpret_cast<const __m256i*>(b_packed + size_t(q) * kDotBlockValues);
      __m256i c0 = _mm256_setzero_si256();
      for (int p = 0; p < 64; ++p)
        c0 = _mm256_add_epi32(
            c0, _mm256_madd_epi16(_mm256_set1_epi32(PairAt(a0, p)), _mm256_loadu_si256(bq + p)));
      _mm256_storeu_si256(
          reinterpret_cast<__m256i*>(dots + size_t(i) * stride + size_t(q) * kDotBlockRows), c0);
    }
  }
}

}  // namespace docunfold::sfm
