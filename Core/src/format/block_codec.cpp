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
/// q[index] known when it returns.
template <typename Fn>
void lorenzo(const Lattice& L, const double* q, int s, Fn&& fn) {
  auto at = [&](int x, int y, int z) -> double {
    return x < 0 || y < 0 || z < 0 ? 0.0 : q[size_t(L.index(x, y, z))];
  };
  for (int z = 0; z < L.n[2]; z += s)
    for (int y = 0; y < L.n[1]; y += s)
      for (int x = 0; x < L.n[0]; x += s) {
        const double p = at(x - s, y, z) + at(x, y - s, z) + at(x, y, z - s) - at(x - s, y - s, z) -
                         at(x - s, y, z - s) - at(x, y - s, z - s) + at(x - s, y - s, z - s);
        fn(L.index(x, y, z), p);
      }
}

/// Prediction of the point at coordinate c (an odd multiple of s) along one axis of length len,
/// from the known points at c -+ s and c -+ 3s; v(k) reads the point at coordinate k on that axis.
template <typename V>
double interpolate(int c, int s, int len, V&& v) {
  const double b = v(c - s);
  if (c + s >= len) return b;
  const double d = v(c + s);
  if (c - 3 * s >= 0 && c + 3 * s < len) return (-v(c - 3 * s) + 9 * b + 9 * d - v(c + 3 * s)) / 16;
  return (b + d) / 2;
}

template <typename Fn>
void interpolation(const Lattice& L, const double* q, Fn&& fn) {
  const int maxn = std::max({L.n[0], L.n[1], L.n[2]});
  int S = 1;
  while (2 * S <= maxn - 1) S *= 2;
  lorenzo(L, q, S, fn);
  for (int s = S / 2; s >= 1; s /= 2) {
    const int s2 = 2 * s;
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s2)
        for (int x = s; x < L.n[0]; x += s2)
          fn(L.index(x, y, z),
             interpolate(x, s, L.n[0], [&](int k) { return q[size_t(L.index(k, y, z))]; }));
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = s; y < L.n[1]; y += s2)
        for (int x = 0; x < L.n[0]; x += s)
          fn(L.index(x, y, z),
             interpolate(y, s, L.n[1], [&](int k) { return q[size_t(L.index(x, k, z))]; }));
    for (int z = s; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s)
        for (int x = 0; x < L.n[0]; x += s)
          fn(L.index(x, y, z),
             interpolate(z, s, L.n[2], [&](int k) { return q[size_t(L.index(x, y, k))]; }));
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
