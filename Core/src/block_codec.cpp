// SPDX-License-Identifier: BSD-3-Clause
#include "afam/block_codec.hpp"

#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include "afam/errors.hpp"

namespace afam {

namespace {

constexpr int64_t kMaxQ = int64_t(1) << 50;
constexpr int64_t kMaxResidual = int64_t(1) << 56;

int64_t floorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

struct Lattice {
  Int3 n;
  int64_t index(int x, int y, int z) const { return (int64_t(z) * n[1] + y) * n[0] + x; }
};

/// Lorenzo over the points whose coordinates are multiples of s; fn(index, prediction) must leave
/// q[index] known when it returns.
template <typename Fn>
void lorenzo(const Lattice& L, std::vector<int64_t>& q, int s, Fn&& fn) {
  auto at = [&](int x, int y, int z) -> int64_t { return x < 0 || y < 0 || z < 0 ? 0 : q[size_t(L.index(x, y, z))]; };
  for (int z = 0; z < L.n[2]; z += s)
    for (int y = 0; y < L.n[1]; y += s)
      for (int x = 0; x < L.n[0]; x += s) {
        const int64_t p = at(x - s, y, z) + at(x, y - s, z) + at(x, y, z - s) - at(x - s, y - s, z) -
                          at(x - s, y, z - s) - at(x, y - s, z - s) + at(x - s, y - s, z - s);
        fn(L.index(x, y, z), p);
      }
}

/// Prediction of the point at coordinate c (an odd multiple of s) along one axis of length len,
/// from the known points at c -+ s and c -+ 3s; v(k) reads the point at coordinate k on that axis.
template <typename V>
int64_t interpolate(int c, int s, int len, V&& v) {
  const int64_t b = v(c - s);
  if (c + s >= len) return b;
  const int64_t d = v(c + s);
  if (c - 3 * s >= 0 && c + 3 * s < len) return floorDiv(-v(c - 3 * s) + 9 * b + 9 * d - v(c + 3 * s) + 8, 16);
  return floorDiv(b + d + 1, 2);
}

template <typename Fn>
void interpolation(const Lattice& L, std::vector<int64_t>& q, Fn&& fn) {
  const int maxn = std::max({L.n[0], L.n[1], L.n[2]});
  int S = 1;
  while (2 * S <= maxn - 1) S *= 2;
  lorenzo(L, q, S, fn);
  for (int s = S / 2; s >= 1; s /= 2) {
    const int s2 = 2 * s;
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s2)
        for (int x = s; x < L.n[0]; x += s2)
          fn(L.index(x, y, z), interpolate(x, s, L.n[0], [&](int k) { return q[size_t(L.index(k, y, z))]; }));
    for (int z = 0; z < L.n[2]; z += s2)
      for (int y = s; y < L.n[1]; y += s2)
        for (int x = 0; x < L.n[0]; x += s)
          fn(L.index(x, y, z), interpolate(y, s, L.n[1], [&](int k) { return q[size_t(L.index(x, k, z))]; }));
    for (int z = s; z < L.n[2]; z += s2)
      for (int y = 0; y < L.n[1]; y += s)
        for (int x = 0; x < L.n[0]; x += s)
          fn(L.index(x, y, z), interpolate(z, s, L.n[2], [&](int k) { return q[size_t(L.index(x, y, k))]; }));
  }
}

template <typename Fn>
void visit(Predictor p, const Lattice& L, std::vector<int64_t>& q, Fn&& fn) {
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

}  // namespace

bool encodeValues(const float* values, Int3 n, double step, Predictor predictor, int zstdLevel,
                  std::vector<uint8_t>& out, std::vector<float>& reconstructed) {
  out.clear();
  if (!(step > 0) || !std::isfinite(step)) return false;
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  std::vector<int64_t> q(count);
  reconstructed.resize(count);
  for (size_t i = 0; i < count; ++i) {
    const double v = std::nearbyint(double(values[i]) / step);
    if (!(std::fabs(v) <= kMaxQuantized)) return false;
    q[i] = int64_t(v);
    reconstructed[i] = static_cast<float>(double(q[i]) * step);
  }
  std::vector<uint8_t> varints;
  varints.reserve(count + count / 4);
  visit(predictor, Lattice{n}, q, [&](int64_t i, int64_t pred) {
    const int64_t r = q[size_t(i)] - pred;
    putVarint((uint64_t(r) << 1) ^ uint64_t(r >> 63), varints);
  });
  out.resize(kCodedHeaderBytes + ZSTD_compressBound(varints.size()));
  std::memcpy(out.data(), &step, 8);
  out[8] = uint8_t(predictor);
  const size_t z = ZSTD_compressCCtx(threadCCtx(), out.data() + kCodedHeaderBytes, out.size() - kCodedHeaderBytes,
                                     varints.data(), varints.size(), zstdLevel);
  if (ZSTD_isError(z)) throw Error(std::string("zstd: ") + ZSTD_getErrorName(z));
  out.resize(kCodedHeaderBytes + z);
  return true;
}

void decodeValues(const uint8_t* data, size_t bytes, Int3 n, float* out, const char* where) {
  auto bad = [&](const std::string& what) { return FormatError(std::string(where) + ": coded payload " + what); };
  if (bytes < kCodedHeaderBytes + 1) throw bad("shorter than its header");
  double step;
  std::memcpy(&step, data, 8);
  if (!(step > 0) || !std::isfinite(step)) throw bad("has an invalid quantization step");
  if (data[8] > uint8_t(Predictor::Interpolation)) throw bad("names unknown predictor " + std::to_string(data[8]));
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  std::vector<uint8_t> varints(count * 10);
  const size_t got = ZSTD_decompressDCtx(threadDCtx(), varints.data(), varints.size(), data + kCodedHeaderBytes,
                                         bytes - kCodedHeaderBytes);
  if (ZSTD_isError(got)) throw bad(std::string("does not decompress (") + ZSTD_getErrorName(got) + ")");
  std::vector<int64_t> q(count, 0);
  size_t pos = 0;
  visit(Predictor(data[8]), Lattice{n}, q, [&](int64_t i, int64_t pred) {
    uint64_t u = 0;
    for (int shift = 0;; shift += 7) {
      if (pos >= got || shift > 63) throw bad("ends inside a residual");
      const uint8_t b = varints[pos++];
      u |= uint64_t(b & 0x7f) << shift;
      if (!(b & 0x80)) break;
    }
    const int64_t r = int64_t(u >> 1) ^ -int64_t(u & 1);
    if (r > kMaxResidual || r < -kMaxResidual) throw bad("holds an absurd residual");
    const int64_t v = pred + r;
    if (v > kMaxQ || v < -kMaxQ) throw bad("decodes a value outside the quantization lattice");
    q[size_t(i)] = v;
  });
  if (pos != got) throw bad("has " + std::to_string(got - pos) + " bytes after its last residual");
  for (size_t i = 0; i < count; ++i) {
    const float v = static_cast<float>(double(q[i]) * step);
    if (!std::isfinite(v)) throw bad("decodes to a value beyond float32");
    out[i] = v;
  }
}

}  // namespace afam
