// SPDX-License-Identifier: BSD-3-Clause
#include "afam/format/block_codec.hpp"

#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "afam/base/errors.hpp"

namespace afam {

namespace {

constexpr double kMaxCode = 1125899906842624.0;  // 2^50: residual codes beyond are refused

struct Lattice {
  Int3 n;
  int64_t index(int x, int y, int z) const { return (int64_t(z) * n[1] + y) * n[0] + x; }
};

/// Lorenzo over the points whose coordinates are multiples of s; fn(index, prediction) must leave
/// q[index] known when it returns. A neighbour outside the lattice reads 0.0; the sum is formed in
/// one fixed order, so encoder and decoder predict bit for bit alike.
template <typename Fn>
void lorenzo(const Lattice& L, const double* q, int s, Fn&& fn) {
  const int64_t sx = s, sy = int64_t(s) * L.n[0], sz = int64_t(s) * L.n[0] * L.n[1];
  for (int z = 0; z < L.n[2]; z += s)
    for (int y = 0; y < L.n[1]; y += s) {
      const int64_t row = L.index(0, y, z);
      const bool hasY = y >= s, hasZ = z >= s;
      // x = 0: no neighbour below in x.
      {
        const double b = hasY ? q[row - sy] : 0.0, c = hasZ ? q[row - sz] : 0.0;
        const double f = hasY && hasZ ? q[row - sy - sz] : 0.0;
        fn(row, 0.0 + b + c - 0.0 - 0.0 - f + 0.0);
      }
      if (hasY && hasZ) {  // every neighbour inside: the common case, no tests
        for (int64_t i = row + sx; i < row + L.n[0]; i += sx)
          fn(i, q[i - sx] + q[i - sy] + q[i - sz] - q[i - sx - sy] - q[i - sx - sz] -
                    q[i - sy - sz] + q[i - sx - sy - sz]);
        continue;
      }
      for (int64_t i = row + sx; i < row + L.n[0]; i += sx) {
        const double a = q[i - sx];
        const double b = hasY ? q[i - sy] : 0.0, c = hasZ ? q[i - sz] : 0.0;
        const double d = hasY ? q[i - sx - sy] : 0.0, e = hasZ ? q[i - sx - sz] : 0.0;
        fn(i, a + b + c - d - e - 0.0 + 0.0);
      }
    }
}

/// Prediction of the point at coordinate c (an odd multiple of s) along one axis of length len,
/// from the known points at c -+ s and c -+ 3s; the point at coordinate k of that axis is
/// line[k * stride].
inline double interpolate(int c, int s, int len, const double* line, int64_t stride) {
  const double b = line[int64_t(c - s) * stride];
  if (c + s >= len) return b;
  const double d = line[int64_t(c + s) * stride];
  if (c - 3 * s >= 0 && c + 3 * s < len)
    return (-line[int64_t(c - 3 * s) * stride] + 9 * b + 9 * d -
            line[int64_t(c + 3 * s) * stride]) /
           16;
  return (b + d) / 2;
}

template <typename Fn>
void interpolation(const Lattice& L, const double* q, Fn&& fn) {
  const int maxn = std::max({L.n[0], L.n[1], L.n[2]});
  int S = 1;
  while (2 * S <= maxn - 1) S *= 2;
  lorenzo(L, q, S, fn);
  const int64_t strideY = L.n[0], strideZ = int64_t(L.n[0]) * L.n[1];
  for (int s = S / 2; s >= 1; s /= 2) {
    const int s2 = 2 * s;
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s2) {
        const int64_t row = L.index(0, y, z);
        for (int x = s; x < L.n[0]; x += s2) fn(row + x, interpolate(x, s, L.n[0], q + row, 1));
      }
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = s; y < L.n[1]; y += s2) {
        const int64_t row = L.index(0, y, z), column = L.index(0, 0, z);
        for (int x = 0; x < L.n[0]; x += s)
          fn(row + x, interpolate(y, s, L.n[1], q + column + x, strideY));
      }
    for (int z = s; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s) {
        const int64_t row = L.index(0, y, z), pillar = L.index(0, y, 0);
        for (int x = 0; x < L.n[0]; x += s)
          fn(row + x, interpolate(z, s, L.n[2], q + pillar + x, strideZ));
      }
  }
}

template <typename Fn>
void visit(Predictor p, const Lattice& L, const double* q, Fn&& fn) {
  if (p == Predictor::Lorenzo)
    lorenzo(L, q, 1, fn);
  else
    interpolation(L, q, fn);
}

void putVarint(uint64_t u, std::vector<uint8_t>& out) {
  while (u >= 0x80) {
    out.push_back(uint8_t(u | 0x80));
    u >>= 7;
  }
  out.push_back(uint8_t(u));
}

struct CCtxDeleter {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};
struct DCtxDeleter {
  void operator()(ZSTD_DCtx* c) const { ZSTD_freeDCtx(c); }
};

ZSTD_CCtx* threadCCtx() {
  thread_local std::unique_ptr<ZSTD_CCtx, CCtxDeleter> ctx(ZSTD_createCCtx());
  return ctx.get();
}

ZSTD_DCtx* threadDCtx() {
  thread_local std::unique_ptr<ZSTD_DCtx, DCtxDeleter> ctx(ZSTD_createDCtx());
  return ctx.get();
}

/// A buffer of at least `count` T owned by the calling thread, its contents left as they were.
template <typename T>
T* threadBuffer(size_t count) {
  thread_local std::unique_ptr<T[]> buffer;
  thread_local size_t capacity = 0;
  if (capacity < count) {
    buffer.reset(new T[count]);
    capacity = count;
  }
  return buffer.get();
}

/// Predicts every value from the values already reconstructed (in the predictor's order) and
/// quantizes the prediction residual: code = round((v - prediction) / step), reconstruction =
/// prediction + code * step, so each reconstructed value lies within step / 2 of its value.
/// false when a code exceeds 2^50.
bool predictQuantize(const float* values, Int3 n, double step, Predictor predictor,
                     std::vector<int64_t>& codes, std::vector<float>& reconstructed) {
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  std::vector<double> r(count, 0.0);
  codes.clear();
  codes.reserve(count);
  bool ok = true;
  visit(predictor, Lattice{n}, r.data(), [&](int64_t i, double pred) {
    const double q = std::nearbyint((double(values[i]) - pred) / step);
    if (!(std::fabs(q) <= kMaxCode)) {
      ok = false;
      r[size_t(i)] = double(values[i]);
      return;
    }
    codes.push_back(int64_t(q));
    r[size_t(i)] = pred + q * step;
  });
  reconstructed.resize(count);
  for (size_t i = 0; i < count; ++i) reconstructed[i] = static_cast<float>(r[i]);
  return ok;
}

}  // namespace

bool quantizeValues(const float* values, Int3 n, double step, Predictor predictor,
                    std::vector<float>& reconstructed) {
  if (!(step > 0) || !std::isfinite(step)) return false;
  std::vector<int64_t> codes;
  return predictQuantize(values, n, step, predictor, codes, reconstructed);
}

double estimateCodedBytes(const float* values, Int3 n, double step, Predictor predictor) {
  if (!(step > 0) || !std::isfinite(step)) return std::numeric_limits<double>::infinity();
  std::vector<int64_t> codes;
  std::vector<float> recon;
  if (!predictQuantize(values, n, step, predictor, codes, recon))
    return std::numeric_limits<double>::infinity();
  std::sort(codes.begin(), codes.end());
  double bits = 0;
  for (size_t i = 0; i < codes.size();) {
    size_t j = i;
    while (j < codes.size() && codes[j] == codes[i]) ++j;
    const double p = double(j - i) / double(codes.size());
    bits -= double(j - i) * std::log2(p);
    i = j;
  }
  return kCodedHeaderBytes + bits / 8;
}

bool encodeValues(const float* values, Int3 n, double step, Predictor predictor, int zstdLevel,
                  std::vector<uint8_t>& out, std::vector<float>& reconstructed) {
  out.clear();
  if (!(step > 0) || !std::isfinite(step)) return false;
  std::vector<int64_t> codes;
  if (!predictQuantize(values, n, step, predictor, codes, reconstructed)) return false;
  std::vector<uint8_t> varints;
  varints.reserve(codes.size() + codes.size() / 4);
  for (const int64_t c : codes) putVarint((uint64_t(c) << 1) ^ uint64_t(c >> 63), varints);
  out.resize(kCodedHeaderBytes + ZSTD_compressBound(varints.size()));
  std::memcpy(out.data(), &step, 8);
  out[8] = uint8_t(predictor);
  const size_t z =
      ZSTD_compressCCtx(threadCCtx(), out.data() + kCodedHeaderBytes,
                        out.size() - kCodedHeaderBytes, varints.data(), varints.size(), zstdLevel);
  if (ZSTD_isError(z)) throw Error(std::string("zstd: ") + ZSTD_getErrorName(z));
  out.resize(kCodedHeaderBytes + z);
  return true;
}

void decodeValues(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where) {
  auto bad = [&](const std::string& what) {
    return FormatError(std::string(where) + ": coded payload " + what);
  };
  if (bytes < kCodedHeaderBytes + 1) throw bad("shorter than its header");
  double step;
  std::memcpy(&step, data, 8);
  if (!(step > 0) || !std::isfinite(step)) throw bad("has an invalid quantization step");
  if (data[8] > uint8_t(Predictor::Interpolation))
    throw bad("names unknown predictor " + std::to_string(data[8]));
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  // The frame says how many varint bytes it holds (at most 10 a value); the buffers are the
  // thread's, reused without being cleared: every value the predictors read is written first.
  const unsigned long long framed =
      ZSTD_getFrameContentSize(data + kCodedHeaderBytes, bytes - kCodedHeaderBytes);
  if (framed == ZSTD_CONTENTSIZE_ERROR) throw bad("does not decompress (not a zstd frame)");
  const size_t capacity = framed == ZSTD_CONTENTSIZE_UNKNOWN
                              ? count * 10
                              : size_t(std::min<unsigned long long>(framed, count * 10));
  uint8_t* varints = threadBuffer<uint8_t>(capacity);
  const size_t got = ZSTD_decompressDCtx(threadDCtx(), varints, capacity, data + kCodedHeaderBytes,
                                         bytes - kCodedHeaderBytes);
  if (ZSTD_isError(got))
    throw bad(std::string("does not decompress (") + ZSTD_getErrorName(got) + ")");
  double* r = threadBuffer<double>(count);
  size_t pos = 0;
  visit(Predictor(data[8]), Lattice{n}, r, [&](int64_t i, double pred) {
    uint64_t u;
    if (pos < got && varints[pos] < 0x80) {
      u = varints[pos++];  // |code| < 64: one byte, the common case
    } else {
      u = 0;
      for (int shift = 0;; shift += 7) {
        if (pos >= got || shift > 63) throw bad("ends inside a residual");
        const uint8_t b = varints[pos++];
        u |= uint64_t(b & 0x7f) << shift;
        if (!(b & 0x80)) break;
      }
    }
    const int64_t code = int64_t(u >> 1) ^ -int64_t(u & 1);
    if (!(std::fabs(double(code)) <= kMaxCode)) throw bad("holds an absurd residual");
    r[size_t(i)] = pred + double(code) * step;
  });
  if (pos != got) throw bad("has " + std::to_string(got - pos) + " bytes after its last residual");
  for (size_t i = 0; i < count; ++i) {
    const float v = static_cast<float>(r[i]);
    if (!std::isfinite(v)) throw bad("decodes to a value beyond float32");
    out[i] = v;
  }
}

}  // namespace afam
