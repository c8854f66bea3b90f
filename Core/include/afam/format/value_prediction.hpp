// SPDX-License-Identifier: BSD-3-Clause
// The block codec's predictions (block_codec.hpp): Lorenzo on a lattice of spacing s and the
// interpolation predictor's point prediction, written once for the CPU codec and the GPU decoder
// (host and device). Each sum is formed in one fixed order, so that encoder and decoders predict
// bit for bit alike (compiled without fused multiply-add on every side).
#pragma once

#include <cstdint>

#include "afam/base/host_device.hpp"
#include "afam/base/types.hpp"

namespace afam::codec {

struct Lattice {
  Int3 n;
  AFAM_HD int64_t index(int x, int y, int z) const { return (int64_t(z) * n[1] + y) * n[0] + x; }
};

/// Lorenzo's prediction of point i from its seven lower neighbours (strides sx, sy, sz), all inside
/// the lattice: the sum in its one fixed order.
template <typename T>
AFAM_HD T lorenzoInterior(const T* q, int64_t i, int64_t sx, int64_t sy, int64_t sz) {
  return q[i - sx] + q[i - sy] + q[i - sz] - q[i - sx - sy] - q[i - sx - sz] - q[i - sy - sz] +
         q[i - sx - sy - sz];
}

/// Lorenzo's prediction of a row's first point (no neighbour below in x; one outside reads 0).
template <typename T>
AFAM_HD T lorenzoRowStart(const T* q, int64_t row, int64_t sy, int64_t sz, bool hasY, bool hasZ) {
  const T b = hasY ? q[row - sy] : T(0), c = hasZ ? q[row - sz] : T(0);
  const T f = hasY && hasZ ? q[row - sy - sz] : T(0);
  return T(0) + b + c - T(0) - T(0) - f + T(0);
}

/// Lorenzo over the row (y, z) of the points whose coordinates are multiples of s, as lorenzo
/// walks it.
template <typename T, typename Fn>
AFAM_HD void lorenzoRow(const Lattice& L, const T* q, int s, int y, int z, Fn&& fn) {
  const int64_t sx = s, sy = int64_t(s) * L.n[0], sz = int64_t(s) * L.n[0] * L.n[1];
  const int64_t row = L.index(0, y, z);
  const bool hasY = y >= s, hasZ = z >= s;
  fn(row, lorenzoRowStart(q, row, sy, sz, hasY, hasZ));  // x = 0
  if (hasY && hasZ) {  // every neighbour inside: the common case, no tests
    for (int64_t i = row + sx; i < row + L.n[0]; i += sx) fn(i, lorenzoInterior(q, i, sx, sy, sz));
    return;
  }
  for (int64_t i = row + sx; i < row + L.n[0]; i += sx) {
    const T a = q[i - sx];
    const T b = hasY ? q[i - sy] : T(0), c = hasZ ? q[i - sz] : T(0);
    const T d = hasY ? q[i - sx - sy] : T(0), e = hasZ ? q[i - sx - sz] : T(0);
    fn(i, a + b + c - d - e - T(0) + T(0));
  }
}

/// Lorenzo over the points whose coordinates are multiples of s; fn(index, prediction) must leave
/// q[index] known when it returns. A neighbour outside the lattice reads 0.0.
template <typename T, typename Fn>
AFAM_HD void lorenzo(const Lattice& L, const T* q, int s, Fn&& fn) {
  for (int z = 0; z < L.n[2]; z += s)
    for (int y = 0; y < L.n[1]; y += s) lorenzoRow(L, q, s, y, z, fn);
}

/// The coarsest lattice spacing S of the interpolation predictor: its first points are Lorenzo's
/// on the lattice of spacing S, then each spacing s = S / 2 .. 1 predicts the points between.
AFAM_HD int coarsestSpacing(Int3 n) {
  int maxn = n[0] > n[1] ? n[0] : n[1];
  maxn = maxn > n[2] ? maxn : n[2];
  int S = 1;
  while (2 * S <= maxn - 1) S *= 2;
  return S;
}

/// Prediction of the point at coordinate c (an odd multiple of s) along one axis of length len,
/// from the known points at c -+ s and c -+ 3s; the point at coordinate k of that axis is
/// line[k * stride].
AFAM_HD double interpolate(int c, int s, int len, const double* line, int64_t stride) {
  const double b = line[int64_t(c - s) * stride];
  if (c + s >= len) return b;
  const double d = line[int64_t(c + s) * stride];
  if (c - 3 * s >= 0 && c + 3 * s < len)
    return (-line[int64_t(c - 3 * s) * stride] + 9 * b + 9 * d -
            line[int64_t(c + 3 * s) * stride]) /
           16;
  return (b + d) / 2;
}

}  // namespace afam::codec
