// SPDX-License-Identifier: BSD-3-Clause
#include "integer_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

#include "afam/base/cpu_features.hpp"
#include "codec_common.hpp"

namespace afam::codec {

namespace {

// The integers live in uint32 words: sums wrap (defined behaviour whatever a damaged payload
// holds) and, as every |k| of a valid payload is below 2^26, equal the exact integer sums.
using Word = uint32_t;
constexpr int32_t kLimit = 1 << 26;  // |k| < kLimit
static_assert((-17 >> 1) == -9, "arithmetic right shift: the predictions round down");

inline Word cubic(Word a, Word b, Word c, Word d) {
  return Word(int32_t(9u * (b + c) - a - d + 8u) >> 4);
}
inline Word linear(Word b, Word c) { return Word(int32_t(b + c + 1u) >> 1); }

/// How the point at coordinate c (an odd multiple of s) of an axis of length len is predicted.
enum class Fit { One, Linear, Cubic };
inline Fit fitAt(int c, int s, int len) {
  if (c + s >= len) return Fit::One;
  return c - 3 * s >= 0 && c + 3 * s < len ? Fit::Cubic : Fit::Linear;
}

/// Predictions of `count` points spaced `step` apart starting at `at`, from their neighbours
/// `off` elements away in the predicted direction (at -+ off, and at -+ 3 off for a cubic).
void predictRows(Fit fit, const Word* at, int64_t off, int64_t step, int count, Word* pred) {
  if (step == 1) {  // the finest passes, most of the points: contiguous, vectorized
    const Word* m1 = at - off;
    if (fit == Fit::Cubic) {
      const Word *m3 = at - 3 * off, *p1 = at + off, *p3 = at + 3 * off;
      for (int j = 0; j < count; ++j) pred[j] = cubic(m3[j], m1[j], p1[j], p3[j]);
    } else if (fit == Fit::Linear) {
      const Word* p1 = at + off;
      for (int j = 0; j < count; ++j) pred[j] = linear(m1[j], p1[j]);
    } else {
      std::copy(m1, m1 + count, pred);
    }
    return;
  }
  for (int j = 0; j < count; ++j) {
    const Word* p = at + j * step;
    pred[j] = fit == Fit::Cubic    ? cubic(p[-3 * off], p[-off], p[off], p[3 * off])
              : fit == Fit::Linear ? linear(p[-off], p[off])
                                   : p[-off];
  }
}

/// Walks the interpolation predictor's points in its visiting order, a run at a time:
/// op(first, step, count, pred) handles the points first, first + step, ... (count of them) whose
/// predictions are pred[0, count); a run's predictions read only points of earlier runs.
template <typename Op>
void interpolationRuns(Int3 n, const Word* k, Op&& op) {
  const Lattice L{n};
  const int S = coarsestSpacing(n);
  lorenzo(L, k, S, [&](int64_t i, Word p) { op(i, int64_t(1), 1, &p); });
  Word* pred = threadScratch<Word>(ScratchSlot::Predictions, size_t(std::max({n[0], n[1], n[2]})));
  const int64_t sy = n[0], sz = int64_t(n[0]) * n[1];
  for (int s = S / 2; s >= 1; s /= 2) {
    const int s2 = 2 * s;
    const int xs = (n[0] + s - 1) / s;  // points of a row at spacing s
    for (int z = 0; z < n[2]; z += s2)  // along x: the points at odd multiples of s
      for (int y = 0; y < n[1]; y += s2) {
        const Word* row = k + L.index(0, y, z);
        int count = 0;
        for (int x = s; x < n[0]; x += s2)
          predictRows(fitAt(x, s, n[0]), row + x, s, 1, 1, pred + count++);
        if (count) op(L.index(s, y, z), int64_t(s2), count, pred);
      }
    for (int z = 0; z < n[2]; z += s2)  // along y: whole rows at spacing s
      for (int y = s; y < n[1]; y += s2) {
        const Word* at = k + L.index(0, y, z);
        predictRows(fitAt(y, s, n[1]), at, s * sy, s, xs, pred);
        op(L.index(0, y, z), int64_t(s), xs, pred);
      }
    for (int z = s; z < n[2]; z += s2)  // along z
      for (int y = 0; y < n[1]; y += s) {
        const Word* at = k + L.index(0, y, z);
        predictRows(fitAt(z, s, n[2]), at, s * sz, s, xs, pred);
        op(L.index(0, y, z), int64_t(s), xs, pred);
      }
  }
}

/// Lorenzo's residual of every point at once: the mixed difference along x, y and z (outside
/// points 0), in place; lorenzoSums inverts it (prefix sums along each axis).
void lorenzoDifferences(Int3 n, Word* r) {
  const int64_t sy = n[0], sz = int64_t(n[0]) * n[1];
  for (int64_t z = n[2] - 1; z >= 1; --z)
    for (int64_t i = 0; i < sz; ++i) r[z * sz + i] -= r[(z - 1) * sz + i];
  for (int64_t z = 0; z < n[2]; ++z)
    for (int64_t y = n[1] - 1; y >= 1; --y)
      for (int64_t x = 0; x < sy; ++x) r[z * sz + y * sy + x] -= r[z * sz + (y - 1) * sy + x];
  for (int64_t row = 0; row < int64_t(n[1]) * n[2]; ++row)
    for (int64_t x = sy - 1; x >= 1; --x) r[row * sy + x] -= r[row * sy + x - 1];
}

/// The prefix sums along x, y and z (the inverse of lorenzoDifferences), compiled twice below.
__attribute__((always_inline)) inline void lorenzoSumsBody(Int3 n, Word* r) {
  const int64_t sy = n[0], sz = int64_t(n[0]) * n[1];
  const int64_t rows = int64_t(n[1]) * n[2];
  int64_t row = 0;
  // Four rows at once, their running sums in registers: four independent chains of one add each
  // (summing in memory waited for each store to reach the next load).
  for (; row + 4 <= rows; row += 4) {
    Word *p0 = r + row * sy, *p1 = p0 + sy, *p2 = p1 + sy, *p3 = p2 + sy;
    Word s0 = p0[0], s1 = p1[0], s2 = p2[0], s3 = p3[0];
    for (int64_t x = 1; x < sy; ++x) {
      p0[x] = s0 += p0[x];
      p1[x] = s1 += p1[x];
      p2[x] = s2 += p2[x];
      p3[x] = s3 += p3[x];
    }
  }
  for (; row < rows; ++row) {
    Word* p = r + row * sy;
    for (int64_t x = 1; x < sy; ++x) p[x] += p[x - 1];
  }
  for (int64_t z = 0; z < n[2]; ++z)
    for (int64_t y = 1; y < n[1]; ++y) {
      Word* p = r + z * sz + y * sy;
      const Word* q = p - sy;
      for (int64_t x = 0; x < sy; ++x) p[x] += q[x];
    }
  for (int64_t z = 1; z < n[2]; ++z) {
    Word* p = r + z * sz;
    const Word* q = p - sz;
    for (int64_t i = 0; i < sz; ++i) p[i] += q[i];
  }
}

// AVX2 where the CPU has it: the y and z passes are plain loops the compiler vectorizes, twice as
// wide there.
AFAM_TARGET_AVX2 void lorenzoSumsAvx2(Int3 n, Word* r) { lorenzoSumsBody(n, r); }
void lorenzoSumsBaseline(Int3 n, Word* r) { lorenzoSumsBody(n, r); }
void lorenzoSums(Int3 n, Word* r) {
  cpuHasAvx2() ? lorenzoSumsAvx2(n, r) : lorenzoSumsBaseline(n, r);
}

/// The residuals of the zstd-decompressed varints v (got bytes, zero padding after them) into r.
void readVarints(const uint8_t* v, size_t got, size_t count, Word* r, const char* where) {
  constexpr size_t kRun = 64;  // values between two bounds checks; padding covers 5 bytes each
  size_t pos = 0;
  for (size_t i = 0; i < count;) {
    if (pos > got) throw badPayload(where, "ends inside a residual");
    uint64_t w[2];
    std::memcpy(w, v + pos, 16);
    if (i + 16 <= count && ((w[0] | w[1]) & 0x8080808080808080ull) == 0) {
      for (int j = 0; j < 16; ++j) {  // 16 one-byte codes: the common case, vectorized
        const uint32_t u = v[pos + size_t(j)];
        r[i + size_t(j)] = (u >> 1) ^ (0u - (u & 1));
      }
      i += 16;
      pos += 16;
      continue;
    }
    for (const size_t end = std::min(count, i + kRun); i < end; ++i) {
      uint32_t u = v[pos++];
      if (u >= 0x80) {  // |code| >= 64: up to 5 bytes
        u &= 0x7f;
        for (int shift = 7;; shift += 7) {
          const uint32_t b = v[pos++];
          if (shift == 28 && b > 0x0f) throw badPayload(where, "holds an absurd residual");
          u |= (b & 0x7f) << shift;
          if (b < 0x80) break;
        }
      }
      r[i] = (u >> 1) ^ (0u - (u & 1));
    }
  }
  if (pos > got) throw badPayload(where, "ends inside a residual");
  if (pos < got)
    throw badPayload(where, "has " + std::to_string(got - pos) + " bytes after its last residual");
}

/// out = (base + k) * step for every k, after checking every k lies in the range an encoder
/// writes and every value is a finite float.
/// out = (base + k) * step (the loop the compiler vectorizes), compiled twice below.
__attribute__((always_inline)) inline void convertBody(const Word* k, size_t count, int64_t base,
                                                       double step, float* out) {
  for (size_t i = 0; i < count; ++i) out[i] = integerValue(base, int32_t(k[i]), step);
}
AFAM_TARGET_AVX2 void convertAvx2(const Word* k, size_t count, int64_t base, double step,
                                  float* out) {
  convertBody(k, count, base, step, out);
}
void convertBaseline(const Word* k, size_t count, int64_t base, double step, float* out) {
  convertBody(k, count, base, step, out);
}

/// Throws unless every k lies in the range an encoder writes.
void checkRange(const Word* k, size_t count, const char* where) {
  uint32_t outside = 0;
  for (size_t i = 0; i < count; ++i) outside |= uint32_t(k[i] + (kLimit - 1)) > 2u * (kLimit - 1);
  if (outside) throw badPayload(where, "decodes beyond its range");
}

/// Throws unless (base + k) * step is a finite float for every |k| < kLimit that may occur.
void checkFinite(const float* out, size_t count, int64_t base, double step, const char* where) {
  if ((std::fabs(double(base)) + kLimit) * step <= std::numeric_limits<float>::max()) return;
  for (size_t i = 0; i < count; ++i)  // only then can one be
    if (!std::isfinite(out[i])) throw badPayload(where, "decodes to a value beyond float32");
}

/// An integer payload's integers, checked to lie in the encoder's range, in the calling thread's
/// scratch.
struct IntegerWords {
  const Word* k;
  int64_t base;
  double step;
};

IntegerWords decodeWords(const uint8_t* data, size_t bytes, Int3 n, const char* where) {
  if (bytes < kIntegerCodedHeaderBytes + 1) throw badPayload(where, "shorter than its header");
  double step;
  int64_t base;
  std::memcpy(&step, data, 8);
  std::memcpy(&base, data + 9, 8);
  if (!(base > -(int64_t(1) << 52) && base < (int64_t(1) << 52)))
    throw badPayload(where, "has an invalid base");
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  size_t got = 0;
  const uint8_t* varints =
      unpackFrame(data + kIntegerCodedHeaderBytes, bytes - kIntegerCodedHeaderBytes, count * 5,
                  5 * 64 + 8, where, got);
  Word* r = threadScratch<Word>(ScratchSlot::Words, count);
  readVarints(varints, got, count, r, where);
  Word* k = r;
  if (Predictor(data[8]) == Predictor::IntegerLorenzo) {
    lorenzoSums(n, k);
  } else {
    k = threadScratch<Word>(ScratchSlot::MoreWords, count);
    size_t pos = 0;
    interpolationRuns(n, k, [&](int64_t first, int64_t stride, int run, const Word* pred) {
      Word* at = k + first;
      const Word* res = r + pos;
      if (stride == 1)
        for (int j = 0; j < run; ++j) at[j] = pred[j] + res[j];
      else
        for (int j = 0; j < run; ++j) at[j * stride] = pred[j] + res[j];
      pos += size_t(run);
    });
  }
  checkRange(k, count, where);
  return IntegerWords{k, base, step};
}

}  // namespace

namespace {
/// The smallest and largest of the values, in eight lanes (a loop that vectorizes, unlike
/// std::minmax_element); a NaN among them is skipped, as there.
void valueRange(const float* values, size_t count, float& lo, float& hi) {
  float l[8], h[8];
  for (int j = 0; j < 8; ++j) l[j] = h[j] = values[0];
  size_t i = 0;
  for (; i + 8 <= count; i += 8)
    for (int j = 0; j < 8; ++j) {
      const float v = values[i + size_t(j)];
      l[j] = v < l[j] ? v : l[j];
      h[j] = v > h[j] ? v : h[j];
    }
  for (; i < count; ++i) {
    l[0] = values[i] < l[0] ? values[i] : l[0];
    h[0] = values[i] > h[0] ? values[i] : h[0];
  }
  lo = l[0];
  hi = h[0];
  for (int j = 1; j < 8; ++j) {
    lo = l[j] < lo ? l[j] : lo;
    hi = h[j] > hi ? h[j] : hi;
  }
}
}  // namespace

namespace {

/// k = round(value / step) - middle for one value; false where it is out of range (its k 0).
__attribute__((always_inline)) inline bool quantizeOne(float value, double step, double middle,
                                                       int32_t& out) {
  const double x = double(value) / step;
  const double q = roundHalfEven(x) - middle;
  const bool in = (std::fabs(x) < kRoundExact) & (std::fabs(q) < kLimit);
  out = in ? int32_t(q) : 0;
  return in;
}

/// quantizeOne for every value, four at a time in vectors of doubles (the compiler kept the
/// plain loop scalar: its select and `ok` chain), the same operations in the same order;
/// compiled also for AVX2 (no FMA: the same k).
__attribute__((always_inline)) inline bool quantizeBody(const float* values, size_t count,
                                                        double step, double middle, int32_t* out) {
  using Float4 = float __attribute__((vector_size(16)));
  using Double4 = double __attribute__((vector_size(32)));
  using Mask4 = int64_t __attribute__((vector_size(32)));
  using Int4 = int32_t __attribute__((vector_size(16)));
  constexpr double kShift = 6755399441055744.0;  // roundHalfEven's 1.5 * 2^52
  Mask4 outside = {0, 0, 0, 0};
  size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    Float4 f;
    std::memcpy(&f, values + i, sizeof f);
    const Double4 x = __builtin_convertvector(f, Double4) / step;
    const Double4 q = ((x + kShift) - kShift) - middle;
    const Mask4 in = ((x < 0 ? -x : x) < kRoundExact) & ((q < 0 ? -q : q) < double(kLimit));
    outside |= ~in;
    const Int4 k = __builtin_convertvector(in ? q : Double4{0, 0, 0, 0}, Int4);
    std::memcpy(out + i, &k, sizeof k);
  }
  bool ok = (outside[0] | outside[1] | outside[2] | outside[3]) == 0;
  for (; i < count; ++i) ok &= quantizeOne(values[i], step, middle, out[i]);
  return ok;
}
AFAM_TARGET_AVX2 bool quantizeAvx2(const float* values, size_t count, double step, double middle,
                                   int32_t* out) {
  return quantizeBody(values, count, step, middle, out);
}

__attribute__((always_inline)) inline void valuesBody(int64_t base, const int32_t* k, size_t count,
                                                      double step, float* out) {
  for (size_t i = 0; i < count; ++i) out[i] = integerValue(base, k[i], step);
}
AFAM_TARGET_AVX2 void valuesAvx2(int64_t base, const int32_t* k, size_t count, double step,
                                 float* out) {
  valuesBody(base, k, count, step, out);
}

}  // namespace

bool integerQuantize(const float* values, size_t count, double step, int64_t& base,
                     HugePageVector<int32_t>& k) {
  if (count == 0) return false;
  float lo, hi;
  valueRange(values, count, lo, hi);
  if (!std::isfinite(lo) || !std::isfinite(hi)) return false;
  const double middle = std::nearbyint((double(lo) + double(hi)) / 2 / step);
  if (!(std::fabs(middle) < 4503599627370496.0)) return false;  // 2^52
  base = int64_t(middle);
  k.resize(count);
  // A value out of roundHalfEven's range, or a code out of kLimit, fails the block.
  return cpuHasAvx2() ? quantizeAvx2(values, count, step, middle, k.data())
                      : quantizeBody(values, count, step, middle, k.data());
}

void integerValues(int64_t base, const int32_t* k, size_t count, double step, float* out) {
  cpuHasAvx2() ? valuesAvx2(base, k, count, step, out) : valuesBody(base, k, count, step, out);
}

void integerResiduals(Predictor p, Int3 n, HugePageVector<int32_t>& k, int32_t* residuals,
                      FreeValues free) {
  Word* r = reinterpret_cast<Word*>(residuals);
  if (p == Predictor::IntegerLorenzo) {
    std::memcpy(r, k.data(), k.size() * sizeof(Word));
    lorenzoDifferences(n, r);
    return;
  }
  Word* kw = reinterpret_cast<Word*>(k.data());
  size_t pos = 0;
  interpolationRuns(n, kw, [&](int64_t first, int64_t step, int count, const Word* pred) {
    for (int j = 0; j < count; ++j) {
      const int64_t i = first + j * step;
      if (free.isFree(i) && std::llabs(int64_t(kw[i]) - int64_t(pred[j])) <= free.slack)
        kw[i] = pred[j];
      r[pos++] = kw[i] - pred[j];
    }
  });
}

namespace {
/// out = (base + k) * step for the `count` integers of w, each a finite float.
void toFloats(const IntegerWords& w, size_t count, float* out, const char* where) {
  cpuHasAvx2() ? convertAvx2(w.k, count, w.base, w.step, out)
               : convertBaseline(w.k, count, w.base, w.step, out);
  checkFinite(out, count, w.base, w.step, where);
}
}  // namespace

void decodeInteger(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where) {
  toFloats(decodeWords(data, bytes, n, where), size_t(n[0]) * size_t(n[1]) * size_t(n[2]), out,
           where);
}

CompactForm decodeIntegerCompact(const uint8_t* data, size_t bytes, Int3 n, double maxShare,
                                 std::vector<float>& out, const char* where) {
  const IntegerWords w = decodeWords(data, bytes, n, where);
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  const auto* k = reinterpret_cast<const int32_t*>(w.k);  // the words are two's complement
  const CompactForm form = packCompact(
      k, count, maxShare, [&w](int64_t v) { return integerValue(w.base, int32_t(v), w.step); },
      out);
  if (form.width == 0) {
    out.resize(count);
    toFloats(w, count, out.data(), where);
    return form;
  }
  checkFinite(out.data(), form.table, w.base, w.step, where);
  return form;
}

}  // namespace afam::codec
