// SPDX-License-Identifier: BSD-3-Clause
#include "lanes_simd.hpp"

#include "afam/base/cpu_features.hpp"
#include "afam/entropy/lanes_coder.hpp"

#if AFAM_HAVE_AVX2_PATH
#include <immintrin.h>

#include <array>

namespace afam::lanes {

namespace {

/// For each 8-bit mask of the lanes that take a word, the index (among the 8 words loaded) of the
/// word each lane takes: the count of lanes before it that take one.
const std::array<std::array<int32_t, 8>, 256>& expandTable() {
  static const auto table = [] {
    std::array<std::array<int32_t, 8>, 256> t{};
    for (int mask = 0; mask < 256; ++mask) {
      int k = 0;
      for (int lane = 0; lane < 8; ++lane) {
        t[size_t(mask)][size_t(lane)] = (mask >> lane) & 1 ? k : 0;
        k += (mask >> lane) & 1;
      }
    }
    return t;
  }();
  return table;
}

/// Eight lanes' step: their bytes written at out, their states moved and renormalised, pos
/// advanced by the words they took.
AFAM_TARGET_AVX2 inline __m256i step8(__m256i x, const uint32_t* table, const uint8_t* words,
                                      uint32_t& pos, uint8_t* out,
                                      const std::array<int32_t, 8>* expand) {
  const __m256i low12 = _mm256_set1_epi32(int(kScale - 1));
  const __m256i e =
      _mm256_i32gather_epi32(reinterpret_cast<const int*>(table), _mm256_and_si256(x, low12), 4);
  // Bytes: the low byte of each 32-bit entry, packed into 8 bytes.
  const __m256i pick =
      _mm256_setr_epi8(0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0, 4, 8, 12, -1,
                       -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1);
  const __m256i packed = _mm256_permutevar8x32_epi32(_mm256_shuffle_epi8(e, pick),
                                                     _mm256_setr_epi32(0, 4, 1, 1, 1, 1, 1, 1));
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out), _mm256_castsi256_si128(packed));
  // x = frequency * (x >> 12) + bias, frequency = (e >> 20) + 1, bias = (e >> 8) & 0xfff.
  const __m256i frequency = _mm256_add_epi32(_mm256_srli_epi32(e, 20), _mm256_set1_epi32(1));
  const __m256i bias = _mm256_and_si256(_mm256_srli_epi32(e, 8), low12);
  x = _mm256_add_epi32(_mm256_mullo_epi32(frequency, _mm256_srli_epi32(x, kScaleBits)), bias);
  // Lanes whose state fell below 2^16 take the next words, in lane order.
  const __m256i need = _mm256_cmpeq_epi32(_mm256_srli_epi32(x, 16), _mm256_setzero_si256());
  const int mask = _mm256_movemask_ps(_mm256_castsi256_ps(need));
  const __m256i w = _mm256_cvtepu16_epi32(
      _mm_loadu_si128(reinterpret_cast<const __m128i*>(words + 2 * size_t(pos))));
  const __m256i taken = _mm256_permutevar8x32_epi32(
      w, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(expand[mask].data())));
  x = _mm256_blendv_epi8(x, _mm256_or_si256(_mm256_slli_epi32(x, 16), taken), need);
  pos += uint32_t(__builtin_popcount(unsigned(mask)));
  return x;
}

}  // namespace

bool vectorPathAvailable() { return cpuHasAvx2(); }

AFAM_TARGET_AVX2 void decodeSteps32(uint32_t* x, const uint32_t* table, const uint8_t* words,
                                    uint32_t wordCount, uint32_t& pos, uint8_t* out, size_t symbols,
                                    size_t& i) {
  const std::array<int32_t, 8>* expand = expandTable().data();
  __m256i v[4];
  for (int k = 0; k < 4; ++k)
    v[k] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(x + 8 * k));
  // A step reads at most 32 words, and each vector's load reads 8 from its own position: room
  // for both while 32 remain.
  // Locals, so that they stay in registers (the byte stores could alias the references).
  uint32_t p = pos;
  size_t n = i;
  while (n + 32 <= symbols && p + 32 <= wordCount) {
    for (int k = 0; k < 4; ++k) v[k] = step8(v[k], table, words, p, out + n + 8 * k, expand);
    n += 32;
  }
  for (int k = 0; k < 4; ++k) _mm256_storeu_si256(reinterpret_cast<__m256i*>(x + 8 * k), v[k]);
  pos = p;
  i = n;
}

}  // namespace afam::lanes

#else  // no x86-64 vector path: the scalar loop does every step

namespace afam::lanes {
bool vectorPathAvailable() { return false; }
void decodeSteps32(uint32_t*, const uint32_t*, const uint8_t*, uint32_t, uint32_t&, uint8_t*,
                   size_t, size_t&) {}
}  // namespace afam::lanes

#endif
